"""Report images: sRGB previews of rendered views, FLIP error heat maps and the
ground truth | test | error triplets, as 8-bit PNG files."""

from __future__ import annotations

import io
from typing import Dict, Sequence

import numpy as np

from .. import metrics
from ..colour import magma8, srgb8

GAP = 4  # pixels of white between the panels of a triplet


def preview(image: Dict[str, np.ndarray]) -> np.ndarray:
    """(h, w, 3) uint8 sRGB of a rendered view, its colour as the metrics compare it; pixels
    whose centre ray is UNKNOWN are marked magenta so holes show (filled or not)."""
    out = srgb8(metrics.visible_colour(image))
    out[np.asarray(image["status"]) == metrics.STATUS_UNKNOWN] = (255, 0, 255)
    return out


def heat_map(error: np.ndarray, vmax: float = 1.0) -> np.ndarray:
    """Per-pixel error in [0, vmax] → (h, w, 3) uint8 through matplotlib's magma colour map."""
    return magma8(np.asarray(error, dtype=np.float64) / vmax)


def side_by_side(panels: Sequence[np.ndarray]) -> np.ndarray:
    """Panels of equal height next to each other with white gaps."""
    h = max(p.shape[0] for p in panels)
    parts = []
    for i, p in enumerate(panels):
        if i:
            parts.append(np.full((h, GAP, 3), 255, np.uint8))
        if p.shape[0] < h:
            p = np.concatenate([p, np.full((h - p.shape[0], p.shape[1], 3), 255, np.uint8)])
        parts.append(p)
    return np.concatenate(parts, axis=1)


def png_bytes(rgb8: np.ndarray) -> bytes:
    """An (h, w, 3) uint8 image as PNG bytes (matplotlib's encoder, no resampling)."""
    import matplotlib.image

    stream = io.BytesIO()
    matplotlib.image.imsave(stream, np.ascontiguousarray(rgb8, dtype=np.uint8), format="png")
    return stream.getvalue()


def triplet(reference: Dict[str, np.ndarray], test: Dict[str, np.ndarray], error_map: np.ndarray) -> np.ndarray:
    """ground truth | test | FLIP error (magma, 0 black … 1 white-yellow)."""
    return side_by_side([preview(reference), preview(test), heat_map(error_map)])
