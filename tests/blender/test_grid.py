"""Probe grids: adding one, fitting it to a scan's full bounds with counts from a spacing,
the probe positions, the refusal of rotated grids, and the overlay's geometry (points
coloured by coverage, cell lines)."""

import json
import math
import os

import bpy
import numpy as np

import helpers


def _box_room_scan():
    path = os.path.join(helpers.tmp_dir(), "box_room.xyz")
    helpers.write_box_room_xyz(path, pitch=0.1)
    (scan,) = helpers.import_scans(path)
    return scan


def test_add_grid_defaults_and_selected_sources():
    scan = _box_room_scan()
    assert scan.select_get()
    assert bpy.ops.object.lfprobe_grid_add() == {"FINISHED"}
    grid_obj = bpy.context.active_object
    grid = grid_obj.lfprobe_grid
    assert grid_obj.type == "EMPTY" and grid_obj.empty_display_type == "CUBE"
    assert grid.is_grid and not grid.baked
    assert tuple(grid.counts) == (2, 2, 2)
    assert grid.resolution == 512 and grid.coarse_resolution == 0
    # The folder is the default until the first bake: //<grid>_probes while the .blend is unsaved.
    assert grid.probe_dir == "" and len(grid.grid_id) == 32
    assert helpers.addon("blender.grid").default_probe_dir(grid_obj) == f"//{grid_obj.name}_probes"
    assert [s.obj for s in grid.sources] == [scan]
    assert helpers.addon("blender.grid").baked_grids(bpy.context.scene) == []


def test_fit_to_the_full_cloud_with_margin_and_spacing():
    scan = _box_room_scan()
    bpy.ops.object.lfprobe_grid_add()
    grid_obj = bpy.context.active_object
    assert bpy.ops.object.lfprobe_grid_fit(margin=0.25, spacing=1.0) == {"FINISHED"}
    # The box room spans −2..2, −1.5..1.5, 0..2.5; 0.25 inside that: 3.5 × 2.5 × 2.0.
    np.testing.assert_allclose(grid_obj.location, (0.0, 0.0, 1.25), atol=1e-6)
    np.testing.assert_allclose(grid_obj.scale, (1.75, 1.25, 1.0), atol=1e-6)
    assert tuple(grid_obj.lfprobe_grid.counts) == (5, 4, 3)  # at most 1 m apart
    grid = helpers.addon("blender.grid")
    positions = grid.probe_positions(grid_obj)
    assert positions.shape == (60, 3)
    np.testing.assert_allclose(positions[0], (-1.75, -1.25, 0.25), atol=1e-6)
    np.testing.assert_allclose(positions[1], (-0.875, -1.25, 0.25), atol=1e-6)  # x fastest
    np.testing.assert_allclose(positions[-1], (1.75, 1.25, 2.25), atol=1e-6)
    # The scan is its source now, once.
    bpy.ops.object.lfprobe_grid_fit(margin=0.25, spacing=1.0)
    assert [s.obj for s in grid_obj.lfprobe_grid.sources] == [scan]


def test_fit_uses_the_full_cloud_not_the_display_subsample():
    path = helpers.shared_data("scans/pumpA_xyzrgb.xyz")
    (full,) = helpers.import_scans(path)
    (small,) = helpers.import_scans(path, display_limit=1000)
    bpy.ops.object.lfprobe_grid_add()
    grid_obj = bpy.context.active_object
    bpy.ops.object.lfprobe_grid_fit(margin=0.0, spacing=0.0)
    assert grid_obj.lfprobe_grid.sources[0].obj == small
    lo, hi = helpers.addon("blender.grid").grid_box(grid_obj)
    vertices = np.empty(len(full.data.vertices) * 3, dtype=np.float32)
    full.data.vertices.foreach_get("co", vertices)
    vertices = vertices.reshape(-1, 3)
    np.testing.assert_allclose(lo, vertices.min(axis=0), atol=1e-5)
    np.testing.assert_allclose(hi, vertices.max(axis=0), atol=1e-5)
    assert tuple(grid_obj.lfprobe_grid.counts) == (2, 2, 2)  # spacing 0 keeps the counts


def test_probe_dir_is_relative_to_the_blend():
    bpy.ops.object.lfprobe_grid_add()
    grid_obj = bpy.context.active_object
    folder = helpers.tmp_dir()
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(folder, "scene.blend"))
    grid = helpers.addon("blender.grid")
    assert grid.probe_dir_abspath(grid_obj) == os.path.join(folder, f"scene_{grid_obj.name}_probes")
    grid_obj.lfprobe_grid.probe_dir = "/somewhere/else"
    assert grid.probe_dir_abspath(grid_obj) == "/somewhere/else"


def test_rotated_grid_is_refused_with_the_reason():
    bpy.ops.object.lfprobe_grid_add()
    grid_obj = bpy.context.active_object
    grid_obj.rotation_euler = (0.0, 0.0, math.radians(30))
    bpy.context.view_layer.update()
    grid = helpers.addon("blender.grid")
    try:
        grid.grid_box(grid_obj)
    except grid.GridError as error:
        assert "rotated" in str(error) and grid_obj.name in str(error) and "30" in str(error), str(error)
    else:
        raise AssertionError("a rotated grid was accepted")


def test_overlay_points_coloured_by_coverage_and_cell_lines():
    bpy.ops.object.lfprobe_grid_add()
    grid_obj = bpy.context.active_object
    grid_obj.location = (1.0, 2.0, 3.0)
    grid_obj.scale = (2.0, 1.0, 0.5)
    grid_obj.lfprobe_grid.counts = (3, 2, 2)
    bpy.context.view_layer.update()
    overlay = helpers.addon("blender.ui.overlay")
    grid_overlay = helpers.addon("core.grid_overlay")
    points, colours, lines = overlay.overlay_geometry(grid_obj)
    assert points.shape == (12, 3) and colours.shape == (12, 4)
    np.testing.assert_allclose(colours, np.tile(grid_overlay.UNBAKED_COLOUR, (12, 1)))
    # Lines: along x one per (y, z) row (4), along y one per (x, z) (6), along z per (x, y) (6).
    assert lines.shape == (2 * 16, 3)
    segments = lines.reshape(-1, 2, 3)
    lengths = sorted(np.round(np.linalg.norm(segments[:, 1] - segments[:, 0], axis=1), 6))
    assert lengths == [1.0] * 6 + [2.0] * 6 + [4.0] * 4, lengths
    assert np.all(lines >= np.array([-1.0, 1.0, 2.5]) - 1e-6) and np.all(lines <= np.array([3.0, 3.0, 3.5]) + 1e-6)
    # After a bake, coverage colours: all unknown is red, all measured is green.
    coverage = [{"surface": 0.0, "inferred": 0.0, "empty": 0.0, "unknown": 1.0}] * 6 + \
               [{"surface": 0.9, "inferred": 0.05, "empty": 0.05, "unknown": 0.0}] * 6
    grid_obj.lfprobe_grid.coverage_json = json.dumps(coverage)
    _, colours, _ = overlay.overlay_geometry(grid_obj)
    np.testing.assert_allclose(colours[0, :2], (1.0, 0.0))
    np.testing.assert_allclose(colours[-1, :2], (0.0, 1.0))
    # Coverage of another grid size is not shown as if it were this one's.
    grid_obj.lfprobe_grid.counts = (2, 2, 2)
    _, colours, _ = overlay.overlay_geometry(grid_obj)
    np.testing.assert_allclose(colours, np.tile(grid_overlay.UNBAKED_COLOUR, (8, 1)))
