#!/usr/bin/python3
"""A scene's views through a probe grid baked from its scans simulated at one density, against
the raw splats and an Open3D Poisson mesh of the same scans: the fidelity issue's scan lines at
any density (the demo scans at 0.1° and 1°), on views --view-width pixels wide (256 by default,
as the figures this tool gave before the demo moved to 640). Every image takes the ground
truth's n×n samples per pixel (the demo preset's 4×4), as the report measures; each line gives
PSNR, SSIM, FLIP, wrong-surface and hole pixels and the frame time. The probes are also seen
from each view's nearest grid probe and from points at --distances metres from it, toward the
view's eye (toward the grid's centre where the eye is at the probe).

usage: /usr/bin/python3 tools/density_check.py [--step-deg 0.1] [--resolution 2048] [--view-width 256]
           [--poisson-depth 10] [--distances 0.4,0.8] [--scene blend/lab_room/lab_room.scene.json]
           [--probes DIR]   (bake into DIR and keep it, or reuse the set already there)
           [--thickness 0.01,0.0025]   (render the probes at each trace thickness)
           [--no-peers]   (the probes alone)
           [--texel-check]   (each view's nearest grid probe against a mesh-baked probe at the
                              same place, texel by texel; also against a probe baked from one
                              scan taken at that place at half its texel angle: what the bake
                              makes of ideal data, apart from where the scanners stood)

At 0.1° the lab room's four scans hold 21.6 M points; the run takes about 5 minutes and 3 GB
on 2 cores (probes 2048²: 30 × 77 MiB in memory; Poisson depth 10: 2 minutes).
"""
import argparse
import dataclasses
import json
import math
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "addon"))

from lfprobe.core import metrics  # noqa: E402
from lfprobe.core.pipeline import BakeOptions, ProbePlacementSpec, bake_from_cloud, bake_from_mesh  # noqa: E402
from lfprobe.core.report import peers  # noqa: E402
from lfprobe.core.report.measure import RunContext, measure  # noqa: E402
from lfprobe.core.report.presets import DEFAULT_TRACE, get_preset  # noqa: E402
from lfprobe.core.report.scene import load_scene  # noqa: E402
from lfprobe.core.report.sweep import Density  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent


def line(method: str, view: str, where: str, figures: dict, ms: float) -> str:
    return (f"{method:28s} {view:15s} {where:34s} PSNR {figures['psnr']:6.2f} dB  "
            f"SSIM {figures['ssim']:.3f}  FLIP {figures['flip']:.3f}  "
            f"wrong surface {100 * figures['wrong_surface_rate']:5.2f} %  "
            f"holes {100 * figures['hole_rate']:5.2f} %  {ms:7.0f} ms")


def texel_figures(test: dict, reference: dict) -> str:
    """Probe `test` against `reference` (read_probe dicts at one resolution), texel by texel: the
    share of texels on the same surface (distance within 2 %), the sRGB PSNR over those, and
    over those at least 3 texels from any other (away from silhouettes); and over the texels
    where both hold a surface, the share on a wrong one and the PSNR over all of them."""
    import numpy as np
    from scipy.ndimage import binary_erosion
    n = int(reference["resolution"])
    def rgb(probe):
        return np.asarray(probe["rgba"], np.float64).reshape(n, n, -1)[..., :3]
    d_ref = np.asarray(reference["distance"], np.float64).reshape(n, n)
    d_test = np.asarray(test["distance"], np.float64).reshape(n, n)
    with np.errstate(invalid="ignore"):
        same = np.isfinite(d_ref) & np.isfinite(d_test) & (np.abs(d_test - d_ref) <= 0.02 * d_ref)
    inner = binary_erosion(same, iterations=3)
    def psnr(mask):
        value = metrics.psnr_over(rgb(reference), rgb(test), mask)
        return float("nan") if value is None else value
    both = np.isfinite(d_ref) & np.isfinite(d_test)
    wrong = both & ~same
    return (f"same surface {100 * same.mean():5.1f} % of texels, PSNR there {psnr(same):5.2f} dB, "
            f"away from their edges {psnr(inner):5.2f} dB; of the texels both see a surface "
            f"{100 * wrong.sum() / max(both.sum(), 1):4.2f} % on a wrong one, PSNR over them "
            f"{psnr(both):5.2f} dB")


def texel_check(ctx, folder: str, anchors: list, resolution: int, scan: dict, work: str) -> None:
    """--texel-check: each anchor's grid probe against a mesh-baked probe there, and the same
    for a probe baked from one scan taken there at half the probe's texel angle."""
    manifest = json.loads(Path(folder, "manifest.json").read_text())
    offset = manifest.get("world_offset", [0.0, 0.0, 0.0])
    step = math.degrees(math.sqrt(4 * math.pi) / resolution) / 2
    for name, anchor in anchors:
        entry = min(manifest["probes"],
                    key=lambda p: math.dist([c + o for c, o in zip(p["position"], offset)], anchor))
        grid_probe = ctx.native.read_probe(os.path.join(folder, entry["file"]))
        mesh_dir = os.path.join(work, f"texel_mesh_{name}")
        bake_from_mesh([ctx.scene.mesh], mesh_dir, ProbePlacementSpec(positions=[anchor]),
                       BakeOptions(resolution=resolution))
        mesh_probe = ctx.native.read_probe(os.path.join(mesh_dir, "probe_00000.exr"))
        print(f"texels {name:15s} grid probe at {tuple(round(c, 2) for c in anchor)} vs mesh-baked: "
              f"{texel_figures(grid_probe, mesh_probe)}", flush=True)
        scanned = ctx.native.start_simulate_scans(
            ctx.mesh, [list(anchor)], step_deg=step, noise_mm=scan["noise_mm"],
            vertical_fov=scan["vertical_fov"], seeds=[1]).run()
        ideal_dir = os.path.join(work, f"texel_ideal_{name}")
        bake_from_cloud(scanned["cloud"], ideal_dir, ProbePlacementSpec(positions=[anchor]),
                        BakeOptions(resolution=resolution))
        del scanned
        ideal = ctx.native.read_probe(os.path.join(ideal_dir, "probe_00000.exr"))
        print(f"texels {name:15s} one {step:.3f}° scan from there vs mesh-baked:  "
              f"{texel_figures(ideal, mesh_probe)}", flush=True)
        shutil.rmtree(mesh_dir, ignore_errors=True)
        shutil.rmtree(ideal_dir, ignore_errors=True)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scene", default=str(ROOT / "blend" / "lab_room" / "lab_room.scene.json"))
    parser.add_argument("--step-deg", type=float, default=0.1)
    parser.add_argument("--resolution", type=int, default=2048)
    parser.add_argument("--poisson-depth", type=int, default=10)
    parser.add_argument("--view-width", type=int, default=256,
                        help="views scaled to this width in pixels, their aspect kept (the demo's are 640)")
    parser.add_argument("--distances", default="0.4,0.8",
                        help="metres from each view's nearest probe (comma-separated; empty: none)")
    parser.add_argument("--probes", default="", help="bake into this folder and keep it, or reuse it")
    parser.add_argument("--thickness", default="",
                        help="trace thicknesses in metres to render the probes with (comma-separated; "
                             "empty: the renderer's default)")
    parser.add_argument("--texel-check", action="store_true",
                        help="each view's nearest grid probe against a mesh-baked probe at the same place, "
                             "texel by texel, and a probe baked from one scan taken there at half the "
                             "texel angle against it too")
    parser.add_argument("--no-peers", action="store_true",
                        help="skip the splats and the Poisson mesh (Open3D's Poisson takes minutes and "
                             "many GB beyond 20 M points)")
    args = parser.parse_args()

    # Timed as the best of two renders, as before the demo preset timed once.
    preset = dataclasses.replace(get_preset("demo"), poisson_depth=args.poisson_depth,
                                 max_view_width=args.view_width, timing_repeats=2)
    work = tempfile.mkdtemp(prefix="lfprobe-density-")
    ctx = RunContext(load_scene(args.scene), preset, work, 0, lambda m: print(m, flush=True))
    scene = ctx.scene
    try:
        start = time.perf_counter()
        scanned = ctx.native.start_simulate_scans(
            ctx.mesh, [list(s) for s in scene.scanners], step_deg=args.step_deg,
            noise_mm=scene.scan["noise_mm"], vertical_fov=scene.scan["vertical_fov"],
            seeds=[i + 1 for i in range(len(scene.scanners))]).run()
        cloud = scanned["cloud"]
        density = Density(args.step_deg, len(cloud), time.perf_counter() - start, cloud)
        print(f"scans at {args.step_deg:g}°: {density.points:,} points in {density.scan_seconds:.1f} s")

        folder = args.probes or os.path.join(work, "probes")
        if not os.path.isfile(os.path.join(folder, "manifest.json")):
            start = time.perf_counter()
            placement = ProbePlacementSpec(grid_min=list(scene.grid_min), grid_max=list(scene.grid_max),
                                           counts=list(scene.grid_counts))
            bake_from_cloud(cloud, folder, placement, BakeOptions(resolution=args.resolution))
            print(f"probe grid {scene.grid_counts} at {args.resolution}² baked in "
                  f"{time.perf_counter() - start:.1f} s into {folder}")
        field = ctx.native.ProbeField.load(folder)

        thicknesses = [float(t) for t in args.thickness.split(",") if t.strip()] or \
            [DEFAULT_TRACE[1]["thickness"]]
        positions = scene.probe_positions()
        distances = [float(d) for d in args.distances.split(",") if d.strip()]
        for view in ctx.views:
            anchor = min(positions, key=lambda q: math.dist(q, view.position))
            eyes = [(f"its eye ({math.dist(anchor, view.position):.2f} m from a probe)", list(view.position))]
            toward = [v - a for v, a in zip(view.position, anchor)]
            if math.hypot(*toward) < 1e-6:
                centre = [sum(p[a] for p in positions) / len(positions) for a in range(3)]
                toward = [c - a for c, a in zip(centre, anchor)]
            length = math.hypot(*toward)
            eyes.append(("at its nearest probe", list(anchor)))
            for d in distances:
                eyes.append((f"{d:g} m from that probe", [a + d * t / length for a, t in zip(anchor, toward)]))
            for where, eye in eyes:
                camera = ctx.camera(view, eye)
                gt, _ = ctx.ground_truth(camera)
                for thickness in thicknesses:
                    trace = dict(DEFAULT_TRACE[1], thickness=thickness)
                    image, stats = ctx.render_probes(field, camera, trace)
                    figures, _ = measure(gt, image)
                    method = f"probes {args.resolution}², {100 * thickness:g} cm"
                    print(line(method, view.name, where, figures, 1e3 * stats["seconds"]), flush=True)
        del field
        if args.texel_check:
            anchors = {}
            for view in ctx.views:
                anchors.setdefault(tuple(min(positions, key=lambda q: math.dist(q, view.position))), view.name)
            texel_check(ctx, folder, [(name, list(a)) for a, name in anchors.items()], args.resolution,
                        scene.scan, work)
        if args.no_peers:
            return 0
        for row in peers.splat_rows(ctx, density)[0]:
            print(line("splats", row["view"], "its eye", row, row["ms_per_frame"]), flush=True)
        rows, _, info = peers.poisson_rows(ctx, density)
        if "error" in info:
            print(f"Poisson: {info['error']}")
        else:
            print(f"Poisson depth {args.poisson_depth}: {info['triangles']:,} triangles, "
                  f"{info['reconstruction_seconds']:.0f} s to build")
        for row in rows:
            print(line(f"Poisson depth {args.poisson_depth}", row["view"], "its eye", row, row["ms_per_frame"]),
                  flush=True)
    finally:
        ctx.cleanup(False)
        shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
