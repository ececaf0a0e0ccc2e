"""`lfprobe bench cluster`: a scan bake in this process against the same bake on a local Dask
cluster of worker processes, on one generated room; the scheduler's own cost per task; and the
scaling to a building-sized job worked out from these figures, with its assumptions printed.
Every figure comes from this one run on this machine."""

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
        print(f"  the client prepared the cloud (normals, spacing, hierarchy) into the cache in "
              f"{c['client_prepare_seconds']:.2f} s; each worker read {c['bytes_read_per_worker'] / 2**20:.1f} "
              f"MiB of parsed scan and had the cloud ready in {c['prepare_seconds_per_worker']:.2f} s "
              f"({c['workers_reading_the_prepared_cloud']} of {c['workers_used']} read it from the cache), "
              f"peak memory {c['peak_memory_per_worker'] / 2**20:.0f} MiB; "
              f"{c['seconds_per_probe']:.3f} s a probe on a worker")
        print(f"  scheduler: {1000 * per_task:.2f} ms a task (round trip of {2000} trivial tasks)")
        print(f"  this machine has {os.cpu_count()} cores: the {workers} workers share them, so no gain "
              "is possible here; what carries over to a cluster is a probe's cost, the cloud's "
              "preparation and reading, and the scheduler's cost")

        # The scaling on paper, from this run's figures.
        bytes_per_point = c["bytes_read_per_worker"] / points
        # Preparing (not reading) the cloud: at a building's scale each worker prepares the
        # stations its probes see, as this run's client did for the whole cloud.
        prepare_per_point = max(c["client_prepare_seconds"], c["prepare_seconds_per_worker"]) / points
        # One core's time for one probe at the paper's resolution.
        probe_seconds = local_probe * (os.cpu_count() or 1) * (PAPER_RESOLUTION / res) ** 2
        task_points = STATIONS_SEEN_PER_TASK * POINTS_PER_STATION
        per_worker = PROBES / WORKERS
        cores = args.cluster_cores
        bake_time = per_worker * probe_seconds / cores
        prepare_time = task_points * prepare_per_point * (os.cpu_count() or 1) / cores
        total = bake_time + prepare_time + per_worker * per_task
        print(f"== on paper: {STATIONS:,} stations × {POINTS_PER_STATION:,} points, {PROBES:,} probes at "
              f"{PAPER_RESOLUTION}², {WORKERS} workers of {cores} cores ==")
        print(f"  assumed: a worker loads the {STATIONS_SEEN_PER_TASK} stations its probes see "
              f"({task_points:,} points, {task_points * bytes_per_point / 2**30:.2f} GiB read at "
              f"{bytes_per_point:.1f} bytes a point); a probe's time grows with its texels from this "
              f"run's {res}² and shrinks with cores from this run's {os.cpu_count()}; the scheduler "
              f"takes {1000 * per_task:.2f} ms a task")
        print(f"  per worker: {per_worker:.0f} probes × {probe_seconds:.3f} core-s / {cores} cores = "
              f"{bake_time / 60:.1f} min baking + {prepare_time / 60:.1f} min preparing its cloud + "
              f"{per_worker * per_task:.1f} s of scheduling: {total / 60:.1f} min in all, against "
              f"{PROBES * probe_seconds / cores / 3600:.1f} h for one such machine")
        base = c["base_memory_per_worker"]
        memory_per_point = c["cloud_memory_per_worker"] / points
        print(f"  memory a worker: about {(base + task_points * memory_per_point) / 2**30:.1f} GiB for "
              f"its {task_points:,} points: {base / 2**20:.0f} MiB before the cloud (the interpreter, "
              f"Dask, lfprobe) and this run's {memory_per_point:.0f} bytes a point for the cloud ready to "
              f"bake (points, normals, spacing, hierarchy), measured as the worker's own memory; the probe "
              f"being baked comes on top ({res}² here)")
        print(f"  not built: loading only the stations a task sees; today each worker loads the whole "
              f"cloud, {STATIONS * POINTS_PER_STATION * bytes_per_point / 2**40:.2f} TiB for this building")
        results["cluster"] = {
            "local_seconds": local_wall, "local_probes_per_second": probes / local_wall,
            "workers": workers, "cluster_seconds": cluster_wall,
            "cluster_probes_per_second": probes / cluster_wall, "identical": identical,
            "bytes_read_per_worker": c["bytes_read_per_worker"],
            "prepare_seconds_per_worker": c["prepare_seconds_per_worker"],
            "peak_memory_per_worker": c["peak_memory_per_worker"],
            "base_memory_per_worker": c["base_memory_per_worker"],
            "cloud_memory_per_worker": c["cloud_memory_per_worker"],
            "worker_seconds_per_probe": c["seconds_per_probe"],
            "scheduler_seconds_per_task": per_task,
            "paper": {"stations": STATIONS, "points_per_station": POINTS_PER_STATION, "probes": PROBES,
                      "workers": WORKERS, "cores_per_worker": cores,
                      "stations_seen_per_task": STATIONS_SEEN_PER_TASK, "resolution": PAPER_RESOLUTION,
                      "minutes": total / 60},
        }
        write_results(args.json, results)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 0
