"""Separable correlations of images with short 1D filters: the kernel the image metrics spend
their time in (SSIM's Gaussian window, FLIP's contrast-sensitivity and feature filters).

scipy.ndimage's correlate1d filters a line in one C pass; without scipy (Blender's own bundled
Python has none) the same sums run in numpy, one shifted slice per weight: 3-4 times slower on
the report's 640×400 views. Both give the same values to rounding (tests/python/test_metrics.py).
"""

from __future__ import annotations

import numpy as np

try:
    from scipy import ndimage as _ndimage
except ImportError:  # pragma: no cover - depends on the Python running
    _ndimage = None


def have_scipy() -> bool:
    return _ndimage is not None


def correlate_edge(image: np.ndarray, weights: np.ndarray, axis: int, use_scipy: bool = True) -> np.ndarray:
    """Σ_k weights[k]·image[i + k − r] along `axis` (0 rows, 1 columns), r = len(weights) // 2
    (odd lengths), borders clamped to the edge pixel; float64, the image's shape."""
    image = np.asarray(image, dtype=np.float64)
    weights = np.asarray(weights, dtype=np.float64)
    if use_scipy and _ndimage is not None:
        return _ndimage.correlate1d(image, weights, axis=axis, mode="nearest")
    radius = len(weights) // 2
    pad = [(0, 0)] * image.ndim
    pad[axis] = (radius, radius)
    padded = np.pad(image, pad, mode="edge")
    n = image.shape[axis]
    out = np.zeros(image.shape, dtype=np.float64)
    for k, weight in enumerate(weights):
        if weight != 0.0:
            out += weight * (padded[k: k + n] if axis == 0 else padded[:, k: k + n])
    return out


def correlate_valid(image: np.ndarray, weights: np.ndarray, use_scipy: bool = True) -> np.ndarray:
    """Correlation of (h, w, ...) with `weights` (odd length n) on both axes, the valid region
    only: out[i, j] = Σ_k Σ_l weights[k]·weights[l]·image[i + k, j + l], (h − n + 1, w − n + 1, ...)."""
    image = np.asarray(image, dtype=np.float64)
    weights = np.asarray(weights, dtype=np.float64)
    n = len(weights)
    h, w = image.shape[0] - n + 1, image.shape[1] - n + 1
    if use_scipy and _ndimage is not None:
        r = n // 2
        # Rows first, cropped before the second pass: the border the crop drops is never read.
        rows = _ndimage.correlate1d(image, weights, axis=0, mode="nearest")[r: r + h]
        return _ndimage.correlate1d(rows, weights, axis=1, mode="nearest")[:, r: r + w]
    rows = sum(weights[k] * image[k: k + h] for k in range(n))
    return sum(weights[k] * rows[:, k: k + w] for k in range(n))
