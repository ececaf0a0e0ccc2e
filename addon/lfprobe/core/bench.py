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
from .bench_formats import best_of, library_parse_benchmark
from .pipeline import load_scans
from .probe_set import PAPER_BYTES_PER_2048_PROBE, coarse_level_bytes, summarize

# The project's shared test data: LFPROBE_SHARED_DATA, else ../shared/data beside the checkout.
SHARED_PUMP_XYZ = os.path.join(
    os.environ.get("LFPROBE_SHARED_DATA")
    or os.path.join(os.path.dirname(__file__), "..", "..", "..", "..", "shared", "data"),
    "scans", "pumpA_xyzrgb.xyz")


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


def face_corners(axis: int, w: float, bmin, bmax):
    """The four corners of a box face (as room_faces gives it), in order around the face: the
    face's two other axes u, v = axis+1, axis+2 (mod 3) go (min, min), (max, min), (max, max),
    (min, max)."""
    u, v = (axis + 1) % 3, (axis + 2) % 3
    corners = []
    for a, b in ((0, 0), (1, 0), (1, 1), (0, 1)):
        p = [0.0, 0.0, 0.0]
        p[axis] = w
        p[u] = (bmin[u], bmax[u])[a]
        p[v] = (bmin[v], bmax[v])[b]
        corners.append(p)
    return corners


def write_room_obj(path: str) -> None:
    """The benchmark room as a mesh (two triangles per box face), the reference geometry that
    Embree traces for the probe-versus-Embree ratio."""
    lines = ["# lfprobe benchmark room"]
    vertex = 0
    for axis, w, bmin, bmax, _, _ in room_faces():
        for p in face_corners(axis, w, bmin, bmax):
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
    del chunks
    colors = room_colour(positions)
    if with_normals:
        return positions, colors, np.concatenate(normal_chunks)
    return positions, colors


def room_colour(positions: np.ndarray) -> np.ndarray:
    """The benchmark room's colour pattern at (n, 3) positions: linear RGB (n, 3) float32. The
    room's mesh has no colours, so a probe's true radiance comes from this at its hit points."""
    x, y, z = (positions[..., a] for a in range(3))
    stripes = 0.5 + 0.5 * np.sin(7.0 * x) * np.cos(5.0 * y)
    return np.stack([0.1 + 0.7 * stripes, 0.2 + 0.3 * (z / 2.7), 0.4 - 0.2 * stripes],
                    axis=-1).astype(np.float32)


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


# Runs of the native reader per figure, the fastest kept: on this shared 2-core machine one parse
# of a 72 MB file varies between 60 and 95 ms from run to run, so three runs were not enough to
# give the same figure twice. The slower numpy.loadtxt side is disturbed relatively less.
NATIVE_PARSE_REPEATS = 7


def parse_benchmark(path: str, label: str, tmp: str, loadtxt_repeats: int) -> dict:
    _native = native.load()
    size = os.path.getsize(path)
    native_seconds = best_of(lambda: _native.load_scans([path], cache_dir=""), NATIVE_PARSE_REPEATS)
    points = len(_native.load_scans([path], cache_dir=""))
    cache = os.path.join(tmp, "cache")
    _native.load_scans([path], cache_dir=cache)
    cached_seconds = best_of(lambda: _native.load_scans([path], cache_dir=cache), NATIVE_PARSE_REPEATS)
    loadtxt_seconds = best_of(lambda: np.loadtxt(path), loadtxt_repeats)
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
        "hierarchy_seconds_per_cloud": summary["hierarchy_seconds"],
        "bake_seconds_per_probe": summary["bake_seconds"] / n,
        "write_seconds_per_probe": summary["write_seconds"] / n,
        "coverage": summary["mean_coverage"],
        "memory_bytes_per_probe": fine + coarse_level_bytes(resolution),
        "memory_fine_bytes_per_probe": fine,
        "disk_bytes_per_probe": info["disk_bytes_per_probe"],
        "paper_bytes_per_2048_probe": PAPER_BYTES_PER_2048_PROBE,
    }


HIERARCHY_PROBE = [1.5, 1.5, 1.4]


def _texel_directions(resolution: int) -> np.ndarray:
    n = resolution
    centres = (np.arange(n, dtype=np.float64) + 0.5) / n
    uv = np.stack(np.meshgrid(centres, centres), axis=-1).reshape(-1, 2).astype(np.float32)
    return native.load().oct_decode(uv).reshape(n, n, 3)


def reference_probe(resolution: int, tmp: str) -> dict:
    """The exact probe at HIERARCHY_PROBE: the room mesh baked with Embree for the distances,
    the room's colour pattern at each texel's hit for the radiance."""
    _native = native.load()
    obj = os.path.join(tmp, "room.obj")
    write_room_obj(obj)
    folder = os.path.join(tmp, "mesh_probe")
    _native.start_bake_probe_set_from_mesh(_native.load_mesh(obj), folder, resolution=resolution,
                                           positions=[HIERARCHY_PROBE]).run()
    probe = _native.read_probe(os.path.join(folder, "probe_00000.exr"))
    hits = np.asarray(HIERARCHY_PROBE) + _texel_directions(resolution) * probe["distance"][..., None]
    probe["true_rgb"] = room_colour(hits)
    shutil.rmtree(folder, ignore_errors=True)
    return probe


def probe_errors(probe: dict, reference: dict) -> dict:
    """A scan-baked probe against the exact one, over the texels the exact probe sees a
    surface: PSNR of the radiance, depth error, and the share of those texels left unknown."""
    surface = reference["state"] == 2
    known = (probe["state"] == 2) | (probe["state"] == 3)
    both = surface & known
    mse = float(np.mean((probe["rgba"][..., :3][both] - reference["true_rgb"][both]) ** 2))
    depth = np.abs(probe["distance"][both] - reference["distance"][both]) / reference["distance"][both]
    return {
        "psnr_db": 10.0 * np.log10(1.0 / max(mse, 1e-20)),
        "depth_error_mean": float(depth.mean()),
        "depth_error_p99": float(np.percentile(depth, 99)),
        "unknown_share": float(np.mean(~known[surface])),
    }


def hierarchy_benchmark(points: int, resolution: int, lods: list, reference: dict, tmp: str,
                        colour_tolerance: float = 0.0) -> dict:
    """One probe baked from a generated room of `points` points, once per lod_texels in `lods`
    (0: every point splatted, as before the point hierarchy), and with colour_tolerance above 0
    once more at lod_texels 1 with that lod_colour_tolerance; each against the exact probe."""
    _native = native.load()
    start = time.perf_counter()
    positions, colors = room_cloud(points)
    generate_seconds = time.perf_counter() - start
    cloud = _native.PointCloud.from_arrays(positions, colors, scanners=[HIERARCHY_PROBE])
    del positions, colors
    row = {"points": points, "resolution": resolution, "generate_seconds": generate_seconds,
           "bakes": []}
    variants = [(float(lod), 0.0) for lod in lods]
    if colour_tolerance > 0.0:
        variants.append((1.0, float(colour_tolerance)))
    for lod, tolerance in variants:
        folder = os.path.join(tmp, f"lod_{lod}_{tolerance}")
        summary = _native.bake_probe_set(cloud, folder, resolution=resolution,
                                         positions=[HIERARCHY_PROBE], positions_in_world=False,
                                         lod_texels=lod, lod_colour_tolerance=tolerance)
        probe = _native.read_probe(os.path.join(folder, "probe_00000.exr"))
        shutil.rmtree(folder, ignore_errors=True)
        row["bakes"].append({"lod_texels": lod, "lod_colour_tolerance": tolerance,
                             "normals_seconds": summary["normals_seconds"],
                             "hierarchy_seconds": summary["hierarchy_seconds"],
                             "bake_seconds": summary["bake_seconds"],
                             **probe_errors(probe, reference)})
    del cloud
    return row


def texel_scaling_benchmark(points: int, resolutions: list, tmp: str) -> dict:
    """One probe at HIERARCHY_PROBE baked from the same generated room at each resolution (the
    default lod_texels): the bake's seconds against the probe's texels. The cloud's normals and
    hierarchy are made once (a prepared-cloud cache in `tmp`), so each row is the probe's own
    bake."""
    _native = native.load()
    positions, colors = room_cloud(points)
    cloud = _native.PointCloud.from_arrays(positions, colors, scanners=[HIERARCHY_PROBE])
    del positions, colors
    cache = os.path.join(tmp, "texel_scaling_cache")
    rows = []
    for res in resolutions:
        folder = os.path.join(tmp, f"texels_{res}")
        summary = _native.bake_probe_set(cloud, folder, resolution=res, positions=[HIERARCHY_PROBE],
                                         positions_in_world=False, cache_dir=cache)
        shutil.rmtree(folder, ignore_errors=True)
        rows.append({"resolution": res, "texels": res * res, "bake_seconds": summary["bake_seconds"],
                     "seconds_per_million_texels": summary["bake_seconds"] / (res * res / 1e6)})
    del cloud
    shutil.rmtree(cache, ignore_errors=True)
    return {"points": points, "rows": rows}


def simulated_scan_benchmark(points: int, tmp: str) -> dict:
    """One full sweep of the benchmark room from its middle at the step that gives about
    `points` rays (every ray meets a wall): streamed into a cloud (start_simulate_scans) and
    written as .xyz then parsed (start_simulate_scan, load_scans), the same scan both ways."""
    _native = native.load()
    mesh_path = os.path.join(tmp, "sim_room.obj")
    write_room_obj(mesh_path)
    mesh = _native.load_mesh(mesh_path)
    # A sweep takes 360/step azimuths of elevations from -60° to 90° (vertical fov 300°).
    step = float(np.sqrt(360.0 * 150.0 / points))
    at = [1.5, 3.0, 1.4]
    start = time.perf_counter()
    streamed = _native.start_simulate_scans(mesh, [at], step_deg=step, noise_mm=1.0).run()
    streamed_seconds = time.perf_counter() - start
    count = len(streamed["cloud"])
    scan_seconds = streamed["stats"][0]["seconds"]
    del streamed
    path = os.path.join(tmp, "sim_scan.xyz")
    start = time.perf_counter()
    _native.start_simulate_scan(mesh, path, at, step_deg=step, noise_mm=1.0).run()
    write_seconds = time.perf_counter() - start
    size = os.path.getsize(path)
    start = time.perf_counter()
    parsed = load_scans([path], [at], cache_dir="")
    parse_seconds = time.perf_counter() - start
    if len(parsed) != count:
        raise RuntimeError(f"the streamed scan has {count} points, its file {len(parsed)}")
    del parsed
    os.remove(path)
    return {"points": count, "step_deg": step, "streamed_seconds": streamed_seconds,
            "scan_seconds": scan_seconds, "write_seconds": write_seconds, "parse_seconds": parse_seconds,
            "file_seconds": write_seconds + parse_seconds, "file_bytes": size}


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
        if args.parse_points > 0:
            generated = os.path.join(tmp, "room.xyz")
            positions, colors = room_cloud(args.parse_points, seed=2)
            srgb = np.clip(np.round(255 * np.power(colors, 1 / 2.2)), 0, 255).astype(np.uint8)
            write_xyz(generated, positions, srgb)
            del positions, colors, srgb
            # Written back before the timing: the file is then read from a warm page cache, not
            # beside the kernel's writeback of it (which takes one of the two cores for a while).
            descriptor = os.open(generated, os.O_RDONLY)
            try:
                os.fsync(descriptor)
            finally:
                os.close(descriptor)
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

        if args.scan_points > 0:
            print(f"\n== a simulated scan of about {args.scan_points:,} points (28 M: a station at the "
                  f"paper's density): streamed into a cloud vs written as .xyz and parsed, this run ==")
            results["simulated_scan"] = s = simulated_scan_benchmark(args.scan_points, tmp)
            print(f"  {s['points']:,} points: streamed into a cloud in {s['streamed_seconds']:.2f} s "
                  f"(scanning {s['scan_seconds']:.2f} s); through a {s['file_bytes'] / 2**30:.2f} GiB .xyz "
                  f"{s['file_seconds']:.2f} s (scan and write {s['write_seconds']:.2f} s, parse "
                  f"{s['parse_seconds']:.2f} s): streaming is {s['file_seconds'] / s['streamed_seconds']:.1f}× faster")

        print("\n== E57 and LAS/LAZ: lfprobe's readers vs the libraries' own, same file, this run ==")
        results["parsing_library_formats"] = library_parse_benchmark(os.path.dirname(pump), tmp)

        print(f"\n== bake: {args.points:,} points, {args.res}² probes ==")
        b = bake_benchmark(args.points, args.res, tmp)
        results["bake"] = b
        mib = 1024 * 1024
        print(
            f"  local geometry (kNN normals + spacing, once per cloud): {b['normals_seconds_per_cloud']:.2f} s\n"
            f"  point hierarchy and the points in its curve order (once per cloud): "
            f"{b['hierarchy_seconds_per_cloud']:.2f} s\n"
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
        resolutions = [int(r) for r in str(args.texel_resolutions).split(",") if r.strip()]
        if resolutions:
            print(f"\n== bake against the probe's texels: one probe from the same {args.points:,} points "
                  f"at {', '.join(f'{r}²' for r in resolutions)} ==")
            t = texel_scaling_benchmark(args.points, resolutions, tmp)
            results["texel_scaling"] = t
            first = t["rows"][0]
            for row in t["rows"]:
                print(f"  {row['resolution']}²: bake {row['bake_seconds']:.2f} s, "
                      f"{row['seconds_per_million_texels']:.3f} s per million texels; "
                      f"{row['texels'] / first['texels']:.0f}× the texels of {first['resolution']}², "
                      f"{row['bake_seconds'] / first['bake_seconds']:.2f}× the time")
        # Empty or 0 skips the comparison, as --scan-points 0 skips the scan (a cloud of no points
        # has nothing to bake: the native error said only that).
        points_list = [n for n in (int(float(p)) for p in str(args.hierarchy_points).split(",")
                                   if p.strip()) if n > 0]
        if points_list:
            lods = [float(x) for x in str(args.hierarchy_lods).split(",")]
            print(f"\n== point hierarchy: one {args.res}² probe from generated rooms, every point "
                  f"(lod_texels 0) vs the hierarchy's cut; errors against the exact (mesh) probe ==")
            reference = reference_probe(args.res, tmp)
            rows = []
            for points in points_list:
                row = hierarchy_benchmark(points, args.res, lods, reference, tmp,
                                          args.hierarchy_colour_tolerance)
                rows.append(row)
                base = row["bakes"][0]
                print(f"{points:,} points (generated in {row['generate_seconds']:.1f} s; normals + "
                      f"spacing {base['normals_seconds']:.2f} s on {os.cpu_count()} cores):")
                for b in row["bakes"]:
                    tolerance = (f", colour tolerance {b['lod_colour_tolerance']:g}"
                                 if b["lod_colour_tolerance"] > 0 else "")
                    print(f"  lod_texels {b['lod_texels']:g}{tolerance}: bake {b['bake_seconds']:.2f} s"
                          f" (+ hierarchy {b['hierarchy_seconds']:.2f} s once per cloud), "
                          f"PSNR {b['psnr_db']:.2f} dB, depth error mean {100 * b['depth_error_mean']:.3f} %"
                          f" p99 {100 * b['depth_error_p99']:.3f} %, unknown {100 * b['unknown_share']:.3f} %;"
                          f" {base['bake_seconds'] / b['bake_seconds']:.2f}× the all-points bake's speed,"
                          f" {b['psnr_db'] - base['psnr_db']:+.2f} dB")
            if len(rows) > 1:
                for first, last in zip(rows[0]["bakes"], rows[-1]["bakes"]):
                    what = (f"lod_texels {first['lod_texels']:g}" if first["lod_texels"] > 0 else "every point")
                    if first["lod_colour_tolerance"] > 0:
                        what += f", colour tolerance {first['lod_colour_tolerance']:g}"
                    print(f"  {rows[-1]['points'] / rows[0]['points']:.0f}× the points ({what}): "
                          f"{last['bake_seconds'] / first['bake_seconds']:.2f}× the bake time, "
                          f"{last['psnr_db'] - first['psnr_db']:+.2f} dB")
            results["hierarchy"] = rows
        write_results(args.json, results)
        return 0
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
