"""Renders a scene with Blender's Cycles the way lfprobe's Embree ground truth sees it, for the
agreement test (tests/python/test_cycles_agreement.py). Run inside Blender:

    blender -b --factory-startup --python-exit-code 1 --python tests/blender/cycles_agreement.py -- \
        --obj SCENE.obj --camera CAM.json --samples 256 --out COLOUR.npy

The OBJ is imported with its axes kept (Z up, as lfprobe's world); every material becomes an
Emission shader of strength 1 whose colour is the MTL's Kd times its map_Kd texture (the base
colour the ground truth records); the world is black. The camera is built from lfprobe's camera
JSON (Blender's own key names). Cycles renders on the CPU with a 1-pixel box filter (the native
ground truth's stratified samples over the pixel square), the Standard view transform and a
32-bit linear EXR; the linear RGBA, top row first, is saved as a .npy array.
"""

import argparse
import json
import os
import sys

import bpy
import numpy as np


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(prog="cycles_agreement.py")
    parser.add_argument("--obj", required=True)
    parser.add_argument("--camera", required=True)
    parser.add_argument("--samples", type=int, default=256)
    parser.add_argument("--out", required=True, help=".npy file for the (h, w, 4) linear RGBA")
    return parser.parse_args(argv)


def read_mtl(obj_path):
    """{material name: (Kd, texture path or None)} from the OBJ's material libraries."""
    folder = os.path.dirname(os.path.abspath(obj_path))
    materials = {}
    with open(obj_path, encoding="utf-8") as stream:
        libraries = [w for line in stream if line.startswith("mtllib") for w in line.split()[1:]]
    for library in libraries:
        path = os.path.join(folder, library)
        current = None
        with open(path, encoding="utf-8") as stream:
            for line in stream:
                words = line.split()
                if not words:
                    continue
                if words[0] == "newmtl":
                    current = words[1]
                    materials[current] = [(0.8, 0.8, 0.8), None]
                elif words[0] == "Kd" and current:
                    values = [float(v) for v in words[1:4]]
                    materials[current][0] = tuple(values * 3 if len(values) == 1 else values)
                elif words[0] == "map_Kd" and current:
                    materials[current][1] = os.path.join(os.path.dirname(path), words[-1])
    return materials


def emission_material(material, kd, texture_path):
    material.use_nodes = True
    nodes, links = material.node_tree.nodes, material.node_tree.links
    nodes.clear()
    output = nodes.new("ShaderNodeOutputMaterial")
    emission = nodes.new("ShaderNodeEmission")
    emission.inputs["Strength"].default_value = 1.0
    links.new(emission.outputs["Emission"], output.inputs["Surface"])
    colour = (kd[0], kd[1], kd[2], 1.0)
    if texture_path is None:
        emission.inputs["Color"].default_value = colour
        return
    image_node = nodes.new("ShaderNodeTexImage")
    image_node.image = bpy.data.images.load(texture_path, check_existing=True)
    image_node.image.colorspace_settings.name = "sRGB"
    image_node.interpolation = "Linear"
    image_node.extension = "REPEAT"
    multiply = nodes.new("ShaderNodeMixRGB")
    multiply.blend_type = "MULTIPLY"
    multiply.inputs["Fac"].default_value = 1.0
    multiply.inputs["Color2"].default_value = colour
    links.new(image_node.outputs["Color"], multiply.inputs["Color1"])
    links.new(multiply.outputs["Color"], emission.inputs["Color"])


def build_camera(scene, camera_json):
    data = bpy.data.cameras.new("lfprobe_camera")
    data.type = "PANO" if camera_json.get("type") == "PANO_EQUIRECT" else "PERSP"
    if data.type == "PANO":
        data.cycles.panorama_type = "EQUIRECTANGULAR"
    data.lens = camera_json.get("lens", 50.0)
    data.sensor_width = camera_json.get("sensor_width", 36.0)
    data.sensor_height = camera_json.get("sensor_height", 24.0)
    data.sensor_fit = camera_json.get("sensor_fit", "AUTO")
    data.shift_x = camera_json.get("shift_x", 0.0)
    data.shift_y = camera_json.get("shift_y", 0.0)
    data.clip_start = camera_json.get("clip_start", 0.1)
    data.clip_end = camera_json.get("clip_end", 1000.0)
    camera = bpy.data.objects.new("lfprobe_camera", data)
    scene.collection.objects.link(camera)
    from mathutils import Matrix

    camera.matrix_world = Matrix(camera_json["matrix_world"])
    scene.camera = camera
    scene.render.resolution_x, scene.render.resolution_y = camera_json["resolution"]
    scene.render.resolution_percentage = 100
    scene.render.pixel_aspect_x = scene.render.pixel_aspect_y = 1.0


def main():
    args = parse_args()
    with open(args.camera, encoding="utf-8") as stream:
        camera_json = json.load(stream)
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    scene = bpy.context.scene
    # lfprobe's world is Blender's (Z up): import without the Y-up conversion.
    bpy.ops.wm.obj_import(filepath=args.obj, forward_axis="Y", up_axis="Z")
    mtl = read_mtl(args.obj)
    for material in bpy.data.materials:
        name = material.name.split(".")[0] if material.name not in mtl else material.name
        kd, texture = mtl.get(name, ((0.8, 0.8, 0.8), None))
        emission_material(material, kd, texture)
    for obj in scene.objects:
        if obj.type == "MESH" and not obj.data.materials:
            default = bpy.data.materials.new("default")
            emission_material(default, (0.8, 0.8, 0.8), None)
            obj.data.materials.append(default)
    world = scene.world or bpy.data.worlds.new("World")
    scene.world = world
    world.use_nodes = True
    background = world.node_tree.nodes.get("Background")
    background.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    background.inputs["Strength"].default_value = 0.0
    build_camera(scene, camera_json)

    scene.render.engine = "CYCLES"
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.samples = args.samples
    cycles.use_adaptive_sampling = False
    cycles.use_denoising = False
    cycles.seed = 1
    cycles.max_bounces = 0  # camera rays see emission directly; nothing bounces
    cycles.pixel_filter_type = "BOX"
    cycles.filter_width = 1.0
    scene.render.film_transparent = True
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    exr = os.path.splitext(args.out)[0] + ".exr"
    scene.render.filepath = exr
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(exr)
    w, h = image.size
    pixels = np.empty(w * h * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    rgba = pixels.reshape(h, w, 4)[::-1]  # Blender's rows run bottom-up; lfprobe's top-down
    np.save(args.out, np.ascontiguousarray(rgba))
    bounds = [tuple(round(c, 4) for c in obj.bound_box[0]) for obj in scene.objects if obj.type == "MESH"]
    print(f"cycles_agreement: {w}x{h}, {args.samples} samples, {len(bounds)} mesh object(s), wrote {args.out}")


main()
