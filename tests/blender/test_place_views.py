"""Add Probes for Views (the operator runs synchronously in blender -b): in the partitioned room
(helpers.write_partitioned_room_xyz) a grid in the open half cannot see the corner behind the
partition; a camera there traces mostly UNKNOWN until a probe is added at its eye. The probe
set in the grid's folder lists the added probe, its world position carries the scene's world
offset, the overlay and the panels show it; the scene camera's path gives views every K
frames; a memory budget stops the loop; bad input and a cancel leave the previous set as it
was; the batch CLI's `place` does the same headless."""

import json
import os

import bpy
import numpy as np
from mathutils import Matrix

import helpers
import probe_scene

RESOLUTION = 64
TARGET = 0.01
GRID_CENTRE, GRID_HALF, GRID_COUNTS = (-1.0, 0.0, 1.25), (0.5, 0.1, 0.1), (2, 1, 1)  # in the open half
HIDDEN_EYE, HIDDEN_TARGET = (1.6, -0.8, 1.25), (2.0, -0.8, 1.0)  # behind the partition
OPEN_EYE, OPEN_TARGET = (-1.2, 0.4, 1.25), (-2.0, 0.4, 1.25)
LENS = 20.0
GEO_OFFSET = (512000.0, 5400000.0, 230.0)


def _room(offset=(0.0, 0.0, 0.0)):
    """A saved scene with the partitioned room imported (in the scene's frame `offset`) and a
    2×1×1 grid at RESOLUTION baking from it; returns (folder of the .blend, scan, grid)."""
    folder = helpers.tmp_dir()
    if any(offset):
        bpy.context.scene["lfprobe_world_offset"] = list(offset)
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(folder, "scene.blend"))
    path = os.path.join(helpers.tmp_dir(), "room.xyz")
    helpers.write_partitioned_room_xyz(path, offset=offset)
    (scan,) = helpers.import_scans(path)
    assert scan.lfprobe_scan.offset() == tuple(offset), scan.lfprobe_scan.offset()
    bpy.ops.object.lfprobe_grid_add()
    grid_obj = bpy.context.active_object
    grid_obj.location, grid_obj.scale = GRID_CENTRE, GRID_HALF
    grid = grid_obj.lfprobe_grid
    grid.counts, grid.resolution = GRID_COUNTS, RESOLUTION
    bpy.context.view_layer.update()
    return folder, scan, grid_obj


def _cameras():
    """The camera behind the partition and one in the open half, at probe_scene's image size."""
    hidden = probe_scene.add_camera("HiddenCam", HIDDEN_EYE, HIDDEN_TARGET, lens=LENS)
    opened = probe_scene.add_camera("OpenCam", OPEN_EYE, OPEN_TARGET, lens=LENS)
    return hidden, opened


def _select(*objects, active=None):
    for obj in bpy.context.view_layer.objects:
        obj.select_set(obj in objects)
    bpy.context.view_layer.objects.active = active


def _unknown_rate(grid_obj, camera_obj) -> float:
    """The camera's UNKNOWN rate through the grid's probe set, as the render engine traces it."""
    probe_view = helpers.addon("blender.probe_view")
    offset = probe_view.frame_offset(bpy.context.scene, grid_obj)
    camera = helpers.addon("blender.camera_export").camera_dict(bpy.context.scene, camera_obj, offset)
    field = probe_view.load_field(probe_view.probe_folder(grid_obj))
    image, _ = field.render(json.dumps(camera), threads=2)
    return float((image["status"] == 2).mean())


class _Layout:
    """Stands in for a panel's UILayout (none exists headless): takes every call, keeps the
    labels' text and the properties drawn."""

    def __init__(self, record=None):
        self.record = record if record is not None else {"labels": [], "props": [], "operators": []}

    def label(self, text="", **_kwargs):
        self.record["labels"].append(text)

    def prop(self, data, name, **_kwargs):
        assert hasattr(data, name), name
        self.record["props"].append(name)

    def operator(self, idname, **_kwargs):
        self.record["operators"].append(idname)
        return type("OperatorProperties", (), {})()

    def template_list(self, *_args, **_kwargs):
        pass

    def row(self, *_args, **_kwargs):
        return _Layout(self.record)

    column = box = row


def _draw_panels(grid_obj) -> dict:
    """Draws the grid panel and its Probes for Views sub-panel; returns what they drew."""
    panels = helpers.addon("blender.ui.panels")
    layout = _Layout()
    context = type("Context", (), {"object": grid_obj})()
    for panel in (panels.LFPROBE_PT_grid, panels.LFPROBE_PT_grid_views):
        assert panel.poll(context)
        panel.draw(type("Panel", (), {"layout": layout})(), context)
    return layout.record


def test_adds_a_probe_for_the_hidden_view_in_the_scene_frame():
    """Georeferenced: the scene's lfprobe_world_offset is the frame of the scan, the grid and the
    cameras; the added probe is at the hidden camera's eye in world coordinates."""
    folder, scan, grid_obj = _room(GEO_OFFSET)
    hidden, opened = _cameras()
    assert bpy.ops.object.lfprobe_bake(grid=grid_obj.name) == {"FINISHED"}
    before = _unknown_rate(grid_obj, hidden)
    assert before > 0.3, before  # the grid cannot see behind the partition
    assert _unknown_rate(grid_obj, opened) <= TARGET

    _select(hidden, opened, active=grid_obj)
    assert bpy.ops.object.lfprobe_place_for_views() == {"FINISHED"}
    after = _unknown_rate(grid_obj, hidden)
    print(f"  hidden view UNKNOWN {before:.2%} → {after:.2%}")
    assert after <= TARGET, after
    assert _unknown_rate(grid_obj, opened) <= TARGET

    probe_dir = helpers.addon("blender.grid").probe_dir_abspath(grid_obj)
    manifest = helpers.addon("core.probe_set").read_manifest(probe_dir)
    assert manifest["layout"] == "positions" and len(manifest["probes"]) == 3
    assert [a["view"] for a in manifest["bake"]["adaptive"]] == [0]  # HiddenCam, the first by name
    assert [s["path"] for s in manifest["sources"]] == scan.lfprobe_scan.paths()
    world = np.add(manifest["world_offset"], manifest["probes"][2]["position"])
    np.testing.assert_allclose(world, np.add(GEO_OFFSET, HIDDEN_EYE), atol=1e-4)
    assert sorted(os.listdir(folder)) == ["scene.blend", "scene_ProbeGrid_probes"]  # no staging left

    grid = grid_obj.lfprobe_grid
    placement = grid.placement()
    assert grid.baked and len(grid.coverage()) == 2
    assert placement["views"] == ["HiddenCam", "OpenCam"] and placement["stop"] == "target"
    assert placement["unknown_before"] > 0.3 and placement["unknown_after"] <= TARGET
    (added,) = placement["added"]
    np.testing.assert_allclose(added["position"], HIDDEN_EYE, atol=1e-4)  # Blender's frame
    assert added["view"] == "HiddenCam" and added["resolution"] == RESOLUTION
    assert placement["memory_bytes"] == helpers.addon("core.native").load().ProbeField.load(probe_dir).memory_bytes

    overlay = helpers.addon("blender.ui.overlay")
    grid_overlay = helpers.addon("core.grid_overlay")
    positions, colours, _lines = overlay.overlay_geometry(grid_obj)
    assert positions.shape == (3, 3) and colours.shape == (3, 4)
    np.testing.assert_allclose(positions[2], HIDDEN_EYE, atol=1e-4)
    np.testing.assert_allclose(colours[2], grid_overlay.ADDED_COLOUR)
    assert not np.allclose(colours[:2], grid_overlay.ADDED_COLOUR)
    drawn = _draw_panels(grid_obj)
    line = next(text for text in drawn["labels"] if "added (magenta)" in text)
    assert line.startswith("1 probe added (magenta) for 2 views: UNKNOWN") and line.endswith("MiB, target met"), line
    assert "object.lfprobe_place_for_views" in drawn["operators"]
    assert {"views_from", "target_unknown", "budget_mib", "max_added"} <= set(drawn["props"])

    # A plain bake replaces the set with the grid's probes alone: nothing added any more.
    assert bpy.ops.object.lfprobe_bake() == {"FINISHED"}
    assert grid.placement() == {} and overlay.overlay_geometry(grid_obj)[0].shape == (2, 3)
    assert not any("added" in text for text in _draw_panels(grid_obj)["labels"])


def test_scene_camera_path_every_k_frames_and_the_memory_budget():
    """The scene camera stands in the open half until frame 5, behind the partition from then
    on: frames 1 and 5 of 1–8 at a step of 4 are the views. A budget that the added probe does
    not fit stops the loop before it, and the set is the grid's probes alone."""
    _folder, _scan, grid_obj = _room()
    bpy.context.preferences.edit.keyframe_new_interpolation_type = "CONSTANT"
    camera = probe_scene.add_camera("PathCam", OPEN_EYE, OPEN_TARGET, lens=LENS)
    core_camera = helpers.addon("core.camera_json")
    for frame, (eye, target) in ((1, (OPEN_EYE, OPEN_TARGET)), (5, (HIDDEN_EYE, HIDDEN_TARGET))):
        camera.matrix_world = Matrix(core_camera.look_at_matrix(eye, target))
        camera.keyframe_insert("location", frame=frame)
        camera.keyframe_insert("rotation_euler", frame=frame)
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, 8
    scene.frame_set(3)
    grid = grid_obj.lfprobe_grid
    grid.views_from, grid.frame_step = "CAMERA_PATH", 4
    _select(active=grid_obj)
    assert bpy.ops.object.lfprobe_place_for_views() == {"FINISHED"}
    assert scene.frame_current == 3
    placement = grid.placement()
    assert placement["views"] == ["PathCam frame 1", "PathCam frame 5"], placement["views"]
    assert [a["view"] for a in placement["added"]] == ["PathCam frame 5"]
    np.testing.assert_allclose(placement["added"][0]["position"], HIDDEN_EYE, atol=1e-4)
    assert placement["unknown_after"] <= TARGET

    # The budget: the grid's probes and half the added one.
    added_bytes = placement["added"][0]["memory_bytes"]
    grid.budget_mib = (placement["memory_bytes"] - added_bytes / 2) / 2**20
    assert bpy.ops.object.lfprobe_place_for_views(grid=grid_obj.name) == {"FINISHED"}
    placement = grid.placement()
    assert placement["added"] == [] and placement["stop"] == "budget", placement
    assert placement["unknown_after"] > 0.3
    assert placement["budget_mib"] == grid.budget_mib
    manifest = helpers.addon("core.probe_set").read_manifest(helpers.addon("blender.grid").probe_dir_abspath(grid_obj))
    assert len(manifest["probes"]) == 2
    assert "memory budget reached" in helpers.addon("blender.operators.place_views").summary_line(placement)
    assert helpers.addon("blender.ui.overlay").overlay_geometry(grid_obj)[0].shape == (2, 3)


def test_bad_input_reports_an_error_and_keeps_the_previous_set():
    folder, scan, grid_obj = _room()
    hidden, _opened = _cameras()
    bpy.ops.object.lfprobe_bake(grid=grid_obj.name)
    probe_dir = helpers.addon("blender.grid").probe_dir_abspath(grid_obj)
    manifest = open(os.path.join(probe_dir, "manifest.json")).read()
    coverage = grid_obj.lfprobe_grid.coverage_json
    place = bpy.ops.object.lfprobe_place_for_views

    _select(active=grid_obj)
    helpers.expect_operator_error(lambda: place(), "no camera is selected")
    helpers.expect_operator_error(lambda: place(cameras=[{"name": "Nope"}]), "no object named 'Nope'")
    helpers.expect_operator_error(lambda: place(cameras=[{"name": scan.name}]), "not a camera")
    hidden.data.type = "ORTHO"
    helpers.expect_operator_error(lambda: place(cameras=[{"name": hidden.name}]), "HiddenCam", "orthographic")
    hidden.data.type = "PERSP"
    grid_obj.lfprobe_grid.views_from = "CAMERA_PATH"
    bpy.context.scene.camera = None
    helpers.expect_operator_error(lambda: place(), "has no camera")
    _select(scan, active=scan)
    helpers.expect_operator_error(lambda: place(), "not a probe grid")
    # No sources, a mesh source, a scan whose file is gone: the grid cannot be baked.
    sources = grid_obj.lfprobe_grid.sources
    sources.remove(0)
    helpers.expect_operator_error(lambda: place(grid=grid_obj.name, cameras=[{"name": "HiddenCam"}]), "no sources")
    bpy.ops.mesh.primitive_cube_add(size=1.0)
    sources.add().obj = bpy.context.active_object
    helpers.expect_operator_error(lambda: place(grid=grid_obj.name, cameras=[{"name": "HiddenCam"}]), "scan points")
    sources.remove(0)
    sources.add().obj = scan
    os.rename(scan.lfprobe_scan.paths()[0], scan.lfprobe_scan.paths()[0] + ".gone")
    helpers.expect_operator_error(lambda: place(grid=grid_obj.name, cameras=[{"name": "HiddenCam"}]), "missing")

    assert open(os.path.join(probe_dir, "manifest.json")).read() == manifest
    assert grid_obj.lfprobe_grid.coverage_json == coverage and grid_obj.lfprobe_grid.placement() == {}
    assert sorted(os.listdir(folder)) == ["scene.blend", "scene_ProbeGrid_probes"]


def test_cancel_keeps_the_previous_set():
    """Cancelled as the placement starts (the progress callback says stop, as Esc does in the
    UI, after the scans were read): the operator ends cancelled, the previous set and the grid
    stay as they were, nothing half made is left."""
    folder, _scan, grid_obj = _room()
    hidden, _opened = _cameras()
    bpy.ops.object.lfprobe_bake(grid=grid_obj.name)
    probe_dir = helpers.addon("blender.grid").probe_dir_abspath(grid_obj)
    manifest = open(os.path.join(probe_dir, "manifest.json")).read()
    job_modal = helpers.addon("blender.operators.job_modal")
    stages = []

    class StopWhenPlacing:
        def __call__(self, fraction, stage):
            stages.append(stage)
            return not stage.startswith(("starting", "base probes", "tracing", "probe "))

    terminal = job_modal.TerminalProgress
    job_modal.TerminalProgress = StopWhenPlacing
    try:
        result = bpy.ops.object.lfprobe_place_for_views(grid=grid_obj.name, cameras=[{"name": hidden.name}])
    finally:
        job_modal.TerminalProgress = terminal
    assert result == {"CANCELLED"}, result
    assert "starting" in stages, stages
    assert open(os.path.join(probe_dir, "manifest.json")).read() == manifest
    assert grid_obj.lfprobe_grid.placement() == {}
    assert sorted(os.listdir(folder)) == ["scene.blend", "scene_ProbeGrid_probes"]


def test_batch_cli_place():
    folder, _scan, grid_obj = _room()
    _cameras()
    grid_obj.lfprobe_grid.probe_dir = "//probes"
    bpy.ops.wm.save_mainfile()
    blend = bpy.data.filepath

    result = probe_scene.run_batch(blend, "place", "--views", "HiddenCam", "OpenCam", "--target-unknown", "0.01",
                                   "--budget-mib", "0", "--max-added", "4")
    output = result.stdout + result.stderr
    assert result.returncode == 0, output
    assert "1 probe added for 2 views" in output and "saved" in output, output
    manifest = helpers.addon("core.probe_set").read_manifest(os.path.join(folder, "probes"))
    assert len(manifest["probes"]) == 3 and len(manifest["bake"]["adaptive"]) == 1
    bpy.ops.wm.open_mainfile(filepath=blend)
    grid = bpy.data.objects["ProbeGrid"].lfprobe_grid
    assert grid.baked and grid.max_added == 4 and len(grid.placement()["added"]) == 1

    result = probe_scene.run_batch(blend, "place", "--views", "Nope")
    assert result.returncode == 2 and "no object named 'Nope'" in result.stderr, result.stdout + result.stderr
    assert "Traceback" not in result.stderr
