"""Probe grids, placed like EEVEE's irradiance volumes: an Empty whose cube [-1, 1]^3,
moved and scaled (never rotated), is the grid's box; the corner probes sit on its corners.
The operators that add a grid, fit it to a scan cloud and edit its sources are in
operators/grid.py."""

import math
import os
import uuid
from typing import NamedTuple, Optional

import bpy

from ..core import native
from ..core.errors import InputError
from ..core.probe_set import MANIFEST, read_manifest


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
    low = tuple(float(location[i] - abs(scale[i])) for i in range(3))
    high = tuple(float(location[i] + abs(scale[i])) for i in range(3))
    counts = tuple(obj.lfprobe_grid.counts)
    for axis in range(3):
        if high[axis] - low[axis] <= 0 and counts[axis] > 1:
            raise GridError(f"grid {obj.name!r} has zero size along {'XYZ'[axis]} but {counts[axis]} probes there")
    return low, high


def probe_positions(obj):
    """The probes of the grid in Blender's frame, x fastest then y then z, where the bake puts
    them (the native core's computation)."""
    low, high = grid_box(obj)
    counts = [int(c) for c in obj.lfprobe_grid.counts]
    return native.load().grid_positions(list(low), list(high), counts)


def default_probe_dir(obj) -> str:
    """//<blend name>_<grid name>_probes: unique per grid and .blend, so that two .blend files
    in one folder never bake into one set (//<grid name>_probes while the .blend is unsaved)."""
    blend = bpy.path.display_name_from_filepath(bpy.data.filepath) if bpy.data.filepath else ""
    prefix = f"{bpy.path.clean_name(blend)}_" if blend else ""
    return f"//{prefix}{bpy.path.clean_name(obj.name)}_probes"


def probe_dir_abspath(grid_obj) -> str:
    """The grid's probe folder as an absolute path ("//" is the folder of the .blend)."""
    path = grid_obj.lfprobe_grid.probe_dir or default_probe_dir(grid_obj)
    return os.path.normpath(bpy.path.abspath(path))


# A probe set is bound to the grid it was baked for: Bake records the grid's id (a random
# string the grid keeps), name and .blend in the manifest's "bake" record under this key, and a
# grid only traces a set whose record names its id. Whether a grid is baked is read from the set
# on disk, not from a property that undo rewinds.
GRID_RECORD = "blender_grid"


def new_grid_id() -> str:
    return uuid.uuid4().hex


def grid_record(obj) -> dict:
    """What a bake records of the grid it bakes for (the manifest's bake[GRID_RECORD])."""
    return {"id": obj.lfprobe_grid.grid_id, "name": obj.name, "blend": os.path.basename(bpy.data.filepath)}


_manifests: dict = {}


def cached_manifest(folder: str) -> Optional[dict]:
    """The manifest of the set in `folder`, or None when there is none or it does not read;
    re-read only when the file changes (panels draw often)."""
    path = os.path.join(folder, MANIFEST)
    try:
        stat = os.stat(path)
    except OSError:
        return None
    key = (stat.st_mtime_ns, stat.st_size)
    hit = _manifests.get(path)
    if hit is not None and hit[0] == key:
        return hit[1]
    try:
        manifest = read_manifest(folder)
    except (OSError, ValueError):
        manifest = None
    _manifests[path] = (key, manifest)
    return manifest


def recorded_grid(manifest: Optional[dict]) -> Optional[dict]:
    """The grid a set was baked for, or None for a set baked outside Blender (./lfprobe bake)."""
    record = ((manifest or {}).get("bake") or {}).get(GRID_RECORD)
    return record if isinstance(record, dict) else None


def _grids_sharing_id(obj) -> list:
    grid_id = obj.lfprobe_grid.grid_id
    if not grid_id:
        return []
    return [o for o in bpy.data.objects if o is not obj and is_grid(o) and o.lfprobe_grid.grid_id == grid_id]


def is_copy(obj, recorded_name: Optional[str]) -> bool:
    """True when `obj` shares its id with other grids (Duplicate copies it) and is not the one
    the id belongs to: the grid named in the set's record, else the first by name."""
    others = _grids_sharing_id(obj)
    if not others:
        return False
    group = [obj, *others]
    owner = next((o for o in group if o.name == recorded_name), None) or min(group, key=lambda o: o.name)
    return owner is not obj


def _described(record: dict) -> str:
    blend = record.get("blend")
    return f"grid {record.get('name')!r}" + (f" of {blend}" if blend else " of an unsaved .blend")


class BoundSet(NamedTuple):
    """The grid's probe folder, the manifest there (None: not baked) and, when the set is not
    this grid's to trace, why (empty otherwise)."""

    folder: str
    manifest: Optional[dict]
    problem: str

    @property
    def usable(self) -> bool:
        return self.manifest is not None and not self.problem


def bound_set(obj) -> BoundSet:
    """The probe set in the grid's folder, checked against the grid it was baked for."""
    folder = probe_dir_abspath(obj)
    manifest = cached_manifest(folder)
    record = recorded_grid(manifest)
    if record is None:
        return BoundSet(folder, manifest, "")
    if record.get("id") != obj.lfprobe_grid.grid_id:
        return BoundSet(folder, manifest, (
            f"the probe set in {folder} was baked for {_described(record)}, not for grid {obj.name!r}: "
            "bake this grid (and give it a Probe Folder of its own if it shares that one)"))
    if is_copy(obj, record.get("name")):
        return BoundSet(folder, manifest, (
            f"grid {obj.name!r} is a copy of {_described(record)} and shares its probe set in {folder}: "
            "bake it to give it a probe set of its own"))
    return BoundSet(folder, manifest, "")


def claim_probe_folder(obj) -> None:
    """Before a bake writes the grid's folder: a grid without an id gets one; a copy that shares
    its original's id gets its own, and its own folder when it shares the original's; a folder
    that holds the set of another grid of this file is refused (GridError), as baking would
    take that grid's probes away."""
    grid = obj.lfprobe_grid
    if not grid.grid_id:
        grid.grid_id = new_grid_id()
    folder = probe_dir_abspath(obj)
    record = recorded_grid(cached_manifest(folder))
    others = _grids_sharing_id(obj)
    if others and is_copy(obj, (record or {}).get("name")):
        grid.grid_id = new_grid_id()
        if folder in {probe_dir_abspath(o) for o in others}:
            grid.probe_dir = ""  # the default: named after this grid
            folder = probe_dir_abspath(obj)
            record = recorded_grid(cached_manifest(folder))
    if record is not None and record.get("id") != grid.grid_id:
        owner = next((o for o in bpy.data.objects if is_grid(o) and o.lfprobe_grid.grid_id == record.get("id")), None)
        if owner is not None:
            raise GridError(
                f"grid {obj.name!r}: its probe folder {folder} holds the probes of grid "
                f"{owner.name!r}, which baking would replace: give this grid a Probe Folder of its own")


def baked_grids(scene) -> list:
    """The scene's grids whose folder holds a probe set baked for them, in name order."""
    return sorted((obj for obj in scene.objects if is_grid(obj) and bound_set(obj).usable),
                  key=lambda obj: obj.name)
