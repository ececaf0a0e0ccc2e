"""Camera files (docs/DESIGN.md §3) without Blender: the JSON the add-on writes from a Blender
camera, built here from a position and a target for scripts, tests and benchmarks."""

from __future__ import annotations

import json
import math
from typing import Sequence

from .atomic_write import atomic_open


def look_at_matrix(position: Sequence[float], target: Sequence[float], up=(0.0, 0.0, 1.0)):
    """Camera-to-world 4×4 rows for a Blender camera at `position` looking at `target`
    (Blender cameras look down their local −Z with +Y up)."""
    f = [t - p for t, p in zip(target, position)]
    norm = math.sqrt(sum(c * c for c in f))
    if norm == 0.0:
        raise ValueError("camera: the target must differ from the position")
    f = [c / norm for c in f]
    x = [f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2], f[0] * up[1] - f[1] * up[0]]
    xn = math.sqrt(sum(c * c for c in x))
    if xn < 1e-9:  # looking straight along `up`: any horizontal x will do
        x = [1.0, 0.0, 0.0]
        xn = 1.0
    x = [c / xn for c in x]
    y = [x[1] * f[2] - x[2] * f[1], x[2] * f[0] - x[0] * f[2], x[0] * f[1] - x[1] * f[0]]
    z = [-c for c in f]
    return [
        [x[0], y[0], z[0], float(position[0])],
        [x[1], y[1], z[1], float(position[1])],
        [x[2], y[2], z[2], float(position[2])],
        [0.0, 0.0, 0.0, 1.0],
    ]


def camera_dict(
    position: Sequence[float],
    target: Sequence[float],
    resolution=(640, 480),
    lens: float = 35.0,
    camera_type: str = "PERSP",
    sensor_width: float = 36.0,
    sensor_height: float = 24.0,
    sensor_fit: str = "AUTO",
    clip_start: float = 0.01,
    clip_end: float = 1000.0,
) -> dict:
    if camera_type not in ("PERSP", "PANO_EQUIRECT"):
        raise ValueError(f'camera type must be "PERSP" or "PANO_EQUIRECT", not "{camera_type}"')
    return {
        "type": camera_type,
        "matrix_world": look_at_matrix(position, target),
        "resolution": [int(resolution[0]), int(resolution[1])],
        "lens": float(lens),
        "sensor_width": float(sensor_width),
        "sensor_height": float(sensor_height),
        "sensor_fit": sensor_fit,
        "shift_x": 0.0,
        "shift_y": 0.0,
        "clip_start": float(clip_start),
        "clip_end": float(clip_end),
    }


def write_camera(path: str, camera: dict) -> None:
    """Writes the camera JSON whole (atomic_open)."""
    with atomic_open(path) as stream:
        json.dump(camera, stream, indent=2)
