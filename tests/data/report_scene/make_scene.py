"""Writes the small test scene of the report and Cycles tests into a folder, at run time:
the benchmark room of lfprobe.core.bench (a 3 × 6 × 2.7 m room, two tables, a column) as an
OBJ with one material per box, a base-colour texture on the room's shell, and the scene file
(`room.scene.json`, the contract of lfprobe.core.report.scene).

    python3 tests/data/report_scene/make_scene.py OUT_DIR
"""

from __future__ import annotations

import json
import os
import sys

import numpy as np

_ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
if os.path.join(_ROOT, "addon") not in sys.path:
    sys.path.insert(0, os.path.join(_ROOT, "addon"))

from lfprobe.core.bench import face_corners, room_faces  # noqa: E402
from lfprobe.core.compare import write_png  # noqa: E402

# Linear base colours of the boxes in bench.ROOM_BOXES order: shell, table, table, column.
MATERIALS = [("shell", (0.8, 0.8, 0.8)), ("table_red", (0.6, 0.12, 0.08)),
             ("table_blue", (0.1, 0.2, 0.55)), ("column_green", (0.15, 0.45, 0.12))]
TEXTURE = "shell_texture.png"
TEXTURE_SIZE = 64
TEXELS_PER_METRE = 8.0  # tiles of 1/8 m: a few pixels each in the test views


def write_texture(path: str) -> None:
    """A smooth two-tone checker (sRGB bytes): 8×8-texel cells, colour ramps across the image."""
    y, x = np.mgrid[0:TEXTURE_SIZE, 0:TEXTURE_SIZE]
    checker = ((x // 8 + y // 8) % 2).astype(np.float64)
    r = 120 + 100 * checker + 30 * x / TEXTURE_SIZE
    g = 110 + 80 * checker + 30 * y / TEXTURE_SIZE
    b = 100 + 60 * (1 - checker)
    rgb = np.clip(np.stack([r, g, b], axis=-1), 0, 255).astype(np.uint8)
    write_png(path, rgb)


def write_room(folder: str, name: str = "room") -> str:
    """room.obj + room.mtl + the texture; returns the OBJ path."""
    os.makedirs(folder, exist_ok=True)
    write_texture(os.path.join(folder, TEXTURE))
    with open(os.path.join(folder, f"{name}.mtl"), "w", encoding="ascii") as mtl:
        for index, (material, colour) in enumerate(MATERIALS):
            mtl.write(f"newmtl {material}\nKd {colour[0]} {colour[1]} {colour[2]}\n")
            if index == 0:
                mtl.write(f"map_Kd {TEXTURE}\n")
            mtl.write("\n")
    lines = [f"mtllib {name}.mtl"]
    vertex = 0
    faces = room_faces()
    per_box = len(faces) // len(MATERIALS)
    for face_index, (axis, w, bmin, bmax, _, _) in enumerate(faces):
        box = face_index // per_box
        if face_index % per_box == 0:
            lines.append(f"o {MATERIALS[box][0]}")
            lines.append(f"usemtl {MATERIALS[box][0]}")
        u, v = (axis + 1) % 3, (axis + 2) % 3
        for p in face_corners(axis, w, bmin, bmax):
            lines.append(f"v {p[0]:.6f} {p[1]:.6f} {p[2]:.6f}")
            scale = TEXELS_PER_METRE / TEXTURE_SIZE
            lines.append(f"vt {p[u] * scale:.6f} {p[v] * scale:.6f}")
        quad = [vertex + 1, vertex + 2, vertex + 3, vertex + 4]
        lines.append(f"f {quad[0]}/{quad[0]} {quad[1]}/{quad[1]} {quad[2]}/{quad[2]}")
        lines.append(f"f {quad[0]}/{quad[0]} {quad[2]}/{quad[2]} {quad[3]}/{quad[3]}")
        vertex += 4
    path = os.path.join(folder, f"{name}.obj")
    with open(path, "w", encoding="ascii") as out:
        out.write("\n".join(lines) + "\n")
    return path


def scene_dict(name: str = "room") -> dict:
    """The scene file: two scanners, a 2×3×2 probe grid, a view at a probe and one between."""
    return {
        "name": name,
        "title": "Benchmark room (generated test scene)",
        "mesh": f"{name}.obj",
        "scanners": [[1.5, 1.5, 1.4], [1.5, 4.5, 1.4]],
        "scan": {"step_deg": 0.25, "noise_mm": 1.0, "vertical_fov": 300},
        "grid": {"min": [0.75, 1.25, 1.0], "max": [2.25, 4.75, 1.8], "counts": [2, 3, 2]},
        "views": [
            {"name": "at_probe", "position": [0.75, 1.25, 1.0], "look_at": [1.8, 6.0, 0.9],
             "lens": 24, "resolution": [160, 120]},
            {"name": "between", "position": [1.5, 2.2, 1.35], "look_at": [1.2, 6.0, 0.8],
             "lens": 24, "resolution": [160, 120]},
        ],
        "walk": {"points": [[0.9, 1.4, 1.3], [2.0, 4.5, 1.3]], "look_at": [1.5, 6.0, 1.0],
                 "frames": 4, "lens": 24},
    }


def write_scene(folder: str, name: str = "room") -> str:
    """Writes the mesh and `<name>.scene.json` into folder; returns the scene file's path."""
    write_room(folder, name)
    path = os.path.join(folder, f"{name}.scene.json")
    with open(path, "w", encoding="utf-8") as out:
        json.dump(scene_dict(name), out, indent=2)
    return path


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: make_scene.py OUT_DIR")
    print(write_scene(sys.argv[1]))
