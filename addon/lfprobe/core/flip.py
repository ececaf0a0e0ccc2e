"""LDR-FLIP, the perceptual image difference of Andersson et al. 2020 ("FLIP: A Difference
Evaluator for Alternating Images", HPG 2020), written in numpy (its filters through scipy's 1D
correlation where scipy is installed: image_filters.py; no bpy).

Inputs are sRGB-encoded images in [0, 1] (h, w, 3). The error map is in [0, 1]; its mean is the
FLIP figure. The steps and constants follow the paper and NVIDIA's reference code (the
`flip_evaluator` package, which this module matches to about 1e-5 in the mean):

Colour pipeline
  1. sRGB → linear RGB → XYZ (D65) → YCxCz (opponent space, normalised by the D65 white).
  2. Each channel is filtered with its contrast sensitivity function, a Gaussian (or, for the
     blue-yellow channel Cz, a sum of two Gaussians) in the form a·sqrt(π/b)·exp(−π²x²/b), x in
     degrees (one pixel = 1/ppd degrees): achromatic a1=1, b1=0.0047; red-green a1=1, b1=0.0053;
     blue-yellow a1=34.1, b1=0.04, a2=13.5, b2=0.025. Filter radius ceil(3·sqrt(0.04/(2π²))·ppd)
     pixels, weights normalised to sum to 1, applied separably with edge-clamped borders (the sum of
     Gaussians is separated as two products of 1D "square-root" Gaussians).
  3. Back to linear RGB, clamped to [0, 1] (the sRGB gamut), then CIELAB (D65) with the Hunt
     adjustment a, b ← 0.01·L·a, 0.01·L·b.
  4. HyAB distance |ΔL| + ||(Δa, Δb)||, raised to qc = 0.7, redistributed to [0, 1]: with cmax =
     HyAB(Hunt-Lab green, Hunt-Lab blue)^0.7, pc = 0.4, pt = 0.95, errors below pc·cmax map
     linearly to [0, pt] and the rest linearly to (pt, 1].
Feature pipeline
  5. Luminance Y of YCxCz normalised to [0, 1] as (Y + 16)/116.
  6. Edges and points: first and second derivatives of a Gaussian with σ = 0.5·w·ppd pixels,
     w = 0.082 degrees, radius ceil(3σ); positive and negative weights of each derivative filter are
     normalised to sum to +1 and −1, the Gaussian to 1; applied separably (derivative along one
     axis, Gaussian along the other), edge-clamped. Edge strength = ||(dx, dy)||, point strength =
     ||(dxx, dyy)||.
  7. ΔE_f = (max(|edge_ref − edge_test|, |point_ref − point_test|) / sqrt(2))^qf, qf = 0.5.
Combination
  8. FLIP = ΔE_c^(1 − ΔE_f) per pixel.
"""

from __future__ import annotations

import math
from typing import Tuple

import numpy as np

from .image_filters import correlate_edge

DEFAULT_PPD = 67.0  # pixels per degree: 0.7 m from a 0.7 m wide 3840-pixel screen is 67.02

QC = 0.7  # colour difference exponent
PC = 0.4  # error redistribution: fraction of cmax that maps to PT
PT = 0.95
W_DEGREES = 0.082  # peak-to-trough width (2σ) of the human edge detector, in degrees
QF = 0.5  # feature difference exponent

# Contrast sensitivity functions as sums of two Gaussians (a1, b1, a2, b2), per YCxCz channel.
CSF_ACHROMATIC = (1.0, 0.0047, 0.0, 1e-5)
CSF_RED_GREEN = (1.0, 0.0053, 0.0, 1e-5)
CSF_BLUE_YELLOW = (34.1, 0.04, 13.5, 0.025)

D65_WHITE = np.array([0.950428545, 1.0, 1.088900371])

LINEAR_RGB_TO_XYZ = np.array(
    [
        [10135552.0 / 24577794.0, 8788810.0 / 24577794.0, 4435075.0 / 24577794.0],
        [2613072.0 / 12288897.0, 8788810.0 / 12288897.0, 887015.0 / 12288897.0],
        [1425312.0 / 73733382.0, 8788810.0 / 73733382.0, 70074185.0 / 73733382.0],
    ]
)
XYZ_TO_LINEAR_RGB = np.array(
    [
        [3.241003275, -1.537398934, -0.498615861],
        [-0.969224334, 1.875930071, 0.041554224],
        [0.055639423, -0.204011202, 1.057148933],
    ]
)


def srgb_to_linear(srgb: np.ndarray) -> np.ndarray:
    """The sRGB decoding curve (IEC 61966-2-1)."""
    s = np.asarray(srgb, dtype=np.float64)
    return np.where(s <= 0.04045, s / 12.92, np.power((np.maximum(s, 0.04045) + 0.055) / 1.055, 2.4))


def _apply_matrix(image: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    return image @ matrix.T


def linear_rgb_to_ycxcz(rgb: np.ndarray) -> np.ndarray:
    """Linear RGB → XYZ (D65) → YCxCz: Y = 116·Y/Yn − 16, Cx = 500·(X/Xn − Y/Yn), Cz = 200·(Y/Yn − Z/Zn)."""
    xyz = _apply_matrix(rgb, LINEAR_RGB_TO_XYZ) / D65_WHITE
    x, y, z = xyz[..., 0], xyz[..., 1], xyz[..., 2]
    return np.stack([116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)], axis=-1)


def ycxcz_to_linear_rgb(ycxcz: np.ndarray) -> np.ndarray:
    """The inverse of linear_rgb_to_ycxcz (unclamped)."""
    y = (ycxcz[..., 0] + 16.0) / 116.0
    x = y + ycxcz[..., 1] / 500.0
    z = y - ycxcz[..., 2] / 200.0
    xyz = np.stack([x, y, z], axis=-1) * D65_WHITE
    return _apply_matrix(xyz, XYZ_TO_LINEAR_RGB)


def linear_rgb_to_hunt_lab(rgb: np.ndarray) -> np.ndarray:
    """Linear RGB → CIELAB (D65) with the Hunt adjustment a, b ← 0.01·L·a, 0.01·L·b."""
    xyz = _apply_matrix(rgb, LINEAR_RGB_TO_XYZ) / D65_WHITE
    delta = 6.0 / 29.0
    f = np.where(xyz > delta**3, np.cbrt(xyz), xyz / (3.0 * delta * delta) + 4.0 / 29.0)
    lightness = 116.0 * f[..., 1] - 16.0
    a = 500.0 * (f[..., 0] - f[..., 1])
    b = 200.0 * (f[..., 1] - f[..., 2])
    return np.stack([lightness, 0.01 * lightness * a, 0.01 * lightness * b], axis=-1)


def hyab(lab1: np.ndarray, lab2: np.ndarray) -> np.ndarray:
    """HyAB distance: |ΔL| + sqrt(Δa² + Δb²)."""
    d = lab1 - lab2
    return np.abs(d[..., 0]) + np.hypot(d[..., 1], d[..., 2])


def max_color_distance() -> float:
    """cmax: the HyAB distance between Hunt-adjusted green and blue, raised to qc."""
    green = linear_rgb_to_hunt_lab(np.array([0.0, 1.0, 0.0]))
    blue = linear_rgb_to_hunt_lab(np.array([0.0, 0.0, 1.0]))
    return float(hyab(green, blue) ** QC)


def _correlate_axis(image: np.ndarray, weights: np.ndarray, axis: int) -> np.ndarray:
    """Σ_k weights[k]·image[i + k − r] along axis (0 rows, 1 columns), borders clamped to the edge."""
    return correlate_edge(image, weights, axis)


def spatial_filter_radius(ppd: float) -> int:
    """Radius in pixels of the CSF filters: ceil(3·sqrt(b_max/(2π²))·ppd), b_max = 0.04."""
    b_max = max(CSF_ACHROMATIC[1], CSF_ACHROMATIC[3], CSF_RED_GREEN[1], CSF_RED_GREEN[3],
                CSF_BLUE_YELLOW[1], CSF_BLUE_YELLOW[3])
    return int(math.ceil(3.0 * math.sqrt(b_max / (2.0 * math.pi**2)) * ppd))


def _csf_gaussian(x2: np.ndarray, a: float, b: float) -> np.ndarray:
    return a * np.sqrt(np.pi / b) * np.exp(-np.pi**2 * x2 / b)


def _csf_gaussian_sqrt(x2: np.ndarray, a: float, b: float) -> np.ndarray:
    """A 1D factor whose outer product with itself is the 2D Gaussian a·sqrt(π/b)·exp(−π²r²/b)·..."""
    return np.sqrt(a * np.sqrt(np.pi / b)) * np.exp(-np.pi**2 * x2 / b)


def spatial_filters(ppd: float):
    """1D CSF filters: (achromatic, red-green, (blue-yellow part 1, part 2)).

    The achromatic and red-green filters are single Gaussians, separable as they are and
    normalised to sum to 1. The blue-yellow filter is a sum of two Gaussians, applied as
    g1⊗g1 + g2⊗g2 with g1, g2 scaled together so that the 2D filter sums to 1.
    """
    radius = spatial_filter_radius(ppd)
    x2 = (np.arange(-radius, radius + 1) / ppd) ** 2
    achromatic = _csf_gaussian(x2, CSF_ACHROMATIC[0], CSF_ACHROMATIC[1])
    red_green = _csf_gaussian(x2, CSF_RED_GREEN[0], CSF_RED_GREEN[1])
    by1 = _csf_gaussian_sqrt(x2, CSF_BLUE_YELLOW[0], CSF_BLUE_YELLOW[1])
    by2 = _csf_gaussian_sqrt(x2, CSF_BLUE_YELLOW[2], CSF_BLUE_YELLOW[3])
    by_norm = 1.0 / math.sqrt(by1.sum() ** 2 + by2.sum() ** 2)
    return achromatic / achromatic.sum(), red_green / red_green.sum(), (by1 * by_norm, by2 * by_norm)


def feature_filters(ppd: float):
    """1D (Gaussian, first derivative, second derivative) filters for edge and point detection.

    σ = 0.5·0.082·ppd pixels, radius ceil(3σ). The Gaussian sums to 1; each derivative's positive
    weights sum to 1 and its negative weights to −1.
    """
    sigma = 0.5 * W_DEGREES * ppd
    radius = int(math.ceil(3.0 * sigma))
    x = np.arange(-radius, radius + 1, dtype=np.float64)
    g = np.exp(-(x * x) / (2.0 * sigma * sigma))
    dg = -x * g
    ddg = (x * x / (sigma * sigma) - 1.0) * g

    def balance(f):
        pos, neg = f[f > 0].sum(), -f[f < 0].sum()
        return np.where(f > 0, f / pos, f / neg)

    return g / g.sum(), balance(dg), balance(ddg)


def _filtered_hunt_lab(ycxcz: np.ndarray, filters) -> np.ndarray:
    achromatic, red_green, (by1, by2) = filters
    y = _correlate_axis(_correlate_axis(ycxcz[..., 0], achromatic, 1), achromatic, 0)
    cx = _correlate_axis(_correlate_axis(ycxcz[..., 1], red_green, 1), red_green, 0)
    cz = (_correlate_axis(_correlate_axis(ycxcz[..., 2], by1, 1), by1, 0)
          + _correlate_axis(_correlate_axis(ycxcz[..., 2], by2, 1), by2, 0))
    rgb = np.clip(ycxcz_to_linear_rgb(np.stack([y, cx, cz], axis=-1)), 0.0, 1.0)
    return linear_rgb_to_hunt_lab(rgb)


def color_difference(ref_ycxcz: np.ndarray, test_ycxcz: np.ndarray, ppd: float) -> np.ndarray:
    """ΔE_c in [0, 1]: the redistributed HyAB^qc distance of the CSF-filtered images."""
    filters = spatial_filters(ppd)
    return _color_difference_of(_filtered_hunt_lab(ref_ycxcz, filters), _filtered_hunt_lab(test_ycxcz, filters))


def _color_difference_of(ref_hunt_lab: np.ndarray, test_hunt_lab: np.ndarray) -> np.ndarray:
    distance = hyab(ref_hunt_lab, test_hunt_lab) ** QC
    cmax = max_color_distance()
    pccmax = PC * cmax
    return np.where(distance < pccmax, distance * (PT / pccmax),
                    PT + (distance - pccmax) / (cmax - pccmax) * (1.0 - PT))


def _features(luminance: np.ndarray, filters) -> Tuple[np.ndarray, np.ndarray]:
    g, dg, ddg = filters
    smooth_x = _correlate_axis(luminance, g, 1)
    dx = _correlate_axis(_correlate_axis(luminance, dg, 1), g, 0)
    dy = _correlate_axis(smooth_x, dg, 0)
    ddx = _correlate_axis(_correlate_axis(luminance, ddg, 1), g, 0)
    ddy = _correlate_axis(smooth_x, ddg, 0)
    return np.hypot(dx, dy), np.hypot(ddx, ddy)


def feature_difference(ref_ycxcz: np.ndarray, test_ycxcz: np.ndarray, ppd: float) -> np.ndarray:
    """ΔE_f in [0, 1]: (max(|Δedge|, |Δpoint|)/sqrt(2))^qf on luminance (Y + 16)/116."""
    filters = feature_filters(ppd)
    return _feature_difference_of(_features((ref_ycxcz[..., 0] + 16.0) / 116.0, filters),
                                  _features((test_ycxcz[..., 0] + 16.0) / 116.0, filters))


def _feature_difference_of(ref_features: Tuple[np.ndarray, np.ndarray],
                           test_features: Tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    (edges_ref, points_ref), (edges_test, points_test) = ref_features, test_features
    diff = np.maximum(np.abs(edges_ref - edges_test), np.abs(points_ref - points_test))
    return (diff / math.sqrt(2.0)) ** QF


class PreparedReference:
    """The reference's half of FLIP at one ppd (its YCxCz, CSF-filtered Hunt Lab, edges and
    points), computed once for every test image compared with it: a report compares each ground
    truth with many renders, and this half was about half of each comparison's FLIP."""

    def __init__(self, ref_srgb: np.ndarray, ppd: float = DEFAULT_PPD):
        ref = np.asarray(ref_srgb, dtype=np.float64)
        _check_flip_input(ref, ref, ppd)
        self.ppd = float(ppd)
        self.shape = ref.shape
        ycxcz = _ycxcz_of(ref)
        self.hunt_lab = _filtered_hunt_lab(ycxcz, spatial_filters(ppd))
        self.features = _features((ycxcz[..., 0] + 16.0) / 116.0, feature_filters(ppd))


def flip_error_map(ref_srgb: np.ndarray, test_srgb: np.ndarray, ppd: float = DEFAULT_PPD) -> np.ndarray:
    """Per-pixel LDR-FLIP error (h, w) in [0, 1] between sRGB images (h, w, 3) in [0, 1]."""
    ref = np.asarray(ref_srgb, dtype=np.float64)
    test = np.asarray(test_srgb, dtype=np.float64)
    _check_flip_input(ref, test, ppd)
    return flip_error_map_against(PreparedReference(ref, ppd), test)


def flip_error_map_against(reference: PreparedReference, test_srgb: np.ndarray) -> np.ndarray:
    """flip_error_map(the reference's image, test_srgb, its ppd), bit for bit, with the
    reference's half computed once (PreparedReference)."""
    test = np.asarray(test_srgb, dtype=np.float64)
    if test.shape != reference.shape:
        raise ValueError(f"FLIP needs two (h, w, 3) images of one size, got {reference.shape} and {test.shape}")
    test_ycxcz = _ycxcz_of(test)
    delta_c = _color_difference_of(reference.hunt_lab,
                                   _filtered_hunt_lab(test_ycxcz, spatial_filters(reference.ppd)))
    delta_f = _feature_difference_of(reference.features,
                                     _features((test_ycxcz[..., 0] + 16.0) / 116.0,
                                               feature_filters(reference.ppd)))
    return np.power(delta_c, 1.0 - delta_f)


def _check_flip_input(ref: np.ndarray, test: np.ndarray, ppd: float) -> None:
    if ref.shape != test.shape or ref.ndim != 3 or ref.shape[2] != 3:
        raise ValueError(f"FLIP needs two (h, w, 3) images of one size, got {ref.shape} and {test.shape}")
    if ppd <= 0:
        raise ValueError(f"pixels per degree must be positive, got {ppd}")


def _ycxcz_of(srgb: np.ndarray) -> np.ndarray:
    return linear_rgb_to_ycxcz(srgb_to_linear(np.clip(srgb, 0.0, 1.0)))


def flip(ref_srgb: np.ndarray, test_srgb: np.ndarray, ppd: float = DEFAULT_PPD) -> Tuple[float, np.ndarray]:
    """(mean LDR-FLIP error, per-pixel error map) between sRGB images in [0, 1]."""
    error_map = flip_error_map(ref_srgb, test_srgb, ppd)
    return float(error_map.mean()), error_map
