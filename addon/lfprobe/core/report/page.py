"""The report page's content: report.html's sections, tables and figures, in order, from
report.json's data and the PNG images (html.py holds the page's building blocks)."""

from __future__ import annotations

import math
from typing import Dict, Optional

from . import html, stability
from .html import num, table, text
from .peers import POISSON_NORMALS

MIB = 1024.0 * 1024.0
METRIC_COLUMNS = [
    ("psnr", "PSNR dB", num(".2f")), ("psnr_answered", "PSNR dB answered", num(".2f")),
    ("ssim", "SSIM", num(".4f")), ("flip", "FLIP", num(".4f")),
    ("depth_absrel", "depth AbsRel", num(".3%", 1.0)), ("hole_rate", "holes", num(".2%")),
    ("wrong_surface_rate", "wrong surface", num(".2%")),
    ("false_hit_rate", "false hits", num(".2%")), ("false_miss_rate", "false misses", num(".2%")),
]


SETTING_COLUMNS = [
    ("setting", "setting", text), ("ms_per_frame", "ms/frame", num(".2f")),
    ("rays_per_second", "M rays/s", num(".2f", 1e-6)), *METRIC_COLUMNS,
    ("texels_per_ray", "texels/ray", num(".1f")), ("probes_per_ray", "probes/ray", num(".2f")),
    ("memory_bytes_per_probe", "MiB/probe (memory)", num(".2f", 1 / MIB)),
    ("disk_bytes_per_probe", "MiB/probe (disk)", num(".2f", 1 / MIB)),
    ("bake_seconds", "bake s", num(".2f")), ("bake_seconds_per_probe", "bake s/probe", num(".3f")),
    ("coverage_unknown", "unknown texels", num(".2%")),
]


def render_page(data: Dict[str, object], pngs: Dict[str, bytes]) -> str:
    """report.html from report.json's data and the images by file name."""
    scene = data["scene"]
    page = html.Page(f"lfprobe error analysis: {scene['title']}")

    def img(name: str, caption: str, width: Optional[int] = None, pixelated: bool = False) -> None:
        if name in pngs:
            page.add(html.image(pngs[name], caption, width, pixelated))

    def findings(key: str) -> None:
        for sentence in data["findings"].get(key, []):
            page.paragraph(sentence, "finding")

    _introduction_section(page, data)
    _definitions_section(page, data)
    _speed_section(page, data, img, findings)
    _distance_section(page, data, img, findings)
    _at_probe_section(page, data, img, findings)
    _resolution_section(page, data, img, findings)
    _images_section(page, data, img)
    _peers_section(page, data, img, findings)
    _planning_section(page, data, img)
    _stability_section(page, data)
    return page.render()


def _introduction_section(page, data: Dict[str, object]) -> None:
    """What was run, where and on what."""
    scene = data["scene"]
    m = data["machine"]
    page.paragraph(
        f"Scene {scene['name']} ({scene['path']}), mesh {scene['mesh']} with {scene['triangles']:,} triangles, "
        f"world offset {tuple(round(c, 3) for c in scene['world_offset'])}. Preset '{data['preset']}', run "
        f"{data['started']} in {data['seconds']:.1f} s on {m['cpu_count']} cores ({m['threads']} threads), "
        f"{m['platform']}, Python {m['python']}. Every figure below was measured in this run.")
    page.paragraph("Scans: " + "; ".join(f"{d['step_deg']:g}° step → {d['points']:,} points "
                                         f"({d['scan_seconds']:.2f} s)" for d in data["densities"])
                   + f" from {len(scene['scanners'])} scanner(s), range noise σ {scene['scan']['noise_mm']:g} mm at 10 m; each "
                   "point's colour is the texture's mean over its footprint (the step times the range), as a "
                   f"scanner's camera records it. Probe grid {scene['grid']['counts']} from "
                   f"{scene['grid']['min']} to {scene['grid']['max']}.", "note")


def _definitions_section(page, data: Dict[str, object]) -> None:
    """The metrics' definitions and the ground truth's figures."""
    page.section("definitions", "Metrics")
    page.add(table([{"metric": k, "definition": v} for k, v in data["definitions"].items()],
                   [("metric", "metric", text), ("definition", "definition", text)]))
    page.paragraph("Ground truth: Embree rays against the reference mesh from the same camera (unlit base colour; "
                   "n×n stratified samples per pixel for the colour). Its agreement with Blender's Cycles "
                   "(emission-only materials, box filter 1 px) is checked by tests/python/test_cycles_agreement.py.", "note")
    page.add(table(data["ground_truth"], [("view", "view", text), ("width", "w", num(".0f")), ("height", "h", num(".0f")),
                                          ("spp", "spp", num(".0f")), ("seconds", "gt render s", num(".3f")),
                                          ("embree_primary_rays_per_second", "Embree primary M rays/s", num(".2f", 1e-6))]))


def _speed_section(page, data: Dict[str, object], img, findings) -> None:
    """Speed against error over the sweep's settings, and the probe trace against Embree."""
    page.section("speed", "Speed against error")
    page.paragraph("One point per setting: fine resolution, probe count, scan density and bake variant, and trace "
                   "settings (mode, surface thickness, coarse min-distance levels). Time is the native renderer's own "
                   "time for the frame (fastest of the preset's repeats), averaged over the views; errors are averaged "
                   "over the views. Ringed points are on the Pareto front of the scan-baked settings (no other is both faster and "
                   "better); mesh-baked probes are the exact reference, not an option for scans.", "note")
    for name, caption in (("speed_ms_psnr.png", "time per frame [ms] against PSNR [dB]"),
                          ("speed_rays_psnr.png", "rays per second [M rays/s] against PSNR [dB]"),
                          ("speed_ms_ssim.png", "time per frame [ms] against SSIM"),
                          ("speed_ms_flip.png", "time per frame [ms] against FLIP (lower is better)")):
        img(name, caption, 560)
    findings("speed")
    page.add(table(data["sweep"], SETTING_COLUMNS, highlight=lambda r: bool(r.get("pareto_front"))))
    page.paragraph("Highlighted rows: Pareto front of ms/frame against PSNR. Per-view rows: sweep_views.csv.", "note")
    page.paragraph(f"Probe trace of the reference setting ({data['reference_setting']}) against Embree on the "
                   "scene's mesh: the same camera rays, made beforehand and timed as trace only, fastest of the "
                   "preset's repeats; Embree with single rays (rtcIntersect1) and in packets flagged coherent (its fastest of 4, 8 "
                   "and 16 rays a call). The aims: more than Embree with the eye at a probe, a third of it "
                   "elsewhere. 'From answer': the same rays started where their own traces ended (the HIT, or "
                   "as far as an UNKNOWN proved them free), so that nothing is left to skip; what they cost is "
                   "the floor under the figure before it. 'Texel colour': the same rays coloured by the texel "
                   "each met alone (no filter, no blending), as Embree's figure includes no colour at all.", "note")
    page.add(table(data["trace_against_embree"], [
        ("view", "view", text), ("distance_to_nearest_probe", "eye to probe m", num(".3f")),
        ("texels_per_ray", "texels/ray", num(".1f")), ("probes_per_ray", "probes/ray", num(".2f")),
        ("trace_rays_per_second", "probe trace M rays/s", num(".2f", 1e-6)),
        ("embree_rays_per_second", "Embree M rays/s", num(".2f", 1e-6)),
        ("embree_packet_rays_per_second", "Embree packets M rays/s", num(".2f", 1e-6)),
        ("trace_over_embree", "trace / Embree", num(".3f")),
        ("trace_over_embree_packets", "trace / packets", num(".3f")),
        ("trace_from_answer_over_embree", "from answer / Embree", num(".3f")),
        ("trace_texel_rays_per_second", "texel colour M rays/s", num(".2f", 1e-6)),
        ("trace_texel_over_embree", "texel colour / Embree", num(".3f"))]))


def _distance_section(page, data: Dict[str, object], img, findings) -> None:
    """Error against the eye's distance from the nearest probe, and the walk."""
    page.section("distance", "Error against the eye's distance from the nearest probe")
    page.paragraph("Each view's eye is moved from the probe nearest to it toward the centre of the grid cell beside it "
                   "(the point farthest from every probe), keeping the viewing direction. Mesh-baked probes isolate "
                   "the tracing error; scan-baked probes add the scan's. Crosses: the scene's walk. What the eye sees "
                   "changes as it moves, so each eye also gets a control: a mesh-baked probe of the same resolution "
                   "placed at the eye itself; the PSNR loss against it is the error due to the distance. 'on guesses': "
                   "the pixels whose centre sample met a hole-filled texel (a surface no scan saw from where the "
                   "stations stood, guessed from the surfaces around it); 'their error': their share of the squared "
                   "error; 'PSNR dB off guesses': the PSNR over the other pixels; 'PSNR dB, seen as exact': the PSNR "
                   "with every pixel that is not a guess taken from the mesh-baked probe at the eye, the guesses "
                   "as they are: the most this view can score from these scans at this resolution.", "note")
    img("distance_psnr.png", "PSNR [dB] against distance to the nearest probe [m]", 560)
    img("distance_flip.png", "FLIP against distance to the nearest probe [m]", 560)
    img("distance_psnr_loss.png", "PSNR loss [dB] against a mesh-baked probe of the same resolution at the eye, "
        "against distance to the nearest probe [m]", 560)
    findings("distance")
    page.add(table(data["distance"], [("source", "probes", text), ("view", "view", text),
                                      ("resolution", "N", num(".0f")),
                                      ("distance_to_nearest_probe", "distance m", num(".3f")),
                                      ("ms_per_frame", "ms/frame", num(".2f")),
                                      ("texels_per_ray", "texels/ray", num(".1f")), *METRIC_COLUMNS,
                                      ("psnr_probe_at_eye", "PSNR dB, probe at eye", num(".2f")),
                                      ("psnr_loss", "PSNR loss dB", num(".2f")),
                                      ("guessed_pixels", "on guesses", num(".2%")),
                                      ("guessed_error_share", "their error", num(".0%")),
                                      ("psnr_off_guesses", "PSNR dB off guesses", num(".2f")),
                                      ("psnr_seen_exact", "PSNR dB, seen as exact", num(".2f"))]))
    if data["walk"]:
        page.add("<h3>Walk</h3>")
        page.add(table(data["walk"], [("frame", "frame", text), ("distance_to_nearest_probe", "distance m", num(".3f")),
                                      ("ms_per_frame", "ms/frame", num(".2f")), *METRIC_COLUMNS]))


def _at_probe_section(page, data: Dict[str, object], img, findings) -> None:
    """Mesh-baked probes seen from their own centre."""
    page.section("at_probe", "Mesh-baked probes from their own centre")
    page.paragraph("A single probe baked from the mesh (an n×n bundle of Embree rays per texel, the colour averaged over "
                   "the rays on the centre ray's surface) at the grid probe nearest each view, seen from that probe's "
                   "centre: every camera ray is one texel lookup. Matched filtering: the probe render takes the ground "
                   "truth's n×n stratified samples per pixel, and both average them; 'PSNR vs converged' compares the "
                   "same render with a ground truth of many more samples, free of the n×n ground truth's own aliasing "
                   "(its score against the converged one is the 'gt itself' column). 'nearest' reads the texel met "
                   "(the paper), 'bilinear' interpolates between the texels around the hit on the same surface, "
                   "'bicubic' does so with Catmull-Rom weights over 4×4 texels. Both sides filter textures over each "
                   "sample's footprint (texture LOD). 'error at silhouettes': the share of the squared error against "
                   "the converged ground truth in pixels beside a depth step. "
                   "'1 spp' is one sample per pixel on both sides, the unfiltered comparison.", "note")
    img("at_probe_psnr.png", "PSNR [dB] against probe resolution N", 520)
    findings("at_probe")
    page.add(table(data["at_probe"], [("view", "view", text), ("resolution", "N", num(".0f")), ("filter", "filter", text),
                                      ("texel_angle_deg", "texel °", num(".3f")), ("pixel_angle_deg", "pixel °", num(".3f")),
                                      ("spp", "spp", num(".0f")), ("psnr", "PSNR dB (matched)", num(".2f")),
                                      ("psnr_vs_converged_gt", "PSNR dB vs converged", num(".2f")),
                                      ("gt_psnr_vs_converged_gt", "gt itself vs converged", num(".2f")),
                                      ("silhouette_error_share", "error at silhouettes", num(".0%")),
                                      ("psnr_one_sample_per_pixel", "PSNR dB (1 spp)", num(".2f")),
                                      ("psnr_one_sample_vs_filtered_gt", "PSNR dB (1 spp vs filtered GT)", num(".2f")),
                                      ("psnr_footprint_one_sample_vs_filtered_gt",
                                       "PSNR dB (1 spp footprint vs filtered GT)", num(".2f")),
                                      ("ssim", "SSIM", num(".4f")), ("flip", "FLIP", num(".4f")),
                                      ("hole_rate", "holes", num(".2%")), ("ms_per_frame", "ms/frame", num(".2f")),
                                      ("bake_seconds", "bake s", num(".2f"))]))


def _resolution_section(page, data: Dict[str, object], img, findings) -> None:
    """Error against fine resolution at each scan density."""
    page.section("resolution", "Error against fine resolution at several scan densities")
    page.paragraph("The paper found 3072² worse than 2048² for its point density: a point baked into one texel leaves "
                   "near surfaces as sieves at high resolution. 'points only' bakes that way (no footprint, no hole "
                   "filling); 'splat + fill' splats each point over its footprint and fills small holes.", "note")
    img("resolution_psnr.png", "PSNR [dB] against fine resolution N", 560)
    img("resolution_flip.png", "FLIP against fine resolution N", 560)
    findings("resolution")


def _images_section(page, data: Dict[str, object], img) -> None:
    """Ground truth | probes | error, per view."""
    scene = data["scene"]
    page.section("images", "Images: ground truth | probes | error")
    page.paragraph(f"Setting: {data['reference_setting']}. Left: ground truth; middle: probe render (magenta: "
                   "UNKNOWN at the pixel's centre, whether the hole fill coloured it or not); right: FLIP error per pixel (magma, black 0 … yellow 1).", "note")
    for view in [v["name"] for v in scene["views"]]:
        img(f"triplet_probes_{view}.png", f"view '{view}': ground truth | scan-baked probes | FLIP error", None, True)
        img(f"confusion_{view}.png", f"view '{view}': confusion of probe answers against ground truth")
        img(f"triplet_mesh_probes_{view}.png", f"view '{view}': ground truth | mesh-baked probes | FLIP error", None, True)


def _peers_section(page, data: Dict[str, object], img, findings) -> None:
    """Splats and the Poisson mesh from the same scans."""
    scene = data["scene"]
    page.section("peers", "Peers: splats and a Poisson mesh")
    page.paragraph("From the densest scan: the raw cloud drawn as z-buffered splats (native, sized by local spacing), "
                   "and an Open3D screened Poisson mesh (normals as the caption below says; "
                   "vertices of the lowest 2% density and outside the cloud's box removed) ray traced with Embree "
                   "from the same camera. Memory: splats hold positions, colours and spacing (28 B/point); the mesh "
                   "holds float32 positions, indices and corner colours (Embree's BVH not counted); probes: the "
                   "loaded maps and coarse levels × probes.", "note")
    poisson = data["peers"]["poisson"]
    if poisson.get("error"):
        page.paragraph(f"Poisson mesh: not available: {poisson['error']}", "fail")
    else:
        page.paragraph(f"Poisson reconstruction (depth {poisson['poisson_depth']}): {poisson['reconstruction_seconds']:.2f} s "
                       f"(normals {poisson['normals_seconds']:.2f} s: "
                       f"{POISSON_NORMALS.get(poisson.get('normals', 'open3d'), poisson.get('normals'))}), "
                       f"{poisson['vertices']:,} vertices, "
                       f"{poisson['triangles']:,} triangles, {poisson['ply_bytes'] / MIB:.2f} MiB PLY, "
                       f"{poisson['memory_bytes'] / MIB:.2f} MiB in memory.")
    findings("peers")
    page.add(table(data["peers"]["rows"], [("method", "method", text), ("view", "view", text),
                                           ("preparation_seconds", "preparation s", num(".2f")),
                                           ("memory_bytes", "memory MiB", num(".2f", 1 / MIB)),
                                           ("ms_per_frame", "ms/frame", num(".2f")),
                                           ("rays_per_second", "M pixels/s", num(".2f", 1e-6)), *METRIC_COLUMNS]))
    img("peers_ms.png", "time per frame [ms] per method and view", 520)
    img("peers_psnr.png", "PSNR [dB] per method and view", 520)
    for view in [v["name"] for v in scene["views"]]:
        img(f"triplet_splats_{view}.png", f"view '{view}': ground truth | splats | FLIP error", None, True)
        img(f"triplet_poisson_{view}.png", f"view '{view}': ground truth | Poisson mesh | FLIP error", None, True)


def _stability_section(page, data: Dict[str, object]) -> None:
    """The hard cases and their verdicts."""
    page.section("stability", "Numerical stability")
    page.paragraph("The hard cases, run on this scene with probes baked from its mesh; each is judged by the "
                   "stated criterion.", "note")
    rows = []
    for case in data["stability"]:
        figures = {k: v for k, v in case.items() if k not in ("case", "checks", "criterion", "passed", "series")}
        rows.append({"case": case["case"], "checks": case["checks"], "criterion": case["criterion"],
                     "result": stability.verdict(case),
                     "figures": ", ".join(f"{k} = {_short(v)}" for k, v in figures.items())})
    page.add(table(rows, [("case", "case", text), ("checks", "what it does", text), ("criterion", "criterion", text),
                          ("result", "result", text), ("figures", "figures", text)]))
    for case in data["stability"]:
        if case.get("series"):
            page.add(f"<h3>{html.esc(case['case'])}</h3>")
            page.add(table(case["series"], [("epsilon_m", "ε m", num(".0e")),
                                            ("status_differs", "pixels changing status", num(".3%")),
                                            ("psnr_vs_lookup", "PSNR dB vs lookup", num(".2f"))]))
    planning_files = (", planning_resolution.csv, planning_walk.csv, planning_storage.csv, planning_iterations.csv"
                      if data.get("planning") is not None else "")
    page.paragraph("Raw figures: report.json, sweep.csv, sweep_views.csv, distance.csv, walk.csv, at_probe.csv, "
                   f"peers.csv, stability.csv, ground_truth.csv{planning_files} beside this file; images in images/.",
                   "note")


def _planning_section(page, data: Dict[str, object], img) -> None:
    plan = data["planning"]
    page.section("planning", "Model only what a scene needs")
    if plan is None:
        page.paragraph(f"Not run by the preset '{data['preset']}': its two planned bakes of the scene grid (up to "
                       "4096² a probe) and the adaptive placement take minutes at this scan density. "
                       "`lfprobe report --preset full` runs it.", "note")
        return
    r, pl, eq = plan["resolution"], plan["placement"], plan["bytes_at_equal_error"]
    page.paragraph("Automatic resolution: the scene grid baked from the densest scan with bake --auto (each probe "
                   "at the resolution its points support: two texels per point spacing, N ≈ 2·sqrt(4π)·r/s at the "
                   "median direction, rounded down to a power of two or the half between, between 64² and 4096²; "
                   "probes inside geometry or against walls moved or dropped; compact storage) against the same "
                   "grid at every fixed resolution of the sweep (lfprobe's splat + fill bake, default trace, full "
                   "and compact storage), errors averaged over the views. "
                   f"Criterion: {r['criterion']}.", "note")
    for sentence in data["findings"].get("planning", []):
        page.paragraph(sentence, "finding")
    page.add(table(r["rows"], [("setting", "setting", text), ("resolution_summary", "N² × probes", text),
                               ("probes", "probes", num(".0f")), ("psnr", "PSNR dB", num(".2f")),
                               ("ssim", "SSIM", num(".4f")), ("flip", "FLIP", num(".4f")),
                               ("hole_rate", "holes", num(".2%")), ("unknown_rate", "UNKNOWN", num(".2%")),
                               ("memory_bytes_per_probe", "MiB/probe", num(".3f", 1 / MIB)),
                               ("memory_bytes", "MiB total", num(".2f", 1 / MIB)),
                               ("bake_seconds", "bake s", num(".2f"))]))
    a, u = pl["adaptive"], pl["uniform"]
    page.add("<h3>Adaptive placement against a uniform grid along the walk</h3>")
    page.paragraph(f"Adaptive: a base grid of {pl['base_counts']} probes, then greedily a probe at the eye of the "
                   f"walk frame with the most UNKNOWN pixels (the paper's simulated probes), until every frame is at "
                   f"most {pl['target_unknown']:.1%} UNKNOWN, {data['preset']}'s limit of added probes, or the memory of "
                   f"the scene grid at {pl['resolution']}² ({pl['budget_bytes'] / MIB:.2f} MiB) is reached. The added "
                   "probes turn the grid into a set of positions traced nearest first. Uniform: a grid over the scene "
                   "grid's box with the probe count nearest the adaptive set's (fewer on a tie; the most even "
                   "spacing among those), so the same memory as far as the counts allow. Every probe is "
                   f"{pl['resolution']}², from the densest scan. The walk frames are the views the adaptive probes "
                   "were placed for (the table's means); the frames halfway between them, which placement never "
                   "saw, are measured apart (\"between\" rows below and placed_for = false in planning_walk.csv).",
                   "note")
    summary_rows = [dict(a, method="adaptive", layout=f"{pl['base_counts']} + {a['added']}"),
                    dict(u, method="uniform grid", layout=str(u["counts"]))]
    summary_rows += [dict(r, **r["between_frames"], method=f"{r['method']}, between frames")
                     for r in summary_rows if r.get("between_frames")]
    if pl.get("scene_grid"):
        summary_rows.append(dict(pl["scene_grid"], method="scene grid (whole budget)",
                                 layout=str(pl["scene_grid"]["counts"])))
    page.add(table(summary_rows,
                   [("method", "method", text), ("layout", "probes", text), ("probes", "count", num(".0f")),
                    ("memory_bytes", "MiB", num(".2f", 1 / MIB)), ("hole_rate", "holes", num(".2%")),
                    ("unknown_rate", "UNKNOWN", num(".2%")), ("psnr", "PSNR dB", num(".2f")),
                    ("ssim", "SSIM", num(".4f")), ("flip", "FLIP", num(".4f")),
                    ("ms_per_frame", "ms/frame", num(".2f")), ("bake_seconds", "bake s", num(".2f"))]))
    img("planning_walk_holes.png", "hole rate per walk frame: adaptive placement and the uniform grid", 520)
    img("planning_walk_psnr.png", "PSNR [dB] per walk frame: adaptive placement and the uniform grid", 520)
    page.add(table(plan["placement_frames"], [("method", "method", text), ("frame", "frame", text),
                                              ("placed_for", "placed for", text),
                                              ("distance_to_nearest_probe", "distance m", num(".3f")),
                                              ("ms_per_frame", "ms/frame", num(".2f")), *METRIC_COLUMNS,
                                              ("unknown_rate", "UNKNOWN", num(".2%"))]))
    if plan.get("storage"):
        page.add("<h3>Storage sized to the data</h3>")
        page.paragraph("Each fixed-resolution set of the table above, loaded twice: at full precision (half RGBA, "
                       "float32 distance, half normals: 18 bytes a texel) and compact (ProbeField.load(storage="
                       "\"compact\"), what bake --auto records: 8-bit sRGB radiance, the precision of the scan's "
                       "colours; 16-bit distance in 1 mm steps, half the ~2 mm range noise of the scanner; 8+8-bit "
                       "octahedral normals, within 1° for the face test; no confidence channel, which the trace "
                       "never reads: 7 bytes a texel). The files on disk are the same. The coarse min-distance "
                       "levels go from float32 to 16-bit codes of the same step, rounded down so that they stay "
                       "bounds.",
                       "note")
        page.add(table(plan["storage"], [
            ("resolution", "N", num(".0f")),
            ("full_memory_bytes_per_probe", "MiB/probe full", num(".3f", 1 / MIB)),
            ("compact_memory_bytes_per_probe", "MiB/probe compact", num(".3f", 1 / MIB)),
            ("memory_ratio", "memory ratio", num(".3f")),
            ("full_psnr", "PSNR full", num(".3f")), ("compact_psnr", "PSNR compact", num(".3f")),
            ("psnr_difference_db", "ΔPSNR dB", num("+.3f")),
            ("full_flip", "FLIP full", num(".4f")), ("compact_flip", "FLIP compact", num(".4f")),
            ("full_depth_absrel", "depth AbsRel full", num(".5f")),
            ("compact_depth_absrel", "depth AbsRel compact", num(".5f")),
            ("full_hole_rate", "holes full", num(".3%")), ("compact_hole_rate", "holes compact", num(".3%")),
            ("full_ms_per_frame", "ms full", num(".2f")), ("compact_ms_per_frame", "ms compact", num(".2f"))]))
    page.add("<h3>Bytes per probe at equal error</h3>")
    page.paragraph(f"Reference: {eq['reference_setting']} (the largest fixed resolution), mean PSNR "
                   f"{eq['reference_psnr']:.2f} dB. Among the {eq['candidates']} scan-baked settings of the sweep "
                   "(default trace, full or compact storage) and auto, the smallest memory per probe (loaded maps "
                   f"and coarse levels) that reaches that PSNR within {eq.get('margin_db', 0.0):g} dB (the margin "
                   f"auto is judged by): {eq['setting']}, {eq['bytes_per_probe'] / MIB:.3f} MiB per probe = "
                   f"{eq['fraction_of_paper']:.2%} of the paper's 24.375 MB per 2048² probe.", "note")


def _short(value) -> str:
    if isinstance(value, float):
        return "∞" if math.isinf(value) else f"{value:.4g}"
    if isinstance(value, list):
        return "(" + ", ".join(_short(v) for v in value) + ")"
    return "n/a" if value is None else str(value)
