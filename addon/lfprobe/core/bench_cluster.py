"""`lfprobe bench cluster`: a scan bake in this process against the same bake on a local Dask
cluster of worker processes, on one generated room; the scheduler's own cost per task; what a
task reads of a row of rooms when it reads the spatial cloud in parts, against workers that load
the whole cloud; and the scaling to a building-sized job worked out from these figures, with its
assumptions printed. Every figure comes from this one run on this machine."""

from __future__ import annotations

import logging
import os
import shutil
import tempfile
import time

import numpy as np

from .bench import room_cloud, write_results, write_xyz
from .cluster_bake import bake_scans_on_cluster
from .pipeline import BakeOptions, ProbePlacementSpec, bake_from_scans, load_scans

# The building of the scaling question.
STATIONS, POINTS_PER_STATION, PROBES, WORKERS = 1_000, 10_000_000, 10_000, 100
# The paper's probe resolution; a probe's bake time is taken to grow with its texels (the
# hierarchy's cut follows the texels, not the points).
PAPER_RESOLUTION = 2048
# Assumed: a probe sees the stations of its own room, about four (as in the paper's room).
STATIONS_SEEN_PER_TASK = 4
# The row of rooms a task reads in parts: rooms of the benchmark room's size, side by side along
# x with a gap, the probes in the first.
BUILDING_ROOMS = 8
ROOM_PITCH = 3.5


def _drop_from_page_cache(path: str) -> None:
    """As a worker on another machine finds a file the client just wrote: not in its memory. The
    pages a task's mapping then holds are the ones it read, not also their cached neighbours
    (the kernel maps those in around each fault)."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
        os.posix_fadvise(fd, 0, 0, os.POSIX_FADV_DONTNEED)
    finally:
        os.close(fd)


def _building(tmp: str, points_per_room: int, res: int, workers: int) -> dict:
    """A row of BUILDING_ROOMS rooms, 4 probes in the first, one probe a task: baked by workers
    that load the whole cloud, then by tasks that read the spatial cloud in parts (from a cold
    page cache). Returns the figures of both."""
    from distributed import Client, LocalCluster

    scan = os.path.join(tmp, "building.xyz")
    parts, colours = [], []
    for room in range(BUILDING_ROOMS):
        p, c = room_cloud(points_per_room, seed=20 + room)
        p[:, 0] += room * ROOM_PITCH
        parts.append(p)
        colours.append(c)
    positions, colors = np.concatenate(parts), np.concatenate(colours)
    del parts, colours
    srgb = np.clip(np.round(255 * np.power(colors, 1 / 2.2)), 0, 255).astype(np.uint8)
    write_xyz(scan, positions, srgb)
    points = len(positions)
    del positions, colors, srgb
    cache = os.path.join(tmp, "building-cache")
    load_scans([scan], cache_dir=cache)
    placement = ProbePlacementSpec(grid_min=[0.4, 0.6, 0.5], grid_max=[2.6, 5.4, 2.2], counts=[2, 2, 1])
    options = BakeOptions(resolution=res)
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                           dashboard_address=None, silence_logs=logging.ERROR)
    client = Client(cluster, set_as_default=False)
    try:
        def bake(name, read_in_parts):
            return bake_scans_on_cluster([scan], os.path.join(tmp, name), placement, options, cache_dir=cache,
                                         scheduler=cluster.scheduler_address, read_in_parts=read_in_parts)
        whole = bake("whole", False)
        first = bake("parts-first", True)  # writes the spatial cloud
        spatial = [os.path.join(cache, n) for n in os.listdir(cache) if n.endswith(".lfpspatial")]
        for path in spatial:
            _drop_from_page_cache(path)
        in_parts = bake("parts", True)
    finally:
        client.close()
        cluster.close()
    w, p = whole["cluster"], in_parts["cluster"]
    return {
        "rooms": BUILDING_ROOMS, "points": points, "probes": 4,
        "identical": _same_files(os.path.join(tmp, "whole"), os.path.join(tmp, "parts")),
        "spatial_cloud_bytes": p["spatial_cloud_bytes"],
        "spatial_seconds": first["cluster"]["client_spatial_cloud_seconds"],
        "bytes_read_per_task": p["bytes_read_per_task"],
        "task_memory": p["cloud_memory_per_worker"],
        "task_seconds_per_probe": p["seconds_per_probe"],
        "whole_bytes_read_per_worker": w["bytes_read_per_worker"],
        "whole_cloud_memory_per_worker": w["cloud_memory_per_worker"],
        "whole_prepare_seconds_per_worker": w["prepare_seconds_per_worker"],
        "whole_seconds_per_probe": w["seconds_per_probe"],
    }


def _same_files(a: str, b: str) -> bool:
    names = sorted(os.listdir(a))
    if names != sorted(os.listdir(b)):
        return False
    for name in names:
        with open(os.path.join(a, name), "rb") as x, open(os.path.join(b, name), "rb") as y:
            if x.read() != y.read():
                return False
    return True


def _scheduler_seconds_per_task(client, tasks: int = 2000) -> float:
    """Round trip of trivial tasks through the scheduler and back: its cost per task."""
    client.gather(client.map(abs, range(-200, 0), pure=False))  # warm up
    start = time.perf_counter()
    client.gather(client.map(abs, range(-tasks, 0), pure=False))
    return (time.perf_counter() - start) / tasks


def main(args) -> int:
    from distributed import Client, LocalCluster

    tmp = tempfile.mkdtemp(prefix="lfprobe-bench-cluster-")
    points, res, workers = args.cluster_points, args.res, args.cluster_workers
    counts = [4, 2, 2]
    probes = int(np.prod(counts))
    placement = ProbePlacementSpec(grid_min=[0.4, 0.6, 0.5], grid_max=[2.6, 5.4, 2.2], counts=counts)
    options = BakeOptions(resolution=res)
    results = {"cpu_count": os.cpu_count(), "points": points, "resolution": res, "probes": probes}
    try:
        scan = os.path.join(tmp, "room.xyz")
        positions, colors = room_cloud(points, seed=3)
        srgb = np.clip(np.round(255 * np.power(colors, 1 / 2.2)), 0, 255).astype(np.uint8)
        write_xyz(scan, positions, srgb)
        del positions, colors, srgb
        cache = os.path.join(tmp, "cache")
        load_scans([scan], cache_dir=cache)  # parsed once: every bake below reads the cache

        print(f"== cluster bake: {probes} probes at {res}² from {points:,} points, this run ==")
        start = time.perf_counter()
        local = bake_from_scans([scan], os.path.join(tmp, "local"), placement, options, cache_dir=cache)
        local_wall = time.perf_counter() - start
        local_probe = local["bake_seconds"] / probes
        print(f"1 process: {local_wall:.2f} s, {probes / local_wall:.2f} probes/s "
              f"(normals {local['normals_seconds']:.2f} s, hierarchy {local['hierarchy_seconds']:.2f} s, "
              f"{local_probe:.3f} s a probe)")

        # The 1-process bake left the cloud prepared in the cache: removed, so that this run's
        # client prepares it (once, for every worker) as a first cluster bake would.
        for name in os.listdir(cache):
            if name.startswith("prepared-"):
                os.remove(os.path.join(cache, name))
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                               dashboard_address=None, silence_logs=logging.ERROR)
        client = Client(cluster, set_as_default=False)
        try:
            start = time.perf_counter()
            summary = bake_scans_on_cluster([scan], os.path.join(tmp, "cluster"), placement, options,
                                            cache_dir=cache, scheduler=cluster.scheduler_address)
            cluster_wall = time.perf_counter() - start
            per_task = _scheduler_seconds_per_task(client)
        finally:
            client.close()
            cluster.close()
        c = summary["cluster"]
        identical = _same_files(os.path.join(tmp, "local"), os.path.join(tmp, "cluster"))
        print(f"{workers} worker processes: {cluster_wall:.2f} s, {probes / cluster_wall:.2f} probes/s "
              f"({local_wall / cluster_wall:.2f}× the 1 process); {c['tasks']} tasks; "
              f"set identical to the 1-process bake: {'yes' if identical else 'NO'}")
        print(f"  the client prepared the cloud (normals, spacing, hierarchy) into the cache and wrote it as a "
              f"spatial cloud ({c['spatial_cloud_bytes'] / 2**20:.1f} MiB) in {c['client_prepare_seconds']:.2f} s; "
              f"{c['tasks_reading_in_parts']} of {c['tasks']} tasks read it in parts, at most "
              f"{c['bytes_read_per_task'] / 2**20:.1f} MiB a task (this room's probes see all of it, and the "
              f"client's writing left it in the page cache), peak memory {c['peak_memory_per_worker'] / 2**20:.0f} "
              f"MiB; {c['seconds_per_probe']:.3f} s a probe on a worker")
        print(f"  scheduler: {1000 * per_task:.2f} ms a task (round trip of {2000} trivial tasks)")
        print(f"  this machine has {os.cpu_count()} cores: the {workers} workers share them, so no gain "
              "is possible here; what carries over to a cluster is a probe's cost, the cloud's "
              "preparation and reading, and the scheduler's cost")

        b = _building(tmp, max(50_000, points // 4), res, workers)
        mib = 2 ** 20
        print(f"== a row of {b['rooms']} rooms, {b['points']:,} points, {b['probes']} probes in the first "
              f"room at {res}², one probe a task, this run ==")
        print(f"  workers that load the whole cloud: each read {b['whole_bytes_read_per_worker'] / mib:.1f} MiB "
              f"(parsed scan and prepared cloud) and held {b['whole_cloud_memory_per_worker'] / mib:.0f} MiB "
              f"for it, ready in {b['whole_prepare_seconds_per_worker']:.2f} s; "
              f"{b['whole_seconds_per_probe']:.3f} s a probe")
        print(f"  tasks that read the spatial cloud in parts ({b['spatial_cloud_bytes'] / mib:.1f} MiB, written "
              f"by the client in {b['spatial_seconds']:.2f} s), from a cold page cache: a task read at most "
              f"{b['bytes_read_per_task'] / mib:.1f} MiB "
              f"({100 * b['bytes_read_per_task'] / max(1, b['spatial_cloud_bytes']):.0f} % of it: its room and the "
              f"next at full density, coarse cells beyond) and held {b['task_memory'] / mib:.0f} MiB for the "
              f"cloud (the pages read and the cuts gathered); {b['task_seconds_per_probe']:.3f} s a probe; "
              f"set identical: {'yes' if b['identical'] else 'NO'}")

        # The scaling on paper, from this run's figures.
        # Preparing the cloud: at a building's scale each station's share, as this run's client
        # did for the whole cloud.
        prepare_per_point = c["client_prepare_seconds"] / points
        # One core's time for one probe at the paper's resolution.
        probe_seconds = local_probe * (os.cpu_count() or 1) * (PAPER_RESOLUTION / res) ** 2
        per_worker = PROBES / WORKERS
        cores = args.cluster_cores
        bake_time = per_worker * probe_seconds / cores
        task_points = STATIONS_SEEN_PER_TASK * POINTS_PER_STATION
        prepare_time = task_points * prepare_per_point * (os.cpu_count() or 1) / cores
        total = bake_time + prepare_time + per_worker * per_task
        # A task's reading grows with its probe's texels, as its cut does, up to the file.
        texel_ratio = (PAPER_RESOLUTION / res) ** 2
        task_bytes = b["bytes_read_per_task"] * texel_ratio
        task_memory = b["task_memory"] * texel_ratio
        spatial_per_point = b["spatial_cloud_bytes"] / b["points"]
        print(f"== on paper: {STATIONS:,} stations × {POINTS_PER_STATION:,} points, {PROBES:,} probes at "
              f"{PAPER_RESOLUTION}², {WORKERS} workers of {cores} cores ==")
        print(f"  assumed: a probe's time grows with its texels from this run's {res}² and shrinks with cores "
              f"from this run's {os.cpu_count()}; so does what its task reads of the spatial cloud (the cut "
              f"follows the texels); the stations are prepared {STATIONS_SEEN_PER_TASK} at a time where their "
              f"probes are baked, at this run's {1e9 * prepare_per_point:.0f} ns a point on {os.cpu_count()} "
              f"cores; the scheduler takes {1000 * per_task:.2f} ms a task")
        print(f"  per worker: {per_worker:.0f} probes × {probe_seconds:.3f} core-s / {cores} cores = "
              f"{bake_time / 60:.1f} min baking + {prepare_time / 60:.1f} min preparing + "
              f"{per_worker * per_task:.1f} s of scheduling: {total / 60:.1f} min in all, against "
              f"{PROBES * probe_seconds / cores / 3600:.1f} h for one such machine")
        print(f"  a task reads about {task_bytes / 2**30:.1f} GiB of the spatial cloud at {PAPER_RESOLUTION}² "
              f"({b['bytes_read_per_task'] / mib:.0f} MiB here × {texel_ratio:.0f}) and holds about "
              f"{task_memory / 2**30:.1f} GiB for it, the worker's {c['base_memory_per_worker'] / mib:.0f} MiB "
              f"before the cloud on top; the building's spatial cloud is "
              f"{STATIONS * POINTS_PER_STATION * spatial_per_point / 2**40:.2f} TiB "
              f"({spatial_per_point:.0f} bytes a point), which no worker loads whole")
        print("  not built: preparing the cloud in parts; the client prepares and writes the whole "
              "spatial cloud itself, so it must hold the cloud (a building's would need a cluster "
              "step of its own)")
        results["cluster"] = {
            "local_seconds": local_wall, "local_probes_per_second": probes / local_wall,
            "workers": workers, "cluster_seconds": cluster_wall,
            "cluster_probes_per_second": probes / cluster_wall, "identical": identical,
            "bytes_read_per_worker": c["bytes_read_per_worker"],
            "bytes_read_per_task": c["bytes_read_per_task"],
            "spatial_cloud_bytes": c["spatial_cloud_bytes"],
            "prepare_seconds_per_worker": c["prepare_seconds_per_worker"],
            "peak_memory_per_worker": c["peak_memory_per_worker"],
            "base_memory_per_worker": c["base_memory_per_worker"],
            "cloud_memory_per_worker": c["cloud_memory_per_worker"],
            "worker_seconds_per_probe": c["seconds_per_probe"],
            "scheduler_seconds_per_task": per_task,
            "building": b,
            "paper": {"stations": STATIONS, "points_per_station": POINTS_PER_STATION, "probes": PROBES,
                      "workers": WORKERS, "cores_per_worker": cores,
                      "stations_seen_per_task": STATIONS_SEEN_PER_TASK, "resolution": PAPER_RESOLUTION,
                      "minutes": total / 60, "bytes_read_per_task": task_bytes,
                      "task_memory_bytes": task_memory},
        }
        write_results(args.json, results)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 0
