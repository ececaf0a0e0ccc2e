"""`lfprobe compare REF.exr TEST.exr [--json] [--ppd 67] [--error-map OUT.png]`.

Compares a test view (probe render, splat) with a ground-truth view of the same camera:
PSNR, SSIM, FLIP, depth AbsRel/RMSE and the HIT/MISS/UNKNOWN confusion, every figure defined in
lfprobe.core.metrics. `add_parsers(subparsers)` adds the subcommand to the lfprobe parser;
`python -m lfprobe.core.cli_compare ...` runs it on its own. Exit status 2 for a missing or
unreadable file or images of different sizes.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import struct
import time
import zlib
from typing import Dict, Optional

import numpy as np

from . import metrics, native
from .atomic_write import atomic_open
from .colour import magma8


def _read(path: str) -> Dict[str, object]:
    if not os.path.isfile(path):
        raise FileNotFoundError(f"no such image: {path}")
    try:
        return native.load().read_image(path)
    except native.NativeModuleError:
        raise
    except Exception as error:  # the native reader's own error types
        raise ValueError(f"cannot read {path}: {error}") from error


def _render_seconds(image: Dict[str, object]) -> Optional[float]:
    """The renderer's own time for the image, when its metadata records one."""
    try:
        stats = json.loads(image.get("metadata") or "{}").get("stats", {})
        seconds = stats.get("seconds")
        return float(seconds) if seconds is not None else None
    except (ValueError, AttributeError, TypeError):
        return None


def write_png(path: str, rgb8: np.ndarray) -> None:
    """Writes an (h, w, 3) uint8 image as an 8-bit RGB PNG (zlib, no filtering)."""
    h, w = rgb8.shape[:2]
    raw = b"".join(b"\x00" + rgb8[y].tobytes() for y in range(h))

    def chunk(tag: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)
    with atomic_open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, 6))
                + chunk(b"IEND", b""))


def _fmt(value, spec: str, unit: str = "") -> str:
    if value is None:
        return "n/a"
    if isinstance(value, float) and value == float("inf"):
        return "inf (identical)"
    return f"{value:{spec}}{unit}"


def _print_table(ref_path: str, test_path: str, r: Dict[str, object]) -> None:
    c = r["counts"]
    rows = [
        ("PSNR (sRGB)", _fmt(r["psnr"], ".2f", " dB")),
        ("SSIM (sRGB, 11×11 σ=1.5)", _fmt(r["ssim"], ".4f")),
        (f"FLIP (LDR, {r['ppd']:g} ppd)", _fmt(r["flip"], ".4f")),
        ("depth AbsRel", _fmt(r["depth_absrel"], ".4%")),
        ("depth RMSE", _fmt(r["depth_rmse"], ".4f", " m")),
        ("hole rate", _fmt(r["hole_rate"], ".3%")),
        ("false hit rate", _fmt(r["false_hit_rate"], ".3%")),
        ("false miss rate", _fmt(r["false_miss_rate"], ".3%")),
        ("unknown rate", _fmt(r["unknown_rate"], ".3%")),
    ]
    print(f"compare {test_path} against {ref_path} ({r['width']}×{r['height']}, "
          f"{r['compare_seconds'] * 1000:.0f} ms)")
    width = max(len(name) for name, _ in rows)
    for name, value in rows:
        print(f"  {name:<{width}}  {value}")
    print(f"  depth over {r['depth_pixels']:,} pixels both hit")
    print("  confusion     test HIT   test MISS   test UNKNOWN")
    for gt in ("gt_hit", "gt_miss"):
        row = c[gt]
        print(f"  {gt.replace('_', ' '):<11} {row['HIT']:>10,} {row['MISS']:>11,} {row['UNKNOWN']:>14,}")
    if c["ref_unknown"]:
        print(f"  ({c['ref_unknown']:,} reference pixels UNKNOWN, left out)")
    for key in ("ref_render_seconds", "test_render_seconds"):
        if r.get(key) is not None:
            print(f"  {key.replace('_', ' ')}: {r[key] * 1000:.1f} ms")


def _strict_json(value):
    """Non-finite numbers become null, so that any JSON parser reads the output (PSNR of
    identical images is infinite: null)."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _strict_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_strict_json(v) for v in value]
    return value


def _cmd_compare(args) -> int:
    if args.ppd <= 0:
        raise ValueError(f"--ppd must be positive, got {args.ppd}")
    ref = _read(args.reference)
    test = _read(args.test)
    start = time.perf_counter()
    result, error_map = metrics.compare_images_with_map(ref, test, ppd=args.ppd)
    result["compare_seconds"] = time.perf_counter() - start
    result["reference"], result["test"] = os.path.abspath(args.reference), os.path.abspath(args.test)
    result["ref_render_seconds"] = _render_seconds(ref)
    result["test_render_seconds"] = _render_seconds(test)
    if args.error_map:
        write_png(args.error_map, magma8(error_map))
        result["error_map"] = os.path.abspath(args.error_map)
    if args.json:
        print(json.dumps(_strict_json(result), indent=2, allow_nan=False))
    else:
        _print_table(args.reference, args.test, result)
        if args.error_map:
            print(f"  FLIP error map: {args.error_map}")
    return 0


def add_parsers(subparsers) -> argparse.ArgumentParser:
    """Adds `compare` to an argparse subparsers object; returns the new parser."""
    compare = subparsers.add_parser(
        "compare", help="metrics of a view against ground truth (PSNR, SSIM, FLIP, depth, holes)")
    compare.add_argument("reference", metavar="REF.exr", help="ground-truth image")
    compare.add_argument("test", metavar="TEST.exr", help="image to evaluate (same camera and size)")
    compare.add_argument("--json", action="store_true",
                         help="print one JSON object (psnr is null for identical images: infinite PSNR)")
    compare.add_argument("--ppd", type=float, default=67.0, help="FLIP pixels per degree (default 67)")
    compare.add_argument("--error-map", metavar="OUT.png", help="write the FLIP error as a magma PNG")
    compare.set_defaults(run=_cmd_compare)
    return compare
