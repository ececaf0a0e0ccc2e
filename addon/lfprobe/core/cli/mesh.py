"""Mesh subcommands (bpy-free): ``gt`` (Embree ground truth of a view) and ``scan`` (a
simulated laser scan of a mesh); ``./lfprobe bake --mesh FILE`` bakes with pipeline.bake_from_mesh."""

from __future__ import annotations

import json

from .arguments import finite_float
from .. import native
from ..progress import TerminalProgress


def _run_job(args, start, summary) -> int:
    """Runs the native job start(_native) with terminal progress (unless --quiet) and prints its
    stats as JSON (--json) or as the line summary(stats) writes."""
    job = start(native.load())
    stats = job.run(None if args.quiet else TerminalProgress())
    if args.json:
        print(json.dumps(stats, indent=2))
        return 0
    print(summary(stats))
    return 0


def _cmd_gt(args) -> int:
    return _run_job(
        args,
        lambda _native: _native.start_ground_truth(
            args.mesh, args.camera, args.out, spp=args.spp, threads=args.threads,
            filter_textures=args.texture_filter == "footprint"),
        lambda stats: (f"ground truth {args.out}: {stats['pixels']} pixels, {stats['hits']} hit, "
                       f"{stats['rays']} rays in {stats['seconds']:.3f} s "
                       f"({stats['rays_per_second'] / 1e6:.2f} M rays/s)"),
    )


def _cmd_scan(args) -> int:
    return _run_job(
        args,
        lambda _native: _native.start_simulate_scan(
            args.mesh, args.out, list(args.at), step_deg=args.step_deg, noise_mm=args.noise_mm,
            vertical_fov=args.vertical_fov, seed=args.seed, horizontal_fov=args.horizontal_fov,
            horizontal_start=args.horizontal_start,
            filter_textures=args.texture_filter == "footprint"),
        lambda stats: (f"scan {args.out}: {stats['points']} points from {stats['rays']} rays "
                       f"in {stats['seconds']:.3f} s"),
    )


def add_parsers(subparsers) -> None:
    """Adds ``gt`` and ``scan`` to the CLI's subparsers (each sets ``run``)."""
    gt = subparsers.add_parser("gt", help="Embree ground truth of a mesh from a camera")
    gt.add_argument("--mesh", required=True, help="mesh file (.obj with .mtl, or .ply)")
    gt.add_argument("--camera", required=True, help="camera JSON file")
    gt.add_argument("--out", required=True, help="output EXR")
    gt.add_argument("--spp", type=int, default=1, help="samples per pixel: 1 or a square (4, 9, ...)")
    gt.add_argument("--texture-filter", choices=["footprint", "point"], default="footprint",
                    help="each sample's texture colour: its mean over the sample's footprint (one of "
                         "the pixel's n×n strata; texture LOD, default) or the texture at the hit "
                         "alone (point; before 2026-11, n×n samples then alias fine textures)")
    gt.add_argument("--threads", type=int, default=0, help="threads (0: all cores)")
    gt.add_argument("--json", action="store_true", help="print the stats as JSON")
    gt.add_argument("--quiet", action="store_true", help="no progress output")
    gt.set_defaults(run=_cmd_gt)

    scan = subparsers.add_parser("scan", help="simulated laser scan of a mesh (.xyz out)")
    scan.add_argument("--mesh", required=True, help="mesh file (.obj with .mtl, or .ply)")
    scan.add_argument("--at", type=finite_float, nargs=3, required=True, metavar=("X", "Y", "Z"),
                      help="scanner position (world)")
    scan.add_argument("--step-deg", type=finite_float, default=0.5, help="angular step (degrees)")
    scan.add_argument("--noise-mm", type=finite_float, default=2.0, help="range noise σ at 10 m (mm)")
    scan.add_argument("--vertical-fov", type=finite_float, default=300.0,
                      help="vertical field of view (degrees; 300: elevation −60° to +90°)")
    scan.add_argument("--horizontal-fov", type=finite_float, default=360.0,
                      help="azimuths swept (degrees; less than 360: a partial sweep)")
    scan.add_argument("--horizontal-start", type=finite_float, default=0.0,
                      help="first azimuth of the sweep (degrees, from +X toward +Y)")
    scan.add_argument("--seed", type=int, default=1, help="noise seed")
    scan.add_argument("--texture-filter", choices=["footprint", "point"], default="footprint",
                      help="each point's colour: the texture's mean over the point's footprint (the "
                           "step times the range, as a scanner's camera pixel records it; default) or "
                           "the texture at the hit alone (point; before 2026-11)")
    scan.add_argument("--out", required=True, help="output .xyz file")
    scan.add_argument("--json", action="store_true", help="print the stats as JSON")
    scan.add_argument("--quiet", action="store_true", help="no progress output")
    scan.set_defaults(run=_cmd_scan)
