"""`lfprobe place` and the planning options of `lfprobe bake --auto`: per-probe resolution
chosen from the data, probes inside geometry moved or dropped, probes against walls moved where
that lets them see more; with --views, probes added greedily where the given views trace UNKNOWN
(lfprobe.core.adaptive)."""

from __future__ import annotations

import json
import os
from collections import Counter

from ..atomic_write import atomic_open
from ..pipeline import ProbePlacementSpec, load_scans, plan_probes
from ..progress import TerminalProgress
from .arguments import (finite_float, COLUMNS_HELP, SCAN_HELP, add_placement_arguments, add_plan_arguments, add_storage_arguments,
                        bake_storage, plan_options, triples)


def read_view_cameras(paths) -> list:
    """Camera JSON files (docs/DESIGN.md §3) as dicts, with messages that name the file."""
    cameras = []
    for path in paths:
        if not os.path.isfile(path):
            raise FileNotFoundError(f"--views: no such camera file: {path}")
        try:
            with open(path, encoding="utf-8") as stream:
                camera = json.load(stream)
        except (json.JSONDecodeError, UnicodeDecodeError) as error:
            raise ValueError(f"{path}: not a camera JSON file: {error}") from error
        if not isinstance(camera, dict) or "matrix_world" not in camera or "resolution" not in camera:
            raise ValueError(f"{path}: expected a camera object with matrix_world and resolution "
                             "(write one with ./lfprobe camera)")
        matrix = camera["matrix_world"]
        if (not isinstance(matrix, list) or len(matrix) != 4
                or any(not isinstance(r, list) or len(r) != 4 for r in matrix)):
            raise ValueError(f"{path}: matrix_world: expected 4×4 rows of numbers")
        cameras.append(camera)
    return cameras


def _load_cloud(args, progress):
    """The --scan files merged, each placed by its --scanner, through the parsed-scan cache."""
    return load_scans(args.scan, triples(args.scanner, "--scanner"), args.columns or "",
                      "" if args.no_cache else args.cache, progress=progress)


def _write_result(args, result: dict) -> bool:
    """Writes the result to --out (if given) and prints it for --json; True when printed, so
    that no summary follows."""
    if args.out:
        with atomic_open(args.out) as f:
            json.dump(result, f, indent=2)
    if args.json:
        print(json.dumps(result, indent=2))
    return bool(args.json)


def _cmd_place_adaptive(args) -> int:
    """place --views: the base placement (if any), then probes at the eyes of the views that
    trace the most UNKNOWN pixels until --target-unknown or --budget-mib is met."""
    from ..adaptive import budget_from_mib, place_adaptively

    if not args.out_probes:
        raise ValueError("place --views bakes the probes it places: give --out-probes DIR")
    if not 0.0 <= args.target_unknown <= 1.0:
        raise ValueError(f"--target-unknown must be a fraction from 0 to 1, got {args.target_unknown}")
    if args.res < 8 or args.res > 8192:
        raise ValueError(f"--res must be from 8 to 8192, got {args.res}")
    budget = budget_from_mib(args.budget_mib)
    cameras = read_view_cameras(args.views)
    positions = triples(args.probe, "--probe")
    grid = [args.grid_min, args.grid_max, args.counts]
    base_grid = None
    if any(g is not None for g in grid):
        ProbePlacementSpec(positions=positions, grid_min=args.grid_min, grid_max=args.grid_max,
                           counts=args.counts).validate()
        base_grid = {"min": list(args.grid_min), "max": list(args.grid_max), "counts": list(args.counts)}
    progress = None if args.quiet else TerminalProgress()
    cloud = _load_cloud(args, progress)
    result = place_adaptively(
        cloud, cameras, args.out_probes, base_positions=positions, base_grid=base_grid,
        resolution=args.res, plan=plan_options(args) if args.auto else None,
        target_unknown=args.target_unknown, budget_bytes=budget, max_added=args.max_added,
        threads=args.threads, log=None if args.quiet else print,
        storage=bake_storage(args), distance_step=args.distance_step)
    data = {"scans": [os.path.abspath(p) for p in args.scan], "points": len(cloud),
            "views": [os.path.abspath(p) for p in args.views], **result.as_dict()}
    if _write_result(args, data):
        return 0
    first, last = result.iterations[0], result.iterations[-1]
    print(f"added {len(result.added)} probe(s) to {result.base_probes} base probe(s); stopped: "
          f"{result.stopped_because}")
    print(f"  UNKNOWN rate over {len(cameras)} view(s): mean {first['mean_unknown_rate']:.2%} → "
          f"{last['mean_unknown_rate']:.2%}, worst {first['max_unknown_rate']:.2%} → "
          f"{last['max_unknown_rate']:.2%}; memory {last['memory_bytes'] / 2**20:.2f} MiB")
    for added in result.added:
        x, y, z = added["position"]
        print(f"  + ({x:.3f}, {y:.3f}, {z:.3f}) at the eye of {args.views[added['view']]} "
              f"(was {added['unknown_rate_before']:.2%} UNKNOWN), {added['resolution']}²")
    print(f"probe set: {result.folder}")
    return 0


def _cmd_place(args) -> int:
    if args.views:
        return _cmd_place_adaptive(args)
    for option, value in (("--out-probes", args.out_probes), ("--budget-mib", args.budget_mib)):
        if value is not None:
            raise ValueError(f"{option} is for adaptive placement: give --views CAM.json too")
    placement = ProbePlacementSpec(positions=triples(args.probe, "--probe"),
                                   grid_min=args.grid_min, grid_max=args.grid_max,
                                   counts=args.counts)
    placement.validate()
    progress = None if args.quiet else TerminalProgress()
    cloud = _load_cloud(args, progress)
    probes = plan_probes(cloud, placement, plan_options(args), progress)
    result = {"scans": [os.path.abspath(p) for p in args.scan], "points": len(cloud),
              "probes": probes}
    if _write_result(args, result):
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
        if not note and p["class"] == "too_close":
            note = " (kept: a move would not let it see more)"
        supported = f", data supports {p['data_resolution']:.0f}" if p["data_resolution"] else ""
        print(f"  {i:3d}: ({x:.3f}, {y:.3f}, {z:.3f}) {p['found']}→{p['class']}{note}, "
              f"{p['resolution']}²{supported}")
    return 0


def add_parsers(sub) -> None:
    place = sub.add_parser(
        "place", help="plan probes from the data: resolution, class, moves, drops; with --views, "
                      "add probes where views trace UNKNOWN",
        description="Plans probes from the data (resolution, class, moves, drops). With --views, "
                    "places probes adaptively instead: the base probes (--probe or a grid; may be "
                    "left out) are baked, every view is traced, and a probe is added at the eye of "
                    "the view with the most UNKNOWN pixels, again and again, until every view is at "
                    "most --target-unknown UNKNOWN or the next probe would exceed --budget-mib; the "
                    "probe set goes to --out-probes.")
    place.add_argument("--scan", nargs="+", required=True, metavar="FILE", help=SCAN_HELP)
    add_placement_arguments(place)
    place.add_argument("--columns", help=COLUMNS_HELP)
    place.add_argument("--cache", default=None, metavar="DIR", help="parsed-scan cache folder")
    place.add_argument("--no-cache", action="store_true")
    place.add_argument("--out", metavar="PLAN.json", help="also write the plan as JSON")
    place.add_argument("--json", action="store_true", help="print the plan as JSON")
    place.add_argument("--quiet", action="store_true")
    adaptive = place.add_argument_group("adaptive placement (--views)")
    adaptive.add_argument("--views", nargs="+", metavar="CAM.json",
                          help="camera files of the views or camera path to serve (./lfprobe camera "
                               "writes them); turns on adaptive placement")
    adaptive.add_argument("--target-unknown", type=finite_float, default=0.01, metavar="F",
                          help="stop when every view has at most this fraction of UNKNOWN pixels "
                               "(default 0.01)")
    adaptive.add_argument("--budget-mib", type=finite_float, default=None, metavar="M",
                          help="memory budget of the whole set, loaded maps and coarse levels (MiB); "
                               "no probe is added that would exceed it")
    adaptive.add_argument("--out-probes", metavar="DIR", help="the probe set written (base + added)")
    adaptive.add_argument("--res", type=int, default=256, help="resolution of every probe (default 256)")
    adaptive.add_argument("--auto", action="store_true",
                          help="plan each probe from the data instead (the planning options below)")
    adaptive.add_argument("--max-added", type=int, default=64, help="most probes added (default 64)")
    add_storage_arguments(adaptive, ["full", "compact"], None,
                          "how the set loads into memory (the budget counts it so): full, or "
                          "compact (7 bytes a texel); default full, compact with --auto")
    adaptive.add_argument("--threads", type=int, default=0, help="render threads (0: every core)")
    add_plan_arguments(place)
    place.set_defaults(run=_cmd_place)
