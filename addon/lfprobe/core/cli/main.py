"""The lfprobe command line (bpy-free): ``./lfprobe SUBCOMMAND ...`` from the checkout.

Subcommands: bake (scan files → probe set), info (what a probe set holds), render (a view
traced through the probes), splat (the raw cloud drawn as splats), camera (a camera file) and
bench (measured figures) are here; store, compare, gt, scan, place and report each have their
module in this package. Exit status: 0 success, 2 bad input, 1 other failure, 130 cancelled.
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from typing import Optional, Sequence

from .. import defaults, native
from . import compare as compare_cli, mesh as mesh_cli, place as place_cli, report as report_cli, storage as storage_cli
from ..cluster_bake import bake_scans_on_cluster
from ..pipeline import BakeOptions, ProbePlacementSpec, bake_from_mesh, bake_from_scans
from ..probe_set import PAPER_BYTES_PER_2048_PROBE, summarize
from ..probe_storage import describe as describe_storage
from ..trace_hints import camera_of, unknown_hint
from ..progress import TerminalProgress
from .arguments import (finite_float, COLUMNS_HELP, SCAN_HELP, add_placement_arguments, add_plan_arguments, add_storage_arguments,
                        bake_storage, plan_options, triples)


def _mib(n: float) -> str:
    return f"{n / (1024 * 1024):.2f} MiB"


def _cmd_bake(args) -> int:
    placement = ProbePlacementSpec(
        positions=triples(args.probe, "--probe"),
        grid_min=args.grid_min,
        grid_max=args.grid_max,
        counts=args.counts,
    )
    options = BakeOptions(
        resolution=args.res,
        splat_scale=args.splat_scale,
        hole_fill_texels=args.hole_fill,
        normal_neighbours=args.normal_k,
        lod_texels=args.lod_texels,
        lod_colour_tolerance=args.lod_colour_tolerance,
        splat_edge_margin=args.splat_edge_margin,
        splat_core_scale=args.splat_core,
    )
    if args.auto:
        if args.mesh:
            raise ValueError("--auto plans from scan points: use it with --scan")
        options.plan = plan_options(args)
    options.storage = bake_storage(args)
    options.distance_step = args.distance_step
    progress = None if args.quiet else TerminalProgress()
    if args.mesh:
        if args.scheduler or args.workers is not None:
            raise ValueError("--scheduler and --workers bake from scans (--scan); bake a mesh locally")
        if args.supersample is not None:
            options.extra["supersample"] = args.supersample
        if args.texture_filter is not None:
            options.extra["filter_textures"] = args.texture_filter == "footprint"
        summary = bake_from_mesh(args.mesh, args.out, placement, options, progress)
        summary.setdefault("points", 0)
        return _print_bake_summary(args, summary, f"{args.mesh[0]}")
    scans = dict(scanners=triples(args.scanner, "--scanner"), columns=args.columns or "",
                 cache_dir="" if args.no_cache else args.cache, progress=progress)
    if args.scheduler or args.workers is not None:
        if args.scheduler and args.workers is not None:
            raise ValueError("give --scheduler (a running cluster) or --workers (a local one), not both")
        summary = bake_scans_on_cluster(args.scan, args.out, placement, options, scheduler=args.scheduler,
                                        workers=args.workers, probes_per_task=args.probes_per_task, **scans)
    else:
        summary = bake_from_scans(args.scan, args.out, placement, options, **scans)
    return _print_bake_summary(args, summary, f"{summary['points']:,} points")


def _print_bake_summary(args, summary: dict, source: str) -> int:
    if args.json:
        print(json.dumps(summary, indent=2))
        return 0
    cov = summary["mean_coverage"]
    n = summary["probe_count"]
    size = "planned resolutions" if getattr(args, "auto", False) else f"{args.res}²"
    print(f"baked {n} probe(s) at {size} from {source} into {summary['folder']}")
    timing = []
    if summary.get("prepared_from_cache"):
        timing.append(f"normals and point hierarchy read from the cache {summary['normals_seconds']:.2f} s")
    elif "normals_seconds" in summary:
        timing.append(f"normals {summary['normals_seconds']:.2f} s")
    if summary.get("hierarchy_seconds"):
        timing.append(f"point hierarchy {summary['hierarchy_seconds']:.2f} s")
    timing.append(f"bake {summary['bake_seconds']:.2f} s ({summary['bake_seconds'] / n:.2f} s/probe)")
    if "write_seconds" in summary:
        timing.append(f"write {summary['write_seconds']:.2f} s")
    print("  " + ", ".join(timing))
    if "cluster" in summary:
        c = summary["cluster"]
        print(f"  cluster: {c['workers']} worker(s), {c['tasks']} task(s) in {c['tasks_seconds']:.2f} s, "
              f"{c['probes_per_second']:.2f} probes/s; " + (
                  f"each task read at most {_mib(c['bytes_read_per_task'])} of the "
                  f"{_mib(c['spatial_cloud_bytes'])} spatial cloud the client prepared in "
                  f"{c.get('client_prepare_seconds', 0.0):.2f} s"
                  if c.get("tasks_reading_in_parts") else
                  f"each worker read {_mib(c['bytes_read_per_worker'])} "
                  f"and made the cloud ready in {c['prepare_seconds_per_worker']:.2f} s "
                  f"({c.get('workers_reading_the_prepared_cloud', 0)} read what the client prepared in "
                  f"{c.get('client_prepare_seconds', 0.0):.2f} s)") +
              f", peak memory {_mib(c['peak_memory_per_worker'])}; "
              f"scheduler overhead {1000 * c['overhead_seconds_per_task']:.1f} ms/task")
    print(
        f"  coverage: surface {100 * cov['surface']:.2f}%, inferred {100 * cov['inferred']:.2f}%, "
        f"unknown {100 * cov['unknown']:.2f}%, empty {100 * cov['empty']:.2f}%"
    )
    if "bytes_in_memory_per_probe" in summary:
        print(
            f"  per probe: {_mib(summary['bytes_in_memory_per_probe'])} in memory, "
            f"{_mib(summary['bytes_on_disk'] / n)} on disk"
        )
    if summary.get("storage"):
        print(f"  storage: {describe_storage(summary['storage'])}")
    return 0


def _cmd_info(args) -> int:
    info = summarize(args.folder)
    if args.json:
        if not args.probes:
            info.pop("probes")
        print(json.dumps(info, indent=2))
        return 0 if not info["missing_files"] else 1
    print(f"probe set {info['folder']} (format {info['format_version']})")
    if info["layout"] == "grid":
        g = info["grid"]
        print(
            f"  grid {g['counts'][0]}×{g['counts'][1]}×{g['counts'][2]}, origin {g['origin']}, "
            f"spacing {g['spacing']} (local frame)"
        )
    print(f"  probes: {info['probe_count']}, resolution(s): {', '.join(map(str, info['resolutions']))}")
    print(f"  world offset: {info['world_offset']}")
    c = info["coverage"]
    print(
        f"  coverage (mean): surface {100 * c['surface']:.2f}%, inferred {100 * c['inferred']:.2f}%, "
        f"unknown {100 * c['unknown']:.2f}%, empty {100 * c['empty']:.2f}%"
    )
    if info.get("storage"):
        print(f"  storage in memory: {describe_storage(info['storage'])}")
    per = info["memory_bytes_per_probe"]
    print(
        f"  memory: {_mib(info['memory_bytes'])} ({_mib(per)} per probe with coarse levels); "
        f"disk: {_mib(info['disk_bytes'])} ({_mib(info['disk_bytes_per_probe'])} per probe)"
    )
    if 2048 in info["resolutions"]:
        print(f"  the paper's 2048² probe: {_mib(PAPER_BYTES_PER_2048_PROBE)}")
    for source in info["sources"]:
        print(f"  source: {source.get('path')} ({source.get('points', '?')} points, sha256 {str(source.get('sha256'))[:12]}…)")
    if args.probes:
        for p in info["probes"]:
            cov = p.get("coverage", {})
            print(
                f"    {p['file']}: at {p['position']}, {p['resolution']}², "
                f"surface {100 * cov.get('surface', 0):.1f}%, inferred {100 * cov.get('inferred', 0):.1f}%, "
                f"unknown {100 * cov.get('unknown', 0):.1f}%"
            )
    for missing in info["missing_files"]:
        print(f"  MISSING: {missing}")
    return 0 if not info["missing_files"] else 1


def fidelity_options(args) -> dict:
    """The image options given on the command line (--spp, --filter, --blend, --hole-fill-px,
    --keep-inferred-hits); those left out keep the native renderer's defaults."""
    options = {key: value for key, value in (("spp", args.spp), ("filter", args.filter), ("blend", args.blend),
                                             ("hole_fill", args.hole_fill_px))
               if value is not None}
    if args.keep_inferred_hits:
        options["prefer_measured"] = False
    return options


def add_fidelity_arguments(parser) -> None:
    parser.add_argument("--spp", type=int, default=None, metavar="N",
                        help="samples per pixel: 1 (default) or a square (4, 9, 16, ...), the ground "
                             "truth's stratified pattern; colour and coverage are averaged, depth, status, "
                             "probe from the pixel centre, steps summed over the pixel's rays")
    parser.add_argument("--filter", choices=["nearest", "bilinear", "footprint", "bicubic"], default=None,
                        help="a HIT's colour: its texel (nearest) or interpolated between the texels "
                             "around it on the same surface (bilinear, default); footprint: as "
                             "bilinear, and where a sample spans more than a texel, the probe's "
                             "prefiltered radiance at the sample's width (one ray per pixel "
                             "anti-aliased, as texture LOD does); bicubic: Catmull-Rom over the 4×4 "
                             "texels around it where all lie on the surface, else bilinear (sharper: "
                             "undoes part of the texels' own averaging)")
    parser.add_argument("--blend", type=int, default=None, metavar="N",
                        help="probes a HIT's colour is blended from, weighted by how finely each sees the "
                             "point (1: the first probe that answers, as the paper; default 4; at most 8)")
    parser.add_argument("--hole-fill-px", type=int, default=None, metavar="N",
                        help="holes of pixels whose rays no probe could answer (UNKNOWN), at most N "
                             "pixels across, are coloured from the HIT pixels around them (a pull-push, "
                             "as a bake fills a probe's narrow holes); their status stays UNKNOWN, so "
                             "the hole rate still counts them, and wider regions (a partial scan's "
                             "unscanned side) stay black. Default: 5%% of the image's larger side "
                             "(32 at 640 pixels); 0: off, UNKNOWN samples black (the paper's image)")
    parser.add_argument("--keep-inferred-hits", action="store_true",
                        help="answer a HIT on a hole-filled (inferred) texel at once, as the paper's "
                             "first-hit rule does; by default such a HIT waits while the other probes "
                             "are asked, and one that measured the point wins")


def _cmd_render(args) -> int:
    _native = native.load()
    job = _native.start_render(args.probes, args.camera, args.out, mode=args.mode,
                               threads=args.threads, thickness=args.thickness,
                               fallback_thickness=args.fallback_thickness,
                               max_probes_per_ray=args.max_probes_per_ray,
                               storage=None if args.storage == "manifest" else args.storage,
                               distance_step=args.distance_step, **fidelity_options(args))
    stats = job.run(None if args.quiet else TerminalProgress())
    if args.json:
        print(json.dumps(stats, indent=2))
        return 0
    rays = stats["rays"]
    pixels = max(stats["hits"] + stats["misses"] + stats["unknown"], 1)
    print(f"rendered {args.out}: {rays:,} rays in {stats['seconds'] * 1000:.1f} ms, "
          f"{stats['rays_per_second'] / 1e6:.2f} M rays/s")
    print(f"  pixels HIT {100 * stats['hits'] / pixels:.2f}%, MISS {100 * stats['misses'] / pixels:.2f}%, "
          f"UNKNOWN {100 * stats['unknown'] / pixels:.2f}%; {stats['mean_steps']:.1f} texels and "
          f"{stats['mean_probes']:.2f} probes per ray")
    if stats.get("guessed"):
        print(f"  guessed: {100 * stats['guessed'] / pixels:.2f}% of the pixels show a hole-filled texel, a "
              f"surface no scan saw (the image's guessed.X channel)")
    if stats.get("holes_filled") or stats.get("holes_left"):
        print(f"  hole fill: {stats['holes_filled']:,} pixels that no probe answered coloured from the pixels "
              f"around them, {stats['holes_left']:,} left black (in holes wider than the fill reaches)")
    hint = unknown_hint(stats, camera_of(args.camera), args.probes)
    if hint:
        print(f"  {hint}")
    return 0


def _cmd_splat(args) -> int:
    from ..pipeline import load_scans

    _native = native.load()
    progress = None if args.quiet else TerminalProgress()
    cloud = load_scans(args.scan, triples(args.scanner, "--scanner"), args.columns or "",
                       "" if args.no_cache else args.cache, progress=progress)
    # The cache that holds the parsed scans also holds their local spacing once a bake or a
    # splat has estimated it.
    job = _native.start_splat(cloud, args.camera, args.out, radius_scale=args.radius_scale,
                              fixed_radius=args.fixed_radius, threads=args.threads,
                              cache_dir="" if args.no_cache else args.cache)
    stats = job.run(progress)
    camera = json.load(open(args.camera, encoding="utf-8"))
    pixels = camera["resolution"][0] * camera["resolution"][1]
    stats["rays_per_second"] = pixels / stats["seconds"] if stats["seconds"] > 0 else 0.0
    if args.json:
        print(json.dumps(stats, indent=2))
        return 0
    print(f"splatted {stats['points']:,} points into {args.out} in {stats['seconds'] * 1000:.1f} ms "
          f"({stats['points_per_second'] / 1e6:.1f} M points/s, {stats['rays_per_second'] / 1e6:.2f} M "
          f"pixels/s); spacing estimate {stats['geometry_seconds']:.2f} s")
    print(f"  covered {100 * stats['covered'] / pixels:.2f}% of {pixels:,} pixels")
    return 0


def _cmd_camera(args) -> int:
    from ..camera_json import camera_dict, write_camera

    write_camera(args.out, camera_dict(args.position, args.look_at, args.res, args.lens, args.type))
    print(f"wrote {args.out}")
    return 0


def _cmd_bench(args) -> int:
    if args.res is None:
        args.res = {"render": 1024, "cluster": 512}.get(args.suite, 2048)
    if args.suite == "render":
        from .. import bench_render

        return bench_render.main(args)
    if args.suite == "cluster":
        from .. import bench_cluster

        return bench_cluster.main(args)
    from .. import bench

    return bench.main(args)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="lfprobe", description="Light field probes from laser scans.")
    sub = parser.add_subparsers(dest="command", required=True)

    bake = sub.add_parser("bake", help="bake a probe set from scan files or a mesh")
    source = bake.add_mutually_exclusive_group(required=True)
    source.add_argument("--scan", nargs="+", metavar="FILE", help=SCAN_HELP)
    source.add_argument("--mesh", nargs="+", metavar="FILE",
                        help="an .obj (+.mtl) or .ply mesh, baked with Embree (exact distances)")
    bake.add_argument("--supersample", type=int, default=None, metavar="N",
                      help="--mesh: n×n rays per texel for its colour, counting only those that meet "
                           "the centre ray's surface (default 4; 1: the centre ray alone)")
    bake.add_argument("--texture-filter", choices=["footprint", "point"], default=None,
                      help="--mesh: each ray's texture colour is its mean over the ray's footprint "
                           "(texture LOD, default) or the texture at the hit alone (point)")
    add_placement_arguments(bake)
    bake.add_argument("--res", type=int, default=defaults.bake("resolution"), help="octahedral map resolution N (N×N texels)")
    bake.add_argument("--out", required=True, metavar="DIR", help="probe set folder to write")
    bake.add_argument("--columns", help=COLUMNS_HELP)
    bake.add_argument("--cache", default=None, metavar="DIR", help="parsed-scan cache folder")
    bake.add_argument("--no-cache", action="store_true", help="parse the scans without the cache")
    bake.add_argument("--splat-scale", type=finite_float, default=defaults.bake("splat_scale"), help="splat radius / point spacing")
    bake.add_argument("--hole-fill", type=int, default=defaults.bake("hole_fill_texels"), help="widest hole (texels across) to fill: a hole where the scans could not see "
                       "behind a near surface continues the surface behind, any other is filled "
                       "from around it; 0: none; default: about 4.8°, 12 texels at 512², 48 at "
                       "2048², at least 4")
    bake.add_argument("--normal-k", type=int, default=defaults.bake("normal_neighbours"), help="neighbours for PCA normals")
    bake.add_argument("--splat-edge-margin", type=finite_float, default=defaults.bake("splat_edge_margin"),
                      metavar="S", help="how far (point spacings) a point at its surface's edge splats "
                                        "outward; negative: full discs (bakes before this option)")
    bake.add_argument("--splat-core", type=finite_float, default=defaults.bake("splat_core_scale"),
                      metavar="S", help="scans: a splat's core, in point spacings: a texel takes the nearest "
                                        "splat whose core reaches it, and the rest of a splat only fills texels "
                                        "no core reaches and the hole fill leaves unknown (default %(default)s; "
                                        "the --splat-scale or more: the whole "
                                        "splat is core, as bakes before this option)")
    bake.add_argument("--lod-texels", type=finite_float, default=defaults.bake("lod_texels"), metavar="T",
                      help="scans: where the point hierarchy's cell surfels are at most T texels apart "
                           "as the probe sees them they stand in for the points, so a probe's cost "
                           "follows its texels, not the cloud (default %(default)s; 0: splat every point)")
    bake.add_argument("--lod-colour-tolerance", type=finite_float,
                      default=defaults.bake("lod_colour_tolerance"), metavar="C",
                      help="scans: above 0, cells up to twice --lod-texels wide also stand in for their "
                           "points where their children's colours agree with theirs within C per channel "
                           "(linear) and their points lie within half a texel of their plane: where the "
                           "cloud is much denser than the texels and its colour smooth, about a quarter "
                           "of the surfels (default %(default)s: off; smooth colour at 10^8 points: 3x "
                           "faster; fine textures lose a little, see the README)")
    cluster = bake.add_argument_group(
        "cluster", "bake the probes on a Dask cluster; the scans, the parse cache and --out must be "
                   "at the same paths on every worker (shared storage)")
    cluster.add_argument("--scheduler", metavar="ADDRESS", default=None,
                         help="a running Dask scheduler (e.g. tcp://host:8786, from `dask scheduler`)")
    cluster.add_argument("--workers", type=int, default=None, metavar="N",
                         help="a local Dask cluster of N worker processes")
    cluster.add_argument("--probes-per-task", type=int, default=1, metavar="K",
                         help="probes baked by one cluster task (default 1)")
    bake.add_argument("--json", action="store_true", help="print the summary as JSON")
    bake.add_argument("--quiet", action="store_true", help="no progress output")
    bake.add_argument("--auto", action="store_true",
                      help="scans: plan first (see `place`): each probe at the resolution its "
                           "points support (--res is then ignored), probes inside geometry or "
                           "against walls moved, useless ones dropped")
    add_plan_arguments(bake)
    add_storage_arguments(bake, ["full", "compact"], None,
                           "how the probes load into memory (the files keep full precision): full "
                           "(18 bytes a texel), compact (7: 8-bit sRGB radiance, 16-bit distance, "
                           "8+8-bit normals, no confidence); default full, compact with --auto")
    bake.set_defaults(run=_cmd_bake)

    storage_cli.add_parsers(sub)

    info = sub.add_parser("info", help="what a probe set holds")
    info.add_argument("folder", metavar="DIR")
    info.add_argument("--json", action="store_true")
    info.add_argument("--probes", action="store_true", help="list every probe")
    info.set_defaults(run=_cmd_info)

    render = sub.add_parser("render", help="render a view by tracing a probe set")
    render.add_argument("--probes", required=True, metavar="DIR", help="probe set folder")
    render.add_argument("--camera", required=True, metavar="CAM.json", help="camera file (docs/DESIGN.md §3)")
    render.add_argument("--out", required=True, metavar="IMG.exr")
    render.add_argument("--mode", choices=["auto", "nearest", "grid"], default="auto",
                        help="auto: grid walk for grid sets, else nearest probes first")
    render.add_argument("--threads", type=int, default=0, help="cores to use (0: all); same image")
    render.add_argument("--thickness", type=finite_float, default=defaults.trace("thickness"),
                        help="surface thickness (m; a texel footprint at the surface's distance is added; "
                             f"default {defaults.trace('thickness'):g})")
    render.add_argument("--fallback-thickness", type=finite_float,
                        default=defaults.trace("fallback_thickness"),
                        metavar="M",
                        help="a ray that no probe answers meets the surface it stopped behind, if it came "
                             "within this distance of it (m; plus a texel footprint; at most --thickness: "
                             f"never; default {defaults.trace('fallback_thickness'):g})")
    render.add_argument("--max-probes-per-ray", type=int, default=defaults.trace("max_probes_per_ray"),
                        metavar="N",
                        help="ask at most N probes about a ray (0: every probe the walk reaches, "
                             "exact); a bound trades answers for time where most rays find none, "
                             "such as a partial scan's unseen parts (default 0)")
    add_fidelity_arguments(render)
    render.add_argument("--json", action="store_true", help="print the stats as JSON")
    render.add_argument("--quiet", action="store_true")
    add_storage_arguments(render, ["manifest", "full", "compact"], "manifest",
                           "how the probes are held in memory for this render: as the set's "
                           "manifest says, full or compact")
    render.set_defaults(run=_cmd_render)

    splat = sub.add_parser("splat", help="render the raw cloud as z-buffered splats (baseline)")
    splat.add_argument("--scan", nargs="+", required=True, metavar="FILE", help=SCAN_HELP)
    splat.add_argument("--scanner", nargs="+", type=finite_float, action="append", metavar="X")
    splat.add_argument("--camera", required=True, metavar="CAM.json")
    splat.add_argument("--out", required=True, metavar="IMG.exr")
    splat.add_argument("--columns", help=COLUMNS_HELP)
    splat.add_argument("--cache", default=None, metavar="DIR")
    splat.add_argument("--no-cache", action="store_true")
    splat.add_argument("--radius-scale", type=finite_float, default=0.8, help="splat half size / spacing")
    splat.add_argument("--fixed-radius", type=finite_float, default=0.0, help="splat half size in metres")
    splat.add_argument("--threads", type=int, default=0)
    splat.add_argument("--json", action="store_true")
    splat.add_argument("--quiet", action="store_true")
    splat.set_defaults(run=_cmd_splat)

    camera = sub.add_parser("camera", help="write a camera file without Blender")
    camera.add_argument("--position", nargs=3, type=finite_float, required=True, metavar=("X", "Y", "Z"))
    camera.add_argument("--look-at", nargs=3, type=finite_float, required=True, metavar=("X", "Y", "Z"))
    camera.add_argument("--res", nargs=2, type=int, default=[640, 480], metavar=("W", "H"))
    camera.add_argument("--lens", type=finite_float, default=35.0, help="focal length in mm (36 mm sensor)")
    camera.add_argument("--type", choices=["PERSP", "PANO_EQUIRECT"], default="PERSP")
    camera.add_argument("--out", required=True, metavar="CAM.json")
    camera.set_defaults(run=_cmd_camera)

    compare_cli.add_parsers(sub)
    mesh_cli.add_parsers(sub)
    report_cli.add_parsers(sub)
    place_cli.add_parsers(sub)

    bench = sub.add_parser("bench", help="benchmarks that print measured figures")
    bench.add_argument("suite", choices=["core", "render", "cluster"],
                       help="core: scan parsing and probe baking; render: probe tracing vs splatting")
    bench.add_argument("--points", type=int, default=10_000_000, help="points in the bake benchmark")
    bench.add_argument("--res", type=int, default=None,
                       help="probe resolution (default: 2048 for core, 1024 for render)")
    bench.add_argument("--parse-points", type=int, default=2_000_000,
                       help="points in the generated file for the parsing comparison (0: skip)")
    bench.add_argument("--splat-points", default="1000000,10000000,30000000",
                       help="render: cloud sizes for the splatting comparison")
    bench.add_argument("--scan-points", type=int, default=28_000_000,
                       help="core: points of the simulated scan streamed into a cloud and written as "
                            "a file (default 28 M, a station at the paper's density; 0: skip)")
    bench.add_argument("--hierarchy-points", default="10000000,100000000",
                       help="core: cloud sizes for the point hierarchy's bake comparison "
                            "(comma-separated; empty or 0: skip)")
    bench.add_argument("--hierarchy-lods", default="0,1,2",
                       help="core: lod_texels values to bake with, 0 (every point) first")
    bench.add_argument("--hierarchy-colour-tolerance", type=finite_float, default=0.01, metavar="C",
                       help="core: one more hierarchy bake per cloud, at lod_texels 1 with this "
                            "lod_colour_tolerance (default %(default)s; 0: skip)")
    bench.add_argument("--texel-resolutions", default="1024,2048,4096",
                       help="core: one probe baked from the bake benchmark's cloud (--points) at each "
                            "of these resolutions: its cost against its texels (comma-separated; "
                            "empty: skip)")
    bench.add_argument("--cluster-points", type=int, default=2_000_000,
                       help="cluster: points of the generated room")
    bench.add_argument("--cluster-workers", type=int, default=2,
                       help="cluster: worker processes of the local Dask cluster")
    bench.add_argument("--cluster-cores", type=int, default=32,
                       help="cluster: cores per worker machine in the on-paper scaling")
    bench.add_argument("--json", metavar="FILE", help="also write the figures as JSON")
    bench.set_defaults(run=_cmd_bench)
    return parser


def _print_lfprobe_warning(message, category, filename, lineno, file=None, line=None):
    """The native jobs' warnings (lfprobe._native.LfprobeWarning: a scan read, but its parse cache
    not written) as one plain line; other warnings as Python prints them."""
    if category.__name__ == "LfprobeWarning":
        print(f"lfprobe: warning: {message}", file=sys.stderr)
    else:
        _python_showwarning(message, category, filename, lineno, file, line)


_python_showwarning = warnings.showwarning


def main(argv: Optional[Sequence[str]] = None) -> int:
    warnings.showwarning = _print_lfprobe_warning
    args = build_parser().parse_args(argv)
    try:
        return args.run(args)
    except native.NativeModuleError as error:
        print(f"lfprobe: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("lfprobe: cancelled", file=sys.stderr)
        return 130
    except (ValueError, FileNotFoundError) as error:
        print(f"lfprobe: error: {error}", file=sys.stderr)
        return 2
    except OSError as error:
        print(f"lfprobe: error: {error}", file=sys.stderr)
        return 1
    except native.cancelled_type():
        print("lfprobe: cancelled", file=sys.stderr)
        return 130
