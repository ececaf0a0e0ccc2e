"""The committed demo scenes open in Blender with their textures, cameras where their scene
files put them, and (the hard scene) the georeferenced frame that the add-on then uses: meshes
handed to the core land at the scene file's world coordinates."""

import json
import os

import bpy
import numpy as np

import helpers

BLEND = os.path.join(helpers.ROOT, "blend")


def _open(name: str) -> dict:
    bpy.ops.wm.open_mainfile(filepath=os.path.join(BLEND, f"{name}.blend"))
    with open(os.path.join(BLEND, name, f"{name}.scene.json"), encoding="utf-8") as f:
        return json.load(f)


def _check_scene(name: str, expected_offset) -> None:
    scene_desc = _open(name)
    scene = bpy.context.scene
    # Textures are stored as relative paths next to the .blend and load.
    images = [im for im in bpy.data.images if im.source == "FILE"]
    assert images, "the scene has no image textures"
    for image in images:
        assert os.path.isfile(bpy.path.abspath(image.filepath)), image.filepath
        assert image.size[0] > 0 and image.size[1] > 0, image.name
    frame = helpers.addon("blender.scan_object").frame_offset(scene)
    if expected_offset is None:
        assert frame is None or np.allclose(frame, 0.0)
        frame = (0.0, 0.0, 0.0)
    else:
        np.testing.assert_allclose(frame, expected_offset, atol=0.0)
    for view in scene_desc["views"]:
        camera = bpy.data.objects[view["name"]]
        world = np.asarray(frame) + np.asarray(camera.matrix_world.translation, dtype=float)
        np.testing.assert_allclose(world, view["position"], atol=1e-3)
    # Meshes handed over in the scene's frame land at the scene file's world coordinates.
    meshes = [o for o in scene.objects if o.type == "MESH"]
    mesh = helpers.addon("blender.mesh_export").native_mesh_from_objects(
        meshes, bpy.context.evaluated_depsgraph_get(), world_offset=list(frame))
    (lo, hi) = mesh.bounds
    grid = scene_desc["grid"]
    assert all(lo[a] <= grid["min"][a] and hi[a] >= grid["max"][a] for a in range(3)), (lo, hi, grid)


def test_lab_room_opens_with_textures_and_cameras():
    _check_scene("lab_room", None)


def test_hard_scene_keeps_its_georeferenced_frame():
    _check_scene("hard_scene", (512000.0, 5400000.0, 230.0))
