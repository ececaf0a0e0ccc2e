"""`lfprobe report --scene SCENE.json --out DIR [--preset tiny|demo|full] [--threads N]`.

Runs the error-analysis sweep of a scene file (lfprobe.core.report) and writes DIR/report.html
(self-contained), DIR/report.json, the CSV files of the sweep rows and DIR/images/.
`add_parsers(subparsers)` adds the subcommand to the lfprobe parser. Exit status 2 for a
missing or invalid scene file (the message names the file and the key).
"""

from __future__ import annotations

import argparse


def _cmd_report(args) -> int:
    from ..report.measure import stderr_log
    from ..report.runner import run_report

    data = run_report(args.scene, args.out, args.preset, args.threads, keep_work=args.keep_work,
                      log=_quiet if args.quiet else stderr_log)
    failed = [c["case"] for c in data["stability"] if c["passed"] is False]
    print(f"report: {args.out}/report.html ({len(data['sweep'])} settings, {len(data['sweep_views'])} "
          f"measured views, {data['seconds']:.1f} s)")
    for key in ("at_probe", "distance", "resolution", "speed", "peers", "planning"):
        for sentence in data["findings"].get(key, []):
            print(f"  {sentence}")
    if failed:
        print(f"  stability cases failing their criterion: {', '.join(failed)}")
    return 0


def _quiet(message: str) -> None:
    """--quiet: progress lines are dropped."""


def add_parsers(subparsers) -> argparse.ArgumentParser:
    """Adds `report` to an argparse subparsers object; returns the new parser."""
    report = subparsers.add_parser(
        "report", help="error-analysis report of a scene: sweep, peers, stability (HTML, JSON, CSV)")
    report.add_argument("--scene", required=True, metavar="SCENE.json", help="scene file (see the README)")
    report.add_argument("--out", required=True, metavar="DIR", help="folder for report.html and its data")
    report.add_argument("--preset", choices=["tiny", "demo", "full"], default="demo",
                        help="tiny: seconds (tests); demo: minutes; full: the big benchmark sweep")
    report.add_argument("--threads", type=int, default=0, help="cores to use (0: all)")
    report.add_argument("--keep-work", action="store_true",
                        help="keep DIR/work (scans, probe sets) instead of deleting it at the end")
    report.add_argument("--quiet", action="store_true", help="no progress lines")
    report.set_defaults(run=_cmd_report)
    return report
