"""The sweep: simulated scans of the scene at several densities, probe sets baked from them
(fine resolution × probe count × bake variant) and from the mesh, every view traced with every
trace setting and measured against the Embree ground truth; plus the error against the eye's
distance from the nearest probe, the walk, and mesh-baked probes seen from their own centre."""

from __future__ import annotations

import json
import math
import shutil
import time
from dataclasses import dataclass
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from .. import pipeline
from ..pipeline import BakeOptions, ProbePlacementSpec, bake_from_mesh
from ..embree_rates import embree_rates
from ..metrics import psnr_seen_as
from .measure import (RunContext, error_share, guessed_figures, measure, nearest_probe_distance, pixel_count,
                      psnr_only, silhouette_pixels, timing)
from .presets import BAKE_VARIANTS, COMPACT_TRACE, DEFAULT_TRACE, LOAD_KEYS
from .scene import grid_positions


@dataclass
class Density:
    """One simulated scan density: every scanner of the scene scanned at step_deg."""
    step_deg: float
    points: int
    scan_seconds: float
    cloud: object

    @property
    def label(self) -> str:
        return f"{self.step_deg:g}° ({self.points:,} points)"


@dataclass
class ProbeSetup:
    """What one probe set was baked from and how."""
    source: str                      # "scan" or "mesh"
    resolution: int
    counts: List[int]
    grid_min: List[float]
    grid_max: List[float]
    bake_variant: str = "splat + fill"
    density: Optional[Density] = None

    @property
    def probes(self) -> int:
        return self.counts[0] * self.counts[1] * self.counts[2]

    def positions(self) -> List[List[float]]:
        return grid_positions(self.grid_min, self.grid_max, self.counts)

    def describe(self) -> Dict[str, object]:
        return {
            "source": self.source,
            "scan_step_deg": None if self.density is None else self.density.step_deg,
            "scan_points": None if self.density is None else self.density.points,
            "resolution": self.resolution,
            "counts": list(self.counts),
            "probes": self.probes,
            "bake": self.bake_variant if self.source == "scan" else "mesh (Embree, exact)",
        }


def scaled_grid(ctx: RunContext, factor: float) -> Tuple[List[float], List[float], List[int]]:
    """The scene grid with counts × factor (at least 1; an axis left with one probe puts it
    in the middle of the grid's extent)."""
    s = ctx.scene
    counts = [max(1, int(round(c * factor))) for c in s.grid_counts]
    lo, hi = list(s.grid_min), list(s.grid_max)
    for axis in range(3):
        if counts[axis] == 1:
            lo[axis] = hi[axis] = 0.5 * (s.grid_min[axis] + s.grid_max[axis])
    return lo, hi, counts


def simulate_scans(ctx: RunContext) -> List[Density]:
    """Scans the mesh from every scanner position at each of the preset's densities, straight
    into a cloud: no .xyz file between (at the paper's density one would take gigabytes and as
    long to parse as the scan takes)."""
    s, p = ctx.scene, ctx.preset
    steps = sorted({max(s.scan["step_deg"] * f, p.min_scan_step_deg) for f in p.scan_step_factors})
    densities = []
    for step in steps:
        scanned = ctx.native.start_simulate_scans(
            ctx.mesh, [list(scanner) for scanner in s.scanners], step_deg=step,
            noise_mm=s.scan["noise_mm"], vertical_fov=s.scan["vertical_fov"],
            seeds=[index + 1 for index in range(len(s.scanners))]).run()
        cloud = scanned["cloud"]
        seconds = sum(stats["seconds"] for stats in scanned["stats"])
        density = Density(step, len(cloud), seconds, cloud)
        ctx.log(f"  scan at {step:g}°: {density.points:,} points from {len(s.scanners)} scanner(s) in {seconds:.2f} s")
        densities.append(density)
    return densities


def bake(ctx: RunContext, setup: ProbeSetup, folder: str) -> Dict[str, object]:
    """Bakes one probe set; returns its bake time and memory figures."""
    placement = ProbePlacementSpec(grid_min=setup.grid_min, grid_max=setup.grid_max, counts=setup.counts)
    if setup.source == "mesh":
        options = BakeOptions(resolution=setup.resolution)
        options.extra["supersample"] = ctx.preset.mesh_supersample
        start = time.perf_counter()
        summary = bake_from_mesh([ctx.scene.mesh], folder, placement, options)
        wall = time.perf_counter() - start
        bake_seconds = summary["bake_seconds"]
    else:
        variant = BAKE_VARIANTS[setup.bake_variant]
        options = BakeOptions(resolution=setup.resolution, splat_scale=variant["splat_scale"],
                              hole_fill_texels=variant["hole_fill_texels"])
        start = time.perf_counter()
        summary = pipeline.bake_from_cloud(setup.density.cloud, folder, placement, options,
                                           cache_dir=ctx.cache_dir)
        wall = time.perf_counter() - start
        bake_seconds = summary["bake_seconds"] + summary.get("normals_seconds", 0.0)
    coverage = summary["mean_coverage"]
    return {
        "bake_seconds": bake_seconds,
        "bake_seconds_per_probe": bake_seconds / setup.probes,
        "bake_wall_seconds": wall,
        "disk_bytes_per_probe": summary["bytes_on_disk"] / setup.probes,
        "coverage_surface": coverage["surface"],
        "coverage_inferred": coverage["inferred"],
        "coverage_unknown": coverage["unknown"],
        # The cloud's normals, spacing and hierarchy read from an earlier bake's cache: its
        # bake_seconds hold the read instead of the estimate.
        "prepared_from_cache": bool(summary.get("prepared_from_cache", False)),
    }


def _row(setup: ProbeSetup, bake_info: dict, memory_per_probe: float, trace_label: str,
         trace: dict, view: str) -> Dict[str, object]:
    row = {"setting": "", "view": view, **setup.describe(), "trace": trace_label,
           "mode": trace["mode"], "thickness": trace["thickness"],
           "fallback_thickness": trace.get("fallback_thickness", 0.0),
           "coarse_levels": trace["use_coarse_levels"],
           "coarse_resolution": int(trace.get("coarse_resolution", 0)) or 1,
           "storage": trace.get("storage", "full"),
           "hole_fill": trace.get("hole_fill", -1),
           "memory_bytes_per_probe": memory_per_probe}
    row.update(bake_info)
    row["setting"] = setting_label(row)
    return row


def setup_label(row: Dict[str, object]) -> str:
    """"scan 1°, splat + fill, 512², 2×3×2 probes" for a row or ProbeSetup.describe()."""
    source = (f"scan {row['scan_step_deg']:g}°, {row['bake']}" if row["source"] == "scan" else "mesh")
    counts = "×".join(str(c) for c in row["counts"])
    return f"{source}, {row['resolution']}², {counts} probes"


def setting_label(row: Dict[str, object]) -> str:
    return f"{setup_label(row)}, {row['trace']}"


def planned_setups(p, densities: Sequence[Density], full_grid: Tuple[List[float], List[float], List[int]],
                   scaled) -> List[Tuple[ProbeSetup, List]]:
    """The probe sets the sweep bakes, each with the trace settings it is rendered with, for the
    preset `p`: scan sets of every density (densest first) at the fine resolutions (a coarser
    density at p.coarse_scan_resolution alone where set), the probe counts of p.count_factors
    (scaled(factor): that grid), then the mesh-baked sets."""
    densest = densities[0]
    reference_res = p.reference_fine_resolution()
    setups: List[Tuple[ProbeSetup, List]] = []
    for density in densities:
        for res in p.fine_resolutions:
            if density is not densest and p.coarse_scan_resolution not in (None, res):
                continue
            for variant in p.bake_variants:
                setup = ProbeSetup("scan", res, full_grid[2], full_grid[0], full_grid[1], variant, density)
                is_reference = density is densest and res == reference_res and variant == "splat + fill"
                traces = list(p.trace_variants) if is_reference else [DEFAULT_TRACE]
                # Compact storage beside full: at every resolution for the storage comparison
                # of "planning", at the reference alone when the preset skips planning.
                if density is densest and variant == "splat + fill" and (p.planning or res == reference_res):
                    traces.append(COMPACT_TRACE)
                setups.append((setup, traces))
    for factor in p.count_factors:
        if factor != 1.0:
            lo, hi, counts = scaled(factor)
            setups.append((ProbeSetup("scan", reference_res, counts, lo, hi, "splat + fill", densest),
                           [DEFAULT_TRACE]))
    for res in p.mesh_grid_resolutions or p.fine_resolutions:
        setups.append((ProbeSetup("mesh", res, full_grid[2], full_grid[0], full_grid[1]), [DEFAULT_TRACE]))
    return setups


class Sweep:
    """Runs the sweep and holds its rows and the images the report shows."""

    def __init__(self, ctx: RunContext):
        self.ctx = ctx
        self.view_rows: List[Dict[str, object]] = []
        self.distance_rows: List[Dict[str, object]] = []
        self.walk_rows: List[Dict[str, object]] = []
        self.at_probe_rows: List[Dict[str, object]] = []
        self.ground_truth_rows: List[Dict[str, object]] = []
        self.embree_rows: List[Dict[str, object]] = []
        self.densities: List[Density] = []
        self.reference_images: Dict[str, Tuple[dict, dict, np.ndarray, dict]] = {}
        self.reference_setting: Optional[str] = None
        self.mesh_triplets: Dict[str, Tuple[dict, dict, np.ndarray, dict]] = {}
        self._controls: Dict[tuple, Tuple[float, dict]] = {}
        # Mesh-baked single probes by (eye, resolution): the distance sweep's control at a grid
        # probe is the probe the at-probe section sees from its centre, baked once for both.
        self._mesh_probes: Dict[tuple, Tuple[str, float, float]] = {}

    # --- the parts ---------------------------------------------------------------------------
    def run(self) -> None:
        ctx, p = self.ctx, self.ctx.preset
        ctx.log("ground truth of every view (Embree)")
        for view in ctx.views:
            camera = ctx.camera(view)
            _, stats = ctx.ground_truth(camera)
            self.ground_truth_rows.append({
                "view": view.name, "width": camera["resolution"][0], "height": camera["resolution"][1],
                "spp": p.gt_spp, "seconds": stats["seconds"], "rays": stats["rays"],
                "rays_per_second": stats["rays_per_second"],
                "embree_primary_rays_per_second": ctx.native.embree_throughput(
                    ctx.mesh, json.dumps(camera), threads=ctx.threads,
                    repeats=p.timing_repeats)["rays_per_second"],
            })
        ctx.log("simulated scans")
        self.densities = simulate_scans(ctx)
        densest = self.densities[0]
        reference_res = p.reference_fine_resolution()
        full_grid = scaled_grid(ctx, 1.0)
        setups = planned_setups(p, self.densities, full_grid, lambda factor: scaled_grid(ctx, factor))
        for index, (setup, traces) in enumerate(setups):
            folder = ctx.work_path("probes", f"set_{index:03d}")
            info = bake(ctx, setup, folder)
            field = ctx.native.ProbeField.load(folder)
            memory_per_probe = field.memory_bytes / field.probe_count
            is_reference = (setup.source == "scan" and setup.density is densest and setup.resolution == reference_res
                            and setup.bake_variant == "splat + fill" and setup.counts == full_grid[2])
            is_mesh_reference = setup.source == "mesh" and setup.resolution == reference_res
            ctx.log(f"  [{index + 1}/{len(setups)}] {setup_label(setup.describe())}: "
                    f"bake {info['bake_seconds']:.2f} s, {memory_per_probe / 2**20:.2f} MiB/probe")
            for trace_label, trace in traces:
                # Coarse resolution and storage are load-time settings: such a variant loads
                # its own field.
                load_args = {k: v for k, v in trace.items() if k in LOAD_KEYS}
                render_args = {k: v for k, v in trace.items() if k not in LOAD_KEYS}
                trace_field = (ctx.native.ProbeField.load(folder, **load_args) if load_args else field)
                trace_memory = trace_field.memory_bytes / trace_field.probe_count
                for view in ctx.views:
                    camera = ctx.camera(view)
                    gt, _ = ctx.ground_truth(camera)
                    # Variants other than the default are timed once: they compare among themselves.
                    image, stats = ctx.render_probes(trace_field, camera, render_args,
                                                     repeats=None if trace_label == DEFAULT_TRACE[0] else 1)
                    figures, error_map = measure(gt, image)
                    row = _row(setup, info, trace_memory, trace_label, trace, view.name)
                    row.update(timing(stats, pixel_count(camera)))
                    row.update({"texels_per_ray": stats["mean_steps"], "probes_per_ray": stats["mean_probes"]})
                    row.update(figures)
                    row.update(guessed_figures(gt, image))
                    self.view_rows.append(row)
                    if trace_label == DEFAULT_TRACE[0] and (is_reference or is_mesh_reference):
                        target = self.reference_images if is_reference else self.mesh_triplets
                        target[view.name] = (gt, image, error_map, row)
                    if trace_label == DEFAULT_TRACE[0] and is_reference:
                        self.embree_rows.append(self.against_embree(
                            trace_field, camera, view.name, row,
                            nearest_probe_distance(view.position, setup.positions())))
            if is_reference:
                self.reference_setting = _row(setup, info, memory_per_probe, *DEFAULT_TRACE, "")["setting"]
                self.distance_sweep(field, setup, "scan")
                self.walk(field, setup)
            if is_mesh_reference:
                self.distance_sweep(field, setup, "mesh")
            del field
            shutil.rmtree(folder, ignore_errors=True)
        self.at_probe()

    def against_embree(self, field, camera: dict, view: str, row: Dict[str, object],
                       eye_to_probe: float) -> Dict[str, object]:
        """The probe trace of the reference setting against Embree on the scene's mesh, the same
        rays measured the same way (made beforehand, trace only, fastest of the repeats): the
        issue's aims are a third of Embree's throughput, more than Embree with the eye at a probe."""
        ctx, p = self.ctx, self.ctx.preset
        text = json.dumps(camera)
        trace = field.trace_throughput(text, threads=ctx.threads, repeats=p.timing_repeats)
        # The same rays started at their own answers: the part of the cost no skipping removes.
        floor = field.trace_throughput(text, threads=ctx.threads, repeats=p.timing_repeats,
                                       start="answer")
        # The same answers coloured by their texel alone, as a lookup (and the paper's trace)
        # colours them: the trace without the filter's and the blend's further lookups, the part
        # comparable with Embree's intersection, which colours nothing.
        texel = field.trace_throughput(text, threads=ctx.threads, repeats=p.timing_repeats,
                                       colour="texel")
        embree = embree_rates(ctx.native, ctx.mesh, text, ctx.threads, p.timing_repeats)
        return {"view": view, "distance_to_nearest_probe": eye_to_probe,
                "texels_per_ray": row["texels_per_ray"], "probes_per_ray": row["probes_per_ray"],
                "trace_rays_per_second": trace["rays_per_second"],
                "embree_rays_per_second": embree["single"],
                "embree_packet_rays_per_second": embree["packet"], "embree_packet": embree["packet_width"],
                "trace_over_embree": trace["rays_per_second"] / embree["single"],
                "trace_over_embree_packets": trace["rays_per_second"] / embree["packet"],
                "trace_from_answer_rays_per_second": floor["rays_per_second"],
                "trace_from_answer_over_embree": floor["rays_per_second"] / embree["single"],
                "trace_texel_rays_per_second": texel["rays_per_second"],
                "trace_texel_over_embree": texel["rays_per_second"] / embree["single"]}

    def _anchor_and_target(self, view, positions: List[List[float]]) -> Tuple[List[float], List[float]]:
        """The probe nearest the view's eye, and the point the eye moves toward: the centre of
        the grid cell beside that probe toward the grid's middle (the farthest point from every
        probe), or 0.5 m along the view direction for a single probe."""
        anchor = min(positions, key=lambda q: math.dist(q, view.position))
        s = self.ctx.scene
        spacing = [(hi - lo) / (n - 1) if n > 1 else 0.0 for lo, hi, n in zip(s.grid_min, s.grid_max, s.grid_counts)]
        middle = [0.5 * (lo + hi) for lo, hi in zip(s.grid_min, s.grid_max)]
        target = [a + (0.5 * d if m >= a else -0.5 * d) for a, d, m in zip(anchor, spacing, middle)]
        if math.dist(target, anchor) == 0.0:
            direction = np.subtract(view.look_at, view.position)
            target = list(np.asarray(anchor) + 0.5 * direction / np.linalg.norm(direction))
        return anchor, target

    def distance_sweep(self, field, setup: ProbeSetup, source: str) -> None:
        """Error as the eye leaves the nearest probe toward the cell centre (default trace)."""
        ctx = self.ctx
        positions = setup.positions()
        for view in ctx.views:
            anchor, target = self._anchor_and_target(view, positions)
            for fraction in ctx.preset.distance_fractions:
                eye = [a + fraction * (t - a) for a, t in zip(anchor, target)]
                camera = ctx.camera(view, eye)
                gt, _ = ctx.ground_truth(camera)
                image, stats = ctx.render_probes(field, camera, DEFAULT_TRACE[1])
                figures, _ = measure(gt, image)
                control, control_image = self._probe_at_eye(view, eye, setup.resolution, camera, gt)
                row = {"source": source, "view": view.name, "resolution": setup.resolution,
                       "fraction_to_cell_centre": fraction, "eye": eye,
                       "distance_to_nearest_probe": nearest_probe_distance(eye, positions),
                       **timing(stats, pixel_count(camera)), "texels_per_ray": stats["mean_steps"], **figures,
                       **guessed_figures(gt, image), "psnr_probe_at_eye": control,
                       "psnr_seen_exact": psnr_seen_as(gt, image, control_image),
                       "psnr_loss": control - figures["psnr"] if math.isfinite(control) and math.isfinite(figures["psnr"]) else None}
                self.distance_rows.append(row)
        ctx.log(f"  error against distance from the nearest probe ({source} probes): "
                f"{len(ctx.views) * len(ctx.preset.distance_fractions)} eyes")

    def _probe_at_eye(self, view, eye: List[float], resolution: int, camera: dict,
                      gt: dict) -> Tuple[float, dict]:
        """PSNR and colour ({"rgba"}) of a mesh-baked probe of the same resolution at the eye itself:
        what this view would score with no distance to travel (the control that removes what the
        eye sees from the comparison between positions)."""
        key = (view.name, tuple(eye), resolution)
        if key not in self._controls:
            folder, _, _ = self._mesh_probe(eye, resolution)
            image, _ = self.ctx.render_probes(self.ctx.native.ProbeField.load(folder), camera, DEFAULT_TRACE[1])
            # Its colour alone is kept (what psnr_seen_as reads): the full image, depth, normals and
            # the rest, would hold every eye's planes until the sweep ends.
            self._controls[key] = (psnr_only(gt, image), {"rgba": image["rgba"]})
        return self._controls[key]

    def _mesh_probe(self, eye: Sequence[float], resolution: int) -> Tuple[str, float, float]:
        """(folder, bake seconds, bake wall seconds) of a mesh-baked probe at `eye`, baked on
        first use and kept until the sweep ends."""
        key = (tuple(float(c) for c in eye), int(resolution))
        if key not in self._mesh_probes:
            ctx = self.ctx
            folder = ctx.work_path("probes", f"mesh_probe_{len(self._mesh_probes):03d}")
            start = time.perf_counter()
            summary = bake_from_mesh([ctx.scene.mesh], folder, ProbePlacementSpec(positions=[list(key[0])]),
                                     BakeOptions(resolution=resolution))
            self._mesh_probes[key] = (folder, summary["bake_seconds"], time.perf_counter() - start)
        return self._mesh_probes[key]

    def _drop_mesh_probes(self) -> None:
        for folder, _, _ in self._mesh_probes.values():
            shutil.rmtree(folder, ignore_errors=True)
        self._mesh_probes.clear()

    def walk(self, field, setup: ProbeSetup) -> None:
        ctx = self.ctx
        positions = setup.positions()
        for view in ctx.scene.walk_views(ctx.preset.walk_frames):
            camera = ctx.camera(view)
            gt, _ = ctx.ground_truth(camera)
            image, stats = ctx.render_probes(field, camera, DEFAULT_TRACE[1])
            figures, _ = measure(gt, image)
            self.walk_rows.append({"frame": view.name, "eye": view.position,
                                   "distance_to_nearest_probe": nearest_probe_distance(view.position, positions),
                                   **timing(stats, pixel_count(camera)), **figures})

    def at_probe(self) -> None:
        """Mesh-baked single probes at the probe nearest each view, seen from their own centre,
        every camera ray one texel lookup. Matched filtering: the probe render takes the ground
        truth's n×n samples per pixel; each radiance filter is measured against that ground truth
        and against a converged one (reference_spp), and one sample per pixel on both sides
        shows what an unfiltered comparison measures instead."""
        ctx = self.ctx
        positions = ctx.scene.probe_positions()
        spp, reference_spp = ctx.preset.gt_spp, ctx.preset.reference_spp
        for res in ctx.preset.mesh_resolutions:
            for view in ctx.views:
                anchor = min(positions, key=lambda q: math.dist(q, view.position))
                folder, bake_seconds, bake_wall = self._mesh_probe(anchor, res)
                field = ctx.native.ProbeField.load(folder)
                camera = ctx.camera(view, anchor)
                # Unfiltered on both sides: the pixel centre, its texture point-sampled.
                gt_centre, _ = ctx.ground_truth(camera, spp=1, filter_textures=False)
                gt, _ = ctx.ground_truth(camera)
                converged, _ = ctx.ground_truth(camera, spp=reference_spp)
                w = camera["resolution"][0]
                fov = 2.0 * math.atan(0.5 * camera["sensor_width"] / camera["lens"])
                # One ray per pixel anti-aliased by the footprint filter, against the filtered
                # ground truth: what the viewport can show without more rays.
                footprint_image, _ = ctx.render_probes(field, camera, {**DEFAULT_TRACE[1], "filter": "footprint"},
                                                       spp=1, repeats=1)
                footprint_psnr = psnr_only(gt, footprint_image)
                silhouettes = silhouette_pixels(converged)
                for radiance_filter in ("nearest", "bilinear", "bicubic"):
                    trace = {**DEFAULT_TRACE[1], "filter": radiance_filter}
                    image, stats = ctx.render_probes(field, camera, trace)
                    figures, _ = measure(gt, image)
                    centre_image, _ = ctx.render_probes(field, camera, trace, spp=1, repeats=1)
                    self.at_probe_rows.append({
                        "view": view.name, "resolution": res, "filter": radiance_filter, "eye": anchor,
                        "spp": spp, "reference_spp": reference_spp,
                        "texel_angle_deg": math.degrees(math.sqrt(4.0 * math.pi) / res),
                        "pixel_angle_deg": math.degrees(fov / w),
                        "psnr": figures["psnr"], "ssim": figures["ssim"], "flip": figures["flip"],
                        "psnr_vs_converged_gt": psnr_only(converged, image),
                        "gt_psnr_vs_converged_gt": psnr_only(converged, gt),
                        "silhouette_pixels": float(silhouettes.mean()),
                        "silhouette_error_share": error_share(converged, image, silhouettes),
                        "gt_silhouette_error_share": error_share(converged, gt, silhouettes),
                        "psnr_one_sample_per_pixel": psnr_only(gt_centre, centre_image),
                        "psnr_one_sample_vs_filtered_gt": psnr_only(gt, centre_image),
                        "psnr_footprint_one_sample_vs_filtered_gt": footprint_psnr,
                        "depth_absrel": figures["depth_absrel"], "hole_rate": figures["hole_rate"],
                        "bake_seconds": bake_seconds, "bake_wall_seconds": bake_wall,
                        "texels_per_ray": stats["mean_steps"], **timing(stats, pixel_count(camera)),
                    })
                del field
        self._drop_mesh_probes()
        ctx.log(f"  mesh-baked probes at their own centre: {len(self.at_probe_rows)} renders")


def aggregate(view_rows: Sequence[Dict[str, object]]) -> List[Dict[str, object]]:
    """One row per setting: metrics and ms per frame averaged over the views, rays per second
    as all rays over all seconds."""
    groups: Dict[str, List[Dict[str, object]]] = {}
    for row in view_rows:
        groups.setdefault(row["setting"], []).append(row)
    out = []
    for setting, rows in groups.items():
        first = rows[0]
        merged = {k: v for k, v in first.items() if k != "view"}
        merged["views"] = len(rows)
        for key in ("psnr", "ssim", "flip", "depth_absrel", "depth_rmse", "hole_rate", "false_hit_rate",
                    "false_miss_rate", "unknown_rate", "ms_per_frame", "texels_per_ray", "probes_per_ray"):
            values = [r[key] for r in rows if r.get(key) is not None and math.isfinite(r[key])]
            merged[key] = float(np.mean(values)) if values else None
        seconds = sum(r["ms_per_frame"] for r in rows) / 1000.0
        rays = sum(r["rays_per_second"] * r["ms_per_frame"] / 1000.0 for r in rows)
        merged["rays_per_second"] = rays / seconds if seconds > 0 else None
        merged.pop("confusion", None)
        out.append(merged)
    return out


def pareto_front(rows: Sequence[Dict[str, object]], cost: str, quality: str, higher_is_better: bool = True) -> List[int]:
    """Indices of the rows no other row beats: at most the cost with at least the quality,
    strictly better in one of them."""
    points = [(r.get(cost), r.get(quality)) for r in rows]
    front = []
    for i, (c, q) in enumerate(points):
        if c is None or q is None:
            continue
        q_i = q if higher_is_better else -q
        dominated = False
        for j, (c2, q2) in enumerate(points):
            if j == i or c2 is None or q2 is None:
                continue
            q_j = q2 if higher_is_better else -q2
            if c2 <= c and q_j >= q_i and (c2 < c or q_j > q_i):
                dominated = True
                break
        if not dominated:
            front.append(i)
    return front
