"""The Embree ground truth agrees with Blender's Cycles rendering the same scene and camera
with emission-only materials and a 1-pixel box filter: PSNR ≥ 40 dB on sRGB colour.

Runs tests/blender/cycles_agreement.py inside `blender -b --factory-startup`. Blender is
required (CI installs Debian's blender): without it this test fails, it does not skip.
"""

import json
import os
import shutil
import subprocess
import time

import numpy as np
import pytest

from conftest import ROOT, report_scene_module

from lfprobe.core import metrics

SCRIPT = os.path.join(ROOT, "tests", "blender", "cycles_agreement.py")
MIN_PSNR_DB = 40.0
CYCLES_SAMPLES = 256
GT_SPP = 64  # 8×8 stratified samples: converged well below 8-bit steps at this image size


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cycles_scene")
    scene_path = report_scene_module().write_scene(str(folder))
    from lfprobe.core.report.scene import load_scene

    return load_scene(scene_path)


def _render_cycles(obj, camera_path, out):
    blender = shutil.which("blender")
    if blender is None:
        pytest.fail("blender is not on PATH: install Debian's blender (apt-get install blender); "
                    "this test needs it and does not skip")
    command = [blender, "-b", "--factory-startup", "--python-exit-code", "1", "--python", SCRIPT, "--",
               "--obj", obj, "--camera", camera_path, "--samples", str(CYCLES_SAMPLES), "--out", out]
    result = subprocess.run(command, capture_output=True, text=True, timeout=300)
    if result.returncode != 0 or not os.path.isfile(out):
        raise AssertionError(f"Blender failed ({result.returncode}):\n{result.stdout[-3000:]}\n{result.stderr[-3000:]}")
    return np.load(out)


@pytest.mark.parametrize("view_index", [0, 1])
def test_ground_truth_agrees_with_cycles(native, scene, tmp_path, view_index):
    view = scene.views[view_index]
    camera = view.camera()
    camera_path = str(tmp_path / "camera.json")
    with open(camera_path, "w", encoding="utf-8") as stream:
        json.dump(camera, stream)
    start = time.perf_counter()
    cycles = _render_cycles(scene.mesh, camera_path, str(tmp_path / "cycles.npy"))
    cycles_seconds = time.perf_counter() - start
    gt_path = str(tmp_path / "gt.exr")
    native.start_ground_truth(scene.mesh, camera_path, gt_path, spp=GT_SPP, threads=0).run()
    gt = native.read_image(gt_path)
    w, h = camera["resolution"]
    assert cycles.shape == (h, w, 4)
    # Both images must show the scene (a black-on-black comparison would pass trivially).
    assert float(np.mean(gt["status"] == metrics.STATUS_HIT)) > 0.99
    assert float(np.mean(cycles[..., :3])) > 0.1
    value = metrics.psnr(gt["rgba"][..., :3], cycles[..., :3])
    print(f"view {view.name}: Embree ground truth ({GT_SPP} spp) vs Cycles ({CYCLES_SAMPLES} samples, box "
          f"filter 1 px): PSNR {value:.2f} dB; Blender run {cycles_seconds:.1f} s")
    assert value >= MIN_PSNR_DB, f"PSNR {value:.2f} dB < {MIN_PSNR_DB} dB"


def test_a_moved_camera_disagrees(native, scene, tmp_path):
    """The comparison can fail: the same Cycles image against a ground truth from a camera
    two pixels to the side stays far below the bound."""
    view = scene.views[0]
    camera = view.camera()
    camera_path = str(tmp_path / "camera.json")
    with open(camera_path, "w", encoding="utf-8") as stream:
        json.dump(camera, stream)
    cycles = _render_cycles(scene.mesh, camera_path, str(tmp_path / "cycles.npy"))
    moved = dict(camera)
    moved["shift_x"] = 0.5 / camera["resolution"][0] * 4  # two pixels sideways
    moved_path = str(tmp_path / "moved.json")
    with open(moved_path, "w", encoding="utf-8") as stream:
        json.dump(moved, stream)
    native.start_ground_truth(scene.mesh, moved_path, str(tmp_path / "gt.exr"), spp=GT_SPP).run()
    gt = native.read_image(str(tmp_path / "gt.exr"))
    assert metrics.psnr(gt["rgba"][..., :3], cycles[..., :3]) < MIN_PSNR_DB - 5.0
