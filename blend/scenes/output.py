"""One scene's files: `<out>/<name>/` with the OBJ, MTL, textures/*.png and `<name>.scene.json`."""

from __future__ import annotations

import os
import time

from . import build_scene
from .obj_export import write_obj
from .scene_file import write_scene_json


def write_scene(name: str, out_root: str, built=None) -> dict:
    """Builds scene `name` (or takes `built`, its (MeshBuilder, scene dict) already built) and
    writes it into out_root/name/; returns the scene file's path, the triangle and texture
    counts and the seconds it took."""
    start = time.perf_counter()
    builder, scene = build_scene(name) if built is None else built
    folder = os.path.join(out_root, name)
    files = write_obj(builder, folder, name)
    scene = dict(scene, mesh=files["obj"])
    scene_path = os.path.join(folder, f"{name}.scene.json")
    write_scene_json(scene_path, scene)
    return {"scene": scene_path, "triangles": files["triangles"], "textures": len(files["textures"]),
            "seconds": time.perf_counter() - start}
