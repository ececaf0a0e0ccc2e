"""The add-on's array arithmetic that lives in core without Blender: the grid overlay's colours
and lines (core.grid_overlay), scan display and shared frames (core.scan_points), Fit Grid to
Scan's box (core.grid_fit) and the mesh export's world transforms (core.mesh_arrays)."""

import numpy as np
import pytest

from lfprobe.core import grid_fit, grid_overlay, mesh_arrays, scan_points


def _lattice(counts):
    nx, ny, nz = counts
    return np.array([(x, y, z) for z in range(nz) for y in range(ny) for x in range(nx)], dtype=np.float64)


def test_coverage_colours_run_from_red_to_green_and_stay_grey_without_coverage():
    colours = grid_overlay.coverage_colours([{"unknown": 1.0}, {"unknown": 0.25}, {}], 3)
    np.testing.assert_allclose(colours[0], (1.0, 0.0, 0.1, 1.0))
    np.testing.assert_allclose(colours[1], (0.25, 0.75, 0.1, 1.0))
    np.testing.assert_allclose(colours[2], (1.0, 0.0, 0.1, 1.0))  # no figure: nothing known
    assert colours.dtype == np.float32
    np.testing.assert_allclose(grid_overlay.coverage_colours([{"unknown": 0.0}], 2),
                               np.tile(grid_overlay.UNBAKED_COLOUR, (2, 1)))


def test_plan_colours_mark_moved_and_dropped_probes_only_for_a_plan_of_the_same_size():
    colours = grid_overlay.coverage_colours([], 3)
    planned = grid_overlay.plan_colours(colours, [{"moved": True}, {"dropped": True, "moved": True}, {}])
    np.testing.assert_allclose(planned[0], grid_overlay.MOVED_COLOUR)
    np.testing.assert_allclose(planned[1], grid_overlay.DROPPED_COLOUR)
    np.testing.assert_allclose(planned[2], grid_overlay.UNBAKED_COLOUR)
    assert grid_overlay.plan_colours(colours, [{"moved": True}]) is colours


def test_cell_lines_join_the_ends_of_every_row_of_probes():
    lines = grid_overlay.cell_lines(_lattice((3, 2, 1)), (3, 2, 1))
    # Rows along x: 2 (one per y); rows along y: 3 (one per x); no z rows with one layer.
    assert lines.shape == (2 * (2 + 3), 3)
    np.testing.assert_allclose(lines[:2], [(0, 0, 0), (2, 0, 0)])
    np.testing.assert_allclose(lines[4:6], [(0, 0, 0), (0, 1, 0)])
    assert grid_overlay.cell_lines(_lattice((1, 1, 1)), (1, 1, 1)).shape == (0, 3)


def test_overlay_geometry_puts_the_probes_added_for_views_after_the_grid_in_magenta():
    positions, colours, lines = grid_overlay.overlay_geometry(
        _lattice((2, 1, 1)), (2, 1, 1), [], [], {"added": [{"position": [5.0, 6.0, 7.0]}]})
    assert positions.dtype == colours.dtype == lines.dtype == np.float32
    np.testing.assert_allclose(positions[2], (5.0, 6.0, 7.0))
    np.testing.assert_allclose(colours[2], grid_overlay.ADDED_COLOUR)
    np.testing.assert_allclose(lines, [(0, 0, 0), (1, 0, 0)])


def test_display_indices_are_a_fixed_sorted_subset_or_none():
    assert scan_points.display_indices(10, 10) is None
    assert scan_points.display_indices(10, 0) is None
    chosen = scan_points.display_indices(1000, 50)
    assert len(chosen) == 50 and len(set(chosen.tolist())) == 50
    assert np.all(np.diff(chosen) > 0)
    np.testing.assert_array_equal(chosen, scan_points.display_indices(1000, 50))


def test_display_indices_show_the_points_they_always_showed():
    # The subset a saved scene was imported with: the seeded draw, shuffled then sorted, as it
    # was drawn before the shuffle was dropped and the sort became a mask.
    for count, limit in ((1000, 50), (300_000, 100_000), (200_000, 199_999), (50_000, 7)):
        before = np.random.default_rng(scan_points.DISPLAY_SEED).choice(count, size=limit, replace=False)
        before.sort()
        np.testing.assert_array_equal(scan_points.display_indices(count, limit), before)


@pytest.mark.parametrize("count", [1, 4095, 4096, 8192, 10_000])
def test_column_bounds_are_numpys_min_and_max(count):
    values = np.random.default_rng(count).normal(size=(count, 3)).astype(np.float32)
    low, high = scan_points.column_bounds(values)
    np.testing.assert_array_equal(low, values.min(axis=0))
    np.testing.assert_array_equal(high, values.max(axis=0))
    with pytest.raises(ValueError):
        scan_points.column_bounds(values[:0])


def test_automatic_point_radius_is_half_the_spacing_over_the_box_faces():
    # A 1 m cube has 6 m² of faces: 600 points are 0.1 m apart, radius 0.05 m.
    assert scan_points.automatic_point_radius((0, 0, 0), (1, 1, 1), 600) == pytest.approx(0.05)


def test_a_cloud_near_the_scene_frame_moves_into_it_and_a_far_one_keeps_its_offset():
    positions = np.array([[1.0, 2.0, 3.0]], dtype=np.float32)
    moved, offset, too_far = scan_points.in_shared_frame(positions, (100.0, 0.0, 0.0), (90.0, 0.0, 0.0))
    assert not too_far and moved.dtype == np.float32
    np.testing.assert_allclose(moved, [[11.0, 2.0, 3.0]])
    np.testing.assert_allclose(offset, (90.0, 0.0, 0.0))
    same, offset, too_far = scan_points.in_shared_frame(positions, (5e4, 0.0, 0.0), (0.0, 0.0, 0.0))
    assert too_far and same is positions
    np.testing.assert_allclose(offset, (5e4, 0.0, 0.0))
    same, offset, too_far = scan_points.in_shared_frame(positions, (1.0, 2.0, 3.0), None)
    assert not too_far and same is positions


def test_object_groups_and_points_split_a_merged_cloud_per_file():
    scans = [{"scanner": [0, 0, 0]}, {"scanner": [1, 1, 1]}]
    merged = scan_points.object_groups(["a", "b"], scans, 4, None)
    assert len(merged) == 1 and merged[0][0] == ["a", "b"] and merged[0][2] == [[0, 0, 0], [1, 1, 1]]
    per_file = scan_points.object_groups(["a", "b"], scans, 4, np.array([0, 1, 1, 0]))
    np.testing.assert_array_equal(per_file[1][1], [1, 2])
    positions = np.arange(12, dtype=np.float32).reshape(4, 3)
    bounds, shown, colours = scan_points.object_points(positions, None, per_file[1][1], 10)
    assert bounds == ((3.0, 4.0, 5.0), (6.0, 7.0, 8.0)) and colours is None
    np.testing.assert_array_equal(shown, positions[1:3])


def test_fitted_box_keeps_a_margin_and_collapses_thin_axes_onto_their_centre():
    low, high = grid_fit.fitted_box([(0, 0, 0), (4, 2, 0.2)], 0.25)
    np.testing.assert_allclose(low, (0.25, 0.25, 0.1))
    np.testing.assert_allclose(high, (3.75, 1.75, 0.1))
    location, scale = grid_fit.box_location_and_scale(low, high)
    np.testing.assert_allclose(location, (2.0, 1.0, 0.1))
    np.testing.assert_allclose(scale, (1.75, 0.75, 1e-4))
    assert grid_fit.counts_for_spacing((3.5, 1.5, 0.0), 1.0) == (5, 3, 1)


def test_mesh_parts_move_vertices_and_normals_to_the_world_frame():
    class Material:
        def __init__(self, uses_colors):
            self.uses_colors = uses_colors

        def as_dict(self):
            return {"uses_colors": self.uses_colors}

    # Scale x by 2 and move by (1, 0, 0); the world offset adds (0, 0, 10).
    matrix = [[2, 0, 0, 1], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
    parts = mesh_arrays.MeshParts()
    slots = [parts.material_slot("lit", lambda: Material(False)), parts.material_slot("paint", lambda: Material(True))]
    assert parts.material_slot("lit", lambda: pytest.fail("described twice")) == 0
    co = np.array([0, 0, 0, 1, 0, 0, 0, 1, 0], dtype=np.float32)
    normals = np.tile(np.array([[1.0, 1.0, 0.0]], dtype=np.float32), (6, 1))
    colours = np.full((6, 3), 0.5, dtype=np.float32)
    parts.add_object("a", co, matrix, (0, 0, 10), np.array([0, 1, 2, 2, 1, 0]), np.array([0, 5]), slots,
                     None, colours, normals)
    arrays = parts.mesh_arrays("m")
    np.testing.assert_allclose(arrays["vertices"], [(1, 0, 10), (3, 0, 10), (1, 1, 10)])
    # The normal transforms by the inverse transpose: (1, 1, 0) → (0.5, 1, 0), normalised.
    np.testing.assert_allclose(arrays["corner_normals"][0], np.array([0.5, 1.0, 0.0]) / np.hypot(0.5, 1.0), rtol=1e-6)
    np.testing.assert_array_equal(arrays["material"], [0, 1])  # slot 5 clipped to the last slot
    np.testing.assert_allclose(arrays["corner_colors"][:3], 1.0)  # material 0 ignores the colours
    np.testing.assert_allclose(arrays["corner_colors"][3:], 0.5)
    assert arrays["corner_uvs"] is None and arrays["object_names"] == ["a"] and arrays["name"] == "m"
    assert mesh_arrays.stack_optional([None, np.zeros((3, 2), np.float32)], [3, 3], 2, 0.5)[0, 0] == 0.5


def test_moved_scans_keep_their_normals_intensities_and_files(native):
    """A scan object moved in Blender: its points and scanner move by the object's matrix, its
    file normals turn with it (perpendicular even under a non-uniform scale), and intensities
    and file paths stay."""
    from lfprobe.core.cloud_transform import transform_scans

    positions = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1]], np.float32)
    normals = np.array([[1, 1, 0], [0, 0, 1], [0, 0, 1]], np.float32) / np.array([[2 ** 0.5], [1], [1]], np.float32)
    cloud = native.PointCloud.from_arrays(positions, normals=normals, scan_index=np.array([0, 0, 1], np.uint32),
                                          scanners=[[0.0, 0.0, 0.0], None],
                                          intensities=np.array([5, 6, 7], np.float32),
                                          scan_paths=["first.xyz", "second.xyz"])
    scale_x = np.diag([2.0, 1.0, 1.0, 1.0])
    scale_x[:3, 3] = (0.0, 0.0, 3.0)
    moved = transform_scans(cloud, [scale_x.tolist(), np.eye(4).tolist()])
    np.testing.assert_allclose(moved.positions[0], (2, 0, 3))
    np.testing.assert_allclose(moved.positions[2], (0, 0, 1))
    # The plane x + y = 1 becomes x/2 + y = 1: its normal (1, 2, 0)/√5, not (2, 1, 0)/√5.
    np.testing.assert_allclose(moved.normals[0], np.array([1, 2, 0]) / 5 ** 0.5, atol=1e-6)
    np.testing.assert_allclose(moved.normals[2], (0, 0, 1))
    assert list(moved.intensities) == [5, 6, 7]
    assert [s["path"] for s in moved.scans] == ["first.xyz", "second.xyz"]
    assert moved.scans[0]["scanner"] == (0.0, 0.0, 3.0)
