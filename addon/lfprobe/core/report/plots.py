"""The report's figures (matplotlib, Agg backend: no display needed). Every function returns
PNG bytes; every axis names its quantity and unit."""

from __future__ import annotations

import io
import math
from typing import Dict, List, Optional, Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from .sweep import pareto_front  # noqa: E402

METRIC_AXES = {
    "psnr": ("PSNR (sRGB) [dB], higher is better", True),
    "ssim": ("SSIM (sRGB, 11×11 σ=1.5) [unitless], higher is better", True),
    "flip": ("mean LDR-FLIP [unitless], lower is better", False),
}


def _png(figure) -> bytes:
    stream = io.BytesIO()
    figure.savefig(stream, format="png", dpi=96, bbox_inches="tight")
    plt.close(figure)
    return stream.getvalue()


def _finite(v) -> bool:
    return v is not None and isinstance(v, (int, float)) and math.isfinite(v)


def speed_vs_error(rows: Sequence[Dict[str, object]], cost: str, metric: str, title: str) -> bytes:
    """One point per setting (mean over the views); the Pareto front of the scan-baked settings
    joined and ringed (mesh-baked probes are the exact reference, not a choice for scans)."""
    cost_axis = {"ms_per_frame": ("time per frame [ms], log scale", False),
                 "rays_per_second": ("rays per second [M rays/s], log scale", True)}[cost]
    label, higher_better = METRIC_AXES[metric]
    figure, axes = plt.subplots(figsize=(7.5, 4.8))
    usable = [r for r in rows if _finite(r.get(cost)) and _finite(r.get(metric))]
    groups: Dict[str, List[Dict[str, object]]] = {}
    for r in usable:
        key = "mesh (exact)" if r["source"] == "mesh" else f"scan {r['scan_step_deg']:g}°, {r['bake']}"
        groups.setdefault(key, []).append(r)
    scale = 1e-6 if cost == "rays_per_second" else 1.0
    for key, group in groups.items():
        axes.scatter([r[cost] * scale for r in group], [r[metric] for r in group], label=key, s=28, alpha=0.85)
    # Cheaper is lower ms or higher rays/s: the front is computed on "cost" in that sense.
    scan = [r for r in usable if r["source"] == "scan"]
    signed = [{"c": (-r[cost] if cost_axis[1] else r[cost]), "q": r[metric]} for r in scan]
    front = sorted(pareto_front(signed, "c", "q", higher_is_better=higher_better), key=lambda i: scan[i][cost])
    if front:
        xs = [scan[i][cost] * scale for i in front]
        ys = [scan[i][metric] for i in front]
        axes.plot(xs, ys, color="black", linewidth=1.0, zorder=0)
        axes.scatter(xs, ys, facecolors="none", edgecolors="black", s=110, linewidths=1.2, label="Pareto front (scan-baked)")
    axes.set_xscale("log")
    # Plain numbers at 1, 2, 3 and 5 of each decade: a range under a decade otherwise labels
    # every minor tick in scientific notation, one over the other.
    axes.xaxis.set_minor_locator(matplotlib.ticker.LogLocator(subs=(2.0, 3.0, 5.0)))
    for formatter in (axes.xaxis.set_major_formatter, axes.xaxis.set_minor_formatter):
        formatter(matplotlib.ticker.FuncFormatter(lambda value, _: f"{value:g}"))
    axes.set_xlabel(cost_axis[0])
    axes.set_ylabel(label)
    axes.set_title(title, fontsize=10)
    axes.grid(True, which="both", alpha=0.3)
    axes.legend(fontsize=7, loc="best")
    return _png(figure)


def _plot_series(axes, rows: Sequence[Dict[str, object]], series_key, x_field: str, y_field: str, style) -> None:
    """One line per series (rows grouped by series_key(row), in the order first seen), its points
    sorted by x_field, rows without a finite y_field left out; style(key) gives plot's keywords."""
    series: Dict[str, List[Dict[str, object]]] = {}
    for r in rows:
        series.setdefault(series_key(r), []).append(r)
    for key, group in series.items():
        group = sorted(group, key=lambda r: r[x_field])
        pts = [(r[x_field], r[y_field]) for r in group if _finite(r.get(y_field))]
        if pts:
            axes.plot(*zip(*pts), **style(key))


def _resolution_axis(axes, rows: Sequence[Dict[str, object]]) -> None:
    """A log2 x axis ticked at the rows' probe resolutions."""
    axes.set_xscale("log", base=2)
    resolutions = sorted({r["resolution"] for r in rows})
    axes.set_xticks(resolutions)
    axes.set_xticklabels([str(r) for r in resolutions])


def error_vs_distance(rows: Sequence[Dict[str, object]], walk_rows: Sequence[Dict[str, object]], metric: str) -> bytes:
    label = METRIC_AXES[metric][0] if metric in METRIC_AXES else (
        "PSNR loss against a probe at the eye [dB], lower is better")
    figure, axes = plt.subplots(figsize=(7.5, 4.5))
    _plot_series(axes, rows, lambda r: f"{r['source']} probes {r['resolution']}², view {r['view']}",
                 "distance_to_nearest_probe", metric, lambda key: dict(marker="o", markersize=4, label=key))
    walk = [(r["distance_to_nearest_probe"], r[metric]) for r in walk_rows if _finite(r.get(metric))]
    if walk:
        axes.scatter(*zip(*walk), marker="x", color="black", label="walk frames (scan probes)")
    axes.set_xlabel("eye's distance from the nearest probe [m]")
    axes.set_ylabel(label)
    axes.set_title(("PSNR loss" if metric == "psnr_loss" else metric.upper()) + " as the eye leaves the probe", fontsize=10)
    axes.grid(True, alpha=0.3)
    axes.legend(fontsize=7)
    return _png(figure)


def error_vs_resolution(rows: Sequence[Dict[str, object]], metric: str) -> bytes:
    label, _ = METRIC_AXES[metric]
    figure, axes = plt.subplots(figsize=(7.5, 4.5))
    _plot_series(axes, rows,
                 lambda r: "mesh (exact)" if r["source"] == "mesh" else f"scan {r['scan_step_deg']:g}° ({r['scan_points']:,} pts), {r['bake']}",
                 "resolution", metric,
                 lambda key: dict(marker="o", markersize=4, label=key, linestyle="--" if "points only" in key else "-"))
    _resolution_axis(axes, rows)
    axes.set_xlabel("fine map resolution N (N×N texels per probe), log scale")
    axes.set_ylabel(label)
    axes.set_title(f"{metric.upper()} against fine resolution (mean over the views)", fontsize=10)
    axes.grid(True, alpha=0.3)
    axes.legend(fontsize=7)
    return _png(figure)


def at_probe(rows: Sequence[Dict[str, object]]) -> bytes:
    figure, axes = plt.subplots(figsize=(7.0, 4.2))
    styles = {"bilinear": ("o", "-"), "bicubic": ("s", "--"), "nearest": ("x", ":")}
    _plot_series(axes, rows, lambda r: f"view {r['view']}, {r['filter']}", "resolution", "psnr",
                 lambda key: dict(marker=styles.get(key.rsplit(", ", 1)[-1], ("x", ":"))[0],
                                  linestyle=styles.get(key.rsplit(", ", 1)[-1], ("x", ":"))[1], label=key))
    _resolution_axis(axes, rows)
    axes.set_xlabel("mesh-baked probe resolution N (N×N), log scale")
    axes.set_ylabel("PSNR, matched samples per pixel [dB]")
    axes.set_title("eye at the probe's centre, probe and ground truth filtered alike", fontsize=10)
    axes.grid(True, alpha=0.3)
    axes.legend(fontsize=7)
    return _png(figure)


def confusion_matrix(counts: Dict[str, Dict[str, int]], title: str) -> bytes:
    """Ground truth {hit, miss} × test {HIT, MISS, UNKNOWN}: counts and row percentages."""
    answers = ["HIT", "MISS", "UNKNOWN"]
    rows = ["gt_hit", "gt_miss"]
    table = [[counts[r][a] for a in answers] for r in rows]
    figure, axes = plt.subplots(figsize=(4.6, 2.4))
    fractions = [[v / max(1, sum(row)) for v in row] for row in table]
    axes.imshow(fractions, cmap="Blues", vmin=0.0, vmax=1.0)
    for i, row in enumerate(table):
        for j, v in enumerate(row):
            axes.text(j, i, f"{v:,}\n{100 * fractions[i][j]:.1f}%", ha="center", va="center", fontsize=8,
                      color="white" if fractions[i][j] > 0.6 else "black")
    axes.set_xticks(range(3))
    axes.set_xticklabels([f"probe {a}" for a in answers], fontsize=8)
    axes.set_yticks(range(2))
    axes.set_yticklabels(["ground truth hit", "ground truth miss"], fontsize=8)
    axes.set_title(title, fontsize=9)
    return _png(figure)


def bar_peers(rows: Sequence[Dict[str, object]], key: str, ylabel: str, title: str, log: bool = False) -> Optional[bytes]:
    usable = [r for r in rows if _finite(r.get(key))]
    if not usable:
        return None
    figure, axes = plt.subplots(figsize=(7.0, 3.6))
    labels = [f"{r['method']}\n{r['view']}" for r in usable]
    axes.bar(range(len(usable)), [r[key] for r in usable], color="tab:blue")
    axes.set_xticks(range(len(usable)))
    axes.set_xticklabels(labels, fontsize=7, rotation=20, ha="right")
    axes.set_ylabel(ylabel)
    if log:
        axes.set_yscale("log")
    axes.set_title(title, fontsize=10)
    axes.grid(True, axis="y", alpha=0.3)
    return _png(figure)


def walk_by_method(rows: Sequence[Dict[str, object]], key: str, ylabel: str,
                   xlabel: str = "walk frame") -> Optional[bytes]:
    """One line per placement method over the walk's frames (report section "planning")."""
    series: Dict[str, List[tuple]] = {}
    for r in rows:
        if _finite(r.get(key)):
            series.setdefault(r["method"], []).append((r["frame"], r[key]))
    if not series:
        return None
    frames = sorted({f for pts in series.values() for f, _ in pts})
    figure, axes = plt.subplots(figsize=(7.0, 3.6))
    for method, pts in series.items():
        axes.plot([frames.index(f) for f, _ in pts], [v for _, v in pts], marker="o", markersize=4, label=method)
    axes.set_xlabel(xlabel)
    axes.set_ylabel(ylabel)
    axes.set_title(f"{ylabel.split(' (')[0]} along the walk", fontsize=10)
    axes.grid(True, alpha=0.3)
    axes.legend(fontsize=8)
    return _png(figure)
