"""Options and option parsing shared by several subcommands: X Y Z triples and the placement
options (bake, place), the planning options (place, bake --auto) and the storage options
(bake, place, render, store)."""

from __future__ import annotations

import argparse
import math
from typing import List, Optional

from .. import defaults


def finite_float(text: str) -> float:
    """argparse type of every number option: a float, but not nan or inf (which float() reads),
    so that a typo is exit 2 with a message instead of a silently meaningless run."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    return value


def triples(values: Optional[List[List[float]]], option: str) -> List[List[float]]:
    """`--probe X Y Z [X Y Z ...]`, given once or repeated, as a list of (x, y, z)."""
    flat = [v for group in (values or []) for v in group]
    if len(flat) % 3:
        raise ValueError(f"{option} takes coordinates in threes (X Y Z), got {len(flat)} numbers")
    return [flat[i : i + 3] for i in range(0, len(flat), 3)]


SCAN_HELP = (".xyz/.txt/.pts/.ply (native readers), .e57 (every station, posed; needs pye57) and "
             ".las/.laz (needs laspy, lazrs): merged into one cloud, one scan per file or E57 station")
SCANNER_HELP = ("scanner positions X Y Z (world coordinates): one per scan file (an E57's stations carry "
                "their own), or, for ONE merged .xyz/.pts/.ply export, one per station it holds: each "
                "point then gets the station named by its --columns `station` column if given, else "
                "the NEAREST station (no line-of-sight test yet)")
COLUMNS_HELP = ('text scans: column names, e.g. "x y z i r g b"; `station` names a merged export\'s '
                "station column (0-based, or 1..N, in --scanner order)")


def add_placement_arguments(parser: argparse.ArgumentParser) -> None:
    """Where the scanners stood and where the probes go, shared by `bake` and `place`."""
    parser.add_argument("--scanner", nargs="+", type=finite_float, action="append", metavar="X",
                        help=SCANNER_HELP)
    parser.add_argument("--probe", nargs="+", type=finite_float, action="append", metavar="X",
                        help="probe positions X Y Z [X Y Z ...] (world coordinates)")
    parser.add_argument("--grid-min", nargs=3, type=finite_float, metavar=("X", "Y", "Z"))
    parser.add_argument("--grid-max", nargs=3, type=finite_float, metavar=("X", "Y", "Z"))
    parser.add_argument("--counts", nargs=3, type=int, metavar=("NX", "NY", "NZ"))


def add_plan_arguments(parser: argparse.ArgumentParser) -> None:
    """The planning options shared by `place` and `bake --auto`."""
    group = parser.add_argument_group("planning (place, bake --auto)")
    group.add_argument("--min-res", type=int, default=64, help="smallest resolution chosen")
    group.add_argument("--max-res", type=int, default=4096, help="largest resolution chosen")
    group.add_argument("--footprint", type=finite_float, default=0.0, metavar="M",
                       help="texel size wanted at a probe's median distance (metres); caps the "
                            "resolution; 0 = as fine as the data supports")
    group.add_argument("--quantile", type=finite_float, default=0.5,
                       help="quantile of the per-direction supported resolutions (0.5: median)")
    group.add_argument("--samples-per-spacing", type=finite_float, default=2.5, metavar="K",
                       help="texels per point spacing along each axis (default 2.5: the splatted "
                            "surface sampled finer than twice its point density)")
    group.add_argument("--clearance", type=finite_float, default=0.05, metavar="M",
                       help="a probe with surfaces nearer than this is too close")
    group.add_argument("--max-move", type=finite_float, default=0.0, metavar="M",
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
        "samples_per_spacing": args.samples_per_spacing,
        "clearance": args.clearance,
        "max_move": args.max_move,
        "classify": not args.no_classify,
        "drop": not args.keep_useless,
    }


def distance_step_help() -> str:
    return (f"compact storage: distance quantum in metres (default {defaults.storage('distance_step'):g}, "
            "half the ~2 mm range noise of a FARO-class scanner at 10 m)")


def add_storage_arguments(parser, choices, default, text: str) -> None:
    parser.add_argument("--storage", choices=choices, default=default, help=text)
    parser.add_argument("--distance-step", type=finite_float, default=0.0, metavar="M", help=distance_step_help())


def bake_storage(args):
    """The storage a bake records: the one asked for, else compact for --auto (it models only
    what the data carries, in memory too), else the manifest's default (None: full)."""
    return args.storage or ("compact" if getattr(args, "auto", False) else None)
