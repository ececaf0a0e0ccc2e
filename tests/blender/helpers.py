"""Helpers for the tests that run inside Blender (tests/blender/run.py runs them): enabling
the add-on the way a user installs it, temporary folders, the shared test data, small scans
with known facts, and checking that an operator reports an error instead of crashing."""

from __future__ import annotations

import atexit
import importlib
import os
import shutil
import tempfile

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# LFPROBE_ADDON_DIR tests another copy of the add-on folder (e.g. an unpacked release).
ADDON_DIR = os.environ.get("LFPROBE_ADDON_DIR", os.path.join(ROOT, "addon", "lfprobe"))
SHARED_DATA = os.environ.get("LFPROBE_SHARED_DATA", os.path.join(ROOT, "..", "shared", "data"))
EXTENSION_REPO = "lfprobe_tests"

# Box room of write_box_room_xyz: x −2..2, y −1.5..1.5, z 0..2.5.
BOX_ROOM_MIN = (-2.0, -1.5, 0.0)
BOX_ROOM_MAX = (2.0, 1.5, 2.5)

_session_dir = tempfile.mkdtemp(prefix="lfprobe-blender-tests-")
atexit.register(shutil.rmtree, _session_dir, True)
# The parse cache of the scans the tests write goes with them, not into ~/.cache.
os.environ["LFPROBE_CACHE"] = os.path.join(_session_dir, "scan-cache")
_counter = [0]


class Skip(Exception):
    """Raised by a test that does not apply to this Blender (run.py reports SKIP, not PASS)."""


def tmp_dir() -> str:
    """A new empty folder, removed when the test run ends."""
    _counter[0] += 1
    path = os.path.join(_session_dir, f"t{_counter[0]:03d}")
    os.makedirs(path)
    return path


def shared_data(name: str) -> str:
    path = os.path.normpath(os.path.join(SHARED_DATA, name))
    if not os.path.exists(path):
        raise FileNotFoundError(f"test data {name} not found at {path} (set LFPROBE_SHARED_DATA)")
    return path


def uses_extensions() -> bool:
    """Blender 4.2+ installs the add-on as an extension; 3.4 as a legacy add-on."""
    return bpy.app.version >= (4, 2, 0)


def _link(folder: str) -> None:
    os.makedirs(folder, exist_ok=True)
    link = os.path.join(folder, "lfprobe")
    if not os.path.islink(link):
        os.symlink(ADDON_DIR, link)


def _raise(error):
    raise error


def addon_module_name() -> str:
    return f"bl_ext.{EXTENSION_REPO}.lfprobe" if uses_extensions() else "lfprobe"


def install_addon() -> str:
    """Makes the add-on findable as a user would install it (preferences are reset between
    tests, so this runs each time); returns its module name."""
    if uses_extensions():
        repos = bpy.context.preferences.extensions.repos
        if not any(repo.module == EXTENSION_REPO for repo in repos):
            folder = os.path.join(_session_dir, "extensions")
            _link(folder)
            repos.new(name="lfprobe tests", module=EXTENSION_REPO, custom_directory=folder, source="USER")
    else:
        scripts = os.path.join(_session_dir, "scripts")
        _link(os.path.join(scripts, "addons"))
        bpy.context.preferences.filepaths.script_directory = scripts
        bpy.utils.refresh_script_paths()
    import addon_utils

    addon_utils.modules_refresh()
    return addon_module_name()


def enable_addon() -> str:
    """Enables the add-on (errors raise); returns its module name."""
    import addon_utils

    name = install_addon()
    module = addon_utils.enable(name, default_set=True, handle_error=_raise)
    if module is None or name not in bpy.context.preferences.addons:
        raise AssertionError(f"add-on {name} did not enable")
    return name


def disable_addon() -> None:
    import addon_utils

    addon_utils.disable(addon_module_name(), default_set=True, handle_error=_raise)


def addon(submodule: str = ""):
    """A module of the enabled add-on, e.g. addon("blender.grid") (never import lfprobe
    directly: as an extension the package is bl_ext.<repo>.lfprobe)."""
    name = addon_module_name()
    return importlib.import_module(f"{name}.{submodule}" if submodule else name)


def expect_operator_error(call, *fragments: str) -> str:
    """Runs an operator call that must fail with a report naming each fragment; returns the
    message. (Blender turns an operator's ERROR report into RuntimeError for Python callers.)"""
    try:
        call()
    except RuntimeError as error:
        message = str(error)
    else:
        raise AssertionError(f"expected an error report containing {fragments}, but the operator succeeded")
    for fragment in fragments:
        if fragment not in message:
            raise AssertionError(f"error report {message!r} does not mention {fragment!r}")
    return message


def import_scans(*paths: str, **options):
    """Imports scan files through the File › Import operator; returns the new scan objects."""
    before = set(bpy.data.objects)
    directory = os.path.dirname(paths[0])
    for path in paths:
        assert os.path.dirname(path) == directory, "one folder at a time, as the file browser gives"
    result = bpy.ops.import_scene.lfprobe_scan(
        directory=directory, files=[{"name": os.path.basename(p)} for p in paths], **options
    )
    assert result == {"FINISHED"}, result
    return sorted((o for o in bpy.data.objects if o not in before), key=lambda o: o.name)


def write_box_room_xyz(path: str, pitch: float = 0.1) -> int:
    """A closed box room (BOX_ROOM_MIN..BOX_ROOM_MAX) sampled on a square pattern of `pitch`
    metres, as an 'x y z r g b' scan seen from a scanner at the room's centre; the colour is
    a ramp over the room. Returns the point count."""
    import numpy as np

    lo, hi = np.array(BOX_ROOM_MIN), np.array(BOX_ROOM_MAX)
    chunks = []
    for axis in range(3):
        u, v = (axis + 1) % 3, (axis + 2) % 3
        uu, vv = np.meshgrid(
            np.linspace(lo[u], hi[u], int(round((hi[u] - lo[u]) / pitch)) + 1),
            np.linspace(lo[v], hi[v], int(round((hi[v] - lo[v]) / pitch)) + 1),
            indexing="ij",
        )
        for wall in (lo[axis], hi[axis]):
            p = np.zeros((uu.size, 3))
            p[:, axis], p[:, u], p[:, v] = wall, uu.ravel(), vv.ravel()
            chunks.append(p)
    p = np.concatenate(chunks)
    rgb = np.column_stack([(p[:, 0] + 2) * 60, (p[:, 1] + 1.5) * 80, p[:, 2] * 100]).astype(int)
    centre = (lo + hi) / 2
    np.savetxt(
        path,
        np.column_stack([p, rgb]),
        fmt=["%.4f"] * 3 + ["%d"] * 3,
        header=f"scanner {centre[0]} {centre[1]} {centre[2]}\nx y z r g b",
    )
    return len(p)


# The partitioned room of write_partitioned_room_xyz (as tests/python/test_adaptive.py's): the
# box room with a 5 cm partition at x = 1 from the wall y = −1.5 to y = 0.3, which hides the
# corner x > 1.05, y < 0.3 from the half x < 1 (where the scanner stands).
PARTITION_SCANNER = (-1.0, 0.0, 1.25)


def write_partitioned_room_xyz(path: str, pitch: float = 0.04, offset=(0.0, 0.0, 0.0)) -> int:
    """The partitioned room, every surface sampled on a square pattern of `pitch` metres (a
    merged, complete scan), as an 'x y z r g b' scan with the scanner at PARTITION_SCANNER;
    `offset` is added to every coordinate (a georeferenced file). Returns the point count."""
    import numpy as np

    def panel(axis, value, u_range, v_range, step):
        u_axis, v_axis = [a for a in range(3) if a != axis]
        uu, vv = np.meshgrid(np.arange(*u_range, step), np.arange(*v_range, step), indexing="ij")
        p = np.zeros((uu.size, 3))
        p[:, axis], p[:, u_axis], p[:, v_axis] = value, uu.ravel(), vv.ravel()
        return p

    lo, hi = np.array(BOX_ROOM_MIN), np.array(BOX_ROOM_MAX)
    chunks = []
    for axis in range(3):
        u, v = [a for a in range(3) if a != axis]
        for wall in (lo[axis], hi[axis]):
            chunks.append(panel(axis, wall, (lo[u], hi[u]), (lo[v], hi[v]), pitch))
    for x in (1.0, 1.05):
        chunks.append(panel(0, x, (-1.5, 0.3), (0.0, 2.5), pitch))
    chunks.append(panel(1, 0.3, (1.0, 1.05 + 1e-9), (0.0, 2.5), pitch / 2))
    p = np.concatenate(chunks)
    rgb = np.column_stack([(p[:, 0] + 2) * 60, (p[:, 1] + 1.5) * 80, p[:, 2] * 100]).astype(int)
    scanner = np.asarray(PARTITION_SCANNER) + np.asarray(offset, dtype=float)
    np.savetxt(
        path,
        np.column_stack([p + np.asarray(offset, dtype=float), rgb]),
        fmt=["%.4f"] * 3 + ["%d"] * 3,
        header=f"scanner {scanner[0]} {scanner[1]} {scanner[2]}\nx y z r g b",
    )
    return len(p)


def srgb_to_linear(value_8bit: float) -> float:
    c = value_8bit / 255.0
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4
