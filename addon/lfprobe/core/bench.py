"""`lfprobe bench core`: scan parsing throughput against numpy.loadtxt on the same file, bake
time per probe for a large cloud, and bytes per probe against the paper's figure. Every
figure comes from this one run on this machine."""

from __future__ import annotations

import json
import os
import shutil
import tempfile
import time

import numpy as np

from . import native
from .bench_formats import library_parse_benchmark
from .probe_set import PAPER_BYTES_PER_2048_PROBE, coarse_level_bytes, summarize

# The project's shared test data: LFPROBE_SHARED_DATA, else ../shared/data beside the checkout.
SHARED_PUMP_XYZ = os.path.join(
    os.environ.get("LFPROBE_SHARED_DATA")
    or os.path.join(os.path.dirname(__file__), "..", "..", "..", "..", "shared", "data"),
    "scans", "pumpA_xyzrgb.xyz")


def _best_of(fn, repeats: int) -> float:
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return best


# Axis-aligned boxes of the benchmark room: the room itself (seen from inside), two tables and
# a column (seen from outside).
ROOM_BOXES = [((0.0, 0.0, 0.0), (3.0, 6.0, 2.7)), ((0.2, 0.5, 0.0), (1.0, 2.5, 0.75)),
              ((2.0, 3.5, 0.0), (2.8, 5.5, 0.75)), ((1.4, 2.9, 0.0), (1.6, 3.1, 2.7))]


def room_faces():
    """(axis, coordinate, box min, box max, area, outward sign) of every face; the room's own
    faces face inward, the furniture's outward."""
    faces = []
    for index, (bmin, bmax) in enumerate(ROOM_BOXES):
        bmin, bmax = np.asarray(bmin, float), np.asarray(bmax, float)
        inward = -1.0 if index == 0 else 1.0
        for axis in range(3):
            u, v = (axis + 1) % 3, (axis + 2) % 3
            area = (bmax[u] - bmin[u]) * (bmax[v] - bmin[v])
            for w, side in ((bmin[axis], -1.0), (bmax[axis], 1.0)):
                faces.append((axis, w, bmin, bmax, area, side * inward))
    return faces


def write_room_obj(path: str) -> None:
    """The benchmark room as a mesh (two triangles per box face), the reference geometry that
    Embree traces for the probe-versus-Embree ratio."""
    lines = ["# lfprobe benchmark room"]
    vertex = 0
    for axis, w, bmin, bmax, _, _ in room_faces():
        u, v = (axis + 1) % 3, (axis + 2) % 3
        for a, b in ((0, 0), (1, 0), (1, 1), (0, 1)):
            p = [0.0, 0.0, 0.0]
            p[axis] = w
            p[u] = (bmin[u], bmax[u])[a]
            p[v] = (bmin[v], bmax[v])[b]
            lines.append(f"v {p[0]:.6f} {p[1]:.6f} {p[2]:.6f}")
        lines.append(f"f {vertex + 1} {vertex + 2} {vertex + 3}")
        lines.append(f"f {vertex + 1} {vertex + 3} {vertex + 4}")
        vertex += 4
    with open(path, "w", encoding="ascii") as out:
        out.write("\n".join(lines) + "\n")


def room_surface_area() -> float:
    return float(sum(f[4] for f in room_faces()))


def room_cloud(points: int, seed: int = 1, with_normals: bool = False):
    """A 3 × 6 × 2.7 m room with tables and a column, sampled uniformly at random, with a
    colour pattern: positions (n,3) float32 and linear colours (n,3) float32, and with
    with_normals the true surface normals (n,3) float32 as a third value. (A single scanner
    could not orient the normals of every face: each of these faces is seen from somewhere.)"""
    rng = np.random.default_rng(seed)
    faces = room_faces()
    areas = np.array([f[4] for f in faces])
    counts = rng.multinomial(points, areas / areas.sum())
    chunks = []
    normal_chunks = []
    for (axis, w, bmin, bmax, _, sign), count in zip(faces, counts):
        p = rng.uniform(bmin, bmax, size=(count, 3))
        p[:, axis] = w
        chunks.append(p)
        n = np.zeros((count, 3), np.float32)
        n[:, axis] = sign
        normal_chunks.append(n)
    positions = np.concatenate(chunks).astype(np.float32)
    stripes = 0.5 + 0.5 * np.sin(7.0 * positions[:, 0]) * np.cos(5.0 * positions[:, 1])
    colors = np.stack(
        [0.1 + 0.7 * stripes, 0.2 + 0.3 * (positions[:, 2] / 2.7), 0.4 - 0.2 * stripes], axis=1
    ).astype(np.float32)
    if with_normals:
        return positions, colors, np.concatenate(normal_chunks)
    return positions, colors


def write_xyz(path: str, positions: np.ndarray, colors_u8: np.ndarray) -> None:
    """FARO-style 'x y z r g b' text, written in blocks."""
    with open(path, "w", encoding="ascii") as out:
        for start in range(0, len(positions), 200_000):
            p = positions[start : start + 200_000]
            c = colors_u8[start : start + 200_000]
            lines = "\n".join(
                f"{x:.5f} {y:.5f} {z:.5f} {r} {g} {b}"
                for (x, y, z), (r, g, b) in zip(p.tolist(), c.tolist())
            )
            out.write(lines + "\n")


def parse_benchmark(path: str, label: str, tmp: str, loadtxt_repeats: int) -> dict:
    _native = native.load()
    size = os.path.getsize(path)
    native_seconds = _best_of(lambda: _native.load_scans([path], cache_dir=""), 3)
    points = len(_native.load_scans([path], cache_dir=""))
    cache = os.path.join(tmp, "cache")
    _native.load_scans([path], cache_dir=cache)
    cached_seconds = _best_of(lambda: _native.load_scans([path], cache_dir=cache), 3)
    loadtxt_seconds = _best_of(lambda: np.loadtxt(path), loadtxt_repeats)
    return {
        "file": label,
        "bytes": size,
        "points": points,
        "native_seconds": native_seconds,
        "native_mb_per_s": size / native_seconds / 1e6,
        "native_mpoints_per_s": points / native_seconds / 1e6,
        "cached_seconds": cached_seconds,
        "loadtxt_seconds": loadtxt_seconds,
        "loadtxt_mb_per_s": size / loadtxt_seconds / 1e6,
        "speedup_vs_loadtxt": loadtxt_seconds / native_seconds,
    }


def bake_benchmark(points: int, resolution: int, tmp: str) -> dict:
    _native = native.load()
    start = time.perf_counter()
    positions, colors = room_cloud(points)
    generate_seconds = time.perf_counter() - start
    # Normals estimated by PCA and oriented toward a scanner in the open middle of the room.
    cloud = _native.PointCloud.from_arrays(positions, colors, scanners=[[1.5, 1.5, 1.4]])
    del positions, colors
    folder = os.path.join(tmp, "probes")
    probes = [[1.5, 1.5, 1.4], [1.5, 4.5, 1.4]]
    summary = _native.bake_probe_set(
        cloud, folder, resolution=resolution, positions=probes, positions_in_world=False
    )
    info = summarize(folder)
    n = summary["probe_count"]
    fine = summary["bytes_in_memory_per_probe"]
    return {
        "points": points,
        "resolution": resolution,
        "probes": n,
        "generate_seconds": generate_seconds,
        "normals_seconds_per_cloud": summary["normals_seconds"],
        "bake_seconds_per_probe": summary["bake_seconds"] / n,
        "write_seconds_per_probe": summary["write_seconds"] / n,
        "coverage": summary["mean_coverage"],
        "memory_bytes_per_probe": fine + coarse_level_bytes(resolution),
        "memory_fine_bytes_per_probe": fine,
        "disk_bytes_per_probe": info["disk_bytes_per_probe"],
        "paper_bytes_per_2048_probe": PAPER_BYTES_PER_2048_PROBE,
    }


def write_results(path: str, results: dict) -> None:
    """A benchmark's figures as JSON, where --json asks for them (no file otherwise)."""
    if path:
        with open(path, "w", encoding="utf-8") as out:
            json.dump(results, out, indent=2)


def main(args) -> int:
    tmp = tempfile.mkdtemp(prefix="lfprobe-bench-")
    results = {"cpu_count": os.cpu_count()}
    try:
        print("== scan parsing: native reader vs numpy.loadtxt, same file, this run ==")
        rows = []
        pump = os.path.abspath(SHARED_PUMP_XYZ)
        if os.path.isfile(pump):
            rows.append(parse_benchmark(pump, "pumpA_xyzrgb.xyz (real scan)", tmp, 3))
        generated = os.path.join(tmp, "room.xyz")
        positions, colors = room_cloud(args.parse_points, seed=2)
        srgb = np.clip(np.round(255 * np.power(colors, 1 / 2.2)), 0, 255).astype(np.uint8)
        write_xyz(generated, positions, srgb)
        del positions, colors, srgb
        rows.append(parse_benchmark(generated, f"generated room, {args.parse_points:,} points", tmp, 1))
        for r in rows:
            print(
                f"{r['file']}: {r['bytes'] / 1e6:.1f} MB, {r['points']:,} points\n"
                f"  native {r['native_seconds']:.3f} s ({r['native_mb_per_s']:.0f} MB/s, "
                f"{r['native_mpoints_per_s']:.1f} M points/s); from cache {r['cached_seconds']:.3f} s\n"
                f"  numpy.loadtxt {r['loadtxt_seconds']:.3f} s ({r['loadtxt_mb_per_s']:.1f} MB/s)\n"
                f"  native is {r['speedup_vs_loadtxt']:.1f}× faster than numpy.loadtxt"
            )
        results["parsing"] = rows
        os.remove(generated)

        print("\n== E57 and LAS/LAZ: lfprobe's readers vs the libraries' own, same file, this run ==")
        results["parsing_library_formats"] = library_parse_benchmark(os.path.dirname(pump), tmp)

        print(f"\n== bake: {args.points:,} points, {args.res}² probes ==")
        b = bake_benchmark(args.points, args.res, tmp)
        results["bake"] = b
        mib = 1024 * 1024
        print(
            f"  local geometry (kNN normals + spacing, once per cloud): {b['normals_seconds_per_cloud']:.2f} s\n"
            f"  bake per probe (splat, resolve, hole fill): {b['bake_seconds_per_probe']:.2f} s\n"
            f"  EXR write per probe: {b['write_seconds_per_probe']:.2f} s\n"
            f"  coverage: surface {100 * b['coverage']['surface']:.2f}%, "
            f"inferred {100 * b['coverage']['inferred']:.2f}%, unknown {100 * b['coverage']['unknown']:.2f}%\n"
            f"  bytes per probe: {b['memory_bytes_per_probe'] / mib:.2f} MiB in memory "
            f"({b['memory_fine_bytes_per_probe'] / mib:.2f} fine maps + coarse levels), "
            f"{b['disk_bytes_per_probe'] / mib:.2f} MiB on disk (ZIP EXR)"
        )
        if args.res == 2048:
            paper = b["paper_bytes_per_2048_probe"]
            print(
                f"  the paper's 2048² probe: {paper / mib:.3f} MiB; ours is "
                f"{b['memory_bytes_per_probe'] / paper:.2f}× in memory, "
                f"{b['disk_bytes_per_probe'] / paper:.2f}× on disk"
            )
        write_results(args.json, results)
        return 0
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
