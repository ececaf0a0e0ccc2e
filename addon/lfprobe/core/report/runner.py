"""`./lfprobe report`: the whole run. Sweeps, peers and stability cases are measured, then
report.json, the CSV files, images/*.png and the self-contained report.html are written."""

from __future__ import annotations

import datetime
import math
import os
import platform
import time
from typing import Callable, Collection, Dict, List, Optional, Sequence

from .. import metrics
from . import files, images, peers, planning, plots, stability
from .measure import RunContext, stderr_log
from .page import render_page
from .presets import DEFAULT_TRACE, get_preset
from .scene import load_scene
from .sweep import Sweep, aggregate, pareto_front

# What the section "Model only what a scene needs" writes beside report.html.
PLANNING_TABLES = ("planning_resolution.csv", "planning_walk.csv", "planning_storage.csv", "planning_iterations.csv")
# Every table _write_tables writes: what a later run may delete.
REPORT_TABLES = ("sweep.csv", "sweep_views.csv", "distance.csv", "walk.csv", "at_probe.csv", "peers.csv",
                 "stability.csv", "ground_truth.csv", "trace_against_embree.csv") + PLANNING_TABLES
# The name prefixes of every image _write_images writes: what a later run may delete.
REPORT_IMAGE_PREFIXES = ("speed_", "distance_", "resolution_", "at_probe_", "peers_", "planning_",
                         "triplet_", "confusion_")


def _finite(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def run_report(scene_path: str, out_dir: str, preset_name: str = "demo", threads: int = 0,
               keep_work: bool = False, log: Callable[[str], None] = stderr_log) -> Dict[str, object]:
    """Runs the report for one scene file into out_dir; returns the report's JSON data."""
    preset = get_preset(preset_name)
    scene = load_scene(scene_path)
    if threads < 0:
        raise ValueError(f"--threads must be 0 (all cores) or more, got {threads}")
    started = datetime.datetime.now().astimezone()
    start = time.perf_counter()
    ctx = RunContext(scene, preset, out_dir, threads, log)
    log(f"report on {scene.path} (preset {preset.name}) into {ctx.out_dir}")
    try:
        sweep = Sweep(ctx)
        sweep.run()
        densest = sweep.densities[0]
        log("peers: splats and the Poisson mesh")
        splat_rows, splat_images = peers.splat_rows(ctx, densest)
        poisson_rows, poisson_images, poisson_info = peers.poisson_rows(ctx, densest)
        stability_cases = stability.run(ctx)
        planning_data = planning.run(ctx, sweep) if ctx.preset.planning else None
        data = _report_data(ctx, sweep, splat_rows, poisson_rows, poisson_info, stability_cases)
        data["planning"] = planning_data
        data["findings"]["planning"] = planning.findings(planning_data) if planning_data else []
        data["started"] = started.isoformat(timespec="seconds")
        data["seconds"] = time.perf_counter() - start
        pngs = _write_images(ctx, sweep, data, splat_images, poisson_images)
        _write_tables(ctx.out_dir, data)
        files.write_json(os.path.join(ctx.out_dir, "report.json"), data)
        files.write_text(os.path.join(ctx.out_dir, "report.html"), render_page(data, pngs))
        for density in sweep.densities:
            density.cloud = None
    finally:
        ctx.cleanup(keep_work)
    log(f"wrote {os.path.join(ctx.out_dir, 'report.html')} in {data['seconds']:.1f} s")
    return data


# --- data ------------------------------------------------------------------------------------
def _report_data(ctx: RunContext, sweep: Sweep, splat_rows, poisson_rows, poisson_info, cases) -> Dict[str, object]:
    rows = aggregate(sweep.view_rows)
    # The front is over the settings a scan allows; mesh-baked probes are the exact reference.
    scan_rows = [r for r in rows if r["source"] == "scan"]
    front = {id(scan_rows[i]) for i in pareto_front(scan_rows, "ms_per_frame", "psnr")}
    for row in rows:
        row["pareto_front"] = id(row) in front
    reference = next((r for r in rows if r["setting"] == sweep.reference_setting), None)
    probe_peer_rows = [dict(r, method=f"probes ({r['setting']})", points=r.get("scan_points"),
                            preparation_seconds=r["bake_seconds"],
                            memory_bytes=r["memory_bytes_per_probe"] * r["probes"])
                       for r in sweep.view_rows if r["setting"] == sweep.reference_setting]
    s = ctx.scene
    data = {
        "format": "lfprobe-report", "format_version": 1,
        "scene": {"path": s.path, "name": s.name, "title": s.title, "mesh": s.mesh,
                  "triangles": ctx.mesh.triangle_count, "world_offset": list(ctx.mesh.world_offset),
                  "scanners": s.scanners, "scan": s.scan,
                  "grid": {"min": s.grid_min, "max": s.grid_max, "counts": s.grid_counts},
                  "views": [{"name": v.name, **{k: ctx.camera(v)[k] for k in ("resolution", "lens")}}
                            for v in ctx.views]},
        "preset": ctx.preset.name,
        "machine": {"cpu_count": os.cpu_count(), "threads": ctx.threads or os.cpu_count(),
                    "platform": platform.platform(), "python": platform.python_version(),
                    "native_version": getattr(ctx.native, "__version__", None)},
        "definitions": dict(metrics.DEFINITIONS),
        "ground_truth": sweep.ground_truth_rows,
        "trace_against_embree": sweep.embree_rows,
        "densities": [{"step_deg": d.step_deg, "points": d.points, "scan_seconds": d.scan_seconds}
                      for d in sweep.densities],
        "reference_setting": sweep.reference_setting,
        "sweep": rows,
        "sweep_views": sweep.view_rows,
        "distance": sweep.distance_rows,
        "walk": sweep.walk_rows,
        "at_probe": sweep.at_probe_rows,
        "peers": {"rows": probe_peer_rows + splat_rows + poisson_rows, "poisson": poisson_info},
        "stability": cases,
    }
    data["findings"] = _findings(data, reference)
    return data


def _series_trend(rows: Sequence[Dict[str, object]], key: str, metric: str) -> List[tuple]:
    pts = sorted((r[key], r[metric]) for r in rows if _finite(r.get(metric)))
    return pts


def _findings(data: Dict[str, object], reference: Optional[Dict[str, object]]) -> Dict[str, List[str]]:
    """Sentences stating what the figures of this run show (no figure is typed in by hand)."""
    f: Dict[str, List[str]] = {"at_probe": [], "distance": [], "resolution": [], "speed": [], "peers": []}
    by_view: Dict[str, List[Dict[str, object]]] = {}
    for r in data["at_probe"]:
        by_view.setdefault(r["view"], []).append(r)
    for view, rows in by_view.items():
        best = [r for r in rows if r.get("filter") == "bilinear"] or rows
        pts = _series_trend(best, "resolution", "psnr")
        if len(pts) >= 2:
            doublings = math.log2(pts[-1][0] / pts[0][0])
            gain = (pts[-1][1] - pts[0][1]) / doublings if doublings else 0.0
            top = max(best, key=lambda r: r["resolution"])
            gt_noise = top["gt_psnr_vs_converged_gt"]
            limit = ("the ground truth's own sampling noise" if top["psnr_vs_converged_gt"] > gt_noise
                     else "the map's resolution")
            at_top = {r.get("filter"): r for r in rows if r["resolution"] == top["resolution"]}
            filters = ", ".join(f"{name} {r['psnr']:.2f} dB" for name, r in at_top.items())
            sentence = (
                f"View '{view}', eye at the probe's centre, mesh-baked probe, bilinear, {top['spp']} samples per "
                f"pixel on both sides: PSNR {pts[0][1]:.2f} dB at {pts[0][0]}² rising to {pts[-1][1]:.2f} dB at "
                f"{pts[-1][0]}² ({gain:+.2f} dB per doubling of the resolution); at {top['resolution']}² by filter: "
                f"{filters}. Against a converged ground truth "
                f"({top['reference_spp']} samples) {top['psnr_vs_converged_gt']:.2f} dB at {top['resolution']}², "
                f"where the {top['spp']}-sample ground truth itself scores {gt_noise:.2f} dB: what limits the error "
                f"there is {limit}.")
            if "silhouette_error_share" in top:
                sentence += (
                    f" The pixels at silhouettes ({100 * top['silhouette_pixels']:.1f} % of the view) carry "
                    f"{100 * top['silhouette_error_share']:.0f} % of the probe's squared error against the converged "
                    f"ground truth (a texel holds one surface; its coverage places the edge inside it, to a fraction "
                    f"of a texel), and {100 * top['gt_silhouette_error_share']:.0f} % of the {top['spp']}-sample "
                    f"ground truth's own.")
            sentence += (
                f" One sample per pixel on both sides gives "
                f"{top['psnr_one_sample_per_pixel']:.2f} dB: aliasing, not the probe. One sample per pixel against "
                f"the {top['spp']}-sample ground truth: {top['psnr_one_sample_vs_filtered_gt']:.2f} dB bilinear, "
                f"{top['psnr_footprint_one_sample_vs_filtered_gt']:.2f} dB with the footprint filter (the probe's "
                f"prefiltered radiance at the pixel's width).")
            f["at_probe"].append(sentence)
    groups: Dict[tuple, List[Dict[str, object]]] = {}
    for r in data["distance"]:
        groups.setdefault((r["source"], r["view"]), []).append(r)
    for (source, view), rows in groups.items():
        pts = _series_trend(rows, "distance_to_nearest_probe", "psnr")
        loss = _series_trend(rows, "distance_to_nearest_probe", "psnr_loss")
        if len(pts) >= 2:
            worst = max(loss, key=lambda p: p[1]) if loss else None
            sentence = (
                f"{source.capitalize()}-baked probes, view '{view}': PSNR {pts[0][1]:.2f} dB with the eye "
                f"{pts[0][0]:.3f} m from the nearest probe, {pts[-1][1]:.2f} dB at {pts[-1][0]:.3f} m; "
                + (f"against a probe at the eye itself the loss is {loss[0][1]:.2f} dB at {loss[0][0]:.3f} m and "
                   f"{loss[-1][1]:.2f} dB at {loss[-1][0]:.3f} m (largest {worst[1]:.2f} dB at {worst[0]:.3f} m)."
                   if loss else "no control figures."))
            guesses = [r for r in sorted(rows, key=lambda r: r["distance_to_nearest_probe"])
                       if r.get("guessed_pixels") is not None and r.get("psnr_off_guesses") is not None]
            if any(r["guessed_pixels"] > 0 for r in guesses):
                sentence += (" Pixels showing guessed surfaces (hole-filled texels: what no scan saw from "
                             "where the stations stood), their share of the squared error, and the PSNR "
                             "over the other pixels: " + "; ".join(
                                 f"{100 * r['guessed_pixels']:.2f} %, {100 * r['guessed_error_share']:.0f} %, "
                                 f"{r['psnr_off_guesses']:.2f} dB at {r['distance_to_nearest_probe']:.3f} m"
                                 for r in guesses) + ".")
                seen = [r for r in guesses if r.get("psnr_seen_exact") is not None]
                if seen:
                    sentence += (" Were all that the scans saw as exact as the mesh-baked probe at the eye, "
                                 "the guesses as they are, the view would score " + "; ".join(
                                     f"{r['psnr_seen_exact']:.2f} dB at {r['distance_to_nearest_probe']:.3f} m"
                                     for r in seen) + ": the bound these scans set at this resolution, made of "
                                 "the guesses' error (what no station saw) and the exact probe's own.")
            f["distance"].append(sentence)
    series: Dict[str, List[Dict[str, object]]] = {}
    for r in data["sweep"]:
        if r["trace"] == DEFAULT_TRACE[0] and r["counts"] == data["scene"]["grid"]["counts"]:
            key = "mesh (exact)" if r["source"] == "mesh" else f"scan {r['scan_step_deg']:g}°, {r['bake']}"
            series.setdefault(key, []).append(r)
    for key, rows in series.items():
        pts = _series_trend(rows, "resolution", "psnr")
        if len(pts) >= 2:
            best = max(pts, key=lambda p: p[1])
            falls = [f"{a[0]}²→{b[0]}² ({b[1] - a[1]:+.2f} dB)" for a, b in zip(pts, pts[1:]) if b[1] < a[1]]
            f["resolution"].append(
                f"{key}: best PSNR {best[1]:.2f} dB at {best[0]}²; "
                + (f"PSNR falls with more resolution at {', '.join(falls)}." if falls
                   else "PSNR does not fall as the resolution grows."))
    front = [r for r in data["sweep"] if r.get("pareto_front")]
    if front:
        f["speed"].append("On the Pareto front of time per frame against PSNR (scan-baked settings): " + "; ".join(
            f"{r['setting']} ({r['ms_per_frame']:.2f} ms, {r['psnr']:.2f} dB)"
            for r in sorted(front, key=lambda r: r["ms_per_frame"])) + ".")
    against = data.get("trace_against_embree") or []
    if against:
        f["speed"].append("Probe trace of the reference setting against Embree on the same rays: " + "; ".join(
            f"'{r['view']}' (eye {r['distance_to_nearest_probe']:.3f} m from a probe) "
            f"{r['trace_rays_per_second'] / 1e6:.2f} M rays/s, {r['trace_over_embree']:.2f}× Embree's single "
            f"rays and {r['trace_over_embree_packets']:.2f}× its packets" for r in against) + ". "
            "Started at their own answers, with no empty space left to skip, the same rays trace at " + "; ".join(
            f"{r['trace_from_answer_over_embree']:.2f}×" for r in against) + " Embree's single rays: "
            "the part of the cost that no skipping of empty space removes.")
        if all(_finite(r.get("trace_texel_over_embree")) for r in against):
            f["speed"].append(
                "Coloured by the texel each ray met alone (the paper's lookup: no filter, no blending, "
                "the same rays), the trace runs at " + "; ".join(
                    f"'{r['view']}' {r['trace_texel_rays_per_second'] / 1e6:.2f} M rays/s "
                    f"({r['trace_texel_over_embree']:.2f}×)" for r in against) +
                " Embree's single rays, which colour nothing: the rest of the default's cost is its "
                "colour, the filter's and the blend's lookups in the probes around each hit.")
    peers_rows = data["peers"]["rows"]
    methods: Dict[str, List[Dict[str, object]]] = {}
    for r in peers_rows:
        methods.setdefault(r["method"].split(" (")[0], []).append(r)
    for name, rows in methods.items():
        ms = [r["ms_per_frame"] for r in rows]
        ps = [r["psnr"] for r in rows if _finite(r.get("psnr"))]
        if ms and ps:
            f["peers"].append(f"{name}: {sum(ms) / len(ms):.2f} ms per frame, PSNR {sum(ps) / len(ps):.2f} dB "
                              f"(mean over {len(rows)} view(s)).")
    if data["peers"]["poisson"].get("error"):
        f["peers"].append(f"Poisson mesh not measured: {data['peers']['poisson']['error']}")
    return f


# --- files -----------------------------------------------------------------------------------
def _write_tables(out_dir: str, data: Dict[str, object]) -> None:
    def without(rows, *keys):
        return [{k: v for k, v in r.items() if k not in keys} for r in rows]

    tables = {
        "sweep.csv": data["sweep"],
        "sweep_views.csv": without(data["sweep_views"], "confusion"),
        "distance.csv": without(data["distance"], "confusion"),
        "walk.csv": without(data["walk"], "confusion"),
        "at_probe.csv": data["at_probe"],
        "peers.csv": without(data["peers"]["rows"], "confusion"),
        "stability.csv": without(data["stability"], "series"),
        "ground_truth.csv": data["ground_truth"],
        "trace_against_embree.csv": data["trace_against_embree"],
    }
    plan = data["planning"]
    if plan is not None:  # a preset that skips the section writes none of its tables
        tables.update({
            "planning_resolution.csv": plan["resolution"]["rows"],
            "planning_walk.csv": plan["placement_frames"],
            "planning_storage.csv": plan.get("storage", []),
            "planning_iterations.csv": without(plan["placement"]["adaptive"]["iterations"], "unknown_rate_per_view"),
        })
    for name, rows in tables.items():
        files.write_csv(os.path.join(out_dir, name), rows)
    files.remove_unwritten(out_dir, tables, lambda name: name in REPORT_TABLES)


def _write_images(ctx: RunContext, sweep: Sweep, data, splat_images, poisson_images) -> Dict[str, bytes]:
    """Writes images/*.png and returns them by name for embedding."""
    pngs: Dict[str, bytes] = {}

    def keep(name: str, png: Optional[bytes]) -> None:
        if png is not None:
            pngs[name] = png
            files.write_bytes(os.path.join(ctx.images_dir, name), png)

    rows = data["sweep"]
    keep("speed_ms_psnr.png", plots.speed_vs_error(rows, "ms_per_frame", "psnr", "time per frame against PSNR, one point per setting"))
    keep("speed_rays_psnr.png", plots.speed_vs_error(rows, "rays_per_second", "psnr", "rays per second against PSNR"))
    keep("speed_ms_ssim.png", plots.speed_vs_error(rows, "ms_per_frame", "ssim", "time per frame against SSIM"))
    keep("speed_ms_flip.png", plots.speed_vs_error(rows, "ms_per_frame", "flip", "time per frame against FLIP"))
    keep("distance_psnr.png", plots.error_vs_distance(data["distance"], data["walk"], "psnr"))
    keep("distance_flip.png", plots.error_vs_distance(data["distance"], data["walk"], "flip"))
    keep("distance_psnr_loss.png", plots.error_vs_distance(data["distance"], [], "psnr_loss"))
    grid_rows = [r for r in rows if r["trace"] == DEFAULT_TRACE[0] and r["counts"] == ctx.scene.grid_counts]
    keep("resolution_psnr.png", plots.error_vs_resolution(grid_rows, "psnr"))
    keep("resolution_flip.png", plots.error_vs_resolution(grid_rows, "flip"))
    keep("at_probe_psnr.png", plots.at_probe(data["at_probe"]))
    peer_rows = data["peers"]["rows"]
    keep("peers_ms.png", plots.bar_peers(peer_rows, "ms_per_frame", "time per frame [ms], log scale",
                                         "render time per frame, same camera", log=True))
    keep("peers_psnr.png", plots.bar_peers(peer_rows, "psnr", "PSNR (sRGB) [dB]", "error against the ground truth"))
    if data["planning"] is not None:
        frames = data["planning"]["placement_frames"]
        walk_axis = "position along the walk (even: a frame placement served; odd: halfway between two)"
        keep("planning_walk_holes.png", plots.walk_by_method(frames, "hole_rate", "hole rate (GT hit, probes not HIT)", walk_axis))
        keep("planning_walk_psnr.png", plots.walk_by_method(frames, "psnr", "PSNR (sRGB) [dB]", walk_axis))
    for label, source in (("probes", sweep.reference_images), ("mesh_probes", sweep.mesh_triplets),
                          ("splats", splat_images), ("poisson", poisson_images)):
        for view, (gt, test, error_map, row) in source.items():
            keep(f"triplet_{label}_{view}.png", images.png_bytes(images.triplet(gt, test, error_map)))
            if label == "probes":
                keep(f"confusion_{view}.png", plots.confusion_matrix(row["confusion"], f"view '{view}', {label}"))
    remove_stale_images(ctx.images_dir, pngs)
    return pngs


def remove_stale_images(images_dir: str, written: Collection[str]) -> List[str]:
    """Deletes the report's own images that this run did not write (a triplet of a view or
    setting an earlier run had, a plot this run had no data for); returns the names removed."""
    return files.remove_unwritten(images_dir, written,
                                  lambda name: name.endswith(".png") and name.startswith(REPORT_IMAGE_PREFIXES))
