"""What a scene is traced through: which baked grid, where its probe set lies, the frame
offset between Blender and the probe set's world, and the loaded ProbeField (cached by
folder and manifest time, so F12, the viewport and compare share one load).

Used by the render engine, compare and the batch CLI; bpy is only read, never changed.
"""

from __future__ import annotations

import os
import threading
from collections import OrderedDict

from ..core import native
from ..core.errors import InputError
from ..core.probe_set import MANIFEST, read_manifest
from . import grid as grid_module
from . import scan_object

MODES = ("auto", "nearest", "grid")
_FIELDS_KEPT = 2  # probe sets in memory at once (F12 and viewport usually share one)


class TraceSetupError(InputError):
    """The scene cannot be traced as it is (the message says what to do)."""


def render_settings(scene):
    return scene.lfprobe_render


def grid_to_trace(scene, name: str = ""):
    """The grid to trace: the one named, else the scene's lfprobe_render.grid, else the
    first baked grid (name order). Raises GridError when there is none."""
    if name:
        obj = scene.objects.get(name)
        if obj is None:
            raise grid_module.GridError(f"no object named '{name}' in scene '{scene.name}'")
        if not grid_module.is_grid(obj):
            raise grid_module.GridError(f"object '{name}' is not a light field probe grid")
        return obj
    chosen = render_settings(scene).grid
    if chosen is not None:
        if not grid_module.is_grid(chosen):
            raise grid_module.GridError(f"the render settings' grid '{chosen.name}' is not a light field probe grid")
        return chosen
    baked = grid_module.baked_grids(scene)
    if not baked:
        raise grid_module.GridError(
            f"scene '{scene.name}' has no baked probe grid: add a probe grid "
            "(Add > Light Field Probe Grid) and bake it"
        )
    return baked[0]


def probe_folder(grid_obj) -> str:
    """The grid's probe set folder; raises TraceSetupError when no finished set is there."""
    folder = grid_module.probe_dir_abspath(grid_obj)
    if not os.path.isdir(folder):
        raise TraceSetupError(
            f"grid '{grid_obj.name}': its probe folder {folder} does not exist; bake the grid "
            "(or set its Probe Folder to a baked probe set)"
        )
    try:
        read_manifest(folder)
    except (FileNotFoundError, ValueError) as error:
        raise TraceSetupError(f"grid '{grid_obj.name}': {error}; bake the grid again") from error
    return folder


def frame_offset(scene, grid_obj=None) -> tuple:
    """World = offset + Blender position. The offset is the one of the grid's scan sources
    (the frame its probe set was baked in), else the scene's scan clouds', else zero."""
    if grid_obj is not None:
        for source in grid_obj.lfprobe_grid.sources:
            obj = source.obj
            if obj is not None and obj.type == "MESH" and obj.lfprobe_scan.is_scan:
                return obj.lfprobe_scan.offset()
    offset = scan_object.frame_offset(scene)
    return tuple(offset) if offset is not None else (0.0, 0.0, 0.0)


_fields: "OrderedDict[tuple, object]" = OrderedDict()
_fields_lock = threading.Lock()


def coarse_resolution(grid_obj) -> int:
    """The grid's coarsest min-distance level kept when its probes are loaded (0: all)."""
    return int(grid_obj.lfprobe_grid.coarse_resolution) if grid_obj is not None else 0


def load_field(folder: str, coarse_resolution: int = 0):
    """The ProbeField of `folder`, loaded once per version of its manifest and coarse level."""
    manifest = os.path.join(folder, MANIFEST)
    try:
        stat = os.stat(manifest)
    except OSError as error:
        raise TraceSetupError(f"{manifest}: cannot read the probe set manifest ({error.strerror})") from error
    key = (os.path.abspath(folder), stat.st_mtime_ns, stat.st_size, int(coarse_resolution))
    with _fields_lock:
        field = _fields.get(key)
        if field is not None:
            _fields.move_to_end(key)
            return field
        _native = native.load()
        try:
            field = _native.ProbeField.load(folder, coarse_resolution=int(coarse_resolution))
        except (_native.InputError, _native.NativeIOError) as error:
            raise TraceSetupError(f"cannot load the probe set {folder}: {error}") from error
        stale = [k for k in _fields if k[0] == key[0]]
        for k in stale:
            del _fields[k]
        _fields[key] = field
        while len(_fields) > _FIELDS_KEPT:
            _fields.popitem(last=False)
        return field


def forget_fields() -> None:
    """Drops the cached probe sets (add-on unregistered, memory wanted back)."""
    with _fields_lock:
        _fields.clear()


def trace_settings(scene) -> dict:
    """The scene's trace settings as keyword arguments of ProbeField.render."""
    settings = render_settings(scene)
    return {"mode": settings.mode.lower(), "thickness": float(settings.thickness), "threads": int(settings.threads),
            "filter": settings.radiance_filter, "blend": int(settings.blend)}


def pixel_samples(scene) -> int:
    """Rays per pixel of a final render (F12, Compare, the batch render): the scene's n×n."""
    n = int(render_settings(scene).samples)
    return n * n
