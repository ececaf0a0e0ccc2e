"""Finds the native module and says plainly what is wrong when it cannot be imported."""

from __future__ import annotations

import glob
import importlib
import os
import sys
import sysconfig

from .errors import LfprobeError

_PACKAGE_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
_PACKAGE_NAME = __name__.rsplit(".", 2)[0]  # "lfprobe", or "bl_ext.<repo>.lfprobe"


class NativeModuleError(LfprobeError, ImportError):
    """The native module is missing or was built for another Python."""


def _diagnose() -> str:
    built = sorted(glob.glob(os.path.join(_PACKAGE_DIR, "_native*.so")))
    wanted = "_native" + (sysconfig.get_config_var("EXT_SUFFIX") or ".so")
    if not built:
        return (
            f"lfprobe's native module is not built (no _native*.so in {_PACKAGE_DIR}). "
            "Run `bash tools/setup.sh` in the lfprobe checkout to build it."
        )
    names = ", ".join(os.path.basename(b) for b in built)
    if wanted in (os.path.basename(b) for b in built):
        # The right file, which the loader refused: damaged, half-written by a build still
        # running, or missing a library it links.
        return (
            f"lfprobe's native module {os.path.join(_PACKAGE_DIR, wanted)} is there but cannot be "
            "loaded; if a build is running, wait for it, else run `bash tools/setup.sh` again"
        )
    return (
        f"lfprobe's native module was built for another Python: found {names}, but Python "
        f"{sys.version.split()[0]} needs {wanted}. Rebuild it with this Python "
        "(tools/setup.sh builds for the system Python 3.11 that Blender uses)."
    )


def cancelled_type() -> type:
    """The native module's Cancelled (a cancelled job), for an `except` clause; an exception type
    that is never raised when the module cannot be loaded (nothing native ran to be cancelled)."""
    try:
        return load().Cancelled
    except NativeModuleError:
        return _NeverRaised


class _NeverRaised(Exception):
    pass


def load():
    """Returns the lfprobe._native module, or raises NativeModuleError with the reason."""
    try:
        # Relative to this package: as a Blender extension it is bl_ext.<repo>.lfprobe.
        return importlib.import_module("._native", _PACKAGE_NAME)
    except ImportError as error:
        raise NativeModuleError(f"{_diagnose()} (import said: {error})") from error
