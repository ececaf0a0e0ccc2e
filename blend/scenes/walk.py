"""Camera positions of a scene's walk: `frames` positions spaced evenly by arc length along the
polyline `points`, the first at its start and the last at its end."""

from __future__ import annotations

import numpy as np


def walk_positions(points, frames: int) -> list:
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3 or len(p) < 2:
        raise ValueError("walk: expected at least two [x, y, z] points")
    if frames < 2:
        raise ValueError("walk: expected at least two frames")
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    if s[-1] == 0.0:
        raise ValueError("walk: the points must not all coincide")
    u = np.linspace(0.0, s[-1], frames)
    return np.column_stack([np.interp(u, s, p[:, k]) for k in range(3)]).tolist()
