"""Fitting a probe grid's box to a scan cloud (the add-on's Fit Grid to Scan): the box inside
the cloud's bounds by a margin, and probe counts for a largest spacing."""

from __future__ import annotations

import math
from typing import Sequence, Tuple

import numpy as np


# Fit Grid's defaults, shared by the operator and the batch import so that both choose the same
# grid for the same scans: probes a quarter metre inside the cloud's bounds, at most a metre apart.
FIT_MARGIN = 0.25
FIT_SPACING = 1.0


def fitted_box(points, margin: float) -> Tuple[np.ndarray, np.ndarray]:
    """(low, high) of the box `margin` inside the bounds of the points (k, 3), e.g. a cloud's
    transformed bounding-box corners; an axis where the margin exceeds half the bounds
    collapses onto their centre."""
    corners = np.array(points, dtype=float)
    low, high = corners.min(axis=0) + margin, corners.max(axis=0) - margin
    centre = (corners.min(axis=0) + corners.max(axis=0)) / 2
    return np.where(low < high, low, centre), np.where(low < high, high, centre)


def box_location_and_scale(low: np.ndarray, high: np.ndarray) -> Tuple[tuple, tuple]:
    """A grid Empty's location and scale for the box (its cube [-1, 1]^3 is the box; a flat
    axis keeps a tiny scale so that the Empty stays invertible)."""
    return tuple((low + high) / 2), tuple(np.maximum((high - low) / 2, 1e-4))


def counts_for_spacing(size: Sequence[float], spacing: float) -> tuple:
    """Probes per axis so that neighbours are at most `spacing` apart (at least one per axis)."""
    return tuple(max(1, int(math.ceil(float(s) / spacing - 1e-9)) + 1) if s > 0 else 1 for s in size)
