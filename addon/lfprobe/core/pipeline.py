"""The scan → probe set pipeline, as plain functions that the CLI and the add-on both call."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Callable, Optional, Sequence

from . import defaults, native
from .probe_set import read_manifest
from .scan_merge import describe_records, load_cloud
from .sources import default_cache_dir, describe_mesh

Progress = Optional[Callable[[float, str], object]]


@dataclass
class ProbePlacementSpec:
    """Probes at explicit positions, or on a grid from min to max corner with counts per axis.
    Coordinates are world coordinates (the scan files' own)."""

    positions: Sequence[Sequence[float]] = ()
    grid_min: Optional[Sequence[float]] = None
    grid_max: Optional[Sequence[float]] = None
    counts: Optional[Sequence[int]] = None

    def validate(self) -> None:
        grid = [self.grid_min, self.grid_max, self.counts]
        if any(g is not None for g in grid):
            if any(g is None for g in grid):
                raise ValueError("a probe grid needs --grid-min, --grid-max and --counts")
            if self.positions:
                raise ValueError("give probe positions (--probe) or a grid, not both")
            if len(self.counts) != 3 or any(int(c) < 1 for c in self.counts):
                raise ValueError("--counts needs three whole numbers of at least 1")
        elif not self.positions:
            raise ValueError("no probes: give --probe X Y Z or a grid")

    def native_kwargs(self) -> dict:
        """positions / grid_min / grid_max / counts as the native bake and plan calls take them."""
        return dict(
            positions=[list(map(float, p)) for p in self.positions],
            grid_min=None if self.grid_min is None else list(map(float, self.grid_min)),
            grid_max=None if self.grid_max is None else list(map(float, self.grid_max)),
            counts=None if self.counts is None else [int(c) for c in self.counts],
        )


@dataclass
class BakeOptions:
    # The native bake's defaults (core/defaults.py).
    resolution: int = field(default_factory=lambda: defaults.bake("resolution"))
    splat_scale: float = field(default_factory=lambda: defaults.bake("splat_scale"))
    hole_fill_texels: int = field(default_factory=lambda: defaults.bake("hole_fill_texels"))
    normal_neighbours: int = field(default_factory=lambda: defaults.bake("normal_neighbours"))
    # Scan bakes: how many texels apart the point hierarchy's cell surfels may be where they
    # stand in for the points (0: every point is splatted).
    lod_texels: float = field(default_factory=lambda: defaults.bake("lod_texels"))
    # Scan bakes: above 0, cells up to twice lod_texels wide also stand in where their
    # children's colours agree with theirs within this much per channel (linear); 0: off.
    lod_colour_tolerance: float = field(default_factory=lambda: defaults.bake("lod_colour_tolerance"))
    # Scan bakes: how far, in point spacings, a point at its surface's edge splats outward
    # (negative: full discs, which grow every silhouette by the splat radius).
    splat_edge_margin: float = field(default_factory=lambda: defaults.bake("splat_edge_margin"))
    # Scan bakes: the splat's core in point spacings; the rest of its disc fills only texels no
    # core reaches (at splat_scale or more: the whole disc is core).
    splat_core_scale: float = field(default_factory=lambda: defaults.bake("splat_core_scale"))
    extra: dict = field(default_factory=dict)
    # None: every probe at `resolution`. A dict: plan first (bake --auto): per-probe resolution
    # from the data, classification, moves and drops, with these options of
    # _native.start_bake_planned_probe_set (e.g. {"min_resolution": 64, "max_resolution": 2048}).
    plan: Optional[dict] = None
    # How the probes load into memory (the files stay full precision): None leaves the
    # manifest's default (full), "full" or "compact" (8-bit sRGB radiance, distance in steps of
    # distance_step metres, 8+8-bit normals, no confidence; see native probe_storage.hpp).
    storage: Optional[str] = None
    distance_step: float = 0.0


def apply_storage(folder: str, summary: Optional[dict], options: BakeOptions) -> Optional[dict]:
    """Records options.storage in the set's manifest (a no-op for None) and the in-memory bytes
    per probe it gives in `summary`. Returns the storage dict the manifest now holds."""
    if options.storage is None:
        return None
    stored = native.load().set_probe_set_storage(folder, options.storage,
                                                 distance_step=float(options.distance_step))
    if summary is not None:
        summary["storage"] = stored
        manifest = read_manifest(folder)
        probes = manifest["probes"]
        if probes:
            summary["bytes_in_memory_per_probe"] = max(int(p.get("memory_bytes", 0)) for p in probes)
    return stored


def load_scans(
    paths: Sequence[str],
    scanners: Sequence[Sequence[float]] = (),
    columns: str = "",
    cache_dir: Optional[str] = None,
    world_offset: Optional[Sequence[float]] = None,
    progress: Progress = None,
):
    """Reads and merges scan files into one native PointCloud (native formats through the parse
    cache, see default_cache_dir; E57 and LAS/LAZ through their libraries, core/scan_formats.py).
    scanners: world positions, one per file (None: the file's own), or none; for one merged
    .xyz/.pts/.ply export, one per station it holds (core/scan_merge.py)."""
    return load_scans_and_sources(paths, scanners, columns, cache_dir, world_offset, progress)[0]


def load_scans_and_sources(
    paths: Sequence[str],
    scanners: Sequence[Sequence[float]] = (),
    columns: str = "",
    cache_dir: Optional[str] = None,
    world_offset: Optional[Sequence[float]] = None,
    progress: Progress = None,
):
    """load_scans, and the manifest's sources: one record per scan index (a file, an E57
    station, a station of a merged export)."""
    cloud, records = load_cloud(
        [str(p) for p in paths], list(scanners), columns,
        default_cache_dir() if cache_dir is None else cache_dir, world_offset, progress,
    )
    return cloud, records


def bake_from_cloud(
    cloud,
    out_dir: str,
    placement: ProbePlacementSpec,
    options: BakeOptions,
    sources: Sequence[dict] = (),
    progress: Progress = None,
    start_only: bool = False,
    cache_dir: str = "",
):
    """Bakes a probe set from a native PointCloud. With start_only, returns the running Job
    (for Blender's modal operator) instead of waiting for the summary. cache_dir: the folder
    whose prepared-cloud cache holds the cloud's normals, spacing and point hierarchy from an
    earlier bake (read when there, written when not; "": computed, not cached)."""
    _native = native.load()
    placement.validate()
    where = dict(**placement.native_kwargs(), sources_json=json.dumps(list(sources)))
    if options.plan is not None:
        plan = {"resolution": int(options.resolution), "splat_scale": float(options.splat_scale),
                "hole_fill_texels": int(options.hole_fill_texels),
                "lod_texels": float(options.lod_texels),
                "lod_colour_tolerance": float(options.lod_colour_tolerance),
                "splat_edge_margin": float(options.splat_edge_margin),
                "splat_core_scale": float(options.splat_core_scale), **options.plan}
        job = _native.start_bake_planned_probe_set(cloud, out_dir, **where, options=plan,
                                                   cache_dir=cache_dir or "")
        if start_only:
            return job
        summary = job.run(progress)
    else:
        kwargs = dict(where, resolution=int(options.resolution), splat_scale=float(options.splat_scale),
                      hole_fill_texels=int(options.hole_fill_texels),
                      normal_neighbours=int(options.normal_neighbours),
                      lod_texels=float(options.lod_texels),
                      lod_colour_tolerance=float(options.lod_colour_tolerance),
                      splat_edge_margin=float(options.splat_edge_margin),
                      splat_core_scale=float(options.splat_core_scale), cache_dir=cache_dir or "")
        if start_only:
            return _native.start_bake_probe_set(cloud, out_dir, **kwargs)
        summary = _native.bake_probe_set(cloud, out_dir, progress=progress, **kwargs)
    apply_storage(out_dir, summary, options)
    return summary


def plan_probes(cloud, placement: ProbePlacementSpec, plan_options: dict,
                progress: Progress = None) -> list:
    """Plans probes without baking them: one dict per probe (position, resolution, class,
    moved, dropped, the figures behind them). World coordinates."""
    _native = native.load()
    placement.validate()
    job = _native.start_plan_probes(cloud, **placement.native_kwargs(), options=dict(plan_options))
    return job.run(progress)


def bake_from_scans(
    scan_paths: Sequence[str],
    out_dir: str,
    placement: ProbePlacementSpec,
    options: BakeOptions,
    scanners: Sequence[Sequence[float]] = (),
    columns: str = "",
    cache_dir: Optional[str] = None,
    progress: Progress = None,
) -> dict:
    """Scan files → probe set folder. Returns the bake summary with the cloud's size and offset."""
    placement.validate()
    cloud, records = load_scans_and_sources(scan_paths, scanners, columns, cache_dir, progress=progress)
    sources = describe_records(records)
    summary = bake_from_cloud(cloud, out_dir, placement, options, sources, progress,
                              cache_dir=default_cache_dir() if cache_dir is None else cache_dir)
    summary["points"] = len(cloud)
    summary["world_offset"] = list(cloud.world_offset)
    return summary


def bake_from_mesh(
    mesh_paths: Sequence[str],
    out_dir: str,
    placement: ProbePlacementSpec,
    options: BakeOptions,
    progress: Progress = None,
    start_only: bool = False,
):
    """Mesh file → probe set folder, baked with Embree (exact distances, normals, base colour).
    One mesh file is supported per bake. options.extra may hold "supersample" (n×n rays per
    texel for the colour; left out: the native default) and "filter_textures" (False: textures
    point-sampled rather than filtered over each ray's footprint). Returns the summary dict, or the running Job with start_only."""
    if len(mesh_paths) != 1:
        raise ValueError(f"bake --mesh takes one mesh file, got {len(mesh_paths)}")
    placement.validate()
    _native = native.load()
    mesh = _native.load_mesh(str(mesh_paths[0]))
    sources = [describe_mesh(mesh_paths[0], mesh.triangle_count)]
    job = _native.start_bake_probe_set_from_mesh(
        mesh,
        out_dir,
        resolution=int(options.resolution),
        **placement.native_kwargs(),
        sources_json=json.dumps(sources),
        **({"supersample": int(options.extra["supersample"])} if options.extra.get("supersample") else {}),
        **({"filter_textures": bool(options.extra["filter_textures"])}
           if "filter_textures" in options.extra else {}),
    )
    if start_only:
        return job
    summary = job.run(progress)
    summary["triangles"] = mesh.triangle_count
    apply_storage(out_dir, summary, options)
    return summary
