import importlib.util
import os
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# LFPROBE_ADDON_DIR: another copy of the add-on's folder, such as the one tools/test.sh builds
# with a sanitized native module; ./lfprobe honours it too.
ADDON_DIR = os.environ.get("LFPROBE_ADDON_DIR") or os.path.join(ROOT, "addon")
sys.path.insert(0, ADDON_DIR)

SHARED_DATA = os.environ.get("LFPROBE_SHARED_DATA", os.path.join(ROOT, "..", "shared", "data"))


@pytest.fixture(scope="session")
def native():
    from lfprobe.core import native as native_loader

    return native_loader.load()


@pytest.fixture(scope="session")
def shared_data():
    if not os.path.isdir(SHARED_DATA):
        pytest.fail(f"test data not found at {SHARED_DATA} (set LFPROBE_SHARED_DATA)")
    return SHARED_DATA


def report_scene_module():
    """tests/data/report_scene/make_scene.py: writes the small room scene (OBJ, MTL, texture,
    scene JSON) that the report and the Cycles agreement tests use."""
    path = os.path.join(ROOT, "tests", "data", "report_scene", "make_scene.py")
    spec = importlib.util.spec_from_file_location("report_make_scene", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def run_cli(*args, check=False, timeout=600):
    """Runs ./lfprobe with args; returns the CompletedProcess (text)."""
    result = subprocess.run(
        [os.path.join(ROOT, "lfprobe"), *map(str, args)],
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    if check and result.returncode != 0:
        raise AssertionError(f"lfprobe {' '.join(map(str, args))} failed:\n{result.stdout}\n{result.stderr}")
    return result


def write_box_room_xyz(path, pitch):
    """A 4 × 3 × 2.5 m box room (x −2..2, y −1.5..1.5, z 0..2.5) sampled on a square pattern of
    `pitch` metres, as an 'x y z r g b' scan with a colour ramp over the room."""
    import numpy as np

    lo, hi = np.array([-2.0, -1.5, 0.0]), np.array([2.0, 1.5, 2.5])
    chunks = []
    for axis in range(3):
        u, v = (axis + 1) % 3, (axis + 2) % 3
        uu, vv = np.meshgrid(np.arange(lo[u], hi[u], pitch), np.arange(lo[v], hi[v], pitch), indexing="ij")
        for wall in (lo[axis], hi[axis]):
            p = np.zeros((uu.size, 3))
            p[:, axis], p[:, u], p[:, v] = wall, uu.ravel(), vv.ravel()
            chunks.append(p)
    p = np.concatenate(chunks)
    rgb = np.column_stack([(p[:, 0] + 2) * 60, (p[:, 1] + 1.5) * 80, p[:, 2] * 100]).astype(int)
    np.savetxt(path, np.column_stack([p, rgb]), fmt=["%.4f"] * 3 + ["%d"] * 3)
