"""Bad inputs give a clear report (the file or object, what was expected) and leave Blender
running with the scene as it was: missing and corrupt scans, files that are not scans, grids
that cannot be baked (no sources, rotated, unsaved .blend, a scan file gone, mixed sources),
and rendering without a camera or without baked probes."""

import os
import struct

import bpy

import helpers


def _scene_state() -> dict:
    return {obj.name: (obj.type, tuple(obj.location)) for obj in bpy.data.objects}


def _box_room_scan():
    path = os.path.join(helpers.tmp_dir(), "box_room.xyz")
    helpers.write_box_room_xyz(path, pitch=0.2)
    (scan,) = helpers.import_scans(path)
    return scan, path


def _import(path):
    return lambda: bpy.ops.import_scene.lfprobe_scan(
        directory=os.path.dirname(path), files=[{"name": os.path.basename(path)}]
    )


def test_missing_scan_file():
    scan, _ = _box_room_scan()
    before = _scene_state()
    missing = os.path.join(helpers.tmp_dir(), "nowhere.xyz")
    helpers.expect_operator_error(_import(missing), missing, "no such file")
    assert _scene_state() == before


def test_corrupt_text_scan_names_line_and_column():
    path = os.path.join(helpers.tmp_dir(), "corrupt.xyz")
    with open(path, "w") as stream:
        stream.write("0 0 0 10 20 30\n1 1 1 10 20 30\n2 2 two 10 20 30\n")
    before = _scene_state()
    helpers.expect_operator_error(_import(path), f"{path}:3", "column 3", "expected a number")
    assert _scene_state() == before
    assert not any(mesh.users == 0 and mesh.name == "corrupt" for mesh in bpy.data.meshes)


def test_truncated_binary_ply_names_the_byte_offset():
    path = os.path.join(helpers.tmp_dir(), "truncated.ply")
    header = ("ply\nformat binary_little_endian 1.0\nelement vertex 100\n"
              "property float x\nproperty float y\nproperty float z\nend_header\n").encode()
    with open(path, "wb") as stream:
        stream.write(header + struct.pack("<30f", *range(30)))  # 10 of 100 vertices
    before = _scene_state()
    helpers.expect_operator_error(_import(path), path, "byte offset")
    assert _scene_state() == before


def test_file_that_is_not_a_scan():
    path = os.path.join(helpers.tmp_dir(), "model.obj")
    with open(path, "w") as stream:
        stream.write("v 0 0 0\n")
    helpers.expect_operator_error(_import(path), path, "not a scan file", ".xyz")


def test_bake_without_a_grid_or_sources():
    folder = helpers.tmp_dir()
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(folder, "scene.blend"))
    helpers.expect_operator_error(lambda: bpy.ops.object.lfprobe_bake(), "no active object")
    helpers.expect_operator_error(lambda: bpy.ops.object.lfprobe_bake(grid="Nope"), "no object named 'Nope'")
    bpy.ops.object.lfprobe_grid_add()
    grid_obj = bpy.context.active_object
    before = _scene_state()
    helpers.expect_operator_error(lambda: bpy.ops.object.lfprobe_bake(), grid_obj.name, "no sources")
    assert _scene_state() == before and not grid_obj.lfprobe_grid.baked
    assert os.listdir(folder) == ["scene.blend"]
    helpers.expect_operator_error(lambda: bpy.ops.object.lfprobe_grid_fit(), "no scan cloud source")


def test_bake_of_an_unsaved_blend_asks_to_save_first():
    scan, _ = _box_room_scan()
    bpy.ops.object.lfprobe_grid_add()
    grid_obj = bpy.context.active_object
    helpers.expect_operator_error(lambda: bpy.ops.object.lfprobe_bake(), "save the .blend first", "//")
    assert not grid_obj.lfprobe_grid.baked
    # An absolute probe folder needs no saved .blend.
    grid_obj.lfprobe_grid.probe_dir = os.path.join(helpers.tmp_dir(), "probes")
    grid_obj.lfprobe_grid.resolution = 8
    grid_obj.lfprobe_grid.counts = (1, 1, 1)
    assert bpy.ops.object.lfprobe_bake() == {"FINISHED"}
    assert os.path.isfile(os.path.join(grid_obj.lfprobe_grid.probe_dir, "manifest.json"))


def test_bake_of_a_rotated_grid():
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(helpers.tmp_dir(), "scene.blend"))
    _box_room_scan()
    bpy.ops.object.lfprobe_grid_add()
    grid_obj = bpy.context.active_object
    grid_obj.rotation_euler = (0.3, 0.0, 0.0)
    bpy.context.view_layer.update()
    helpers.expect_operator_error(lambda: bpy.ops.object.lfprobe_bake(), "rotated", "axis-aligned")


def test_bake_when_the_scan_file_is_gone():
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(helpers.tmp_dir(), "scene.blend"))
    scan, path = _box_room_scan()
    bpy.ops.object.lfprobe_grid_add()
    os.remove(path)
    helpers.expect_operator_error(lambda: bpy.ops.object.lfprobe_bake(), scan.name, path, "missing")


def test_bake_from_scans_and_meshes_at_once():
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(helpers.tmp_dir(), "scene.blend"))
    scan, _ = _box_room_scan()
    bpy.ops.mesh.primitive_cube_add()
    cube = bpy.context.active_object
    scan.select_set(True)
    bpy.ops.object.lfprobe_grid_add()
    cube.select_set(True)
    bpy.ops.object.lfprobe_grid_source_add()
    helpers.expect_operator_error(lambda: bpy.ops.object.lfprobe_bake(), "mixes scan clouds", cube.name)


def _engine_scene():
    scene = bpy.context.scene
    scene.render.engine = "LFPROBE"
    scene.render.resolution_x, scene.render.resolution_y = 16, 12
    scene.render.resolution_percentage = 100
    return scene


def test_render_without_a_camera():
    scene = _engine_scene()
    _box_room_scan()
    before = _scene_state()
    helpers.expect_operator_error(lambda: bpy.ops.render.render(), "camera")
    assert _scene_state() == before and scene.render.engine == "LFPROBE"


def test_render_without_baked_probes():
    scene = _engine_scene()
    _box_room_scan()
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(camera)
    scene.camera = camera
    before = _scene_state()
    message = helpers.expect_operator_error(lambda: bpy.ops.render.render(), "bake")
    assert "grid" in message.lower(), message
    assert _scene_state() == before
