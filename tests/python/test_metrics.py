"""Image metrics (lfprobe.core.metrics, lfprobe.core.flip) and `compare` on rendered EXRs.

SSIM is checked against scikit-image and FLIP against NVIDIA's flip_evaluator (both must agree
to the stated tolerances); PSNR, depth errors and the confusion on hand-made values.
"""

import json
import math
import os
import sys

import numpy as np
import pytest

from conftest import ROOT, run_cli, write_box_room_xyz

from lfprobe.core import flip as flip_module
from lfprobe.core import metrics

PYDEPS = os.path.join(ROOT, "build", "pydeps")
if PYDEPS not in sys.path:
    sys.path.append(PYDEPS)


def _base_image(h, w):
    """A smooth linear-RGB image with an edge-rich patch and a stripe pattern."""
    yy, xx = np.mgrid[0:h, 0:w]
    image = np.stack([xx / w, yy / h, 0.5 + 0.4 * np.sin(xx / 5.0)], axis=-1) ** 2.2
    image[h // 4 : h // 2, w // 3 : 2 * w // 3] = [0.8, 0.05, 0.02]
    return image


def _box_blur(image):
    return (image + np.roll(image, 1, 0) + np.roll(image, -1, 0) + np.roll(image, 1, 1) + np.roll(image, -1, 1)) / 5


def _pairs(h, w, seed=0):
    rng = np.random.default_rng(seed)
    ref = _base_image(h, w)
    return ref, {
        "identical": ref.copy(),
        "noise": np.clip(ref + rng.normal(0.0, 0.04, ref.shape), 0.0, 1.0),
        "blur": _box_blur(ref),
        "shift": np.roll(ref, 2, axis=1),
        "colour shift": np.clip(ref * [1.15, 0.85, 1.0], 0.0, 1.0),
    }


# -- SSIM against scikit-image ------------------------------------------------------------------

@pytest.mark.parametrize("size", [(37, 53), (11, 11), (64, 48), (20, 131)])
def test_ssim_matches_skimage(size):
    skimage_metrics = pytest.importorskip("skimage.metrics")
    ref, tests = _pairs(*size)
    worst = 0.0
    for name, test in tests.items():
        expected = skimage_metrics.structural_similarity(
            metrics.srgb_encode(ref), metrics.srgb_encode(test), channel_axis=2, gaussian_weights=True,
            sigma=1.5, use_sample_covariance=False, data_range=1)
        got = metrics.ssim(ref, test)
        assert got == pytest.approx(expected, abs=1e-4), name
        worst = max(worst, abs(got - expected))
    assert metrics.ssim(ref, ref) == pytest.approx(1.0, abs=1e-12)
    print(f"max |ssim - skimage| at {size}: {worst:.2e}")


def test_ssim_rejects_images_smaller_than_the_window():
    with pytest.raises(ValueError, match="11"):
        metrics.ssim(np.zeros((10, 20, 3)), np.zeros((10, 20, 3)))


# -- FLIP against flip_evaluator ----------------------------------------------------------------

@pytest.fixture(scope="module")
def flip_evaluator():
    return pytest.importorskip("flip_evaluator", reason=f"flip_evaluator not installed in {PYDEPS}")


@pytest.mark.parametrize("ppd", [67.0, 30.0])
def test_flip_matches_flip_evaluator(flip_evaluator, ppd):
    ref, tests = _pairs(47, 71, seed=1)
    ref_srgb = metrics.srgb_encode(ref)
    worst = 0.0
    for name, test in tests.items():
        test_srgb = metrics.srgb_encode(test)
        # flip_evaluator converts its float32 inputs to linear in place: pass copies.
        their_map, their_mean, _ = flip_evaluator.evaluate(
            ref_srgb.astype(np.float32), test_srgb.astype(np.float32), "LDR", applyMagma=False,
            parameters={"ppd": ppd})
        mean, error_map = metrics.flip(ref, test, ppd=ppd)
        assert error_map.shape == ref.shape[:2]
        assert mean == pytest.approx(their_mean, abs=1e-3), name
        assert np.abs(error_map - np.asarray(their_map).reshape(error_map.shape)).max() < 1e-3, name
        worst = max(worst, abs(mean - their_mean))
    print(f"max |flip - flip_evaluator| at {ppd} ppd: {worst:.2e}")


def test_flip_properties():
    ref, tests = _pairs(40, 40, seed=3)
    mean, error_map = metrics.flip(ref, ref)
    assert mean == 0.0 and not error_map.any()
    noisy, _ = metrics.flip(ref, tests["noise"])
    blurred, _ = metrics.flip(ref, tests["blur"])
    assert 0.0 < blurred < 1.0 and 0.0 < noisy < 1.0
    black_white, bw_map = flip_module.flip(np.zeros((16, 16, 3)), np.ones((16, 16, 3)))
    assert black_white == pytest.approx(1.0, abs=0.05) and bw_map.max() <= 1.0
    with pytest.raises(ValueError):
        metrics.flip(ref, ref[:-1])


# -- PSNR ---------------------------------------------------------------------------------------

def test_psnr_known_values():
    ref = _base_image(30, 40)
    assert metrics.psnr(ref, ref) == math.inf
    # A constant offset of 0.1 in sRGB-encoded colour (kept inside [0,1]) gives 10·log10(1/0.01) = 20 dB.
    encoded = np.full((30, 40, 3), 0.4)
    linear_of = lambda s: np.where(s <= 0.04045, s / 12.92, ((s + 0.055) / 1.055) ** 2.4)  # noqa: E731
    assert metrics.psnr(linear_of(encoded), linear_of(encoded + 0.1)) == pytest.approx(20.0, abs=1e-9)
    # Clamping: values beyond [0,1] count as 0 and 1, so black vs over-bright white is 0 dB.
    assert metrics.psnr(np.full((4, 4, 3), -1.0), np.full((4, 4, 3), 7.0)) == pytest.approx(0.0, abs=1e-12)


def test_srgb_encode_curve():
    values = metrics.srgb_encode(np.array([-1.0, 0.0, 0.0031308, 0.18, 1.0, 2.0, np.nan]))
    assert values[0] == 0.0 and values[1] == 0.0 and values[-1] == 0.0
    assert values[2] == pytest.approx(0.04045, abs=1e-6)
    assert values[3] == pytest.approx(0.4613561, abs=1e-6)
    assert values[4] == pytest.approx(1.0) and values[5] == pytest.approx(1.0)


# -- depth and confusion ------------------------------------------------------------------------

def test_depth_errors_on_hand_made_arrays():
    ref = np.array([[1.0, 2.0, 4.0], [np.inf, 5.0, 1.0]])
    test = np.array([[1.1, 1.0, 4.0], [3.0, np.inf, 100.0]])
    ref_hit = np.array([[True, True, True], [False, True, True]])
    test_hit = np.array([[True, True, True], [True, False, False]])
    result = metrics.depth_errors(ref, test, ref_hit, test_hit)
    # Only the first row is hit by both: errors 0.1, −1, 0.
    assert result["pixels"] == 3
    assert result["absrel"] == pytest.approx((0.1 / 1.0 + 1.0 / 2.0 + 0.0) / 3)
    assert result["rmse"] == pytest.approx(math.sqrt((0.01 + 1.0 + 0.0) / 3))
    none = metrics.depth_errors(ref, test, np.zeros_like(ref_hit), test_hit)
    assert none == {"absrel": None, "rmse": None, "pixels": 0}


def test_confusion_on_hand_made_arrays():
    miss, hit, unknown = 0, 1, 2
    ref = np.array([hit, hit, hit, hit, miss, miss, miss, unknown], dtype=np.uint8)
    test = np.array([hit, miss, unknown, hit, hit, miss, unknown, hit], dtype=np.uint8)
    result = metrics.confusion(ref.reshape(2, 4), test.reshape(2, 4))
    assert result["counts"] == {"gt_hit": {"HIT": 2, "MISS": 1, "UNKNOWN": 1},
                                "gt_miss": {"HIT": 1, "MISS": 1, "UNKNOWN": 1}, "ref_unknown": 1}
    assert result["hole_rate"] == pytest.approx(2 / 4)
    assert result["false_miss_rate"] == pytest.approx(1 / 4)
    assert result["false_hit_rate"] == pytest.approx(1 / 3)
    assert result["unknown_rate"] == pytest.approx(2 / 8)
    all_hit = metrics.confusion(np.ones((3, 3), np.uint8), np.ones((3, 3), np.uint8))
    assert all_hit["hole_rate"] == 0.0 and all_hit["false_hit_rate"] == 0.0 and all_hit["false_miss_rate"] == 0.0


def test_compare_images_measures_colour_as_rendered_and_counts_holes_by_status():
    h, w = 24, 32
    colour = np.concatenate([_base_image(h, w), np.ones((h, w, 1))], axis=-1).astype(np.float32)
    depth = np.full((h, w), 2.0, np.float32)
    ref = {"rgba": colour, "depth": depth, "status": np.ones((h, w), np.uint8)}
    test_status = np.ones((h, w), np.uint8)
    test_status[:, :8] = 2  # UNKNOWN
    # Left black, as a render without the hole fill leaves UNKNOWN samples: an error.
    black = np.where(test_status[..., None] == 1, colour, 0.0).astype(np.float32)
    result = metrics.compare_images(ref, {"rgba": black, "depth": depth, "status": test_status})
    assert result["psnr"] == pytest.approx(metrics.psnr(colour[..., :3], black[..., :3]))
    assert result["psnr_answered"] == float("inf")
    # Coloured by the hole fill, here exactly: the picture is right, the status still says the
    # probes did not answer there.
    result = metrics.compare_images(ref, {"rgba": colour, "depth": depth, "status": test_status})
    assert result["psnr"] == float("inf")
    for figures in (result, metrics.compare_images(ref, {"rgba": black, "depth": depth, "status": test_status})):
        assert figures["hole_rate"] == pytest.approx(0.25) and figures["unknown_rate"] == pytest.approx(0.25)
        assert figures["false_miss_rate"] == 0.0 and figures["depth_absrel"] == 0.0
        assert figures["depth_pixels"] == h * (w - 8)
    assert set(metrics.DEFINITIONS) <= set(result["definitions"])


def test_a_prepared_reference_gives_the_same_bits_and_refuses_another_reference():
    # The report compares each ground truth with many renders: its half of SSIM and FLIP is made
    # once (metrics.PreparedColour). Every figure and the FLIP map stay the same bits.
    h, w = 40, 56
    ref_rgb, tests = _pairs(h, w)
    depth = np.full((h, w), 2.0, np.float32)
    status = np.ones((h, w), np.uint8)

    def image(rgb):
        rgba = np.concatenate([rgb, np.ones((h, w, 1))], axis=-1).astype(np.float32)
        return {"rgba": rgba, "depth": depth, "status": status}

    ref = image(ref_rgb)
    for ppd in (20.0, 67.0):
        prepared = metrics.PreparedColour(ref, ppd)
        for name, test_rgb in tests.items():
            plain, plain_map = metrics.compare_images_with_map(ref, image(test_rgb), ppd)
            figures, error_map = metrics.compare_images_with_map(ref, image(test_rgb), ppd, prepared=prepared)
            for key in ("psnr", "ssim", "flip", "psnr_answered", "depth_absrel"):
                assert figures[key] == plain[key], (name, ppd, key)
            assert np.array_equal(error_map, plain_map), (name, ppd)
    # Made from another image (even an equal one) or at another ppd: refused, not silently used.
    with pytest.raises(ValueError, match="another reference"):
        metrics.compare_images_with_map(image(ref_rgb), ref, 67.0, prepared=metrics.PreparedColour(ref, 67.0))
    with pytest.raises(ValueError, match="another reference"):
        metrics.compare_images_with_map(ref, ref, 20.0, prepared=metrics.PreparedColour(ref, 67.0))
    # A reference under SSIM's window: no SSIM, as without preparing.
    small = image(ref_rgb)
    small = {key: value[:8, :8] for key, value in small.items()}
    figures, _ = metrics.compare_images_with_map(small, small, 67.0, prepared=metrics.PreparedColour(small, 67.0))
    assert figures["ssim"] is None and figures["psnr"] == float("inf")


# -- compare on EXRs ----------------------------------------------------------------------------

REQUIRED_KEYS = {"psnr", "ssim", "flip", "depth_absrel", "depth_rmse", "hole_rate", "false_hit_rate",
                 "false_miss_rate"}


def run_compare(*args):
    """`./lfprobe compare ...`"""
    return run_cli("compare", *args, timeout=120)


@pytest.fixture(scope="module")
def views(tmp_path_factory):
    """A box room scanned at 4 cm, one 64² probe, and 40×30 views: probe render, splat, and a
    probe render at another size."""
    folder = tmp_path_factory.mktemp("compare")
    scan = folder / "room.xyz"
    write_box_room_xyz(scan, 0.04)
    probes = folder / "probes"
    run_cli("bake", "--scan", scan, "--scanner", 0, 0, 1.25, "--probe", 0, 0, 1.2, "--res", 64,
            "--out", probes, "--no-cache", "--quiet", check=True)
    out = {}
    for name, res in (("cam", (40, 30)), ("small", (32, 30))):
        camera = folder / f"{name}.json"
        run_cli("camera", "--position", 0, 0, 1.25, "--look-at", 2, 0.3, 1.0, "--res", *res, "--lens", 20,
                "--out", camera, check=True)
        out[name] = camera
    views = {"render": folder / "render.exr", "small": folder / "small.exr", "splat": folder / "splat.exr"}
    run_cli("render", "--probes", probes, "--camera", out["cam"], "--out", views["render"], "--quiet", check=True)
    run_cli("render", "--probes", probes, "--camera", out["small"], "--out", views["small"], "--quiet", check=True)
    run_cli("splat", "--scan", scan, "--scanner", 0, 0, 1.25, "--camera", out["cam"], "--out", views["splat"],
            "--no-cache", "--quiet", check=True)
    views["folder"] = folder
    return views


def test_compare_identical_images(views):
    result = run_compare(views["render"], views["render"], "--json")
    assert result.returncode == 0, result.stderr
    report = json.loads(result.stdout)  # exactly one JSON object
    assert REQUIRED_KEYS <= set(report) and REQUIRED_KEYS <= set(report["definitions"])
    assert report["psnr"] is None and report["ssim"] == pytest.approx(1.0)  # infinite PSNR
    assert report["flip"] == 0.0 and report["hole_rate"] == 0.0
    assert report["depth_absrel"] == 0.0 and report["depth_rmse"] == 0.0
    assert report["width"] == 40 and report["height"] == 30


def test_compare_splat_against_render_with_error_map(views):
    png = views["folder"] / "flip.png"
    result = run_compare(views["render"], views["splat"], "--json", "--ppd", 40, "--error-map", png)
    assert result.returncode == 0, result.stderr
    report = json.loads(result.stdout)
    assert 0.0 < report["flip"] < 1.0 and 0.0 < report["ssim"] < 1.0 and 10.0 < report["psnr"] < 60.0
    assert report["ppd"] == 40.0 and report["depth_pixels"] > 0
    assert 0.0 <= report["depth_absrel"] < 0.2
    data = png.read_bytes()
    assert data.startswith(b"\x89PNG\r\n\x1a\n") and data[12:16] == b"IHDR"
    assert int.from_bytes(data[16:20], "big") == 40 and int.from_bytes(data[20:24], "big") == 30
    table = run_compare(views["render"], views["splat"])
    assert table.returncode == 0 and "PSNR" in table.stdout and "hole rate" in table.stdout


def test_compare_errors_exit_2(views):
    mismatch = run_compare(views["render"], views["small"], "--json")
    assert mismatch.returncode == 2 and "differ in size" in mismatch.stderr and "40×30" in mismatch.stderr
    assert mismatch.stdout == ""
    missing = run_compare(views["folder"] / "nope.exr", views["render"])
    assert missing.returncode == 2 and "nope.exr" in missing.stderr


def test_lfprobe_compare_when_wired(views):
    """The same command through ./lfprobe, once cli.py adds cli_compare's parser."""
    from lfprobe.core import cli

    try:
        cli.build_parser().parse_args(["compare", "a.exr", "b.exr"])
    except SystemExit:
        pytest.skip("compare is not wired into lfprobe.core.cli yet")
    result = run_cli("compare", views["render"], views["render"], "--json")
    assert result.returncode == 0, result.stderr
    assert REQUIRED_KEYS <= set(json.loads(result.stdout))
    mismatch = run_cli("compare", views["render"], views["small"])
    assert mismatch.returncode == 2


def test_scipys_correlation_and_the_numpy_sums_give_the_same_filtered_images():
    """The metrics filter with scipy.ndimage where it is installed and with numpy sums where it is
    not (Blender's bundled Python): both paths, edge-clamped and valid-region, on an image whose
    borders differ from its inside, agree to rounding."""
    from lfprobe.core import image_filters

    if not image_filters.have_scipy():
        pytest.skip("scipy is not installed: only the numpy path runs here")
    rng = np.random.default_rng(7)
    image = rng.random((37, 53, 3))
    image[:, 0] = 5.0  # a bright border column: the clamp must read it
    for weights in (flip_module.feature_filters(67.0)[1], np.array([0.25, 0.5, 0.25]),
                    metrics._gaussian_window_1d()):
        for axis in (0, 1):
            fast = image_filters.correlate_edge(image, weights, axis)
            slow = image_filters.correlate_edge(image, weights, axis, use_scipy=False)
            assert fast.shape == image.shape
            np.testing.assert_allclose(fast, slow, rtol=0, atol=1e-12)
        fast = image_filters.correlate_valid(image, weights)
        slow = image_filters.correlate_valid(image, weights, use_scipy=False)
        assert fast.shape == slow.shape == (37 - len(weights) + 1, 53 - len(weights) + 1, 3)
        np.testing.assert_allclose(fast, slow, rtol=0, atol=1e-12)
