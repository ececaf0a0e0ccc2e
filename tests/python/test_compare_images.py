"""./lfprobe compare on images other than lfprobe's own renders (issue 19): a Cycles render saved
as plain EXR (several codecs), as Blender's multilayer EXR, as PNG (8 and 16 bit) and JPEG,
measured against a probe render; bad files and mismatched sizes; and lfprobe against lfprobe
giving the figures it always gave.

The Blender images come from tests/blender/write_compare_images.py (Blender 3.4.1 renders the
default scene with Cycles, 64×48, about 1.5 s). Blender is required: without it this test fails,
it does not skip. The reference pixels for scikit-image are read by tests/blender/exr_channels.py
(uncompressed EXR) and Pillow (8-bit PNG), not by the reader under test."""

import json
import os
import shutil
import subprocess

import numpy as np
import pytest

from conftest import ROOT, run_cli, write_box_room_xyz

from lfprobe.core import image_files, metrics
from lfprobe.core.colour import srgb_encode
from lfprobe.core.compare import write_png

import sys

sys.path.insert(0, os.path.join(ROOT, "tests", "blender"))
from exr_channels import read_exr_channels as independent_exr, write_exr_channels  # noqa: E402

WIDTH, HEIGHT = 64, 48
SCRIPT = os.path.join(ROOT, "tests", "blender", "write_compare_images.py")


@pytest.fixture(scope="module")
def renders(tmp_path_factory):
    """Two probe renders (bilinear and nearest) of a small box room, 64×48."""
    folder = tmp_path_factory.mktemp("compare_room")
    scan = folder / "room.xyz"
    write_box_room_xyz(scan, 0.04)
    probes = folder / "probes"
    run_cli("bake", "--scan", scan, "--scanner", 0, 0, 1.25, "--probe", 0, 0, 1.25, "--res", 64,
            "--out", probes, "--no-cache", "--quiet", check=True)
    camera = folder / "cam.json"
    run_cli("camera", "--position", 0, 0, 1.25, "--look-at", 2, 0.5, 1.0, "--res", WIDTH, HEIGHT,
            "--lens", 20, "--out", camera, check=True)
    out = {}
    for name in ("bilinear", "nearest"):
        out[name] = folder / f"{name}.exr"
        run_cli("render", "--probes", probes, "--camera", camera, "--out", out[name], "--filter", name,
                "--quiet", check=True)
    return out


@pytest.fixture(scope="module")
def blender_images(tmp_path_factory):
    """The default scene rendered by Cycles and saved as plain/multilayer EXR, PNG and JPEG."""
    folder = tmp_path_factory.mktemp("blender_images")
    blender = shutil.which("blender")
    if blender is None:
        pytest.fail("blender is not on PATH: install Debian's blender; this test needs it and does not skip")
    result = subprocess.run([blender, "-b", "--factory-startup", "--python-exit-code", "1", "-P", SCRIPT, "--",
                             str(folder), str(WIDTH), str(HEIGHT)], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    return folder


def _compare_json(ref, test):
    result = run_cli("compare", ref, test, "--json", check=True)
    return json.loads(result.stdout)


def _skimage_figures(ref_encoded, test_encoded):
    from skimage.metrics import peak_signal_noise_ratio, structural_similarity

    psnr = peak_signal_noise_ratio(ref_encoded, test_encoded, data_range=1.0)
    ssim = structural_similarity(ref_encoded, test_encoded, channel_axis=2, gaussian_weights=True, sigma=1.5,
                                 use_sample_covariance=False, data_range=1.0)
    return psnr, ssim


def _probe_encoded(native, path):
    """The probe render's colour as compare measures it: not-HIT pixels black, sRGB-encoded."""
    return srgb_encode(metrics.visible_colour(native.read_image(str(path))))


def test_rgb_only_exr_against_a_probe_render_equals_scikit_image(native, renders, blender_images):
    """A Cycles render saved as RGB EXR (ZIP) against a probe render: PSNR and SSIM are
    scikit-image's on the sRGB-encoded clamped colour, the reference's pixels read from the same
    render saved uncompressed by an independent reader."""
    plain = independent_exr(str(blender_images / "rgb_none.exr"))
    ref_encoded = srgb_encode(np.stack([plain[c] for c in "RGB"], axis=-1))
    test_encoded = _probe_encoded(native, renders["bilinear"])
    psnr, ssim = _skimage_figures(ref_encoded, test_encoded)
    for name in ("rgb_zip.exr", "rgb_none.exr", "rgba_rle.exr"):
        figures = _compare_json(blender_images / name, renders["bilinear"])
        print(f"{name}: PSNR {figures['psnr']:.6f} dB (scikit-image {psnr:.6f}, Δ {figures['psnr'] - psnr:.1e}), "
              f"SSIM {figures['ssim']:.8f} (Δ {figures['ssim'] - ssim:.1e})")
        assert figures["psnr"] == pytest.approx(psnr, abs=1e-9)
        assert figures["ssim"] == pytest.approx(ssim, abs=1e-12)
        assert figures["reference_source"].startswith("EXR RGB")
        assert figures["test_source"] == "lfprobe EXR"
        # psnr_answered needs only the test's status, which the probe render has.
        assert figures["computed"] == ["psnr", "ssim", "flip", "psnr_answered"]
        assert figures["psnr_answered"] is not None
        for key in ("depth_absrel", "depth_rmse", "hole_rate", "false_hit_rate", "unknown_rate"):
            assert figures[key] is None and key in figures["not_computed"], key
        assert "reference" in figures["not_computed"]["depth_absrel"]


def test_png_against_a_probe_render_equals_scikit_image(native, renders, blender_images):
    """An 8-bit PNG is sRGB: decoded to linear and encoded again for the metrics, so its figures
    are scikit-image's on the PNG's own values / 255 (Pillow's reading)."""
    from PIL import Image

    with Image.open(blender_images / "rgb8.png") as image:
        ref_encoded = np.asarray(image.convert("RGB"), dtype=np.float64) / 255.0
    test_encoded = _probe_encoded(native, renders["nearest"])
    psnr, ssim = _skimage_figures(ref_encoded, test_encoded)
    figures = _compare_json(blender_images / "rgb8.png", renders["nearest"])
    print(f"rgb8.png: PSNR {figures['psnr']:.6f} dB (scikit-image {psnr:.6f}, Δ {figures['psnr'] - psnr:.1e}), "
          f"SSIM {figures['ssim']:.8f} (Δ {figures['ssim'] - ssim:.1e})")
    assert figures["psnr"] == pytest.approx(psnr, abs=1e-9)
    assert figures["ssim"] == pytest.approx(ssim, abs=1e-12)
    assert figures["reference_source"] == "PNG 8-bit sRGB"
    # The probe render as the reference, the PNG as the test: same colour figures, and
    # psnr_answered needs the test's status, which a PNG lacks.
    swapped = _compare_json(renders["nearest"], blender_images / "rgb8.png")
    assert swapped["psnr"] == pytest.approx(psnr, abs=1e-9)
    assert "psnr_answered" in swapped["not_computed"] and swapped["psnr_answered"] is None
    # The PNG against the EXR of the same Cycles render: high PSNR, still scikit-image's figures.
    plain = independent_exr(str(blender_images / "rgb_none.exr"))
    psnr, ssim = _skimage_figures(srgb_encode(np.stack([plain[c] for c in "RGB"], axis=-1)), ref_encoded)
    same = _compare_json(blender_images / "rgb_zip.exr", blender_images / "rgb8.png")
    print(f"rgb_zip.exr vs rgb8.png: PSNR {same['psnr']:.4f} dB (Δ {same['psnr'] - psnr:.1e}), "
          f"SSIM {same['ssim']:.6f} (Δ {same['ssim'] - ssim:.1e})")
    assert same["psnr"] > 45 and same["psnr"] == pytest.approx(psnr, abs=1e-9)
    assert same["ssim"] == pytest.approx(ssim, abs=1e-12)
    assert same["computed"] == ["psnr", "ssim", "flip"]


def test_other_images_read_as_the_same_render(blender_images):
    """One Cycles render in every file kind reads to the same linear colour: bit for bit from
    lossless EXR codecs (PIZ too) and the multilayer file's Combined pass, to half precision from a half
    EXR, to 16-bit and 8-bit steps from PNG (alpha premultiplied, as EXR's is), JPEG near."""
    plain = independent_exr(str(blender_images / "rgb_none.exr"))
    rgb = np.stack([plain[c] for c in "RGB"], axis=-1)
    with_alpha = independent_exr(str(blender_images / "multilayer_none.exr"))
    alpha = with_alpha["ViewLayer.Combined.A"]
    limits = {"rgb_zip.exr": 0, "rgba_rle.exr": 0, "rgb_piz.exr": 0, "multilayer.exr": 0, "multilayer_none.exr": 0,
              "rgba_zips_half.exr": 1e-3, "rgba16.png": 3e-5, "rgb8.png": 5e-3, "rgb.jpg": 0.06}
    for name, limit in limits.items():
        image = image_files.read_any_image(str(blender_images / name))
        assert image["rgba"].shape == (HEIGHT, WIDTH, 4), name
        assert np.abs(image["rgba"][..., :3] - rgb).max() <= limit, name
        if name.startswith(("rgba", "multilayer")):
            assert np.abs(image["rgba"][..., 3] - alpha).max() <= max(limit, 0), name
    multilayer = image_files.read_any_image(str(blender_images / "multilayer.exr"))
    assert multilayer["source"] == "EXR RGBA, layer ViewLayer.Combined"
    assert "status" not in multilayer and "depth" not in multilayer


def test_the_colour_layer_of_a_multilayer_exr():
    names = ["RenderLayer.Combined.R", "RenderLayer.Combined.G", "RenderLayer.Combined.B", "RenderLayer.Combined.A",
             "RenderLayer.DiffCol.R", "RenderLayer.DiffCol.G", "RenderLayer.DiffCol.B", "RenderLayer.Depth.Z"]
    assert image_files.colour_layer(names, "x.exr") == "RenderLayer.Combined"
    assert image_files.colour_layer(["Beauty.R", "Beauty.G", "Beauty.B", "Z"], "x.exr") == "Beauty"
    assert image_files.colour_layer(["R", "G", "B", "ViewLayer.Combined.R"], "x.exr") == ""
    with pytest.raises(image_files.ImageFileError, match="x.exr.*several colour layers.*A.Combined, B.Combined"):
        image_files.colour_layer(["A.Combined.R", "A.Combined.G", "A.Combined.B",
                                  "B.Combined.R", "B.Combined.G", "B.Combined.B"], "x.exr")
    with pytest.raises(image_files.ImageFileError, match="x.exr.*no R, G, B"):
        image_files.colour_layer(["Y", "Z"], "x.exr")


def test_bad_files_and_mismatched_sizes_exit_2_naming_the_file(renders, blender_images, tmp_path):
    small = tmp_path / "small.png"
    write_png(str(small), np.zeros((24, 32, 3), dtype=np.uint8))
    garbage = tmp_path / "garbage.exr"
    garbage.write_bytes(b"this is not an image at all\n" * 10)
    truncated = tmp_path / "truncated.exr"
    truncated.write_bytes((blender_images / "rgb_zip.exr").read_bytes()[:300])
    cut_png = tmp_path / "cut.png"
    cut_png.write_bytes((blender_images / "rgba16.png").read_bytes()[:400])
    cases = [
        (renders["bilinear"], small, ["small.png", "32×24", "64×48"]),
        (small, renders["bilinear"], ["small.png", "32×24"]),
        (renders["bilinear"], garbage, ["garbage.exr", "not an image"]),
        (garbage, renders["bilinear"], ["garbage.exr"]),
        (truncated, renders["bilinear"], ["truncated.exr"]),
        (cut_png, renders["bilinear"], ["cut.png"]),
        (tmp_path / "missing.png", renders["bilinear"], ["missing.png"]),
    ]
    for ref, test, words in cases:
        result = run_cli("compare", ref, test)
        assert result.returncode == 2, (ref, test, result.stdout, result.stderr)
        assert "Traceback" not in result.stderr
        for word in words:
            assert word in result.stderr, (word, result.stderr)


def test_lfprobe_against_lfprobe_gives_the_figures_it_always_gave(native, renders):
    """Two probe renders: every key and value of metrics.compare_images_with_map (what compare
    printed before other images were read), the paths and render times, and everything computed."""
    ref_path, test_path = renders["bilinear"], renders["nearest"]
    figures = _compare_json(ref_path, test_path)
    reference, test = native.read_image(str(ref_path)), native.read_image(str(test_path))
    expected, _map = metrics.compare_images_with_map(reference, test)
    expected.update({
        "reference": os.path.abspath(ref_path), "test": os.path.abspath(test_path),
        "ref_render_seconds": json.loads(reference["metadata"])["stats"]["seconds"],
        "test_render_seconds": json.loads(test["metadata"])["stats"]["seconds"],
    })
    expected = json.loads(json.dumps(expected, allow_nan=True).replace("Infinity", "null"))
    for key, value in expected.items():
        assert figures[key] == value, key
    assert figures["counts"]["gt_hit"]["HIT"] > 0 and figures["depth_pixels"] > 0
    # A probe render as the test also gives its guessed surfaces (compare's own additions).
    guessed = metrics.guessed_figures(reference, test)
    assert set(guessed) == {"guessed_pixels", "guessed_error_share", "psnr_off_guesses"}
    for key, value in guessed.items():
        assert figures[key] == pytest.approx(value), key
    assert set(figures) - set(expected) == {"compare_seconds", "computed", "not_computed", "reference_source",
                                            "test_source", *guessed}
    assert figures["not_computed"] == {}
    assert figures["computed"] == ["psnr", "ssim", "flip", "psnr_answered", *metrics.GEOMETRY_METRICS]
    table = run_cli("compare", ref_path, test_path, check=True).stdout
    assert "confusion     test HIT" in table and "not computed" not in table
    assert f"{guessed['guessed_pixels']:.2%} of the pixels" in table


def test_renders_with_the_older_channel_names_read_as_before(native, renders, tmp_path):
    """A render names its analysis channels as Blender passes (status.X, probe.X, steps.X); one
    written before, with the single-token status, probe, steps, still reads as lfprobe's own
    EXR: the same planes, and compare measures it with every figure."""
    new_path = renders["nearest"]
    channels, _size = image_files.read_exr_channels(str(new_path))
    assert {"status.X", "probe.X", "steps.X"} <= set(channels)
    assert not {"status", "probe", "steps"} & set(channels)
    old_names = {"status.X": "status", "probe.X": "probe", "steps.X": "steps"}
    old_path = tmp_path / "older.exr"
    write_exr_channels(str(old_path), {old_names.get(name, name): plane for name, plane in channels.items()})
    old, new = image_files.read_any_image(str(old_path)), image_files.read_any_image(str(new_path))
    assert old["source"] == new["source"] == "lfprobe EXR"
    for key in ("rgba", "depth", "normal", "status", "probe", "steps"):
        assert np.array_equal(old[key], new[key]), key
    figures = _compare_json(renders["bilinear"], old_path)
    assert figures["test_source"] == "lfprobe EXR" and figures["not_computed"] == {}
    assert figures == {**_compare_json(renders["bilinear"], new_path), "compare_seconds": figures["compare_seconds"],
                       "test": figures["test"], "test_render_seconds": None}
