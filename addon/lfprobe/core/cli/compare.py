"""`lfprobe compare REF.exr TEST.exr [--json] [--ppd 67] [--error-map OUT.png]`.

Compares a test view (probe render, splat) with a ground-truth view of the same camera:
PSNR, SSIM, FLIP, depth AbsRel/RMSE and the HIT/MISS/UNKNOWN confusion, every figure defined in
lfprobe.core.metrics and measured by lfprobe.core.compare. Either image may be lfprobe's own EXR,
another EXR (RGB, RGBA, Blender multilayer) or a PNG/JPEG; figures an image cannot give are
printed as "not computed" with the reason. `add_parsers(subparsers)` adds the subcommand to the
lfprobe parser. Exit status 2 for a missing or unreadable file or images of different sizes.
"""

from __future__ import annotations

import argparse
import json
from typing import Dict

from .arguments import finite_float
from ..compare import compare_files
from ..json_values import strict_json


def _fmt(value, spec: str, unit: str = "") -> str:
    if value is None:
        return "n/a"
    if isinstance(value, float) and value == float("inf"):
        return "inf (identical)"
    return f"{value:{spec}}{unit}"


def _print_table(ref_path: str, test_path: str, r: Dict[str, object]) -> None:
    c = r["counts"]
    missing = r.get("not_computed", {})
    rows = [
        ("psnr", "PSNR (sRGB)", _fmt(r["psnr"], ".2f", " dB")),
        ("ssim", "SSIM (sRGB, 11×11 σ=1.5)", _fmt(r["ssim"], ".4f")),
        ("flip", f"FLIP (LDR, {r['ppd']:g} ppd)", _fmt(r["flip"], ".4f")),
        ("depth_absrel", "depth AbsRel", _fmt(r["depth_absrel"], ".4%")),
        ("depth_rmse", "depth RMSE", _fmt(r["depth_rmse"], ".4f", " m")),
        ("hole_rate", "hole rate", _fmt(r["hole_rate"], ".3%")),
        ("false_hit_rate", "false hit rate", _fmt(r["false_hit_rate"], ".3%")),
        ("false_miss_rate", "false miss rate", _fmt(r["false_miss_rate"], ".3%")),
        ("unknown_rate", "unknown rate", _fmt(r["unknown_rate"], ".3%")),
    ]
    print(f"compare {test_path} against {ref_path} ({r['width']}×{r['height']}, "
          f"{r['compare_seconds'] * 1000:.0f} ms)")
    if "reference_source" in r:
        print(f"  reference: {r['reference_source']}; test: {r['test_source']}")
    width = max(len(name) for _key, name, _ in rows)
    for key, name, value in rows:
        print(f"  {name:<{width}}  {'not computed' if key in missing else value}")
    if c is not None:
        print(f"  depth over {r['depth_pixels']:,} pixels both hit")
        print("  confusion     test HIT   test MISS   test UNKNOWN")
        for gt in ("gt_hit", "gt_miss"):
            row = c[gt]
            print(f"  {gt.replace('_', ' '):<11} {row['HIT']:>10,} {row['MISS']:>11,} {row['UNKNOWN']:>14,}")
        if c["ref_unknown"]:
            print(f"  ({c['ref_unknown']:,} reference pixels UNKNOWN, left out)")
    reasons: Dict[str, list] = {}
    for key, why in missing.items():
        reasons.setdefault(why, []).append(key)
    for why, keys in reasons.items():
        print(f"  not computed: {', '.join(keys)}: {why}")
    if r.get("guessed_pixels") is not None:
        off = r["psnr_off_guesses"]
        print(f"  guessed surfaces (hole-filled texels, what no scan saw): {r['guessed_pixels']:.2%} of the "
              f"pixels, {r['guessed_error_share']:.0%} of the squared error; PSNR over the other pixels "
              f"{_fmt(off, '.2f', ' dB')}")
    for key in ("ref_render_seconds", "test_render_seconds"):
        if r.get(key) is not None:
            print(f"  {key.replace('_', ' ')}: {r[key] * 1000:.1f} ms")


def _cmd_compare(args) -> int:
    result = compare_files(args.reference, args.test, ppd=args.ppd, error_map_path=args.error_map)
    if args.json:
        print(json.dumps(strict_json(result), indent=2, allow_nan=False))
    else:
        _print_table(args.reference, args.test, result)
        if args.error_map:
            print(f"  FLIP error map: {args.error_map}")
    return 0


def add_parsers(subparsers) -> argparse.ArgumentParser:
    """Adds `compare` to an argparse subparsers object; returns the new parser."""
    compare = subparsers.add_parser(
        "compare", help="metrics of a view against ground truth (PSNR, SSIM, FLIP, depth, holes)")
    compare.add_argument("reference", metavar="REF.exr",
                         help="ground-truth image: lfprobe EXR, other EXR (RGB, RGBA, Blender multilayer), PNG or JPEG")
    compare.add_argument("test", metavar="TEST.exr", help="image to evaluate (same camera and size; same kinds)")
    compare.add_argument("--json", action="store_true",
                         help="print one JSON object (psnr is null for identical images: infinite PSNR)")
    compare.add_argument("--ppd", type=finite_float, default=67.0, help="FLIP pixels per degree (default 67)")
    compare.add_argument("--error-map", metavar="OUT.png", help="write the FLIP error as a magma PNG")
    compare.set_defaults(run=_cmd_compare)
    return compare
