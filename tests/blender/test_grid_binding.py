"""A probe set is bound to the grid it was baked for: two .blend files in one folder, each with
the default grid, bake into folders of their own and each traces its own probes; a duplicated
grid bakes into its own folder and leaves the original's set alone; a grid pointed at another
grid's set is refused with a message naming both; whether a grid is baked is read from the set
on disk, so losing the grid's properties (as undo does) does not lose the bake."""

import json
import os

import bpy

import helpers

RESOLUTION = 16


def _grid_over_box_room(folder: str, blend_name: str):
    """A new file: the box room imported, a default grid fitted to it, saved as `blend_name`."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    helpers.enable_addon()
    scan = os.path.join(folder, "room.xyz")
    if not os.path.isfile(scan):
        helpers.write_box_room_xyz(scan, pitch=0.1)
    helpers.import_scans(scan)
    assert bpy.ops.object.lfprobe_grid_add() == {"FINISHED"}
    grid_obj = bpy.context.active_object
    bpy.ops.object.lfprobe_grid_fit(margin=1.0, spacing=0.0)
    grid_obj.lfprobe_grid.counts = (2, 1, 1)
    grid_obj.lfprobe_grid.resolution = RESOLUTION
    blend = os.path.join(folder, blend_name)
    bpy.ops.wm.save_as_mainfile(filepath=blend)
    return grid_obj, blend


def _manifest(folder: str) -> dict:
    with open(os.path.join(folder, "manifest.json"), encoding="utf-8") as stream:
        return json.load(stream)


def _traced_folder(grid_obj) -> str:
    return helpers.addon("blender.probe_view").probe_folder(grid_obj)


def _expect_trace_refused(grid_obj, *fragments) -> str:
    probe_view = helpers.addon("blender.probe_view")
    try:
        probe_view.probe_folder(grid_obj)
    except probe_view.TraceSetupError as error:
        message = str(error)
        for fragment in fragments:
            assert fragment in message, (fragment, message)
        return message
    raise AssertionError(f"grid {grid_obj.name!r} traced a probe set that is not its own")


def test_two_blend_files_in_one_folder_bake_and_trace_their_own_probes():
    folder = helpers.tmp_dir()
    first, first_blend = _grid_over_box_room(folder, "first.blend")
    assert first.name == "ProbeGrid"
    assert bpy.ops.object.lfprobe_bake() == {"FINISHED"}
    first_id = first.lfprobe_grid.grid_id
    bpy.ops.wm.save_mainfile()
    first_set = os.path.join(folder, "first_ProbeGrid_probes")
    first_manifest = open(os.path.join(first_set, "manifest.json")).read()

    second, second_blend = _grid_over_box_room(folder, "second.blend")
    assert second.name == "ProbeGrid"
    assert bpy.ops.object.lfprobe_bake() == {"FINISHED"}
    second_set = os.path.join(folder, "second_ProbeGrid_probes")
    assert _traced_folder(second) == second_set
    record = _manifest(second_set)["bake"]["blender_grid"]
    assert record == {"id": second.lfprobe_grid.grid_id, "name": "ProbeGrid", "blend": "second.blend"}
    assert record["id"] != first_id
    bpy.ops.wm.save_mainfile()

    # The first file's set is untouched and still the one its grid traces.
    assert open(os.path.join(first_set, "manifest.json")).read() == first_manifest
    bpy.ops.wm.open_mainfile(filepath=first_blend)
    grid_obj = bpy.data.objects["ProbeGrid"]
    assert _traced_folder(grid_obj) == first_set
    assert helpers.addon("blender.grid").baked_grids(bpy.context.scene) == [grid_obj]
    # Pointed at the other file's set, the grid refuses it and says whose it is.
    grid_obj.lfprobe_grid.probe_dir = "//second_ProbeGrid_probes"
    _expect_trace_refused(grid_obj, "baked for grid 'ProbeGrid' of second.blend", "not for grid 'ProbeGrid'")
    assert helpers.addon("blender.grid").baked_grids(bpy.context.scene) == []


def test_duplicated_grid_bakes_into_its_own_folder():
    folder = helpers.tmp_dir()
    original, _blend = _grid_over_box_room(folder, "scene.blend")
    assert bpy.ops.object.lfprobe_bake() == {"FINISHED"}
    original_set = _traced_folder(original)
    before = open(os.path.join(original_set, "manifest.json")).read()

    copy = original.copy()  # what Duplicate does: the properties come along, folder and id too
    bpy.context.scene.collection.objects.link(copy)
    copy.location.x += 0.5
    assert copy.lfprobe_grid.probe_dir == original.lfprobe_grid.probe_dir
    grid = helpers.addon("blender.grid")
    # Until it is baked the copy has no set of its own: it is not traced, the original is.
    _expect_trace_refused(copy, f"grid {copy.name!r} is a copy of grid 'ProbeGrid'")
    assert grid.baked_grids(bpy.context.scene) == [original]

    assert bpy.ops.object.lfprobe_bake(grid=copy.name) == {"FINISHED"}
    copy_set = _traced_folder(copy)
    assert copy_set != original_set and os.path.basename(copy_set) == f"scene_{bpy.path.clean_name(copy.name)}_probes"
    assert copy.lfprobe_grid.grid_id != original.lfprobe_grid.grid_id
    assert open(os.path.join(original_set, "manifest.json")).read() == before
    assert _traced_folder(original) == original_set
    assert grid.baked_grids(bpy.context.scene) == sorted([original, copy], key=lambda o: o.name)
    # The copy's probes are where the copy is, not where the original is.
    first_x = _manifest(copy_set)["probes"][0]["position"][0]
    assert abs(first_x - _manifest(original_set)["probes"][0]["position"][0] - 0.5) < 1e-5


def test_a_folder_holding_another_grids_set_is_refused_before_baking():
    folder = helpers.tmp_dir()
    first, _blend = _grid_over_box_room(folder, "scene.blend")
    assert bpy.ops.object.lfprobe_bake() == {"FINISHED"}
    bpy.ops.object.lfprobe_grid_add()
    other = bpy.context.active_object
    other.lfprobe_grid.sources.add().obj = first.lfprobe_grid.sources[0].obj
    other.lfprobe_grid.resolution = RESOLUTION
    other.lfprobe_grid.probe_dir = first.lfprobe_grid.probe_dir
    before = open(os.path.join(_traced_folder(first), "manifest.json")).read()
    helpers.expect_operator_error(lambda: bpy.ops.object.lfprobe_bake(grid=other.name),
                                  "holds the probes of grid 'ProbeGrid'", "Probe Folder of its own")
    assert open(os.path.join(_traced_folder(first), "manifest.json")).read() == before


def test_baked_state_is_read_from_the_set_not_from_grid_properties():
    folder = helpers.tmp_dir()
    grid_obj, _blend = _grid_over_box_room(folder, "scene.blend")
    assert bpy.ops.object.lfprobe_bake() == {"FINISHED"}
    grid = grid_obj.lfprobe_grid
    # What undo rewinds: the flag and the coverage the bake put on the grid.
    grid.baked = False
    grid.coverage_json = "[]"
    bound = helpers.addon("blender.grid").bound_set(grid_obj)
    assert bound.usable and len(bound.manifest["probes"]) == 2
    assert helpers.addon("blender.grid").baked_grids(bpy.context.scene) == [grid_obj]
    assert _traced_folder(grid_obj) == bound.folder
