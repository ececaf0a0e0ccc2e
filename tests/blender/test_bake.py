"""Baking a grid headless (the operator runs synchronously in blender -b): the probe set
lands next to the .blend, probes see the walls where the scan has them (the frames of
Blender, the scan and the probe set agree), coverage goes onto the grid, a georeferenced scan
bakes in its world frame, a moved scan object bakes where it is shown, a failed re-bake keeps
the previous probe set, and meshes bake through mesh_export."""

import json
import os

import bpy
import numpy as np

import helpers

RESOLUTION = 32


def _saved_scene() -> str:
    folder = helpers.tmp_dir()
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(folder, "scene.blend"))
    return folder


def _box_room_grid(counts=(2, 2, 1), margin=1.0):
    path = os.path.join(helpers.tmp_dir(), "box_room.xyz")
    helpers.write_box_room_xyz(path, pitch=0.05)
    (scan,) = helpers.import_scans(path)
    bpy.ops.object.lfprobe_grid_add()
    grid_obj = bpy.context.active_object
    bpy.ops.object.lfprobe_grid_fit(margin=margin, spacing=0.0)
    grid_obj.lfprobe_grid.counts = counts
    grid_obj.lfprobe_grid.resolution = RESOLUTION
    return scan, grid_obj, path


def _wall_error(probe: dict, direction, wall_distance: float) -> float:
    """|stored − true| distance for the probe's texel in a world direction to an axis-aligned
    wall `wall_distance` away along it (the texel's own direction, by the octahedral map,
    is a little off the axis: the true distance along it is wall_distance / cos)."""
    _native = helpers.addon("core.native").load()
    uv = _native.oct_encode(np.array([direction], dtype=np.float32))[0]
    n = probe["resolution"]
    x, y = (min(int(c * n), n - 1) for c in uv)
    centre = np.array([[(x + 0.5) / n, (y + 0.5) / n]], dtype=np.float32)
    texel_direction = _native.oct_decode(centre)[0]
    expected = wall_distance / float(np.dot(texel_direction, direction))
    return abs(float(probe["distance"][y, x]) - expected)


def test_bake_next_to_the_blend_with_coverage():
    folder = _saved_scene()
    scan, grid_obj, path = _box_room_grid()
    assert bpy.ops.object.lfprobe_bake() == {"FINISHED"}
    probe_dir = os.path.join(folder, f"scene_{grid_obj.name}_probes")  # //<blend>_<grid>_probes
    assert os.path.isfile(os.path.join(probe_dir, "manifest.json"))
    assert not os.path.exists(probe_dir + ".baking")
    manifest = helpers.addon("core.probe_set").read_manifest(probe_dir)
    assert len(manifest["probes"]) == 4 and manifest["layout"] == "grid"
    first_probe = helpers.addon("blender.grid").probe_positions(grid_obj)[0]
    np.testing.assert_allclose(manifest["grid"]["origin"], first_probe, atol=1e-5)
    assert manifest["grid"]["counts"] == [2, 2, 1]
    assert [s["path"] for s in manifest["sources"]] == [path]
    grid = grid_obj.lfprobe_grid
    assert grid.baked
    assert json.loads(grid.coverage_json) == [p["coverage"] for p in manifest["probes"]]
    assert helpers.addon("blender.grid").baked_grids(bpy.context.scene) == [grid_obj]
    # Inside a closed room, a probe sees walls almost everywhere, at the walls' distances.
    _native = helpers.addon("core.native").load()
    probe = _native.read_probe(os.path.join(probe_dir, manifest["probes"][0]["file"]))
    position = np.array(manifest["probes"][0]["position"])
    np.testing.assert_allclose(position, first_probe, atol=1e-5)
    assert probe["coverage"]["unknown"] < 0.1, probe["coverage"]
    for direction, wall in (((-1, 0, 0), position[0] + 2.0), ((0, 0, 1), 2.5 - position[2]), ((0, 0, -1), position[2])):
        assert _wall_error(probe, direction, wall) < 0.02, (direction, wall)


def test_rebake_replaces_and_a_failed_bake_keeps_the_previous_set():
    folder = _saved_scene()
    scan, grid_obj, path = _box_room_grid()
    bpy.ops.object.lfprobe_bake()
    probe_dir = helpers.addon("blender.grid").probe_dir_abspath(grid_obj)
    before = open(os.path.join(probe_dir, "manifest.json")).read()
    grid_obj.lfprobe_grid.counts = (3, 2, 1)
    assert bpy.ops.object.lfprobe_bake() == {"FINISHED"}
    assert len(json.loads(open(os.path.join(probe_dir, "manifest.json")).read())["probes"]) == 6
    assert sorted(os.listdir(folder)) == sorted(["scene.blend", os.path.basename(probe_dir)])
    # The scan file goes bad: the bake fails with the file's name, the set stays as it was.
    after_first = open(os.path.join(probe_dir, "manifest.json")).read()
    assert after_first != before
    with open(path, "a") as stream:
        stream.write("1.0 2.0 oops 4 5 6\n")
    coverage = grid_obj.lfprobe_grid.coverage_json
    helpers.expect_operator_error(lambda: bpy.ops.object.lfprobe_bake(), os.path.basename(path), "oops")
    assert open(os.path.join(probe_dir, "manifest.json")).read() == after_first
    assert grid_obj.lfprobe_grid.baked and grid_obj.lfprobe_grid.coverage_json == coverage
    assert sorted(os.listdir(folder)) == sorted(["scene.blend", os.path.basename(probe_dir)])


def test_georeferenced_scan_bakes_in_its_world_frame():
    _saved_scene()
    path = helpers.shared_data("scans/autzen_trim_xyzrgb.xyz")
    (scan,) = helpers.import_scans(path)
    bpy.ops.object.lfprobe_grid_add()
    grid_obj = bpy.context.active_object
    grid_obj.location = (10.0, -20.0, 30.0)
    grid_obj.scale = (5.0, 5.0, 5.0)
    grid_obj.lfprobe_grid.counts = (2, 1, 1)
    grid_obj.lfprobe_grid.resolution = 16
    bpy.context.view_layer.update()
    assert bpy.ops.object.lfprobe_bake() == {"FINISHED"}
    manifest = helpers.addon("core.probe_set").read_manifest(
        helpers.addon("blender.grid").probe_dir_abspath(grid_obj))
    offset = np.array(scan.lfprobe_scan.offset())
    world = np.array(manifest["world_offset"]) + np.array([p["position"] for p in manifest["probes"]])
    np.testing.assert_allclose(world, offset + np.array([[5.0, -20.0, 30.0], [15.0, -20.0, 30.0]]), atol=1e-6)


def test_moved_scan_object_bakes_where_it_is_shown():
    _saved_scene()
    scan, grid_obj, _ = _box_room_grid(counts=(1, 1, 1))
    scan.location = (1.0, 0.0, 0.0)
    grid_obj.location = (1.0, 0.0, 1.25)  # the room's centre, moved with it
    bpy.context.view_layer.update()
    assert bpy.ops.object.lfprobe_bake() == {"FINISHED"}
    probe_dir = helpers.addon("blender.grid").probe_dir_abspath(grid_obj)
    manifest = helpers.addon("core.probe_set").read_manifest(probe_dir)
    probe = helpers.addon("core.native").load().read_probe(os.path.join(probe_dir, manifest["probes"][0]["file"]))
    assert _wall_error(probe, (-1, 0, 0), 2.0) < 0.03
    assert _wall_error(probe, (1, 0, 0), 2.0) < 0.03
    assert _wall_error(probe, (0, 1, 0), 1.5) < 0.03


def test_mesh_source_bakes_through_mesh_export():
    _saved_scene()
    bpy.ops.mesh.primitive_cube_add(size=4.0, location=(0.0, 0.0, 0.0))
    cube = bpy.context.active_object
    bpy.ops.object.lfprobe_grid_add()
    grid_obj = bpy.context.active_object
    assert [s.obj for s in grid_obj.lfprobe_grid.sources] == []  # meshes are added explicitly
    cube.select_set(True)
    assert bpy.ops.object.lfprobe_grid_source_add() == {"FINISHED"}
    grid_obj.location = (0.5, 0.0, 0.0)
    grid_obj.scale = (0.5, 0.5, 0.5)
    grid_obj.lfprobe_grid.counts = (2, 1, 1)
    grid_obj.lfprobe_grid.resolution = RESOLUTION
    bpy.context.view_layer.update()
    assert bpy.ops.object.lfprobe_bake() == {"FINISHED"}
    probe_dir = helpers.addon("blender.grid").probe_dir_abspath(grid_obj)
    manifest = helpers.addon("core.probe_set").read_manifest(probe_dir)
    _native = helpers.addon("core.native").load()
    first = _native.read_probe(os.path.join(probe_dir, manifest["probes"][0]["file"]))  # at x = 0
    second = _native.read_probe(os.path.join(probe_dir, manifest["probes"][1]["file"]))  # at x = 1
    assert first["coverage"]["unknown"] == 0.0
    assert _wall_error(first, (1, 0, 0), 2.0) < 1e-3
    assert _wall_error(second, (1, 0, 0), 1.0) < 1e-3
    assert _wall_error(second, (0, 0, -1), 2.0) < 1e-3


def test_plan_from_data_sizes_moves_and_shows_the_probes():
    """Plan From Data: each probe at the resolution the 5 cm scan supports (capped by the grid's
    Resolution), a probe on a wall's plane moved off it; the plan goes onto the grid, and the
    overlay colours moved probes blue."""
    _saved_scene()
    scan, grid_obj, _path = _box_room_grid(counts=(2, 1, 1), margin=0.0)
    grid = grid_obj.lfprobe_grid
    grid.resolution = 512
    grid.plan_from_data = True
    # margin 0: the probes sit on the planes of the room's walls, where the side behind the wall
    # (never scanned) is unknown: a step into the room lets them see it, so they move.
    assert bpy.ops.object.lfprobe_bake() == {"FINISHED"}
    plan = grid.plan()
    assert len(plan) == 2
    assert all(p["moved"] and p["class"] == "useful" for p in plan), plan
    assert all(p["classification"]["unknown"] < 0.05 for p in plan), plan
    manifest = helpers.addon("core.probe_set").read_manifest(helpers.addon("blender.grid").probe_dir_abspath(grid_obj))
    for record, planned in zip(manifest["probes"], plan):
        assert record["resolution"] == planned["resolution"] <= 512
    overlay = helpers.addon("blender.ui.overlay")
    grid_overlay = helpers.addon("core.grid_overlay")
    _positions, colours, _lines = overlay.overlay_geometry(grid_obj)
    for colour, planned in zip(colours, plan):
        if planned["dropped"]:
            np.testing.assert_allclose(colour, grid_overlay.DROPPED_COLOUR, atol=1e-6)
        elif planned["moved"]:
            np.testing.assert_allclose(colour, grid_overlay.MOVED_COLOUR, atol=1e-6)


def test_estimate_coverage_before_baking_writes_nothing():
    folder = _saved_scene()
    _scan, grid_obj, _ = _box_room_grid(counts=(2, 2, 1))
    assert bpy.ops.object.lfprobe_grid_estimate() == {"FINISHED"}
    estimate = grid_obj.lfprobe_grid.estimate()
    assert estimate["probes"] == 4 and estimate["counts"] == [2, 2, 1]
    assert len(estimate["unknown"]) == 4
    assert estimate["mean_unknown"] < 0.1, estimate  # inside a closed room scanned all round
    assert estimate["mostly_unknown"] == 0
    assert not any(name.endswith("_probes") for name in os.listdir(folder))
    # Moved out of the room, the probes see its walls from behind, which no scan saw.
    grid_obj.location.x += 10.0
    assert bpy.ops.object.lfprobe_grid_estimate() == {"FINISHED"}
    assert grid_obj.lfprobe_grid.estimate()["mean_unknown"] > 0.5
