"""`lfprobe bench render`: probe tracing against splatting the raw cloud, same camera, same
run. Prints rays per second on 1 and 2 threads, texels visited per ray, the ratio to Embree's
primary-ray throughput on the room's mesh for the same rays (and for the same rays started at
their own answers: the part of a trace's cost that skipping empty space cannot remove), and
milliseconds per frame of the splat baseline for growing clouds (tracing does not depend on the
cloud's size: the probes hold a fixed number of texels)."""

from __future__ import annotations

import json
import math
import os
import shutil
import tempfile
import time

from . import native
from .bench import SHARED_PUMP_XYZ, room_cloud, room_surface_area, write_results, write_room_obj
from .camera_json import camera_dict
from .embree_rates import embree_rates

PROBES = {"min": [0.75, 1.0, 1.4], "max": [2.25, 5.0, 1.4], "counts": [2, 3, 1]}


def _views():
    at_probe = [0.75, 1.0, 1.4]
    return {
        "at a probe": camera_dict(at_probe, [2.0, 5.5, 1.0], (480, 360), lens=24),
        "between probes": camera_dict([1.5, 2.0, 1.3], [1.5, 6.0, 1.0], (480, 360), lens=24),
        "panorama between probes": camera_dict([1.5, 4.0, 1.5], [1.5, 6.0, 1.5], (720, 360),
                                               camera_type="PANO_EQUIRECT"),
    }


def _best_render(field, camera_text, threads, repeats=3, **settings):
    best = None
    for _ in range(repeats):
        _, stats = field.render(camera_text, threads=threads, **settings)
        if best is None or stats["seconds"] < best["seconds"]:
            best = stats
    return best


def _without_known_space(field, camera_text, row) -> None:
    """The same view asking every probe on (the set's known space unused, as before it was
    written): rays per second on 2 threads, probes and texels per ray, and whether the image is
    the same."""
    with_it, _ = field.render(camera_text, threads=2)
    without, _ = field.render(camera_text, threads=2, stop_where_no_probe_can_answer=False)
    stats = _best_render(field, camera_text, 2, stop_where_no_probe_can_answer=False)
    row["without_known_space"] = {
        "rays_per_second_2_threads": stats["rays_per_second"],
        "texels_per_ray": stats["mean_steps"], "probes_per_ray": stats["mean_probes"],
        "same_image": all(bool((with_it[k] == without[k]).all())
                          for k in ("rgba", "status", "depth", "probe"))}


def _known_space_line(row) -> str:
    w = row["without_known_space"]
    return (f"    asking every probe on (the set's known space unused): "
            f"{w['rays_per_second_2_threads'] / 1e6:.3f} M rays/s on 2 threads, "
            f"{w['probes_per_ray']:.1f} probes and {w['texels_per_ray']:.0f} texels per ray: "
            f"the known space gives {row['rays_per_second_2_threads'] / w['rays_per_second_2_threads']:.2f}× "
            f"the rays per second, the image {'the same' if w['same_image'] else 'DIFFERENT'}")


def _bake(_native, n, res, folder):
    positions, colors, normals = room_cloud(n, with_normals=True)
    cloud = _native.PointCloud.from_arrays(positions, colors, normals)
    del positions, colors, normals
    start = time.perf_counter()
    _native.bake_probe_set(cloud, folder, resolution=res, grid_min=PROBES["min"],
                           grid_max=PROBES["max"], counts=PROBES["counts"])
    return cloud, time.perf_counter() - start


def _unknown_texels(folder: str) -> float:
    """Mean fraction of unknown texels over the probes of a baked set (from its manifest)."""
    with open(os.path.join(folder, "manifest.json"), encoding="utf-8") as f:
        probes = json.load(f)["probes"]
    return sum(p["coverage"]["unknown"] for p in probes) / len(probes)


def _trace_row(_native, field, mesh, name: str, text: str) -> dict:
    """One view traced through the probes on 1 and 2 threads, and Embree on the same rays."""
    one = _best_render(field, text, 1)
    two = _best_render(field, text, 2)
    row = {
        "view": name,
        "rays": one["rays"],
        "rays_per_second_1_thread": one["rays_per_second"],
        "rays_per_second_2_threads": two["rays_per_second"],
        "ms_per_frame_2_threads": 1000 * two["seconds"],
        "texels_per_ray": two["mean_steps"],
        "probes_per_ray": two["mean_probes"],
        "hit_rate": two["hits"] / two["rays"],
        "unknown_rate": two["unknown"] / two["rays"],
    }
    embree = embree_rates(_native, mesh, text, threads=2, repeats=3)
    # Measured as Embree's figure is: rays made beforehand, trace only.
    trace_only = field.trace_throughput(text, threads=2, repeats=3)
    # The same rays started where their own traces ended: no empty space left to skip, so what
    # remains is what every trace costs however little it walks.
    from_answer = field.trace_throughput(text, threads=2, repeats=3, start="answer")
    # The same rays coloured by the texel each met alone (no filter, no blending): the trace
    # without its colour's further lookups, as Embree's figure includes no colour.
    texel = field.trace_throughput(text, threads=2, repeats=3, colour="texel")
    best_packet = embree["packet_width"]
    row["embree_rays_per_second_2_threads"] = embree["single"]
    row["embree_packet_rays_per_second_2_threads"] = embree["packet"]
    row["embree_best_packet"] = best_packet
    row["trace_only_rays_per_second_2_threads"] = trace_only["rays_per_second"]
    row["trace_over_embree"] = trace_only["rays_per_second"] / embree["single"]
    row["trace_over_embree_packets"] = trace_only["rays_per_second"] / embree["packet"]
    row["frame_over_embree"] = two["rays_per_second"] / embree["single"]
    row["trace_from_answer_rays_per_second_2_threads"] = from_answer["rays_per_second"]
    row["trace_from_answer_over_embree"] = from_answer["rays_per_second"] / embree["single"]
    row["trace_texel_rays_per_second_2_threads"] = texel["rays_per_second"]
    row["trace_texel_over_embree"] = texel["rays_per_second"] / embree["single"]
    print(
        f"  {name}: {row['rays']:,} rays; {row['rays_per_second_1_thread'] / 1e6:.2f} M "
        f"rays/s on 1 thread, {row['rays_per_second_2_threads'] / 1e6:.2f} M on 2 "
        f"({row['ms_per_frame_2_threads']:.1f} ms/frame); {row['texels_per_ray']:.1f} "
        f"texels and {row['probes_per_ray']:.2f} probes per ray; HIT "
        f"{100 * row['hit_rate']:.1f}%, UNKNOWN {100 * row['unknown_rate']:.1f}%\n"
        f"    trace only (rays made beforehand, as Embree is measured): "
        f"{row['trace_only_rays_per_second_2_threads'] / 1e6:.2f} M rays/s; Embree "
        f"{row['embree_rays_per_second_2_threads'] / 1e6:.2f} M rays/s on 2 threads: "
        f"probe trace / Embree = {row['trace_over_embree']:.3f} (whole frame incl. "
        f"ray generation and pixel writes / Embree = {row['frame_over_embree']:.3f})\n"
        f"    Embree in coherent packets of {best_packet} (rtcIntersect{best_packet}, its fastest "
        f"of 4, 8, 16): {embree['packet'] / 1e6:.2f} M rays/s: probe trace / "
        f"Embree packets = {row['trace_over_embree_packets']:.3f}\n"
        f"    the same rays started at their own answers (nothing left to skip): "
        f"{row['trace_from_answer_rays_per_second_2_threads'] / 1e6:.2f} M rays/s: "
        f"/ Embree = {row['trace_from_answer_over_embree']:.3f}\n"
        f"    the same rays coloured by their texel alone (the paper's lookup: no filter, no "
        f"blending): {row['trace_texel_rays_per_second_2_threads'] / 1e6:.2f} M rays/s: / Embree = "
        f"{row['trace_texel_over_embree']:.3f}"
    )
    return row


# The real pump-room scan as a new user meets it in Blender: Fit Grid's defaults (margin 0.25 m,
# spacing 1 m: 6 × 6 × 5 probes) at the grid's default 512², one station at the origin.
PUMP_VIEW = {"position": [-0.5, -2.5, 0.2], "look_at": [-2.5, -4.5, -0.5], "res": (320, 180)}


def real_scan_row(_native, tmp: str) -> dict:
    """The pump room through the probes Fit Grid gives it: opening the set (every probe read,
    or lazily as the add-on does), the first frame, and rays per second, texels and probes per
    ray on 1 and 2 threads."""
    from .grid_fit import counts_for_spacing, fitted_box

    pump = os.path.abspath(SHARED_PUMP_XYZ)
    cloud = _native.load_scans([pump], scanners=[[0.0, 0.0, 0.0]], cache_dir="")
    positions = cloud.positions
    low, high = fitted_box([positions.min(axis=0), positions.max(axis=0)], 0.25)
    counts = counts_for_spacing(high - low, 1.0)
    offset = list(cloud.world_offset)
    folder = os.path.join(tmp, "pump_probes")
    start = time.perf_counter()
    _native.bake_probe_set(cloud, folder, resolution=512, grid_min=[float(v) for v in low],
                           grid_max=[float(v) for v in high], counts=[int(c) for c in counts],
                           positions_in_world=False)
    bake_seconds = time.perf_counter() - start
    world = [p + o for p, o in zip(PUMP_VIEW["position"], offset)]
    target = [p + o for p, o in zip(PUMP_VIEW["look_at"], offset)]
    text = json.dumps(camera_dict(world, target, PUMP_VIEW["res"], lens=24))
    start = time.perf_counter()
    eager = _native.ProbeField.load(folder)
    open_all = time.perf_counter() - start
    del eager
    start = time.perf_counter()
    lazy = _native.ProbeField.load(folder, lazy=True)
    open_lazy = time.perf_counter() - start
    start = time.perf_counter()
    lazy.render(text, threads=2)
    first_frame = time.perf_counter() - start
    row = {"view": "pump room (real scan, Fit Grid defaults)", "counts": list(counts),
           "probes": int(counts[0] * counts[1] * counts[2]), "bake_seconds": bake_seconds,
           "unknown_texels": _unknown_texels(folder), "open_all_seconds": open_all,
           "open_lazy_seconds": open_lazy, "first_frame_seconds": first_frame,
           "probes_read_by_first_frame": lazy.loaded_probe_count}
    for threads in (1, 2):
        stats = _best_render(lazy, text, threads)
        row[f"rays_per_second_{threads}_threads"] = stats["rays_per_second"]
        row["texels_per_ray"] = stats["mean_steps"]
        row["probes_per_ray"] = stats["mean_probes"]
        row["unknown_rays"] = stats["unknown"] / stats["rays"]
    _without_known_space(lazy, text, row)
    shutil.rmtree(folder, ignore_errors=True)
    return row


# The demo's lab room, scanned from its first station at 0.5°: once over the whole circle and
# once over a 90° window of azimuth (a partial sweep), each baked into the scene's probe grid
# at 512² and traced from the scene's view between probes.
LAB_SCENE = os.path.join(os.path.dirname(__file__), "..", "..", "..", "blend", "lab_room",
                         "lab_room.scene.json")
PARTIAL_SWEEP = {"step_deg": 0.5, "horizontal_start": 45.0, "horizontal_fov": 90.0,
                 "res": (320, 200), "probe_res": 512}


def partial_sweep_rows(_native, tmp: str) -> list:
    """One station of the lab room, a complete and a partial sweep through the same probe grid
    and view: rays per second on 1 and 2 threads, texels and probes per ray, UNKNOWN rays."""
    with open(LAB_SCENE, encoding="utf-8") as f:
        scene = json.load(f)
    mesh = os.path.join(os.path.dirname(LAB_SCENE), scene["mesh"])
    station = [float(v) for v in scene["scanners"][0]]
    view = next(v for v in scene["views"] if v["name"] == "between_probes")
    text = json.dumps(camera_dict(view["position"], view["look_at"], PARTIAL_SWEEP["res"],
                                  lens=view["lens"]))
    rows = []
    for label, fov in (("complete sweep", 360.0), ("90° window", PARTIAL_SWEEP["horizontal_fov"])):
        xyz = os.path.join(tmp, f"lab_station_{int(fov)}.xyz")
        scanned = _native.start_simulate_scan(
            mesh, xyz, station, step_deg=PARTIAL_SWEEP["step_deg"],
            noise_mm=scene["scan"]["noise_mm"], vertical_fov=scene["scan"]["vertical_fov"],
            horizontal_fov=fov, horizontal_start=PARTIAL_SWEEP["horizontal_start"]).run()
        cloud = _native.load_scans([xyz], cache_dir="")
        folder = os.path.join(tmp, f"lab_probes_{int(fov)}")
        start = time.perf_counter()
        _native.bake_probe_set(cloud, folder, resolution=PARTIAL_SWEEP["probe_res"],
                               grid_min=scene["grid"]["min"], grid_max=scene["grid"]["max"],
                               counts=scene["grid"]["counts"])
        bake_seconds = time.perf_counter() - start
        del cloud
        field = _native.ProbeField.load(folder)
        row = {"view": f"lab room, one station, {label}", "horizontal_fov": fov,
               "points": scanned["points"], "bake_seconds": bake_seconds,
               "unknown_texels": _unknown_texels(folder)}
        for threads in (1, 2):
            stats = _best_render(field, text, threads)
            row[f"rays_per_second_{threads}_threads"] = stats["rays_per_second"]
            row["texels_per_ray"] = stats["mean_steps"]
            row["probes_per_ray"] = stats["mean_probes"]
            row["unknown_rays"] = stats["unknown"] / stats["rays"]
        _without_known_space(field, text, row)
        del field
        shutil.rmtree(folder, ignore_errors=True)
        rows.append(row)
    rows[1]["complete_over_partial"] = (rows[0]["rays_per_second_2_threads"]
                                        / rows[1]["rays_per_second_2_threads"])
    return rows


def main(args) -> int:
    _native = native.load()
    tmp = tempfile.mkdtemp(prefix="lfprobe-bench-render-")
    results = {"cpu_count": os.cpu_count(), "trace": [], "sizes": []}
    try:
        sizes = sorted(int(float(s)) for s in args.splat_points.split(",") if s.strip())
        views = _views()
        room_obj = os.path.join(tmp, "room.obj")
        write_room_obj(room_obj)
        mesh = _native.load_mesh(room_obj)
        for n in sizes:
            print(f"== {n:,} points: probes {PROBES['counts']} grid at {args.res}² baked from them ==")
            folder = os.path.join(tmp, f"probes_{n}")
            cloud, bake_seconds = _bake(_native, n, args.res, folder)
            unknown = _unknown_texels(folder)
            # A sparse cloud leaves texels no point reached: each is UNKNOWN to a ray that
            # crosses it (the next probe is asked), and it keeps the coarse cells around it
            # from being skipped.
            print(f"  bake (normals, spacing, {PROBES['counts'][0] * PROBES['counts'][1] * PROBES['counts'][2]} probes): {bake_seconds:.1f} s; "
                  f"unknown texels {100 * unknown:.2f}%")
            field = _native.ProbeField.load(folder)
            print("  probe tracing (grid walk), best of 3; Embree on the room's mesh, same rays:")
            for name, camera in views.items():
                row = _trace_row(_native, field, mesh, name, json.dumps(camera))
                row["points"] = n
                row["unknown_texels"] = unknown
                results["trace"].append(row)
            text = json.dumps(views["between probes"])
            trace = _best_render(field, text, 2)
            del field
            # The spacing of uniform samples: one point per spacing² of surface.
            radius = 0.8 * math.sqrt(room_surface_area() / n)
            best = None
            for _ in range(2):
                job = _native.start_splat(cloud, text, os.path.join(tmp, "splat.exr"),
                                          fixed_radius=radius, threads=2)
                stats = job.run()
                if best is None or stats["seconds"] < best["seconds"]:
                    best = stats
            del cloud
            shutil.rmtree(folder, ignore_errors=True)
            row = {"points": n, "bake_seconds": bake_seconds, "unknown_texels": unknown,
                   "trace_ms_per_frame": 1000 * trace["seconds"],
                   "trace_rays_per_second": trace["rays_per_second"],
                   "trace_texels_per_ray": trace["mean_steps"],
                   "splat_ms_per_frame": 1000 * best["seconds"],
                   "splat_points_per_second": best["points_per_second"],
                   "splat_coverage": best["covered"] / (480 * 360)}
            row["splat_over_trace"] = row["splat_ms_per_frame"] / row["trace_ms_per_frame"]
            results["sizes"].append(row)
            print(f"  view 'between probes', 2 threads: probe trace {row['trace_ms_per_frame']:.1f} ms "
                  f"({row['trace_texels_per_ray']:.1f} texels/ray); splatting the cloud "
                  f"{row['splat_ms_per_frame']:.1f} ms ({row['splat_points_per_second'] / 1e6:.1f} M "
                  f"points/s): splat/trace = {row['splat_over_trace']:.2f}\n")
        if os.path.isfile(os.path.abspath(SHARED_PUMP_XYZ)):
            print("== the real pump-room scan, one station, Fit Grid's defaults, 512² probes ==")
            pump = real_scan_row(_native, tmp)
            results["real_scan"] = pump
            complete = next((r for r in results["trace"] if r["view"] == "between probes"), None)
            print(f"  {pump['counts'][0]}×{pump['counts'][1]}×{pump['counts'][2]} probes baked in "
                  f"{pump['bake_seconds']:.1f} s, {100 * pump['unknown_texels']:.1f}% of texels unknown\n"
                  f"  opening the set: {pump['open_all_seconds']:.2f} s reading every probe, "
                  f"{pump['open_lazy_seconds']:.3f} s lazily (as F12 and the viewport do); first "
                  f"{PUMP_VIEW['res'][0]}×{PUMP_VIEW['res'][1]} frame {pump['first_frame_seconds']:.2f} s, "
                  f"reading {pump['probes_read_by_first_frame']} of {pump['probes']} probes\n"
                  f"  {pump['rays_per_second_1_threads'] / 1e6:.3f} / {pump['rays_per_second_2_threads'] / 1e6:.3f} M rays/s "
                  f"on 1 / 2 threads, {pump['texels_per_ray']:.0f} texels and {pump['probes_per_ray']:.1f} probes "
                  f"per ray, {100 * pump['unknown_rays']:.0f}% of rays UNKNOWN")
            print(_known_space_line(pump))
            if complete is not None:
                ratio = complete["trace_only_rays_per_second_2_threads"] / pump["rays_per_second_2_threads"]
                pump["complete_over_partial"] = ratio
                print(f"  the complete scan's 'between probes' view ({complete['points']:,} points) "
                      f"traces {ratio:.1f}× as many rays per second (the aim: within 2×)")
        if os.path.isfile(LAB_SCENE):
            res = PARTIAL_SWEEP["res"]
            print(f"== the lab room from one station at {PARTIAL_SWEEP['step_deg']}°, the whole "
                  f"circle and a {PARTIAL_SWEEP['horizontal_fov']:.0f}° window of azimuth, the "
                  f"scene's grid at {PARTIAL_SWEEP['probe_res']}², its view between probes at "
                  f"{res[0]}×{res[1]} ==")
            results["partial_sweep"] = partial_sweep_rows(_native, tmp)
            for row in results["partial_sweep"]:
                print(f"  {row['view']}: {row['points']:,} points, {100 * row['unknown_texels']:.1f}% "
                      f"of texels unknown; {row['rays_per_second_1_threads'] / 1e6:.3f} / "
                      f"{row['rays_per_second_2_threads'] / 1e6:.3f} M rays/s on 1 / 2 threads, "
                      f"{row['texels_per_ray']:.0f} texels and {row['probes_per_ray']:.1f} probes per "
                      f"ray, {100 * row['unknown_rays']:.0f}% of rays UNKNOWN")
                print(_known_space_line(row))
            print(f"  the complete sweep traces {results['partial_sweep'][1]['complete_over_partial']:.1f}× "
                  f"as many rays per second as the partial one (the aim: within 2×)")
        print("summary: points, unknown texels, probe trace ms/frame, splat ms/frame")
        for row in results["sizes"]:
            print(f"  {row['points']:>12,}  {100 * row['unknown_texels']:6.2f}%  "
                  f"{row['trace_ms_per_frame']:8.1f}  {row['splat_ms_per_frame']:8.1f}")
        print("summary: probe trace only / Embree single rays, / Embree packets (2 threads), "
              "/ Embree single rays with each ray started at its own answer (the floor: no "
              "empty space left to skip), and / Embree single rays with each HIT coloured by its "
              "texel alone (no filter, no blending; the aims are judged on the default colour); "
              "the aims: faster than Embree with the eye at a probe, a third of it elsewhere")
        for row in results["trace"]:
            aim = 1.0 if row["view"] == "at a probe" else 1.0 / 3.0
            met = min(row["trace_over_embree"], row["trace_over_embree_packets"]) >= aim
            row["aim"] = aim
            row["aim_met"] = met
            print(f"  {row['points']:>12,}  {row['view']:<24} "
                  f"{row['trace_only_rays_per_second_2_threads'] / 1e6:6.2f} M rays/s  "
                  f"{row['trace_over_embree']:6.3f}  {row['trace_over_embree_packets']:6.3f}  "
                  f"floor {row['trace_from_answer_over_embree']:6.3f}  "
                  f"texel colour {row['trace_texel_over_embree']:6.3f}  "
                  f"aim {aim:.3f}: {'met' if met else 'not met'}")
        write_results(args.json, results)
        return 0
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
