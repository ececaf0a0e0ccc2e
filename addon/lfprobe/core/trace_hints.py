"""What to tell a user whose render came out (almost) all UNKNOWN: the command still succeeded
(UNKNOWN is an honest answer), but a picture with nothing in it usually has a simple cause the
numbers alone do not name: the camera stands outside the probe grid, or the probes never saw
what it looks at."""

from __future__ import annotations

import json
import os
from typing import Optional

import numpy as np

# At or above this share of UNKNOWN pixels a render gets a hint.
MOSTLY_UNKNOWN = 0.99


def _camera_position(camera: dict) -> Optional[np.ndarray]:
    matrix = camera.get("matrix_world")
    if not matrix:
        return None
    return np.asarray(matrix, dtype=np.float64)[:3, 3]


def camera_of(camera_argument: str) -> dict:
    """The camera a command was given (a JSON file, or JSON text), or {} when it cannot be read
    (the render itself has already read it: a hint never fails a command)."""
    try:
        if os.path.isfile(camera_argument):
            with open(camera_argument, encoding="utf-8") as f:
                return json.load(f)
        return json.loads(camera_argument)
    except (OSError, ValueError, TypeError):
        return {}


def unknown_hint(stats: dict, camera: dict, probe_folder: str) -> Optional[str]:
    """A one-line hint when at least MOSTLY_UNKNOWN of the pixels are UNKNOWN, else None.
    `camera` is the camera JSON as a dict (world coordinates); the probe set's manifest gives
    the grid box (local coordinates plus its world offset)."""
    pixels = stats.get("hits", 0) + stats.get("misses", 0) + stats.get("unknown", 0)
    if pixels <= 0 or stats.get("unknown", 0) < MOSTLY_UNKNOWN * pixels:
        return None
    share = 100.0 * stats["unknown"] / pixels
    try:
        with open(os.path.join(probe_folder, "manifest.json"), encoding="utf-8") as f:
            manifest = json.load(f)
    except (OSError, ValueError):
        manifest = {}
    eye = _camera_position(camera)
    offset = np.asarray(manifest.get("world_offset", [0.0, 0.0, 0.0]), dtype=np.float64)
    grid = manifest.get("grid")
    if eye is not None and grid:
        low = offset + np.asarray(grid["origin"], dtype=np.float64)
        high = low + np.asarray(grid["spacing"], dtype=np.float64) * (np.asarray(grid["counts"]) - 1)
        # Outside by more than half a cell: the probes look at the room from elsewhere.
        slack = 0.5 * np.asarray(grid["spacing"], dtype=np.float64)
        if np.any(eye < low - slack) or np.any(eye > high + slack):
            return (f"hint: {share:.1f}% of the pixels are UNKNOWN: the camera at "
                    f"({eye[0]:.2f}, {eye[1]:.2f}, {eye[2]:.2f}) stands outside the probe grid "
                    f"({low[0]:.2f}, {low[1]:.2f}, {low[2]:.2f}) to ({high[0]:.2f}, {high[1]:.2f}, "
                    f"{high[2]:.2f}); move the camera inside it, or the grid around the views")
    return (f"hint: {share:.1f}% of the pixels are UNKNOWN: the probes never saw what this camera "
            f"looks at (is the probe set baked from scans of this part of the room, and is it the "
            f"set this view belongs to?)")
