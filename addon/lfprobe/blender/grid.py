"""Probe grids, placed like EEVEE's irradiance volumes: an Empty whose cube [-1, 1]^3,
moved and scaled (never rotated), is the grid's box; the corner probes sit on its corners.
The operators that add a grid, fit it to a scan cloud and edit its sources are in
operators/grid.py."""

import math
import os

import bpy
import numpy as np

from ..core import native
from ..core.errors import InputError


ROTATION_TOLERANCE = 1e-6


class GridError(InputError):
    """A grid that cannot be baked or drawn as it is (the message says why)."""


def is_grid(obj) -> bool:
    return obj is not None and obj.type == "EMPTY" and obj.lfprobe_grid.is_grid


def grid_box(obj) -> tuple:
    """(min corner, max corner) of the grid's box in Blender's frame. Raises GridError for a
    rotated grid (the probes' maps are axis-aligned) or a flat one."""
    matrix = obj.matrix_world
    location, rotation, scale = matrix.decompose()
    angle = rotation.to_axis_angle()[1]
    if abs(angle) > ROTATION_TOLERANCE:
        raise GridError(
            f"grid {obj.name!r} is rotated by {math.degrees(angle):.3g}°: probe grids must stay "
            "axis-aligned (clear its rotation, Alt+R)"
        )
    low = np.array([location[i] - abs(scale[i]) for i in range(3)], dtype=float)
    high = np.array([location[i] + abs(scale[i]) for i in range(3)], dtype=float)
    counts = tuple(obj.lfprobe_grid.counts)
    for axis in range(3):
        if high[axis] - low[axis] <= 0 and counts[axis] > 1:
            raise GridError(f"grid {obj.name!r} has zero size along {'XYZ'[axis]} but {counts[axis]} probes there")
    return low, high


def probe_positions(obj) -> np.ndarray:
    """The probes of the grid in Blender's frame, x fastest then y then z, where the bake puts
    them (the native core's computation)."""
    low, high = grid_box(obj)
    counts = [int(c) for c in obj.lfprobe_grid.counts]
    return native.load().grid_positions([float(v) for v in low], [float(v) for v in high], counts)


def default_probe_dir(obj) -> str:
    return f"//{bpy.path.clean_name(obj.name)}_probes"


def probe_dir_abspath(grid_obj) -> str:
    """The grid's probe folder as an absolute path ("//" is the folder of the .blend)."""
    path = grid_obj.lfprobe_grid.probe_dir or default_probe_dir(grid_obj)
    return os.path.normpath(bpy.path.abspath(path))


def baked_grids(scene) -> list:
    """The scene's grids that have a finished probe set, in name order."""
    return sorted(
        (obj for obj in scene.objects if is_grid(obj) and obj.lfprobe_grid.baked),
        key=lambda obj: obj.name,
    )
