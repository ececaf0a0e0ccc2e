"""The report section "Model only what a scene needs": automatic per-probe resolution against
every fixed resolution, adaptive placement against a uniform grid of the same memory along the
scene's walk, and bytes per probe at equal error against the paper's 24.375 MB per 2048² probe."""

from __future__ import annotations

import dataclasses
import math
import shutil
import time
from collections import Counter
from typing import Dict, List, Optional

from .. import pipeline
from ..adaptive import place_adaptively
from ..pipeline import BakeOptions, ProbePlacementSpec
from ..probe_set import PAPER_BYTES_PER_2048_PROBE, read_manifest
from .measure import RunContext, measure, nearest_probe_distance, pixel_count, timing
from .presets import COMPACT_TRACE, DEFAULT_TRACE
from .scene import grid_positions
from .sweep import Sweep, aggregate, scaled_grid, setup_label

# "Matches the best fixed resolution's error": mean PSNR over the views within this margin.
PSNR_MATCH_DB = 0.1
AUTO_SETTING = "auto (bake --auto: resolution from the data, classified)"
AUTO_UNCLASSIFIED_SETTING = "auto resolution only (bake --auto --no-classify), compact storage"


def _finite(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _mean(rows: List[Dict[str, object]], key: str) -> Optional[float]:
    values = [r[key] for r in rows if _finite(r.get(key))]
    return sum(values) / len(values) if values else None


def _fixed_rows(ctx: RunContext, sweep: Sweep, trace=DEFAULT_TRACE) -> List[Dict[str, object]]:
    """The sweep's fixed-resolution settings on the densest scan, scene grid, lfprobe's bake,
    `trace` (the default trace, or the default trace on compact storage): one aggregated row per
    resolution."""
    densest = sweep.densities[0]
    rows = [r for r in sweep.view_rows
            if r["source"] == "scan" and r["scan_step_deg"] == densest.step_deg and r["bake"] == "splat + fill"
            and r["counts"] == list(ctx.scene.grid_counts) and r["trace"] == trace[0]]
    compact = trace[1].get("storage") == "compact"
    out = []
    for row in sorted(aggregate(rows), key=lambda r: r["resolution"]):
        out.append({"setting": f"fixed {row['resolution']}²" + (", compact storage" if compact else ""),
                    "resolution": row["resolution"], "storage": "compact" if compact else "full",
                    "resolutions": [row["resolution"]] * row["probes"],
                    "resolution_summary": f"{row['resolution']}² × {row['probes']}", "probes": row["probes"],
                    **{k: row.get(k) for k in ("psnr", "ssim", "flip", "hole_rate", "unknown_rate", "depth_absrel",
                                               "depth_rmse", "ms_per_frame", "bake_seconds",
                                               "memory_bytes_per_probe")},
                    "memory_bytes": row["memory_bytes_per_probe"] * row["probes"]})
    return out


def storage_comparison(full: List[Dict[str, object]], compact: List[Dict[str, object]]) -> List[Dict[str, object]]:
    """Per fixed resolution: the same probes loaded full and compact, error and memory side by side."""
    by_resolution = {r["resolution"]: r for r in compact}
    out = []
    for f in full:
        c = by_resolution.get(f["resolution"])
        if c is None:
            continue
        row = {"resolution": f["resolution"], "probes": f["probes"]}
        for key in ("psnr", "flip", "depth_absrel", "depth_rmse", "hole_rate", "ms_per_frame", "memory_bytes_per_probe"):
            row[f"full_{key}"], row[f"compact_{key}"] = f.get(key), c.get(key)
        row["psnr_difference_db"] = (c["psnr"] - f["psnr"]) if _finite(c.get("psnr")) and _finite(f.get("psnr")) else None
        row["memory_ratio"] = c["memory_bytes_per_probe"] / f["memory_bytes_per_probe"]
        out.append(row)
    return out


def _auto_rows(ctx: RunContext, sweep: Sweep) -> List[Dict[str, object]]:
    """The planned bake (bake --auto with the CLI's defaults: compact storage) of the scene grid
    from the densest scan, traced and measured on every view, with the same probes loaded at full
    precision; and the plan's resolutions without classification (no probe moved or dropped),
    which tells the resolution choice from the moves."""
    densest = sweep.densities[0]
    s = ctx.scene
    placement = ProbePlacementSpec(grid_min=s.grid_min, grid_max=s.grid_max, counts=s.grid_counts)
    rows = []
    for name, plan, storages in (("unclassified", {"classify": False}, ("compact",)),
                                 ("auto", {}, ("full", "compact"))):
        folder = ctx.work_path("planning", name)
        start = time.perf_counter()
        summary = pipeline.bake_from_cloud(densest.cloud, folder, placement, BakeOptions(plan=plan, storage="compact"),
                                           cache_dir=ctx.cache_dir)
        wall = time.perf_counter() - start
        for storage in storages:
            row = _auto_row(ctx, folder, summary, wall, storage)
            if name == "unclassified":
                row["setting"] = AUTO_UNCLASSIFIED_SETTING
            rows.append(row)
        shutil.rmtree(folder, ignore_errors=True)
    return rows


def _auto_row(ctx: RunContext, folder: str, summary: dict, wall: float, storage: str) -> Dict[str, object]:
    manifest = read_manifest(folder)
    plan = manifest["bake"].get("plan", [])
    field = ctx.native.ProbeField.load(folder, storage=storage)
    view_rows = []
    for view in ctx.views:
        camera = ctx.camera(view)
        gt, _ = ctx.ground_truth(camera)
        image, stats = ctx.render_probes(field, camera, DEFAULT_TRACE[1])
        figures, _ = measure(gt, image)
        figures.pop("confusion")
        view_rows.append({**figures, **timing(stats, pixel_count(camera))})
    kept = [p["resolution"] for p in plan if not p["dropped"]]
    row = {"setting": AUTO_SETTING + (", compact storage" if storage == "compact" else ", full storage"),
           "storage": storage, "resolution": None, "resolutions": sorted(kept),
           "resolution_counts": {str(k): v for k, v in sorted(Counter(kept).items())},
           "resolution_summary": ", ".join(f"{k}² × {v}" for k, v in sorted(Counter(kept).items()))
           + (f", {len(plan) - len(kept)} dropped" if len(plan) > len(kept) else ""),
           "probes": field.probe_count,
           **{k: _mean(view_rows, k) for k in ("psnr", "ssim", "flip", "hole_rate", "unknown_rate", "depth_absrel",
                                               "depth_rmse", "ms_per_frame")},
           "bake_seconds": summary["bake_seconds"] + summary.get("normals_seconds", 0.0),
           "bake_wall_seconds": wall,
           "memory_bytes": field.memory_bytes, "memory_bytes_per_probe": field.memory_bytes / field.probe_count,
           "moved": sum(1 for p in plan if p["moved"]), "dropped": sum(1 for p in plan if p["dropped"]),
           "classes": dict(Counter(p["class"] for p in plan)),
           "data_resolution_median": _median([p["data_resolution"] for p in plan if p.get("data_resolution")])}
    del field
    return row


def _median(values: List[float]) -> Optional[float]:
    values = sorted(values)
    if not values:
        return None
    mid = len(values) // 2
    return values[mid] if len(values) % 2 else 0.5 * (values[mid - 1] + values[mid])


def resolution_comparison(fixed: List[Dict[str, object]], auto: Dict[str, object]) -> Dict[str, object]:
    """Does auto match the best fixed resolution's error (PSNR within PSNR_MATCH_DB) with no
    more memory? The figures either way."""
    best = max((r for r in fixed if _finite(r.get("psnr"))), key=lambda r: r["psnr"])
    return {
        "best_fixed": best["setting"], "best_fixed_psnr": best["psnr"], "best_fixed_flip": best["flip"],
        "best_fixed_memory_bytes": best["memory_bytes"], "auto_psnr": auto["psnr"], "auto_flip": auto["flip"],
        "auto_memory_bytes": auto["memory_bytes"],
        "psnr_difference_db": auto["psnr"] - best["psnr"],
        "flip_difference": auto["flip"] - best["flip"],
        "memory_ratio": auto["memory_bytes"] / best["memory_bytes"],
        "matches_best_error": auto["psnr"] >= best["psnr"] - PSNR_MATCH_DB,
        "no_more_memory": auto["memory_bytes"] <= best["memory_bytes"],
        "criterion": f"auto's mean PSNR over the views at least the best fixed resolution's minus "
                     f"{PSNR_MATCH_DB} dB, with total memory at most that setting's",
    }


def _uniform_counts(ctx: RunContext, probes: int):
    """The grid over the scene grid's box whose probe count is nearest `probes` (fewer on a tie),
    and among those the one with the most even spacing over its axes."""
    s = ctx.scene
    extent = [hi - lo for lo, hi in zip(s.grid_min, s.grid_max)]
    best = None
    for nx in range(1, 2 * s.grid_counts[0] + 2):
        for ny in range(1, 2 * s.grid_counts[1] + 2):
            for nz in range(1, 2 * s.grid_counts[2] + 2):
                counts = [nx, ny, nz]
                if any(n > 1 and e == 0.0 for n, e in zip(counts, extent)):
                    continue
                # One probe on an axis leaves the whole extent to it: count that as its spacing.
                spacing = [e / (n - 1) if n > 1 else e for n, e in zip(counts, extent) if e > 0.0]
                evenness = max(spacing) / min(spacing) if spacing else 1.0
                total = nx * ny * nz
                key = (abs(total - probes), total, evenness)
                if best is None or key < best[0]:
                    best = (key, counts)
    counts = best[1]
    # An axis with one probe puts it in the middle of the box (as scaled_grid does).
    lo = [lo if n > 1 else 0.5 * (lo + hi) for lo, hi, n in zip(s.grid_min, s.grid_max, counts)]
    hi = [hi if n > 1 else 0.5 * (l + hi) for l, hi, n in zip(s.grid_min, s.grid_max, counts)]
    return lo, hi, counts


def _evaluation_walk(ctx: RunContext):
    """The frames placement serves and, when the scene has a walk, the frames halfway between
    them (which placement never saw): (views, placed_for flags)."""
    s = ctx.scene
    if not s.walk:
        return list(ctx.views), [True] * len(ctx.views)
    frames = s.walk["frames"]
    dense = dataclasses.replace(s, walk=dict(s.walk, frames=2 * frames - 1)).walk_views() if frames > 1 else s.walk_views()
    views = []
    for k, view in enumerate(dense):
        view.name = f"walk_{k / 2:06.2f}" if len(dense) > frames else view.name
        views.append(view)
    return views, [k % 2 == 0 or len(dense) == frames for k in range(len(dense))]


def _walk_rows(ctx: RunContext, field, method: str, walk, placed_for, positions, memory: int) -> List[Dict[str, object]]:
    rows = []
    for view, seen in zip(walk, placed_for):
        camera = ctx.camera(view)
        gt, _ = ctx.ground_truth(camera)
        image, stats = ctx.render_probes(field, camera, DEFAULT_TRACE[1])
        figures, _ = measure(gt, image)
        figures.pop("confusion")
        rows.append({"method": method, "frame": view.name, "placed_for": seen,
                     "probes": len(positions), "memory_bytes": memory,
                     "distance_to_nearest_probe": nearest_probe_distance(view.position, positions),
                     **timing(stats, pixel_count(camera)), **figures})
    return rows


def placement_comparison(ctx: RunContext, sweep: Sweep, fixed: List[Dict[str, object]]) -> Dict[str, object]:
    """Adaptive placement (a half-density base grid plus probes at the walk's eyes, within the
    memory of the scene grid) against a uniform grid of as near the same probe count as the
    scene grid's proportions allow, all probes at the sweep's reference resolution."""
    p, s = ctx.preset, ctx.scene
    densest = sweep.densities[0]
    walk = s.walk_views() or list(ctx.views)
    cameras = [ctx.camera(v) for v in walk]
    resolution = p.middle_fine_resolution()
    per_probe = next(r["memory_bytes_per_probe"] for r in fixed if r["resolution"] == resolution)
    full_probes = s.grid_counts[0] * s.grid_counts[1] * s.grid_counts[2]
    budget = per_probe * full_probes
    base_lo, base_hi, base_counts = scaled_grid(ctx, p.planning_base_factor)
    folder = ctx.work_path("planning", "adaptive")
    start = time.perf_counter()
    result = place_adaptively(densest.cloud, cameras, folder,
                              base_grid={"min": base_lo, "max": base_hi, "counts": base_counts},
                              resolution=resolution, target_unknown=p.planning_target_unknown,
                              budget_bytes=budget, max_added=p.planning_max_added, threads=ctx.threads,
                              log=ctx.log)
    adaptive_seconds = time.perf_counter() - start
    adaptive_field = ctx.native.ProbeField.load(folder)
    manifest = read_manifest(folder)
    adaptive_positions = [_world(manifest, r) for r in manifest["probes"]]
    evaluation, placed_for = _evaluation_walk(ctx)
    rows = _walk_rows(ctx, adaptive_field, "adaptive", evaluation, placed_for, adaptive_positions,
                      adaptive_field.memory_bytes)
    adaptive_memory, adaptive_probes = adaptive_field.memory_bytes, adaptive_field.probe_count
    del adaptive_field
    shutil.rmtree(folder, ignore_errors=True)

    lo, hi, counts = _uniform_counts(ctx, adaptive_probes)
    uniform_folder = ctx.work_path("planning", "uniform")
    summary = pipeline.bake_from_cloud(densest.cloud, uniform_folder,
                                       ProbePlacementSpec(grid_min=lo, grid_max=hi, counts=counts),
                                       BakeOptions(resolution=resolution), cache_dir=ctx.cache_dir)
    uniform_field = ctx.native.ProbeField.load(uniform_folder)
    uniform_positions = grid_positions(lo, hi, counts)
    rows += _walk_rows(ctx, uniform_field, "uniform grid", evaluation, placed_for, uniform_positions,
                       uniform_field.memory_bytes)
    uniform_memory = uniform_field.memory_bytes
    del uniform_field
    shutil.rmtree(uniform_folder, ignore_errors=True)

    def means(method: str) -> Dict[str, object]:
        keys = ("hole_rate", "unknown_rate", "psnr", "ssim", "flip", "ms_per_frame")
        group = [r for r in rows if r["method"] == method and r["placed_for"]]
        between = [r for r in rows if r["method"] == method and not r["placed_for"]]
        return {**{k: _mean(group, k) for k in keys},
                "between_frames": {k: _mean(between, k) for k in keys} if between else None}

    return {
        "resolution": resolution, "frames": len(walk), "between_frames": placed_for.count(False),
        "target_unknown": p.planning_target_unknown,
        "budget_bytes": budget, "base_counts": base_counts,
        "adaptive": {"probes": adaptive_probes, "memory_bytes": adaptive_memory, "added": len(result.added),
                     "stopped_because": result.stopped_because, "seconds": adaptive_seconds,
                     "bake_seconds": result.bake_seconds, "iterations": result.iterations,
                     "added_probes": result.added, **means("adaptive")},
        "uniform": {"counts": counts, "probes": counts[0] * counts[1] * counts[2], "memory_bytes": uniform_memory,
                    "bake_seconds": summary["bake_seconds"] + summary.get("normals_seconds", 0.0),
                    **means("uniform grid")},
        # The scene's own grid at the same resolution (the sweep's reference set, measured on the
        # walk by the sweep): what the designed grid scores with the whole budget.
        "scene_grid": {"counts": list(s.grid_counts), "probes": full_probes, "memory_bytes": budget,
                       **{k: _mean(sweep.walk_rows, k) for k in ("hole_rate", "unknown_rate", "psnr", "ssim", "flip",
                                                                 "ms_per_frame")}} if sweep.walk_rows else None,
        "frames_rows": rows,
    }


def _world(manifest: dict, record: dict) -> List[float]:
    return [o + c for o, c in zip(manifest["world_offset"], record["position"])]


def bytes_at_equal_error(rows: List[Dict[str, object]], reference: Dict[str, object]) -> Dict[str, object]:
    """The smallest memory per probe among the settings whose mean PSNR reaches the reference's
    (the largest fixed resolution on the densest scan) within PSNR_MATCH_DB, the margin auto is
    judged by, per probe and against the paper."""
    reaching = [r for r in rows
                if _finite(r.get("psnr")) and r["psnr"] >= reference["psnr"] - PSNR_MATCH_DB] or [reference]
    smallest = min(reaching, key=lambda r: (r["memory_bytes_per_probe"], r["memory_bytes"]))
    return {
        "reference_setting": reference["setting"], "reference_psnr": reference["psnr"],
        "reference_bytes_per_probe": reference["memory_bytes_per_probe"],
        "setting": smallest["setting"], "psnr": smallest["psnr"], "flip": smallest.get("flip"),
        "bytes_per_probe": smallest["memory_bytes_per_probe"], "memory_bytes": smallest["memory_bytes"],
        "paper_bytes_per_2048_probe": PAPER_BYTES_PER_2048_PROBE,
        "fraction_of_paper": smallest["memory_bytes_per_probe"] / PAPER_BYTES_PER_2048_PROBE,
        "reference_fraction_of_paper": reference["memory_bytes_per_probe"] / PAPER_BYTES_PER_2048_PROBE,
        "candidates": len(rows), "margin_db": PSNR_MATCH_DB,
    }


def run(ctx: RunContext, sweep: Sweep) -> Dict[str, object]:
    ctx.log("model only what a scene needs: auto resolution, adaptive placement")
    fixed = _fixed_rows(ctx, sweep)
    fixed_compact = _fixed_rows(ctx, sweep, COMPACT_TRACE)
    unclassified, auto_full, auto = _auto_rows(ctx, sweep)
    ctx.log(f"  auto: {auto['probes']} probes, resolutions {auto['resolution_counts']}, "
            f"PSNR {auto['psnr']:.2f} dB, {auto['memory_bytes'] / 2**20:.2f} MiB compact, "
            f"{auto_full['psnr']:.2f} dB, {auto_full['memory_bytes'] / 2**20:.2f} MiB full")
    resolution_rows = fixed + fixed_compact + [unclassified, auto_full, auto]
    # bake --auto (compact) against the best of every fixed resolution, stored either way.
    comparison = resolution_comparison(fixed + fixed_compact, auto)
    comparison["unclassified_psnr"] = unclassified["psnr"]
    comparison["unclassified_memory_bytes"] = unclassified["memory_bytes"]
    placement = placement_comparison(ctx, sweep, fixed)
    # Equal error: every scan-baked setting of the sweep (default trace, full or compact) and auto.
    scan_settings = [dict(r, memory_bytes=r["memory_bytes_per_probe"] * r["probes"])
                     for r in aggregate(sweep.view_rows)
                     if r["source"] == "scan" and r["trace"] in (DEFAULT_TRACE[0], COMPACT_TRACE[0])]
    for r in scan_settings:
        r["setting"] = setup_label(r) + (", compact storage" if r.get("storage") == "compact" else "")
    reference = dict(fixed[-1], setting=f"scan {sweep.densities[0].step_deg:g}°, splat + fill, {fixed[-1]['setting']}")
    equal_error = bytes_at_equal_error(scan_settings + [unclassified, auto_full, auto], reference)
    return {"resolution": {"rows": resolution_rows, **comparison},
            "storage": storage_comparison(fixed, fixed_compact),
            "placement": {k: v for k, v in placement.items() if k != "frames_rows"},
            "placement_frames": placement["frames_rows"],
            "bytes_at_equal_error": equal_error}


def findings(planning: Dict[str, object]) -> List[str]:
    """Sentences that state what this run's planning figures show."""
    r, pl, eq = planning["resolution"], planning["placement"], planning["bytes_at_equal_error"]
    mib = 1024.0 * 1024.0
    holds = r["matches_best_error"] and r["no_more_memory"]
    out = [
        f"Automatic resolution: mean PSNR {r['auto_psnr']:.2f} dB (FLIP {r['auto_flip']:.4f}) with "
        f"{r['auto_memory_bytes'] / mib:.2f} MiB; the best fixed resolution, {r['best_fixed']}, "
        f"{r['best_fixed_psnr']:.2f} dB (FLIP {r['best_fixed_flip']:.4f}) with "
        f"{r['best_fixed_memory_bytes'] / mib:.2f} MiB: {r['psnr_difference_db']:+.2f} dB at "
        f"{r['memory_ratio']:.2f}× the memory. "
        + ("Auto matches the best fixed resolution's error with no more memory."
           if holds else
           "Auto does NOT match the best fixed resolution's error with no more memory ("
           + ("PSNR within the margin" if r["matches_best_error"] else f"{-r['psnr_difference_db']:.2f} dB worse")
           + ", " + ("memory no more" if r["no_more_memory"] else f"{(r['memory_ratio'] - 1) * 100:.0f} % more memory")
           + ").")
        + (f" The same resolutions without classification (no probe moved or dropped): "
           f"{r['unclassified_psnr']:.2f} dB." if _finite(r.get("unclassified_psnr")) else ""),
    ]
    a, u = pl["adaptive"], pl["uniform"]
    out.append(
        f"Along the walk ({pl['frames']} frames, probes of {pl['resolution']}²): adaptive placement "
        f"({a['probes']} probes: {pl['base_counts']} base grid + {a['added']} at the eyes, "
        f"{a['memory_bytes'] / mib:.2f} MiB; stopped: {a['stopped_because']}) holes {a['hole_rate']:.2%}, "
        f"PSNR {a['psnr']:.2f} dB, FLIP {a['flip']:.4f}; uniform grid {u['counts']} ({u['probes']} probes, "
        f"{u['memory_bytes'] / mib:.2f} MiB) holes {u['hole_rate']:.2%}, PSNR {u['psnr']:.2f} dB, "
        f"FLIP {u['flip']:.4f} (means over the frames placement served)."
        + (f" On the {pl['between_frames']} frames halfway between them, which placement never saw: adaptive "
           f"holes {a['between_frames']['hole_rate']:.2%}, PSNR {a['between_frames']['psnr']:.2f} dB; uniform "
           f"holes {u['between_frames']['hole_rate']:.2%}, PSNR {u['between_frames']['psnr']:.2f} dB."
           if a.get("between_frames") else "")
        + (f" The scene's own grid {pl['scene_grid']['counts']} at {pl['resolution']}² "
           f"({pl['scene_grid']['memory_bytes'] / mib:.2f} MiB) on the same frames: holes "
           f"{pl['scene_grid']['hole_rate']:.2%}, PSNR {pl['scene_grid']['psnr']:.2f} dB."
           if pl.get("scene_grid") else ""))
    storage = planning.get("storage") or []
    if storage:
        worst = min(storage, key=lambda r: r["psnr_difference_db"] if _finite(r.get("psnr_difference_db")) else 0.0)
        out.append(
            "Storage sized to the data (the same probes loaded compact: 8-bit sRGB radiance, 16-bit distance in "
            "1 mm steps, 8+8-bit octahedral normals, no confidence; 7 bytes a texel against 18): "
            + "; ".join(f"{r['resolution']}² {r['full_memory_bytes_per_probe'] / mib:.2f} → "
                        f"{r['compact_memory_bytes_per_probe'] / mib:.2f} MiB per probe "
                        f"({r['memory_ratio']:.2f}×), PSNR {r['full_psnr']:.2f} → {r['compact_psnr']:.2f} dB"
                        for r in storage)
            + f". The largest PSNR change is {worst['psnr_difference_db']:+.3f} dB (at {worst['resolution']}²).")
    out.append(
        f"At equal error (mean PSNR within {eq['margin_db']:g} dB of {eq['reference_psnr']:.2f} dB, "
        f"{eq['reference_setting']}): the "
        f"smallest memory per probe is {eq['bytes_per_probe'] / mib:.3f} MiB ({eq['setting']}), "
        f"{eq['fraction_of_paper']:.2%} of the paper's 24.375 MB per 2048² probe "
        f"(the reference setting: {eq['reference_bytes_per_probe'] / mib:.3f} MiB, "
        f"{eq['reference_fraction_of_paper']:.2%}).")
    return out
