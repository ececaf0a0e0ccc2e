"""Reading any mix of scan files into one native PointCloud: the native readers' formats
(.xyz/.pts/.ply, through the parse cache) and the library formats (E57, LAS/LAZ,
core/scan_formats.py), one scan index per file or E57 station, one world offset chosen as the
native merge chooses it (docs/DESIGN.md §3), and merged exports that hold several stations in
one file (each point given its station: a column of the file, else the nearest station).

Clouds made only of native formats with one scanner per file (or none) come straight from the
native load_scans, exactly as before."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import List, Optional, Sequence

import numpy as np

from . import native
from .errors import InputError
from .scan_formats import ScanArrays, is_library_format, read_scan_arrays
from .scan_points import column_bounds

NEAR_ORIGIN_LIMIT = 1024.0  # native world_offset.hpp: kNearOriginLimit
STATION_COLUMN = "station"  # the name of a merged export's station column in `columns`


@dataclass
class ScanRecord:
    """What the manifest records of one scan index: its file, points, scanner (world) and,
    for library formats, the station and CRS the file states."""

    path: str
    points: int
    scanner: Optional[List[float]]
    metadata: dict = field(default_factory=dict)


def world_offset_for_bounds(low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """The native rule (world_offset.cpp): none for data within ±1024 units of the origin,
    else the bounding box's centre rounded to whole units."""
    if np.any(low > high):
        return np.zeros(3)
    if np.max(np.maximum(np.abs(low), np.abs(high))) <= NEAR_ORIGIN_LIMIT:
        return np.zeros(3)
    return np.round(0.5 * (low + high))


def _triple(value, what: str) -> Optional[np.ndarray]:
    if value is None:
        return None
    v = np.asarray(value, dtype=np.float64).reshape(-1)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise InputError(f"{what}: expected three finite numbers, got {value!r}")
    return v


def station_columns(columns: str) -> tuple:
    """(the columns the native reader takes, the index of the station column or None): a
    `station` column is read here, and the native reader skips it as `_`."""
    names = columns.split()
    if STATION_COLUMN not in names:
        return columns, None
    return " ".join("_" if n == STATION_COLUMN else n for n in names), names.index(STATION_COLUMN)


def nearest_station(positions: np.ndarray, stations: np.ndarray) -> np.ndarray:
    """Index of the nearest station of each point (ties to the lower index). positions (n, 3)
    and stations (k, 3) in one frame."""
    return nearest_visible_station(positions, stations, np.ones((len(stations), len(positions)), dtype=bool))


def nearest_visible_station(positions: np.ndarray, stations: np.ndarray, visible: np.ndarray) -> np.ndarray:
    """The nearest station among those that see each point (visible: (k, n) bool), the nearest
    of all where none does (ties to the lower index)."""
    d2 = np.stack([np.einsum("ij,ij->i", positions - s, positions - s) for s in stations])
    best = np.argmin(np.where(visible, d2, np.inf), axis=0)
    unseen = ~visible.any(axis=0)
    best[unseen] = np.argmin(d2[:, unseen], axis=0)
    return best.astype(np.uint32)


VISIBILITY_BIN_DEG = 1.0  # the direction cells a station's front surface is found in
VISIBILITY_TOLERANCE = (0.02, 0.03)  # (metres, fraction of the range) a point may lie behind it


def front_surface_visibility(positions: np.ndarray, stations: np.ndarray,
                             bin_deg: float = VISIBILITY_BIN_DEG,
                             tolerance=VISIBILITY_TOLERANCE) -> np.ndarray:
    """(k, n): whether each station sees each point, judged from the cloud itself: the point is
    within `tolerance` of the nearest point in its direction cell (bin_deg × bin_deg of azimuth
    and elevation) seen from the station. A coarse line-of-sight test: a point on the far side
    of a box from a station lies behind the box's near faces; thin or sparsely sampled
    occluders can let it through."""
    cells_az = int(round(360.0 / bin_deg))
    cells_el = int(round(180.0 / bin_deg))
    visible = np.zeros((len(stations), len(positions)), dtype=bool)
    for k, station in enumerate(stations):
        d = positions - station
        r = np.linalg.norm(d, axis=1)
        az = ((np.degrees(np.arctan2(d[:, 1], d[:, 0])) + 180.0) / bin_deg).astype(np.int64) % cells_az
        el = np.clip(((np.degrees(np.arcsin(np.clip(d[:, 2] / np.maximum(r, 1e-12), -1, 1))) + 90.0) / bin_deg)
                     .astype(np.int64), 0, cells_el - 1)
        cell = az * cells_el + el
        front = np.full(cells_az * cells_el, np.inf)
        np.minimum.at(front, cell, r)
        visible[k] = r <= front[cell] + tolerance[0] + tolerance[1] * front[cell]
    return visible


def _station_column_values(path: str, column: int, count: int, stations: int) -> np.ndarray:
    """The station column of a text export: whole numbers 0..stations−1 (or 1..stations, taken
    as counted from 1), one per point row (lines that do not start with a number are skipped, as
    header and comment lines are by the native reader)."""
    values = []
    with open(path, "r", encoding="utf-8", errors="replace") as stream:
        for number, line in enumerate(stream, 1):
            parts = line.replace(",", " ").split()
            if not parts:
                continue
            try:
                float(parts[0])
            except ValueError:
                continue
            if len(parts) <= column:
                # A count line (.pts) has one field; a point row short of the station column is an error.
                if len(parts) == 1:
                    continue
                raise InputError(f"{path}:{number}: no station column (column {column + 1} of the columns given)")
            try:
                values.append(float(parts[column]))
            except ValueError as error:
                raise InputError(f"{path}:{number}: station {parts[column]!r} is not a number") from error
    station = np.asarray(values, dtype=np.float64)
    if len(station) != count:
        raise InputError(f"{path}: {len(station):,} station values for {count:,} points read")
    if len(station) and station.min() >= 1 and station.max() == stations:
        station = station - 1  # counted from 1
    if len(station) and (np.any(station != np.round(station)) or station.min() < 0 or station.max() >= stations):
        raise InputError(f"{path}: station column values must be whole numbers 0..{stations - 1} "
                         f"(or 1..{stations}), one per --scanner position; found {station.min():g}..{station.max():g}")
    return station.astype(np.uint32)


def needs_python_merge(paths: Sequence[str], scanners: Sequence) -> bool:
    """False when the native load_scans does the whole job (native formats, one scanner per
    file or none)."""
    return (any(is_library_format(p) for p in paths) or (len(paths) == 1 and len(scanners) > 1)
            or any(s is None for s in scanners))


def load_cloud(paths: Sequence[str], scanners: Sequence = (), columns: str = "",
               cache_dir: str = "", world_offset: Optional[Sequence[float]] = None,
               progress=None):
    """(native PointCloud, [ScanRecord per scan index]). scanners: world positions, one per
    file (None: the file's own, an E57's station pose), or, for one text/PLY file, one per
    station it merges. See the module docstring."""
    _native = native.load()
    paths = [str(p) for p in paths]
    scanners = list(scanners)
    merged_stations = len(paths) == 1 and len(scanners) > 1
    if scanners and len(scanners) != len(paths) and not merged_stations:
        raise InputError(f"{len(scanners)} scanner positions for {len(paths)} scan files: give one per file "
                         "(or, for one merged file, one per station it holds)")
    given = [_triple(s, f"scanner {i + 1}") for i, s in enumerate(scanners)]
    if merged_stations and is_library_format(paths[0]):
        raise InputError(f"{paths[0]}: several --scanner positions apply to one merged .xyz/.pts/.ply export; "
                         "an E57 carries its stations' poses and a LAS has none")

    if not needs_python_merge(paths, scanners):
        cloud = _native.load_scans(paths, scanners=[list(map(float, s)) for s in given],
                                   world_offset=None if world_offset is None else list(map(float, world_offset)),
                                   columns=columns, cache_dir=cache_dir, progress=progress)
        offset = np.asarray(cloud.world_offset, dtype=np.float64)
        records = [ScanRecord(p, int(s["points"]), None if s["scanner"] is None else [float(v) for v in np.asarray(s["scanner"]) + offset])
                   for p, s in zip(paths, cloud.scans)]
        return cloud, records

    parts = []  # per scan index: ScanArrays (positions world, double), normals or None
    normals_of = []
    native_paths = [p for p in paths if not is_library_format(p)]
    native_columns, station_column = station_columns(columns) if merged_stations else (columns, None)
    native_cloud = None
    if native_paths:
        native_cloud = _native.load_scans(native_paths, columns=native_columns, cache_dir=cache_dir,
                                          progress=progress)
    native_scans = iter(range(len(native_paths)))
    for file_index, path in enumerate(paths):
        scanner = given[file_index] if file_index < len(given) and not merged_stations else None
        if is_library_format(path):
            stations = read_scan_arrays(path)
            if scanner is not None and len(stations) > 1:
                raise InputError(f"{path}: holds {len(stations)} stations with their own poses; "
                                 "a --scanner position for it applies only to a file of one station")
            for station in stations:
                if scanner is not None:
                    station.scanner = tuple(scanner)
                parts.append(station)
                normals_of.append(None)
            continue
        i = next(native_scans)
        members = native_cloud.scan_index == i
        offset = np.asarray(native_cloud.world_offset, dtype=np.float64)
        own = native_cloud.scans[i]["scanner"]
        if scanner is None and own is not None:
            scanner = np.asarray(own) + offset
        positions = native_cloud.positions[members].astype(np.float64) + offset
        colors = None if native_cloud.colors is None else native_cloud.colors[members]
        intensities = None if native_cloud.intensities is None else native_cloud.intensities[members]
        normals = None if native_cloud.normals is None else native_cloud.normals[members]
        parts.append(ScanArrays(path, positions, colors, intensities,
                                None if scanner is None else tuple(map(float, scanner))))
        normals_of.append(normals)

    if merged_stations:
        whole = parts[0]
        stations = np.array(given)
        if station_column is not None:
            station = _station_column_values(whole.path, station_column, len(whole.positions), len(given))
            rule = "station column"
        else:
            centre = stations.mean(axis=0)
            local, local_stations = whole.positions - centre, stations - centre
            station = nearest_visible_station(local, local_stations, front_surface_visibility(local, local_stations))
            rule = "nearest station that sees it"
        split = []
        split_normals = []
        for k in range(len(given)):
            members = station == k
            split.append(ScanArrays(whole.path, whole.positions[members],
                                    None if whole.colors is None else whole.colors[members],
                                    None if whole.intensities is None else whole.intensities[members],
                                    tuple(map(float, given[k])), {"station": k, "station_rule": rule}))
            split_normals.append(None if normals_of[0] is None else normals_of[0][members])
        parts, normals_of = split, split_normals

    return _from_parts(_native, parts, normals_of, world_offset)


def _from_parts(_native, parts: List[ScanArrays], normals_of: list, world_offset):
    """One native cloud of the parts, in order, with the native merge's rules: the world
    offset of the whole's bounds, mid grey where a part has no colour, zero normals where a
    part has none."""
    if world_offset is not None:
        offset = np.asarray(world_offset, dtype=np.float64)
    else:
        non_empty = [p.positions for p in parts if len(p.positions)]
        if non_empty:
            bounds = [column_bounds(p) for p in non_empty]
            low = np.min([b[0] for b in bounds], axis=0)
            high = np.max([b[1] for b in bounds], axis=0)
            offset = world_offset_for_bounds(low, high)
        else:
            offset = np.zeros(3)
    total = sum(len(p.positions) for p in parts)
    positions = np.empty((total, 3), dtype=np.float32)
    scan_index = np.empty(total, dtype=np.uint32)
    any_colour = any(p.colors is not None for p in parts)
    any_normal = any(n is not None for n in normals_of)
    # Intensity is kept only where every part has it: the bake maps intensity to grey over the
    # cloud's range, which a part without it would distort.
    all_intensity = bool(parts) and all(p.intensities is not None for p in parts)
    colors = np.empty((total, 3), dtype=np.float32) if any_colour else None
    normals = np.zeros((total, 3), dtype=np.float32) if any_normal else None
    intensities = np.empty(total, dtype=np.float32) if all_intensity else None
    grey = float(((0.5 + 0.055) / 1.055) ** 2.4)  # sRGB mid grey, decoded, as the native merge
    first = 0
    for index, part in enumerate(parts):
        n = len(part.positions)
        block = slice(first, first + n)
        positions[block] = part.positions - offset  # double, then float32
        scan_index[block] = index
        if colors is not None:
            colors[block] = grey if part.colors is None else part.colors
        if normals is not None and normals_of[index] is not None:
            normals[block] = normals_of[index]
        if intensities is not None:
            intensities[block] = part.intensities
        first += n
    scanners = [None if p.scanner is None else list(np.asarray(p.scanner, dtype=np.float64) - offset) for p in parts]
    cloud = _native.PointCloud.from_arrays(positions, colors=colors, normals=normals, scan_index=scan_index,
                                           scanners=scanners, world_offset=[float(v) for v in offset],
                                           intensities=intensities, scan_paths=[str(p.path) for p in parts])
    records = [ScanRecord(p.path, len(p.positions), None if p.scanner is None else [float(v) for v in p.scanner],
                          dict(p.metadata)) for p in parts]
    return cloud, records


def describe_records(records: Sequence[ScanRecord]) -> list:
    """The manifest's sources of a loaded cloud: sources.describe_scan per scan index (a file's
    hash computed once), with the station and CRS of library formats."""
    from .sources import describe_scan

    hashes = {}
    out = []
    for record in records:
        entry = dict(describe_scan(record.path, record.points, record.scanner, sha256=hashes.get(record.path)))
        hashes[record.path] = entry["sha256"]
        entry.update(record.metadata)
        out.append(entry)
    return out


def loaded_with_records(result, paths: Sequence[str]):
    """(cloud, records) from what a load job returned: load_cloud's pair as it is, or a native
    load_scans cloud (one scan per file) with its records made here."""
    if isinstance(result, tuple):
        return result
    offset = np.asarray(result.world_offset, dtype=np.float64)
    return result, [ScanRecord(str(p), int(s["points"]),
                               None if s["scanner"] is None else [float(v) for v in np.asarray(s["scanner"]) + offset])
                    for p, s in zip(paths, result.scans)]


def file_of_each_scan(records: Sequence[ScanRecord], paths: Sequence[str]) -> List[int]:
    """The index in `paths` of the file each scan index came from (an E57 or a merged export
    gives several scans of one file, in file order)."""
    out, current = [], -1
    for record in records:
        if current < 0 or str(paths[current]) != record.path or record.metadata.get("station", 0) == 0:
            current += 1
            while current < len(paths) and str(paths[current]) != record.path:
                current += 1
            if current >= len(paths):
                raise ValueError(f"{record.path}: not among the files loaded")
        out.append(current)
    return out
