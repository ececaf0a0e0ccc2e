"""What tracing a view through a baked probe set takes, as plain data (`TraceTarget`), and the
loaded ProbeFields, cached by folder and manifest version so that F12, the viewport and compare
share one load. The add-on builds a TraceTarget from a scene (blender/probe_view.py); the
render engine, compare and the batch CLI trace through it."""

from __future__ import annotations

import os
import threading
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Tuple

from . import native
from .errors import InputError
from .probe_set import MANIFEST

_FIELDS_KEPT = 2  # probe sets in memory at once (F12 and viewport usually share one)


class TraceSetupError(InputError):
    """The scene cannot be traced as it is (the message says what to do)."""


@dataclass
class TraceTarget:
    """A view to trace: the grid's probe set (folder, coarsest min-distance level kept on load,
    0: all), the frame offset (world = offset + Blender position), the camera JSON as a dict,
    the trace settings (ProbeField.render's mode, thickness, threads, filter, blend) and the
    samples per pixel of a final render."""

    grid_name: str
    folder: str
    coarse_resolution: int
    offset: Tuple[float, float, float]
    camera: dict
    trace: dict = field(default_factory=dict)
    spp: int = 1

    def load_field(self):
        return load_field(self.folder, self.coarse_resolution)


_fields: "OrderedDict[tuple, object]" = OrderedDict()
_fields_lock = threading.Lock()


def load_field(folder: str, coarse_resolution: int = 0):
    """The ProbeField of `folder`, loaded once per version of its manifest and coarse level."""
    manifest = os.path.join(folder, MANIFEST)
    try:
        stat = os.stat(manifest)
    except OSError as error:
        raise TraceSetupError(f"{manifest}: cannot read the probe set manifest ({error.strerror})") from error
    key = (os.path.abspath(folder), stat.st_mtime_ns, stat.st_size, int(coarse_resolution))
    with _fields_lock:
        cached = _fields.get(key)
        if cached is not None:
            _fields.move_to_end(key)
            return cached
        _native = native.load()
        try:
            # Lazily: F12 and the viewport start tracing at once, and a probe's maps are read
            # the first time a ray reaches it.
            loaded = _native.ProbeField.load(folder, coarse_resolution=int(coarse_resolution), lazy=True)
        except (_native.InputError, _native.NativeIOError) as error:
            raise TraceSetupError(f"cannot load the probe set {folder}: {error}") from error
        stale = [k for k in _fields if k[0] == key[0]]
        for k in stale:
            del _fields[k]
        _fields[key] = loaded
        while len(_fields) > _FIELDS_KEPT:
            _fields.popitem(last=False)
        return loaded


def forget_fields() -> None:
    """Drops the cached probe sets (add-on unregistered, memory wanted back)."""
    with _fields_lock:
        _fields.clear()
