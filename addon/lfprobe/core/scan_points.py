"""The arithmetic of showing a loaded scan cloud in Blender, without Blender: which points the
viewport shows, how large they are drawn, whether a cloud can share the scene's frame, and
which points go into which object (the add-on's scan import and scan objects call these)."""

from __future__ import annotations

from typing import List, Optional, Sequence, Tuple

import numpy as np

DISPLAY_SEED = 20240601  # fixed: the same file always shows the same subsample
# Clouds further than this from the scene's frame keep their own world offset: float32
# positions (Blender's) hold about 1 mm at 10 km.
SHARED_FRAME_LIMIT = 10_000.0


def display_indices(point_count: int, limit: int) -> np.ndarray | None:
    """The points shown in the viewport: all of them up to `limit`, else a deterministic
    random subset (a stride would alias with the scanner's row/column pattern), in file order."""
    if limit <= 0 or point_count <= limit:
        return None
    rng = np.random.default_rng(DISPLAY_SEED)
    # shuffle=False: the same points (the shuffle only reorders them, after they are drawn), and
    # a mask puts them in file order in one pass where a sort of 2 M indices took 0.12 s.
    chosen = rng.choice(point_count, size=limit, replace=False, shuffle=False)
    mask = np.zeros(point_count, dtype=bool)
    mask[chosen] = True
    return np.flatnonzero(mask)


def automatic_point_radius(bounds_min, bounds_max, displayed: int) -> float:
    """Half the mean point spacing, taking the points to lie on the box's faces (a room)."""
    size = np.maximum(np.asarray(bounds_max, float) - np.asarray(bounds_min, float), 1e-6)
    area = 2.0 * (size[0] * size[1] + size[1] * size[2] + size[2] * size[0])
    return float(0.5 * np.sqrt(area / max(displayed, 1)))


def in_shared_frame(positions: np.ndarray, world_offset: Sequence[float],
                    frame: Optional[Sequence[float]]) -> Tuple[np.ndarray, np.ndarray, bool]:
    """(positions, world offset, too_far) of a cloud moved into the scene's frame (world =
    frame + position) when it is close enough, so that scans line up in Blender; a cloud too
    far away, or a scene without a frame, keeps its own offset (too_far says which)."""
    offset = np.array(world_offset, dtype=float)
    if frame is None or not np.any(np.asarray(frame) != offset):
        return positions, offset, False
    shift = offset - np.asarray(frame)
    if np.abs(shift).max() + np.abs(positions).max() < SHARED_FRAME_LIMIT:
        return (positions.astype(np.float64) + shift).astype(np.float32), np.asarray(frame, dtype=float), False
    return positions, offset, True


def object_groups(paths: Sequence[str], scans: Sequence[dict], point_count: int,
                  scan_index: Optional[np.ndarray]) -> List[tuple]:
    """(paths, point indices, scanner positions) of each object to make: one for the merged
    cloud (scan_index None), else one per scan file."""
    if scan_index is None:
        return [(list(paths), np.arange(point_count), [s["scanner"] for s in scans])]
    return [([p], np.flatnonzero(scan_index == i), [scans[i]["scanner"]]) for i, p in enumerate(paths)]


def file_scanners(scans: Sequence[dict], file_of_scan: Sequence[int], files: int) -> list:
    """One scanner per file (the cloud's frame) from the cloud's scans: a file's only scan's
    scanner, None for a file of several stations (an E57), whose poses stay in the file."""
    out: list = [None] * files
    counts = [0] * files
    for scan, f in zip(scans, file_of_scan):
        counts[f] += 1
        out[f] = scan["scanner"] if counts[f] == 1 else None
    return out


def file_of_each_point(file_of_scan: Sequence[int], scan_index: np.ndarray) -> np.ndarray:
    """The file index of every point, from its scan index (object_groups' grouping by file)."""
    return np.asarray(file_of_scan, dtype=np.uint32)[np.asarray(scan_index)]


def column_bounds(values: np.ndarray, rows_at_once: int = 4096) -> Tuple[np.ndarray, np.ndarray]:
    """(min, max) of each column of an (n, 3) array, n > 0. numpy reduces a narrow array down its
    long axis slowly (0.39 s for both of 10 M points): viewed as rows of `rows_at_once` points,
    the reduction runs along wide rows, then over the few that are left (16 ms)."""
    whole = len(values) - len(values) % rows_at_once
    low = high = None
    if whole > 0:
        wide = values[:whole].reshape(-1, values.shape[1] * rows_at_once)
        low = wide.min(axis=0).reshape(rows_at_once, -1).min(axis=0)
        high = wide.max(axis=0).reshape(rows_at_once, -1).max(axis=0)
    if whole < len(values):
        rest = values[whole:]
        low = rest.min(axis=0) if low is None else np.minimum(low, rest.min(axis=0))
        high = rest.max(axis=0) if high is None else np.maximum(high, rest.max(axis=0))
    if low is None:
        raise ValueError("column_bounds: no values")
    return low, high


def object_points(positions: np.ndarray, colors: Optional[np.ndarray], members: np.ndarray,
                  display_limit: int) -> tuple:
    """(bounds (min, max), displayed positions, displayed colours or None) of one object's
    points: the bounds of all its members, the display subset of them (display_indices)."""
    # Members are sorted and distinct (object_groups): as many as the points are all of them,
    # whose bounds need no copy of 10 M positions first.
    own = positions if len(members) == len(positions) else positions[members]
    low, high = column_bounds(own)
    bounds = (tuple(map(float, low)), tuple(map(float, high)))
    subset = display_indices(len(members), display_limit)
    if subset is not None:
        members = members[subset]
    return bounds, positions[members], None if colors is None else colors[members]
