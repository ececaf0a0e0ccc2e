"""`lfprobe place` and the planning options of `lfprobe bake --auto`: per-probe resolution
chosen from the data, probes inside geometry or against walls moved or dropped."""

from __future__ import annotations

import argparse
import json
import os
from collections import Counter

from .pipeline import ProbePlacementSpec, load_scans, plan_probes
from .progress import TerminalProgress


def add_plan_arguments(parser: argparse.ArgumentParser) -> None:
    """The planning options shared by `place` and `bake --auto`."""
    group = parser.add_argument_group("planning (place, bake --auto)")
    group.add_argument("--min-res", type=int, default=64, help="smallest resolution chosen")
    group.add_argument("--max-res", type=int, default=4096, help="largest resolution chosen")
    group.add_argument("--footprint", type=float, default=0.0, metavar="M",
                       help="texel size wanted at a probe's median distance (metres); caps the "
                            "resolution; 0 = as fine as the data supports")
    group.add_argument("--quantile", type=float, default=0.5,
                       help="quantile of the per-direction supported resolutions (0.5: median)")
    group.add_argument("--clearance", type=float, default=0.05, metavar="M",
                       help="a probe with surfaces nearer than this is too close")
    group.add_argument("--max-move", type=float, default=0.0, metavar="M",
                       help="how far a probe may be moved (0: 0.45 × grid spacing, 0.25 m loose)")
    group.add_argument("--no-classify", action="store_true",
                       help="no classification, no moves, no drops (resolution only)")
    group.add_argument("--keep-useless", action="store_true",
                       help="keep probes that stay inside, too close, blind or idle at full size")


def plan_options(args, auto_resolution: bool = True) -> dict:
    return {
        "auto_resolution": auto_resolution,
        "min_resolution": args.min_res,
        "max_resolution": args.max_res,
        "footprint": args.footprint,
        "quantile": args.quantile,
        "clearance": args.clearance,
        "max_move": args.max_move,
        "classify": not args.no_classify,
        "drop": not args.keep_useless,
    }


def _cmd_place(args) -> int:
    from .cli import _triples  # the CLI's own X Y Z parsing

    placement = ProbePlacementSpec(positions=_triples(args.probe, "--probe"),
                                   grid_min=args.grid_min, grid_max=args.grid_max,
                                   counts=args.counts)
    placement.validate()
    progress = None if args.quiet else TerminalProgress()
    cloud = load_scans(args.scan, _triples(args.scanner, "--scanner"), args.columns or "",
                       "" if args.no_cache else args.cache, progress=progress)
    probes = plan_probes(cloud, placement, plan_options(args), progress)
    result = {"scans": [os.path.abspath(p) for p in args.scan], "points": len(cloud),
              "probes": probes}
    if args.out:
        tmp = args.out + ".tmp"
        with open(tmp, "w", encoding="utf-8") as f:
            json.dump(result, f, indent=2)
        os.replace(tmp, args.out)
    if args.json:
        print(json.dumps(result, indent=2))
        return 0
    classes = Counter(p["class"] for p in probes)
    kept = [p for p in probes if not p["dropped"]]
    texels = sum(p["resolution"] ** 2 for p in probes)
    print(f"planned {len(probes)} probe(s) from {len(cloud):,} points: "
          + ", ".join(f"{k} {v}" for k, v in sorted(classes.items())))
    print(f"  moved {sum(p['moved'] for p in probes)}, dropped {len(probes) - len(kept)}; "
          f"{texels / 1e6:.2f} M texels in all")
    for i, p in enumerate(probes):
        x, y, z = p["position"]
        note = " (dropped)" if p["dropped"] else (f" (moved {p['moved_by']:.3f} m)" if p["moved"] else "")
        supported = f", data supports {p['data_resolution']:.0f}" if p["data_resolution"] else ""
        print(f"  {i:3d}: ({x:.3f}, {y:.3f}, {z:.3f}) {p['found']}→{p['class']}{note}, "
              f"{p['resolution']}²{supported}")
    return 0


def add_parsers(sub) -> None:
    place = sub.add_parser("place", help="plan probes from the data: resolution, class, moves, drops")
    place.add_argument("--scan", nargs="+", required=True, metavar="FILE")
    place.add_argument("--scanner", nargs="+", type=float, action="append", metavar="X",
                       help="scanner positions X Y Z, one per scan file (world coordinates)")
    place.add_argument("--probe", nargs="+", type=float, action="append", metavar="X",
                       help="probe positions X Y Z [X Y Z ...] (world coordinates)")
    place.add_argument("--grid-min", nargs=3, type=float, metavar=("X", "Y", "Z"))
    place.add_argument("--grid-max", nargs=3, type=float, metavar=("X", "Y", "Z"))
    place.add_argument("--counts", nargs=3, type=int, metavar=("NX", "NY", "NZ"))
    place.add_argument("--columns", help='text scans: column names, e.g. "x y z i r g b"')
    place.add_argument("--cache", default=None, metavar="DIR", help="parsed-scan cache folder")
    place.add_argument("--no-cache", action="store_true")
    place.add_argument("--out", metavar="PLAN.json", help="also write the plan as JSON")
    place.add_argument("--json", action="store_true", help="print the plan as JSON")
    place.add_argument("--quiet", action="store_true")
    add_plan_arguments(place)
    place.set_defaults(run=_cmd_place)
