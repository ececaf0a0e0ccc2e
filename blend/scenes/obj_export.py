"""Writes a MeshBuilder as OBJ + MTL with its textures as PNG files beside them.

Positions are world coordinates (world offset added in double, written with 6 decimals: a
micrometre even at 5,400,000 m). Kd is linear, as Blender and the native reader take it; a
textured material has Kd 1 1 1 so that the texture alone is its base colour."""

from __future__ import annotations

import io
import os

import numpy as np

from .files import write_atomic, write_png
from .mesh_builder import MeshBuilder


def write_obj(builder: MeshBuilder, folder: str, name: str) -> dict:
    """Writes `folder/name.obj`, `folder/name.mtl` and `folder/textures/*.png`. Returns the file
    names (relative to folder) and the triangle count."""
    os.makedirs(os.path.join(folder, "textures"), exist_ok=True)
    texture_files = {}
    for tex_name, pixels in sorted(builder.textures.items()):
        rel = f"textures/{tex_name}.png"
        write_png(os.path.join(folder, rel), pixels)
        texture_files[tex_name] = rel

    mtl = io.StringIO()
    mtl.write(f"# lfprobe demo scene {name}: linear base colours\n")
    for m in builder.materials:
        kd = (1.0, 1.0, 1.0) if m.texture else m.base_color
        mtl.write(f"\nnewmtl {m.name}\nKd {kd[0]:.4f} {kd[1]:.4f} {kd[2]:.4f}\nKa 0 0 0\nKs 0 0 0\nillum 1\n")
        if m.texture:
            mtl.write(f"map_Kd {texture_files[m.texture]}\n")
    write_atomic(os.path.join(folder, f"{name}.mtl"), mtl.getvalue().encode("ascii"))

    vertices, triangles, uvs, material, obj = builder.indexed()
    world = vertices + builder.world_offset
    out = io.StringIO()
    out.write(f"# lfprobe demo scene {name}: {len(triangles)} triangles, world coordinates (metres, Z up)\n")
    out.write(f"mtllib {name}.mtl\n")
    out.write("".join(f"v {x:.6f} {y:.6f} {z:.6f}\n" for x, y, z in world.tolist()))
    out.write("".join(f"vt {u:.5f} {v:.5f}\n" for u, v in uvs.reshape(-1, 2).tolist()))
    # Faces grouped by object, then material, in the order the scene added them.
    order = np.lexsort((material, obj))
    current = (None, None)
    for t in order.tolist():
        key = (int(obj[t]), int(material[t]))
        if key[0] != current[0]:
            out.write(f"o {builder.object_names[key[0]]}\n")
            current = (key[0], None)
        if key[1] != current[1]:
            out.write(f"usemtl {builder.materials[key[1]].name}\n")
            current = key
        a, b, c = (int(i) + 1 for i in triangles[t])
        ta = 3 * t + 1
        out.write(f"f {a}/{ta} {b}/{ta + 1} {c}/{ta + 2}\n")
    write_atomic(os.path.join(folder, f"{name}.obj"), out.getvalue().encode("ascii"))
    return {"obj": f"{name}.obj", "mtl": f"{name}.mtl", "textures": sorted(texture_files.values()),
            "triangles": int(len(triangles))}
