"""File › Import › Scan Cloud: each format of the shared data, checked against facts of the
files themselves (point counts, first point and colour, scanner, world offset), the display
subsample, several files at once, and that the points render in Cycles with their colours."""

import json
import os

import bpy
import numpy as np

import helpers

PUMP_POINTS = 155_201
OFFICE_POINTS = 254_456
AUTZEN_POINTS = 110_000


def _first_data_line(path: str) -> list:
    with open(path, encoding="ascii") as stream:
        for line in stream:
            fields = line.split()
            if len(fields) >= 6 and not line.startswith(("#", "//")):
                return [float(f) for f in fields]
    raise AssertionError(f"{path}: no data line")


def _vertices(obj) -> np.ndarray:
    co = np.empty(len(obj.data.vertices) * 3, dtype=np.float32)
    obj.data.vertices.foreach_get("co", co)
    return co.reshape(-1, 3)


def _colours(obj) -> np.ndarray:
    attribute = obj.data.attributes["Col"]
    assert attribute.data_type == "FLOAT_COLOR" and attribute.domain == "POINT"
    rgba = np.empty(len(attribute.data) * 4, dtype=np.float32)
    attribute.data.foreach_get("color", rgba)
    return rgba.reshape(-1, 4)


def _check_scan_object(obj, path, points):
    props = obj.lfprobe_scan
    assert props.is_scan
    assert props.point_count == points, props.point_count
    assert props.display_count == points == len(obj.data.vertices)
    assert props.paths() == [os.path.abspath(path)]
    assert obj.modifiers[0].type == "NODES" and obj.modifiers[0].node_group is not None
    assert obj.data.materials[0] is not None


def test_pump_xyz_points_colours_and_first_point():
    path = helpers.shared_data("scans/pumpA_xyzrgb.xyz")
    (obj,) = helpers.import_scans(path)
    _check_scan_object(obj, path, PUMP_POINTS)
    assert obj.lfprobe_scan.offset() == (0.0, 0.0, 0.0)
    x, y, z, r, g, b = _first_data_line(path)[:6]
    np.testing.assert_allclose(_vertices(obj)[0], [x, y, z], atol=1e-5)
    expected = [helpers.srgb_to_linear(c) for c in (r, g, b)] + [1.0]
    np.testing.assert_allclose(_colours(obj)[0], expected, atol=1e-5)


def test_viewport_draws_the_display_points_in_srgb():
    path = helpers.shared_data("scans/pumpA_xyzrgb.xyz")
    (obj,) = helpers.import_scans(path)
    positions, colours = helpers.addon("blender.ui.scan_display").display_arrays(obj)
    np.testing.assert_array_equal(positions, _vertices(obj))
    # The viewport draws display-referred colour: the file's 8-bit sRGB values again.
    np.testing.assert_allclose(colours[0, :3] * 255, _first_data_line(path)[3:6], atol=0.01)
    assert np.abs(colours[:, :3] * 255 - np.round(colours[:, :3] * 255)).max() < 0.01
    assert colours.shape == (PUMP_POINTS, 4) and np.all(colours[:, 3] == 1.0)
    # Blender itself draws only the bounds: its black loose-vertex dots would cover the colours.
    assert obj.display_type == "BOUNDS"


def test_pts_matches_xyz_point_for_point():
    (xyz,) = helpers.import_scans(helpers.shared_data("scans/pumpA_xyzrgb.xyz"))
    (pts,) = helpers.import_scans(helpers.shared_data("scans/pumpA.pts"))
    _check_scan_object(pts, helpers.shared_data("scans/pumpA.pts"), PUMP_POINTS)
    np.testing.assert_array_equal(_vertices(pts), _vertices(xyz))
    np.testing.assert_array_equal(_colours(pts), _colours(xyz))


def test_office_ply_with_its_sensor_origin():
    path = helpers.shared_data("scans/office1.ply")
    (obj,) = helpers.import_scans(path)
    _check_scan_object(obj, path, OFFICE_POINTS)
    assert obj.lfprobe_scan.scanners() == [[0.0, 0.0, 0.0]]
    colours = _colours(obj)
    assert colours[:, :3].std() > 0.05, "the office's colours were not read"
    # The Kinect looks down +z: every point is in front of the sensor.
    assert _vertices(obj)[:, 2].min() > 0.0


def test_autzen_keeps_its_world_offset():
    path = helpers.shared_data("scans/autzen_trim_xyzrgb.xyz")
    (obj,) = helpers.import_scans(path)
    _check_scan_object(obj, path, AUTZEN_POINTS)
    props = obj.lfprobe_scan
    offset = np.array(props.offset())
    assert offset[0] > 6e5 and offset[1] > 8e5, offset  # Oregon Lambert, feet
    # Stored in double precision as JSON, and as Blender's single-precision vector for display.
    assert json.loads(props.world_offset_json) == list(offset)
    np.testing.assert_allclose(props.world_offset, offset, rtol=1e-6)
    # Blender holds small local coordinates: world = offset + local, to the file's precision.
    local = _vertices(obj)
    assert np.abs(local).max() < 1000.0
    first = np.array(_first_data_line(path)[:3])
    np.testing.assert_allclose(offset + local[0].astype(np.float64), first, atol=1e-3)
    assert props.bounds_min[0] < 0 < props.bounds_max[0]


def test_display_subsample_of_a_large_cloud():
    path = helpers.shared_data("scans/pumpA_xyzrgb.xyz")
    (full,) = helpers.import_scans(path)
    (small,) = helpers.import_scans(path, display_limit=10_000)
    props = small.lfprobe_scan
    assert props.point_count == PUMP_POINTS and props.display_count == 10_000
    assert len(small.data.vertices) == 10_000
    # Every displayed point is a point of the cloud, with its colour, and they are spread out.
    everything = {tuple(p) for p in np.concatenate([_vertices(full), _colours(full)[:, :3]], axis=1).tolist()}
    shown = np.concatenate([_vertices(small), _colours(small)[:, :3]], axis=1)
    assert all(tuple(p) in everything for p in shown.tolist())
    assert len({tuple(p) for p in shown.tolist()}) == 10_000
    np.testing.assert_allclose(props.bounds_min, full.lfprobe_scan.bounds_min)
    # Deterministic: the same subsample every time.
    (again,) = helpers.import_scans(path, display_limit=10_000)
    np.testing.assert_array_equal(_vertices(again), _vertices(small))


def test_several_files_merged_or_separate():
    xyz, pts = helpers.shared_data("scans/pumpA_xyzrgb.xyz"), helpers.shared_data("scans/pumpA.pts")
    (merged,) = helpers.import_scans(xyz, pts)
    assert merged.lfprobe_scan.point_count == 2 * PUMP_POINTS
    assert merged.lfprobe_scan.paths() == [xyz, pts]
    separate = helpers.import_scans(xyz, pts, separate_objects=True)
    assert len(separate) == 2
    assert sorted(o.lfprobe_scan.paths()[0] for o in separate) == sorted([xyz, pts])
    assert all(o.lfprobe_scan.point_count == PUMP_POINTS for o in separate)


def test_second_scan_shares_the_scene_frame():
    # A second georeferenced scan nearby lands in the first one's local frame.
    path = helpers.shared_data("scans/autzen_trim_xyzrgb.xyz")
    shifted = os.path.join(helpers.tmp_dir(), "autzen_shifted.xyz")
    data = np.loadtxt(path, max_rows=2000)
    data[:, 0] += 1000.0  # 1000 ft east: a different rounded centre
    np.savetxt(shifted, data, fmt=["%.2f"] * 3 + ["%d"] * 3)
    (first,) = helpers.import_scans(path)
    (second,) = helpers.import_scans(shifted)
    assert second.lfprobe_scan.offset() == first.lfprobe_scan.offset()
    offset = np.array(second.lfprobe_scan.offset())
    np.testing.assert_allclose(offset + _vertices(second)[0], data[0, :3], atol=2e-3)


def test_points_render_in_cycles_with_their_colours():
    folder = helpers.tmp_dir()
    path = os.path.join(folder, "box_room.xyz")
    helpers.write_box_room_xyz(path, pitch=0.05)
    (obj,) = helpers.import_scans(path, point_radius=0.05)
    scene = bpy.context.scene
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(camera)
    scene.camera = camera
    camera.location = (0.0, 0.0, 1.25)
    camera.rotation_euler = (np.pi / 2, 0.0, np.pi / 2)  # looking down −X
    camera.data.lens = 50
    scene.render.engine = "CYCLES"
    scene.cycles.samples = 4
    scene.cycles.device = "CPU"
    scene.cycles.use_denoising = False
    scene.render.resolution_x = scene.render.resolution_y = 24
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    scene.render.image_settings.file_format = "PNG"
    scene.render.filepath = os.path.join(folder, "render.png")
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(scene.render.filepath)
    pixels = np.array(image.pixels[:]).reshape(24, 24, 4)
    centre = pixels[10:14, 10:14, :3].reshape(-1, 3).mean(axis=0)
    # The wall x = −2 around (y, z) = (0, 1.25): colour (0, 120, 125) in 8-bit sRGB.
    np.testing.assert_allclose(centre * 255, [0, 120, 125], atol=8)


def test_the_preferences_choose_the_scan_cache():
    """The add-on's preferences hold the parse cache's folder; imports and bakes read through it
    (as an extension its default is the extension's user folder)."""
    preferences = helpers.addon("blender.preferences")
    prefs = bpy.context.preferences.addons[preferences.ADDON_PACKAGE].preferences
    default = preferences.scan_cache_dir()
    if helpers.uses_extensions():
        assert "lfprobe" in default and os.path.isdir(default)
    cache = os.path.join(helpers.tmp_dir(), "scan cache")
    prefs.cache_folder = cache
    assert preferences.scan_cache_dir() == cache
    path = os.path.join(helpers.tmp_dir(), "room.xyz")
    helpers.write_box_room_xyz(path, pitch=0.1)
    helpers.import_scans(path)
    assert os.listdir(cache), "the import wrote its parse-cache entry into the chosen folder"
    prefs.cache_folder = ""


def test_import_has_presets_and_takes_dropped_files():
    """The import keeps operator presets; in Blender 4.1+ a FileHandler imports scan files
    dropped on the viewport (Blender hands the operator `directory` and `files`)."""
    operator = bpy.ops.import_scene.lfprobe_scan.get_rna_type()
    assert "PRESET" in bpy.types.IMPORT_SCENE_OT_lfprobe_scan.bl_options
    assert operator is not None
    if bpy.app.version < (4, 1, 0):
        assert not hasattr(bpy.types, "FileHandler")
        return
    handler = getattr(bpy.types, "LFPROBE_FH_scan", None)
    assert handler is not None, "the FileHandler is registered"
    assert handler.bl_import_operator == "import_scene.lfprobe_scan"
    assert {".xyz", ".pts", ".ply", ".e57", ".las", ".laz"} <= set(handler.bl_file_extensions.split(";"))
    # What a drop does: the operator invoked with the dropped files runs without a browser.
    folder = helpers.tmp_dir()
    helpers.write_box_room_xyz(os.path.join(folder, "dropped.xyz"), pitch=0.1)
    result = bpy.ops.import_scene.lfprobe_scan("INVOKE_DEFAULT", directory=folder,
                                               files=[{"name": "dropped.xyz"}])
    assert result in ({"FINISHED"}, {"RUNNING_MODAL"}), result
    assert "dropped" in bpy.data.objects
