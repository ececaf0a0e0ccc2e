"""Compare: ground truth of reference meshes (handed over from Blender, no files) against the
probes from the active camera; metrics written as compare.json, images loaded into Blender;
bad input reported without touching the scene."""

from __future__ import annotations

import json
import os

import bpy
import numpy as np

import helpers
import probe_scene

METRIC_KEYS = ("psnr", "ssim", "flip", "depth_absrel", "depth_rmse", "hole_rate", "false_hit_rate",
               "false_miss_rate")


def _reference_collection(*objects):
    collection = bpy.data.collections.new("Reference")
    bpy.context.scene.collection.children.link(collection)
    for obj in objects:
        for owner in list(obj.users_collection):
            owner.objects.unlink(obj)
        collection.objects.link(obj)
    return collection


def test_compare_writes_metrics_and_loads_the_images():
    probe_scene.traced_scene()
    room = probe_scene.add_room_mesh()
    _reference_collection(room)
    out = helpers.tmp_dir()
    assert bpy.ops.lfprobe.compare(collection="Reference", directory=out) == {"FINISHED"}

    with open(os.path.join(out, "compare.json"), encoding="utf-8") as stream:
        report = json.load(stream)
    for key in METRIC_KEYS:
        assert key in report, key
    # The probes were baked from a scan of this very room: the depths agree closely and
    # nothing the ground truth hits is a hole.
    assert report["depth_absrel"] < 0.01, report["depth_absrel"]
    assert report["hole_rate"] < 0.02 and report["false_hit_rate"] == 0.0
    assert report["reference_objects"] == ["Room"] and report["grid"] == "ProbeGrid"
    assert report["ref_render_seconds"] > 0 and report["test_render_seconds"] > 0
    # The probe render's guessed surfaces are measured too, and named in the summary when any.
    assert 0.0 <= report["guessed_pixels"] <= 1.0 and 0.0 <= report["guessed_error_share"] <= 1.0
    compare_op = helpers.addon("blender.operators.compare")
    assert ("guessed surfaces" in compare_op.summary_line(report)) == (report["guessed_pixels"] > 0)
    assert "guessed surfaces 1.50% of the pixels (40% of the error)" in compare_op.summary_line(
        {**report, "guessed_pixels": 0.015, "guessed_error_share": 0.4})
    for name in ("camera.json", "ground_truth.exr", "probes.exr", "error_flip.png"):
        assert os.path.isfile(os.path.join(out, name)), name

    native = helpers.addon("core.native").load()
    gt = native.read_image(os.path.join(out, "ground_truth.exr"))
    hit = gt["status"] == 1
    assert hit.mean() > 0.99
    # Unlit base colour of the Principled BSDF (linear).
    assert np.allclose(gt["rgba"][hit][:, :3], (0.5, 0.4, 0.3), atol=1e-5)
    for name in ("LFP Ground Truth", "LFP Probes", "LFP FLIP Error"):
        image = bpy.data.images.get(name)
        assert image is not None and tuple(image.size) != (0, 0), name

    # A second compare into the same folder reloads the images instead of piling up copies.
    images_before = len(bpy.data.images)
    room.select_set(True)
    bpy.context.view_layer.objects.active = room
    assert bpy.ops.lfprobe.compare(directory=out) == {"FINISHED"}
    assert len(bpy.data.images) == images_before


def test_mesh_export_carries_image_textures_and_transforms():
    """An Image Texture feeding Base Color becomes the mesh's texture; the object's transform
    is applied: a textured plane moved in front of the camera shows the texture's colour."""
    mesh_export = helpers.addon("blender.mesh_export")
    native = helpers.addon("core.native").load()
    camera = probe_scene.add_camera(position=(0.0, 0.0, 0.0), target=(0.0, 0.0, -1.0))
    bpy.ops.mesh.primitive_plane_add(size=1.0)
    plane = bpy.context.active_object
    plane.location = (0.0, 0.0, -3.0)
    image = bpy.data.images.new("flat", 8, 8, float_buffer=True)
    image.pixels.foreach_set(np.tile(np.array([0.25, 0.5, 0.125, 1.0], dtype=np.float32), 64))
    material = bpy.data.materials.new("textured")
    material.use_nodes = True
    nodes = material.node_tree.nodes
    bsdf = next(n for n in nodes if n.type == "BSDF_PRINCIPLED")
    texture = nodes.new("ShaderNodeTexImage")
    texture.image = image
    material.node_tree.links.new(texture.outputs["Color"], bsdf.inputs["Base Color"])
    plane.data.materials.append(material)

    depsgraph = bpy.context.evaluated_depsgraph_get()
    mesh = mesh_export.native_mesh_from_objects([plane], depsgraph)
    assert mesh.triangle_count == 2 and mesh.objects == ["Plane"]
    low, high = mesh.bounds
    assert np.allclose(low, (-0.5, -0.5, -3.0)) and np.allclose(high, (0.5, 0.5, -3.0))
    camera_export = helpers.addon("blender.camera_export")
    work = helpers.tmp_dir()
    out = os.path.join(work, "gt.exr")
    job = native.start_ground_truth(mesh, json.dumps(camera_export.camera_dict(bpy.context.scene, camera)), out)
    job.run(None)
    gt = native.read_image(out)
    h, w = gt["status"].shape
    assert gt["status"][h // 2, w // 2] == 1
    assert np.allclose(gt["rgba"][h // 2, w // 2, :3], (0.25, 0.5, 0.125), atol=1e-4)
    assert abs(gt["depth"][h // 2, w // 2] - 3.0) < 1e-3  # the pixel centre is half a pixel off the axis


def _snapshot():
    scene = bpy.context.scene
    return sorted(o.name for o in scene.objects), scene.camera.name if scene.camera else None


def test_compare_bad_input_is_reported_and_the_scene_stays():
    probe_scene.traced_scene()
    room = probe_scene.add_room_mesh()
    out = helpers.tmp_dir()
    for obj in bpy.context.scene.objects:
        obj.select_set(False)
    before = _snapshot()
    helpers.expect_operator_error(lambda: bpy.ops.lfprobe.compare(directory=out), "no reference meshes")
    helpers.expect_operator_error(lambda: bpy.ops.lfprobe.compare(collection="Nope", directory=out),
                                  "no collection named 'Nope'")
    room.select_set(True)
    helpers.expect_operator_error(lambda: bpy.ops.lfprobe.compare(directory=out, spp=3), "square")
    bpy.context.scene.camera = None
    helpers.expect_operator_error(lambda: bpy.ops.lfprobe.compare(directory=out), "no active camera")
    assert _snapshot() == (before[0], None)
    assert not os.path.exists(os.path.join(out, "compare.json"))
