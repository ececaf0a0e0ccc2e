"""Builds blend/lab_room.blend and blend/hard_scene.blend from the same data as the OBJ files.

Run from anywhere:
    blender -b --factory-startup --python-exit-code 1 -P blend/build_blend.py [-- lab_room|hard_scene|all]

Per scene it first writes blend/<scene>/ (OBJ + MTL + textures/*.png + <name>.scene.json, via
blend.scenes), then a .blend beside it holding: one mesh object per scene object with a UV map
and Principled BSDF materials whose Base Color is the scene's PNG texture (referenced with a
relative path, so Cycles, EEVEE and the add-on all see it), one camera per view (and an
animated 'walk' camera), an empty per scanner and an empty box showing the probe grid.

Blender keeps object data in float32, which cannot hold georeferenced coordinates (5,400,000 m
is 0.5 m apart in float32), so objects are placed in the scene's local frame and the scene's
custom property `lfprobe_world_offset` holds the offset: world = offset + Blender location.
"""

from __future__ import annotations

import os
import sys

import bpy
from mathutils import Vector

BLEND_DIR = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(BLEND_DIR))

from blend.scenes import SCENE_NAMES, build_scene  # noqa: E402  (needs the path above)
from blend.scenes.output import write_scene  # noqa: E402
from blend.scenes.walk import walk_positions  # noqa: E402


def _reset() -> None:
    """An empty file: factory startup's cube, light and camera removed; no .blend1 backups
    beside the committed files when they are rebuilt."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.context.preferences.filepaths.save_version = 0


def _materials(builder, folder: str) -> list:
    images = {}
    for name in builder.textures:
        path = os.path.join(folder, "textures", f"{name}.png")
        image = bpy.data.images.load(path, check_existing=True)
        image.colorspace_settings.name = "sRGB"
        images[name] = image
    result = []
    for m in builder.materials:
        mat = bpy.data.materials.new(m.name)
        mat.use_nodes = True
        nodes = mat.node_tree.nodes
        bsdf = nodes.get("Principled BSDF")
        bsdf.inputs["Roughness"].default_value = 0.7
        bsdf.inputs["Specular"].default_value = 0.2
        if m.texture:
            node = nodes.new("ShaderNodeTexImage")
            node.image = images[m.texture]
            node.interpolation = "Linear"
            node.extension = "REPEAT"  # as the native reader samples: wrap, bilinear
            node.location = (-400, 200)
            mat.node_tree.links.new(node.outputs["Color"], bsdf.inputs["Base Color"])
        else:
            bsdf.inputs["Base Color"].default_value = (*m.base_color, 1.0)  # linear, like MTL Kd
        mat.diffuse_color = (*m.base_color, 1.0)  # solid viewport colour
        result.append(mat)
    return result


def _objects(builder, materials: list, collection) -> int:
    for index, name in enumerate(builder.object_names):
        vertices, faces, uvs, material, _ = builder.indexed(index)
        used = sorted(set(material.tolist()))
        slot = {m: i for i, m in enumerate(used)}
        mesh = bpy.data.meshes.new(name)
        mesh.from_pydata(vertices.tolist(), [], faces.tolist())
        layer = mesh.uv_layers.new(name="UVMap")
        layer.data.foreach_set("uv", uvs.reshape(-1).tolist())
        for m in used:
            mesh.materials.append(materials[m])
        mesh.polygons.foreach_set("material_index", [slot[m] for m in material.tolist()])
        mesh.validate()
        mesh.update()
        collection.objects.link(bpy.data.objects.new(name, mesh))
    return len(builder.object_names)


def _local(point, offset) -> Vector:
    """World → Blender's local frame, subtracted in double before mathutils' float32 Vector
    (5,400,000.9 − 5,400,000 done in float32 is off by up to 0.25 m)."""
    return Vector([float(p) - float(o) for p, o in zip(point, offset)])


def _look_at(position: Vector, target: Vector):
    return (target - position).to_track_quat("-Z", "Y").to_euler()


def _cameras(scene_desc: dict, offset, collection, scene) -> None:
    for view in scene_desc["views"]:
        cam = bpy.data.cameras.new(view["name"])
        cam.lens = view["lens"]
        cam.sensor_width = 36.0
        cam.sensor_fit = "AUTO"
        cam.clip_start = 0.01
        cam.clip_end = 1000.0
        ob = bpy.data.objects.new(view["name"], cam)
        position = _local(view["position"], offset)
        ob.location = position
        ob.rotation_euler = _look_at(position, _local(view["look_at"], offset))
        ob["resolution"] = list(view["resolution"])
        collection.objects.link(ob)
    first = scene_desc["views"][0]
    scene.camera = bpy.data.objects[first["name"]]
    scene.render.resolution_x, scene.render.resolution_y = first["resolution"]
    scene.render.resolution_percentage = 100
    walk = scene_desc.get("walk")
    if walk:
        cam = bpy.data.cameras.new("walk")
        cam.lens = walk.get("lens", 24)
        ob = bpy.data.objects.new("walk", cam)
        collection.objects.link(ob)
        target = _local(walk["look_at"], offset)
        for frame, p in enumerate(walk_positions(walk["points"], walk["frames"]), start=1):
            ob.location = _local(p, offset)
            ob.rotation_euler = _look_at(ob.location, target)
            ob.keyframe_insert("location", frame=frame)
            ob.keyframe_insert("rotation_euler", frame=frame)
        scene.frame_start, scene.frame_end = 1, walk["frames"]


def _markers(scene_desc: dict, offset, collection) -> None:
    for i, p in enumerate(scene_desc["scanners"], start=1):
        ob = bpy.data.objects.new(f"scanner_{i}", None)
        ob.empty_display_type = "SPHERE"
        ob.empty_display_size = 0.1
        ob.location = _local(p, offset)
        collection.objects.link(ob)
    grid = scene_desc["grid"]
    lo, hi = _local(grid["min"], offset), _local(grid["max"], offset)
    ob = bpy.data.objects.new("probe_grid", None)
    ob.empty_display_type = "CUBE"
    ob.location = (lo + hi) / 2
    ob.scale = [max((b - a) / 2, 0.01) for a, b in zip(lo, hi)]
    ob["counts"] = list(grid["counts"])
    collection.objects.link(ob)


def build_blend(name: str) -> str:
    builder, scene_desc = build_scene(name)
    info = write_scene(name, BLEND_DIR, built=(builder, scene_desc))
    folder = os.path.join(BLEND_DIR, name)
    _reset()
    scene = bpy.context.scene
    scene.name = scene_desc["name"]
    offset = builder.world_offset.tolist()
    scene["lfprobe_world_offset"] = list(builder.world_offset.tolist())
    scene["lfprobe_scene_json"] = f"//{name}/{name}.scene.json"
    scene.view_settings.view_transform = "Standard"  # base colours shown as they are
    world = bpy.data.worlds.new("World")
    world.color = (0.05, 0.05, 0.05)
    scene.world = world

    geometry = bpy.data.collections.new("geometry")
    cameras = bpy.data.collections.new("cameras")
    markers = bpy.data.collections.new("scanners_and_probes")
    for c in (geometry, cameras, markers):
        scene.collection.children.link(c)
    materials = _materials(builder, folder)
    count = _objects(builder, materials, geometry)
    _cameras(scene_desc, offset, cameras, scene)
    _markers(scene_desc, offset, markers)

    path = os.path.join(BLEND_DIR, f"{name}.blend")
    # Blender writes to a temporary file and renames it; relative_remap stores the texture
    # paths relative to the .blend (//<scene>/textures/...), so nothing is packed.
    bpy.ops.wm.save_as_mainfile(filepath=path, compress=True, relative_remap=True)
    print(f"blend {name}: {count} objects, {info['triangles']} triangles, "
          f"{len(scene_desc['views'])} views -> {path} ({os.path.getsize(path) / 1e6:.2f} MB)")
    return path


def main() -> None:
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    which = argv[0] if argv else "all"
    if which not in (*SCENE_NAMES, "all"):
        raise SystemExit(f"build_blend.py: unknown scene '{which}': expected {', '.join(SCENE_NAMES)} or all")
    for name in SCENE_NAMES if which == "all" else (which,):
        build_blend(name)


main()
