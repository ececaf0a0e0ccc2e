"""What the viewport overlay draws of a probe grid, as plain arrays (the add-on's ui/overlay.py
hands them to the GPU): probe colours by coverage, by the plan and for probes added for views,
and the lines through each row of probes."""

from __future__ import annotations

from typing import Sequence

import numpy as np

UNBAKED_COLOUR = (0.75, 0.75, 0.75, 1.0)
# Planned probes (Plan From Data) by what the plan found: moved ones and dropped ones stand
# out from the coverage colours of the probes kept where they were.
MOVED_COLOUR = (0.2, 0.6, 1.0, 1.0)
DROPPED_COLOUR = (0.15, 0.15, 0.15, 1.0)
# Probes that Add Probes for Views put at the eyes of views: not on the grid, and in none of
# the coverage colours (whose blue stays low) nor the plan's.
ADDED_COLOUR = (1.0, 0.2, 1.0, 1.0)


def coverage_colours(coverage: list, probe_count: int) -> np.ndarray:
    """RGBA per probe: from red (nothing known) to green (every direction surface, inferred or
    empty); grey when there is no coverage for each probe."""
    colours = np.tile(np.asarray(UNBAKED_COLOUR, dtype=np.float32), (probe_count, 1))
    if len(coverage) != probe_count:
        return colours
    unknown = np.array([float(c.get("unknown", 1.0)) for c in coverage], dtype=np.float32)
    known = np.clip(1.0 - unknown, 0.0, 1.0)
    colours[:, 0] = 1.0 - known
    colours[:, 1] = known
    colours[:, 2] = 0.1
    return colours


def plan_colours(colours: np.ndarray, plan: list) -> np.ndarray:
    """Coverage colours with moved probes in blue and dropped probes in near-black."""
    if len(plan) != len(colours):
        return colours
    out = colours.copy()
    for i, probe in enumerate(plan):
        if probe.get("dropped"):
            out[i] = DROPPED_COLOUR
        elif probe.get("moved"):
            out[i] = MOVED_COLOUR
    return out


def added_positions(placement: dict) -> np.ndarray:
    """Positions (n, 3) of the probes added for views, from a grid's placement record."""
    added = placement.get("added", [])
    return np.array([a["position"] for a in added], dtype=np.float64).reshape(-1, 3)


def cell_lines(positions: np.ndarray, counts: Sequence[int]) -> np.ndarray:
    """Line segment end points (2k, 3) of a grid's cells: every row of probes along each axis
    (positions in the grid's order, x fastest)."""
    nx, ny, nz = (int(c) for c in counts)
    lattice = positions.reshape(nz, ny, nx, 3)
    segments = []
    if nx > 1:
        segments.append(np.stack([lattice[:, :, 0], lattice[:, :, -1]], axis=-2).reshape(-1, 3))
    if ny > 1:
        segments.append(np.stack([lattice[:, 0, :], lattice[:, -1, :]], axis=-2).reshape(-1, 3))
    if nz > 1:
        segments.append(np.stack([lattice[0], lattice[-1]], axis=-2).reshape(-1, 3))
    return np.concatenate(segments) if segments else np.zeros((0, 3))


def overlay_geometry(positions: np.ndarray, counts: Sequence[int], coverage: list, plan: list,
                     placement: dict):
    """(probe positions (n, 3), probe colours (n, 4), line end points (2k, 3)) as float32: the
    grid's probes first, then the probes added for views."""
    colours = plan_colours(coverage_colours(coverage, len(positions)), plan)
    added = added_positions(placement)
    lines = cell_lines(positions, counts)
    positions = np.concatenate([positions, added])
    colours = np.concatenate([colours, np.tile(np.asarray(ADDED_COLOUR, dtype=np.float32), (len(added), 1))])
    return positions.astype(np.float32), colours.astype(np.float32), lines.astype(np.float32)
