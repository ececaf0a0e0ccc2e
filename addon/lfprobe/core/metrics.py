"""Image metrics for comparing a rendered view with ground truth (docs/DESIGN.md §6).

numpy, with scipy's 1D correlation where it is installed (image_filters.py); no bpy. Every
figure is defined in the docstring of the function that computes it, and `DEFINITIONS` repeats
the definitions that `compare --json` prints.

Colour metrics work on sRGB-encoded colour: the linear RGB of the EXR is clamped to [0, 1] and
passed through the sRGB curve (`srgb_encode`), so the data range is 1.
"""

from __future__ import annotations

import math
from typing import Dict, Optional, Tuple

import numpy as np

from . import flip as _flip
from .image_filters import correlate_valid
from .colour import srgb_encode  # noqa: F401  (metrics.srgb_encode: what the figures encode with)

STATUS_MISS, STATUS_HIT, STATUS_UNKNOWN = 0, 1, 2

SSIM_SIGMA = 1.5
SSIM_WINDOW = 11  # 2·int(3.5·σ + 0.5) + 1: the Gaussian truncated at 3.5σ, as scikit-image does
SSIM_K1, SSIM_K2 = 0.01, 0.03

# Depth off by more than this fraction: the pixel shows another surface than the reference's.
WRONG_SURFACE_RELATIVE = 0.05

DEFINITIONS = {
    "colour": "RGB of each image as rendered: each pixel the mean of its samples, a sample that is "
              "not HIT adding black unless the hole fill of the render coloured it (its status stays UNKNOWN); "
              "clamped to [0,1] and sRGB-encoded; data range 1",
    "psnr": "10·log10(1/MSE) over all pixels and the three channels of the sRGB colour, in dB; "
            "infinite when the images are identical (null in compare --json)",
    "ssim": "SSIM per channel (11×11 Gaussian window σ=1.5, K1=0.01, K2=0.03, population "
            "covariances), averaged over the valid region (5-pixel border dropped), then over channels",
    "flip": "mean LDR-FLIP error (Andersson et al. 2020) of the sRGB colour at the given pixels per degree",
    "depth_absrel": "mean of |d_test − d_ref| / d_ref over pixels that both images hit with finite "
                    "positive depth; null when there are none",
    "depth_rmse": "sqrt(mean((d_test − d_ref)²)) over the same pixels, in scene units; null when none",
    "hole_rate": "pixels the ground truth hits but the test does not (test MISS or UNKNOWN) / pixels "
                 "the ground truth hits; 0 when it hits none",
    "false_hit_rate": "pixels the test calls HIT where the ground truth misses / pixels the ground "
                      "truth misses; 0 when it misses none",
    "false_miss_rate": "pixels the test calls MISS where the ground truth hits / pixels the ground "
                       "truth hits; 0 when it hits none (a subset of the holes)",
    "unknown_rate": "pixels the test calls UNKNOWN / all pixels",
    "psnr_answered": "PSNR as psnr over the pixels the test answered (status HIT or MISS): the error of "
                     "what the probes show, apart from what they honestly call UNKNOWN (unknown_rate); "
                     "null when the test answered no pixel",
    "wrong_surface_rate": "pixels both images hit whose test depth differs from the reference depth by more "
                          f"than {WRONG_SURFACE_RELATIVE:.0%} of it (another surface shown) / pixels both hit; "
                          "0 when there are none",
    "counts": "confusion counts: ground truth (hit, miss) × test (HIT, MISS, UNKNOWN); reference "
              "pixels that are themselves UNKNOWN are left out and counted in ref_unknown",
    "guessed_pixels": "probe renders only: pixels whose centre sample met a hole-filled texel (a surface no "
                      "scan saw there, guessed by the bake from around it) / all pixels",
    "guessed_error_share": "probe renders only: the share of the squared sRGB error (as psnr) on those pixels",
    "psnr_off_guesses": "probe renders only: PSNR as psnr over the other pixels; null when every pixel is a guess",
}


def _check_pair(ref: np.ndarray, test: np.ndarray) -> None:
    if ref.shape != test.shape:
        raise ValueError(f"images differ in size: {ref.shape} vs {test.shape}")


def psnr(ref_rgb: np.ndarray, test_rgb: np.ndarray) -> float:
    """PSNR in dB of two linear RGB images, on sRGB-encoded clamped colour with data range 1:
    10·log10(1 / MSE), MSE over all pixels and channels; +inf when the encoded images are equal."""
    return _psnr_encoded(srgb_encode(ref_rgb), srgb_encode(test_rgb))


def _psnr_encoded(ref: np.ndarray, test: np.ndarray) -> float:
    _check_pair(ref, test)
    mse = float(np.mean((ref - test) ** 2))
    return math.inf if mse == 0.0 else 10.0 * math.log10(1.0 / mse)


def _gaussian_window_1d() -> np.ndarray:
    radius = SSIM_WINDOW // 2
    x = np.arange(-radius, radius + 1, dtype=np.float64)
    g = np.exp(-0.5 * (x / SSIM_SIGMA) ** 2)
    return g / g.sum()


def _valid_filter(image: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Separable correlation of (h, w, ...) with weights on both axes, valid region only
    (output shrinks by len(weights) − 1 on each axis)."""
    return correlate_valid(image, weights)


def ssim_map(ref_srgb: np.ndarray, test_srgb: np.ndarray) -> np.ndarray:
    """The SSIM map (h − 10, w − 10, c) of two images already in the [0, 1] range (no encoding).

    SSIM = ((2·μx·μy + C1)(2·σxy + C2)) / ((μx² + μy² + C1)(σx² + σy² + C2)), C1 = (0.01)²,
    C2 = (0.03)², local means and population (co)variances under an 11×11 Gaussian window with
    σ = 1.5, evaluated only where the window lies inside the image.
    """
    x = np.asarray(ref_srgb, dtype=np.float64)
    y = np.asarray(test_srgb, dtype=np.float64)
    _check_pair(x, y)
    return _ssim_map_against(_SsimSide(x), y)


class _SsimSide:
    """One image's local means and variances under the SSIM window: a reference's are made once
    for every image compared with it (PreparedColour)."""

    def __init__(self, image: np.ndarray):
        x = image[..., None] if image.ndim == 2 else image
        if min(x.shape[0], x.shape[1]) < SSIM_WINDOW:
            raise ValueError(f"SSIM needs images of at least {SSIM_WINDOW}×{SSIM_WINDOW} pixels, got "
                             f"{x.shape[1]}×{x.shape[0]}")
        g = _gaussian_window_1d()
        self.x = x
        self.mu = _valid_filter(x, g)
        self.var = _valid_filter(x * x, g) - self.mu * self.mu


def _ssim_map_against(ref: _SsimSide, test_srgb: np.ndarray) -> np.ndarray:
    y = test_srgb[..., None] if test_srgb.ndim == 2 else test_srgb
    g = _gaussian_window_1d()
    mu_x, var_x = ref.mu, ref.var
    mu_y = _valid_filter(y, g)
    var_y = _valid_filter(y * y, g) - mu_y * mu_y
    cov_xy = _valid_filter(ref.x * y, g) - mu_x * mu_y
    c1, c2 = SSIM_K1**2, SSIM_K2**2  # data range 1
    return ((2 * mu_x * mu_y + c1) * (2 * cov_xy + c2)) / ((mu_x**2 + mu_y**2 + c1) * (var_x + var_y + c2))


def ssim(ref_rgb: np.ndarray, test_rgb: np.ndarray) -> float:
    """Mean SSIM of two linear RGB images on sRGB-encoded clamped colour (see `ssim_map`): the
    mean of each channel's map over the valid region, then the mean over channels. Equals
    skimage.metrics.structural_similarity(channel_axis=2, gaussian_weights=True, sigma=1.5,
    use_sample_covariance=False, data_range=1) on the encoded images."""
    return _ssim_encoded(srgb_encode(ref_rgb), srgb_encode(test_rgb))


def _ssim_encoded(ref: np.ndarray, test: np.ndarray) -> float:
    return float(ssim_map(ref, test).mean(axis=(0, 1)).mean())


def flip(ref_rgb: np.ndarray, test_rgb: np.ndarray, ppd: float = _flip.DEFAULT_PPD) -> Tuple[float, np.ndarray]:
    """(mean, per-pixel map) of LDR-FLIP between two linear RGB images, computed on their
    sRGB-encoded clamped colour at ppd pixels per degree (see lfprobe.core.flip)."""
    return _flip.flip(srgb_encode(ref_rgb), srgb_encode(test_rgb), ppd)


def depth_errors(ref_depth: np.ndarray, test_depth: np.ndarray, ref_hit: np.ndarray,
                 test_hit: np.ndarray) -> Dict[str, Optional[float]]:
    """Depth errors over the pixels both images hit (and whose depths are finite, reference > 0):
    absrel = mean(|d_test − d_ref| / d_ref), rmse = sqrt(mean((d_test − d_ref)²)), pixels = their
    count. absrel and rmse are None when there are no such pixels."""
    ref = np.asarray(ref_depth, dtype=np.float64)
    test = np.asarray(test_depth, dtype=np.float64)
    _check_pair(ref, test)
    mask = (np.asarray(ref_hit, dtype=bool) & np.asarray(test_hit, dtype=bool)
            & np.isfinite(ref) & np.isfinite(test) & (ref > 0))
    n = int(mask.sum())
    if n == 0:
        return {"absrel": None, "rmse": None, "pixels": 0}
    diff = test[mask] - ref[mask]
    return {
        "absrel": float(np.mean(np.abs(diff) / ref[mask])),
        "rmse": float(np.sqrt(np.mean(diff * diff))),
        "pixels": n,
    }


def confusion(ref_status: np.ndarray, test_status: np.ndarray) -> Dict[str, object]:
    """Probe answers {HIT, MISS, UNKNOWN} against ground truth {hit, miss}.

    Ground truth hit: reference status HIT (1); miss: status MISS (0); reference pixels with any
    other status are left out (counted in ref_unknown). Rates:
      hole_rate       = #(gt hit, test MISS or UNKNOWN) / #gt hit   (0 when #gt hit = 0)
      false_miss_rate = #(gt hit, test MISS) / #gt hit              (0 when #gt hit = 0)
      false_hit_rate  = #(gt miss, test HIT) / #gt miss             (0 when #gt miss = 0)
      unknown_rate    = #(test UNKNOWN) / #all pixels
    Returns those rates and counts = {"gt_hit": {HIT, MISS, UNKNOWN}, "gt_miss": {...},
    "ref_unknown": n}.
    """
    ref = np.asarray(ref_status)
    test = np.asarray(test_status)
    _check_pair(ref, test)
    gt_hit, gt_miss = ref == STATUS_HIT, ref == STATUS_MISS
    answers = {"HIT": test == STATUS_HIT, "MISS": test == STATUS_MISS, "UNKNOWN": test == STATUS_UNKNOWN}
    counts = {
        "gt_hit": {name: int((gt_hit & a).sum()) for name, a in answers.items()},
        "gt_miss": {name: int((gt_miss & a).sum()) for name, a in answers.items()},
        "ref_unknown": int((~gt_hit & ~gt_miss).sum()),
    }
    n_hit, n_miss = int(gt_hit.sum()), int(gt_miss.sum())
    holes = n_hit - counts["gt_hit"]["HIT"]
    return {
        "hole_rate": holes / n_hit if n_hit else 0.0,
        "false_miss_rate": counts["gt_hit"]["MISS"] / n_hit if n_hit else 0.0,
        "false_hit_rate": counts["gt_miss"]["HIT"] / n_miss if n_miss else 0.0,
        "unknown_rate": float(answers["UNKNOWN"].mean()) if test.size else 0.0,
        "counts": counts,
    }


def psnr_over(ref_rgb: np.ndarray, test_rgb: np.ndarray, mask: np.ndarray) -> Optional[float]:
    """PSNR as psnr() over the pixels where `mask` is true; None when it selects none."""
    mask = np.asarray(mask, dtype=bool)
    if not mask.any():
        return None
    return psnr(np.asarray(ref_rgb)[mask], np.asarray(test_rgb)[mask])


def _squared_error(reference: Dict[str, np.ndarray], test: Dict[str, np.ndarray]) -> np.ndarray:
    """Per pixel, the squared sRGB error summed over the channels (what psnr averages)."""
    return ((srgb_encode(visible_colour(reference)) - srgb_encode(visible_colour(test))) ** 2).sum(axis=-1)


def error_share(reference: Dict[str, np.ndarray], test: Dict[str, np.ndarray],
                mask: np.ndarray) -> float:
    """The fraction of the squared error (sRGB, as psnr) that the pixels of `mask` carry."""
    squared = _squared_error(reference, test)
    total = float(squared.sum())
    return float(squared[np.asarray(mask, dtype=bool)].sum()) / total if total > 0 else 0.0


def _guessed_mask(test: Dict[str, np.ndarray]) -> np.ndarray:
    """The pixels of a probe render whose centre sample met a hole-filled texel, as booleans in
    the image's shape."""
    return np.asarray(test["guessed"]).reshape(np.asarray(test["rgba"]).shape[:2]) != 0


def guessed_figures(reference: Dict[str, np.ndarray], test: Dict[str, np.ndarray]) -> Dict[str, object]:
    """Where a probe render shows a guess (its "guessed" plane: the centre sample HIT a
    hole-filled texel, a surface no scan saw there): the share of the pixels
    (guessed_pixels), the share of the squared error they carry (guessed_error_share) and the
    PSNR over the other pixels (psnr_off_guesses, None when every pixel is a guess). Empty for
    images without the plane (ground truth, splats, other files, renders from before it)."""
    if "guessed" not in test:
        return {}
    guessed = _guessed_mask(test)
    # The images encoded once for all three figures.
    squared = _squared_error(reference, test)
    total = float(squared.sum())
    off = ~guessed
    off_mse = float(squared[off].sum()) / (3 * int(off.sum())) if off.any() else None
    return {"guessed_pixels": float(guessed.mean()),
            "guessed_error_share": float(squared[guessed].sum()) / total if total > 0 else 0.0,
            "psnr_off_guesses": None if off_mse is None else
            (math.inf if off_mse == 0.0 else 10.0 * math.log10(1.0 / off_mse))}


def psnr_seen_as(reference: Dict[str, np.ndarray], test: Dict[str, np.ndarray],
                 stand_in: Dict[str, np.ndarray]) -> Optional[float]:
    """PSNR of `test` (a probe render with its "guessed" plane) with every pixel that is not a
    guess taken from `stand_in`, an image of the same camera: what `test` would score were all it
    shows of what the scans saw as exact as `stand_in`, its guesses (what no scan saw) as they
    are. None for images without the plane."""
    if "guessed" not in test:
        return None
    guessed = _guessed_mask(test)
    mixed = np.where(guessed[..., None], visible_colour(test), visible_colour(stand_in))
    return psnr(visible_colour(reference), mixed)


def wrong_surface_rate(ref_depth: np.ndarray, test_depth: np.ndarray, ref_hit: np.ndarray,
                       test_hit: np.ndarray) -> float:
    """Of the pixels both images hit with finite positive depth, the fraction whose test depth is
    off by more than WRONG_SURFACE_RELATIVE of the reference's."""
    ref_d, test_d = np.asarray(ref_depth, np.float64), np.asarray(test_depth, np.float64)
    both = np.asarray(ref_hit) & np.asarray(test_hit) & np.isfinite(ref_d) & np.isfinite(test_d) & (ref_d > 0)
    if not both.any():
        return 0.0
    return float(np.mean(np.abs(test_d[both] - ref_d[both]) > WRONG_SURFACE_RELATIVE * ref_d[both]))


def visible_colour(image: Dict[str, np.ndarray]) -> np.ndarray:
    """Linear RGB of a read_image dict as the image shows it. lfprobe's renders store colour
    premultiplied by coverage, each pixel the mean of its samples with the samples that are not
    HIT black (or given the hole fill's colour), so nothing is masked here: a pixel whose centre
    ray is UNKNOWN or MISS keeps the colour its other samples gave it, as the ground truth's
    pixel keeps its own. (Masking by the centre's status, as before, blacked out 15 of 16 HIT
    samples of a pixel whose centre alone was UNKNOWN, and a filled hole's colour.)"""
    return np.asarray(image["rgba"], dtype=np.float64)[..., :3]


def compare_images(ref: Dict[str, np.ndarray], test: Dict[str, np.ndarray],
                   ppd: float = _flip.DEFAULT_PPD) -> Dict[str, object]:
    """All metrics between a ground-truth image and a test image; see compare_images_with_map."""
    return compare_images_with_map(ref, test, ppd)[0]


class _ReferenceColour:
    """A reference colour image's half of psnr, ssim and flip at one ppd: its sRGB encoding, its
    SSIM window statistics (None under the window) and its half of FLIP."""

    def __init__(self, ref_rgb: np.ndarray, ppd: float):
        self.ppd = float(ppd)
        self.encoded = srgb_encode(ref_rgb)
        try:
            self.ssim: Optional[_SsimSide] = _SsimSide(self.encoded)
        except ValueError:
            self.ssim = None
        self.flip = _flip.PreparedReference(self.encoded, ppd)


class PreparedColour(_ReferenceColour):
    """A ground truth's half of the colour metrics, made once for every image compared with it
    (compare_images_with_map's `prepared`): the report compares each ground truth with many
    renders. The figures are the same bits as without it."""

    def __init__(self, ref: Dict[str, np.ndarray], ppd: float = _flip.DEFAULT_PPD):
        self.image = ref
        self.rgb = visible_colour(ref)
        super().__init__(self.rgb, ppd)

    def serves(self, ref: Dict[str, np.ndarray], ppd: float) -> bool:
        """Whether this was prepared from `ref` itself (the same object) at `ppd`."""
        return self.image is ref and self.ppd == float(ppd)


def _colour_figures(ref_rgb: np.ndarray, test_rgb: np.ndarray, ppd: float,
                    prepared: Optional[PreparedColour] = None) -> Tuple[Dict[str, object], np.ndarray]:
    """({psnr, ssim, flip}, FLIP error map) of two colour images; ssim None under its window.
    Each image is sRGB-encoded once for the three (what psnr, ssim and flip each do); the
    reference's half comes from `prepared` where given (made from it at this ppd)."""
    reference = prepared if prepared is not None else _ReferenceColour(ref_rgb, ppd)
    test = srgb_encode(test_rgb)
    _check_pair(reference.encoded, test)
    ssim_value = (None if reference.ssim is None
                  else float(_ssim_map_against(reference.ssim, test).mean(axis=(0, 1)).mean()))
    error_map = _flip.flip_error_map_against(reference.flip, test)
    return ({"psnr": _psnr_encoded(reference.encoded, test), "ssim": ssim_value,
             "flip": float(error_map.mean())}, error_map)


def compare_images_with_map(ref: Dict[str, np.ndarray], test: Dict[str, np.ndarray],
                            ppd: float = _flip.DEFAULT_PPD,
                            prepared: Optional[PreparedColour] = None) -> Tuple[Dict[str, object], np.ndarray]:
    """(metrics, FLIP error map) between a ground-truth and a test image (read_image dicts of one size).

    Colour metrics (psnr, ssim, flip) use every pixel's colour as rendered (visible_colour). ssim is None for images under 11 pixels on a side. Returns psnr, ssim, flip,
    depth_absrel, depth_rmse, depth_pixels, psnr_answered, wrong_surface_rate, hole_rate, false_hit_rate, false_miss_rate,
    unknown_rate, counts, width, height, ppd and the definitions of all of them. `prepared`: the
    reference's PreparedColour at this ppd, for a reference compared with many images.
    """
    if prepared is not None and not prepared.serves(ref, ppd):
        raise ValueError("compare: the prepared colour was made from another reference or ppd")
    if ref["rgba"].shape != test["rgba"].shape:
        h0, w0 = ref["rgba"].shape[:2]
        h1, w1 = test["rgba"].shape[:2]
        raise ValueError(f"images differ in size: reference {w0}×{h0}, test {w1}×{h1}")
    height, width = ref["rgba"].shape[:2]
    ref_rgb = visible_colour(ref) if prepared is None else prepared.rgb
    test_rgb = visible_colour(test)
    result, error_map = _colour_figures(ref_rgb, test_rgb, ppd, prepared)
    ref_hit, test_hit = ref["status"] == STATUS_HIT, test["status"] == STATUS_HIT
    depth = depth_errors(ref["depth"], test["depth"], ref_hit, test_hit)
    result.update({
        "depth_absrel": depth["absrel"],
        "depth_rmse": depth["rmse"],
        "depth_pixels": depth["pixels"],
        "psnr_answered": psnr_over(ref_rgb, test_rgb, test["status"] != STATUS_UNKNOWN),
        "wrong_surface_rate": wrong_surface_rate(ref["depth"], test["depth"], ref_hit, test_hit),
    })
    result.update(confusion(ref["status"], test["status"]))
    result.update({"width": int(width), "height": int(height), "ppd": float(ppd),
                   "definitions": dict(DEFINITIONS)})
    return result, error_map


# Metrics that need lfprobe's status and depth planes in both images, and why each may be missing.
GEOMETRY_METRICS = ("depth_absrel", "depth_rmse", "wrong_surface_rate", "hole_rate", "false_hit_rate",
                    "false_miss_rate", "unknown_rate")
COLOUR_METRICS = ("psnr", "ssim", "flip")


def availability(ref: Dict[str, np.ndarray], test: Dict[str, np.ndarray],
                 ssim_value: Optional[float]) -> Tuple[list, Dict[str, str]]:
    """(metrics computed, {metric not computed: why}) for a pair of images: colour metrics
    always (SSIM unless an image is under 11 pixels on a side), psnr_answered where the test has
    a status plane, depth and the HIT/MISS/UNKNOWN figures where both have status and depth
    (lfprobe's own renders: a status says which pixels hit, which other files do not say)."""
    missing: Dict[str, str] = {}
    if ssim_value is None:
        missing["ssim"] = f"images under {SSIM_WINDOW}×{SSIM_WINDOW} pixels"
    lacking = [name for name, image in (("reference", ref), ("test", test))
               if "status" not in image or "depth" not in image]
    if lacking:
        why = (f"the {' and the '.join(lacking)} image{'s have' if len(lacking) > 1 else ' has'} no "
               "status and depth planes (only lfprobe's rendered EXRs have them)")
        for name in GEOMETRY_METRICS:
            missing[name] = why
    if "status" not in test:
        missing["psnr_answered"] = "the test image has no status plane (only lfprobe's rendered EXRs have one)"
    order = COLOUR_METRICS + ("psnr_answered",) + GEOMETRY_METRICS
    return [name for name in order if name not in missing], missing


def compare_colour_with_map(ref: Dict[str, np.ndarray], test: Dict[str, np.ndarray],
                            ppd: float = _flip.DEFAULT_PPD) -> Tuple[Dict[str, object], np.ndarray]:
    """(metrics, FLIP error map) of a pair that is not two lfprobe renders: the keys of
    compare_images_with_map, with psnr, ssim and flip on each image's colour as rendered,
    psnr_answered where the test
    has a status, and the depth and confusion figures None (see `availability`)."""
    if ref["rgba"].shape[:2] != test["rgba"].shape[:2]:
        h0, w0 = ref["rgba"].shape[:2]
        h1, w1 = test["rgba"].shape[:2]
        raise ValueError(f"images differ in size: reference {w0}×{h0}, test {w1}×{h1}")
    height, width = ref["rgba"].shape[:2]

    ref_rgb, test_rgb = visible_colour(ref), visible_colour(test)
    result, error_map = _colour_figures(ref_rgb, test_rgb, ppd)
    result.update({
        "depth_absrel": None,
        "depth_rmse": None,
        "depth_pixels": None,
        "psnr_answered": (psnr_over(ref_rgb, test_rgb, test["status"] != STATUS_UNKNOWN)
                          if "status" in test else None),
        "wrong_surface_rate": None,
        "hole_rate": None,
        "false_miss_rate": None,
        "false_hit_rate": None,
        "unknown_rate": None,
        "counts": None,
        "width": int(width), "height": int(height), "ppd": float(ppd),
        "definitions": dict(DEFINITIONS),
    })
    return result, error_map
