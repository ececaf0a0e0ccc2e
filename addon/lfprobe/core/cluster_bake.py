"""Baking a probe set's probes on a Dask cluster (a running scheduler, or a local cluster of
worker processes) instead of in this process.

The client (this process) reads the scans once, which fills the parse cache, opens the set's
staging folder and hands the probes out as tasks of `probes_per_task` probes each. With a cache
folder (shared storage: the scan files, the cache folder and the output folder must be at the
same paths on every worker), the client prepares the cloud (normals, spacing, point hierarchy)
and writes it as a spatial cloud (native spatial_cloud.hpp): the points in the hierarchy's
order and the hierarchy's levels, which a task maps and reads only where its probes' cuts go:
the full-density points near its probes and coarse cells elsewhere, so a cloud larger than a
worker's memory still bakes. Without a cache folder each worker reads the scans itself and makes
the whole cloud ready once (kept for its later tasks). A worker writes each of its probes
atomically into the staging folder. The client writes the manifest last, only when
every probe is there, and swaps the set in: the result is the set a local bake writes, byte for
byte. A worker that dies mid-task leaves at most a temporary file, which the finish removes;
Dask runs its task again on another worker. Cancelling (Ctrl-C, the progress callback, Esc in
Blender) removes the staging folder, which also stops the tasks still running: a worker checks
for it between probes and the native bake refuses to write into a folder that is gone.

Workers run one task at a time (`--nthreads 1`): a task's bake already uses every core of its
machine (TBB).
"""

from __future__ import annotations

import dataclasses
import json
import logging
import os
import resource
import threading
import time
from dataclasses import dataclass
from typing import Callable, Optional, Sequence

from . import cluster_task, native
from .errors import InputError, LfprobeError
from .cloud_transform import transform_scans
from .pipeline import BakeOptions, ProbePlacementSpec, apply_storage, load_scans_and_sources
from .scan_merge import describe_records, file_of_each_scan
from .sources import default_cache_dir

Progress = Optional[Callable[[float, str], object]]

# How long the client waits for a scheduler to answer before it says it cannot be reached.
CONNECT_TIMEOUT_SECONDS = 10.0
# How often the client looks at the tasks and calls the progress callback.
POLL_SECONDS = 0.1
# How long a cancelled bake waits for the tasks still running to notice and stop writing.
CANCEL_GRACE_SECONDS = 5.0


class SchedulerUnreachableError(InputError):
    """The Dask scheduler given cannot be reached (or Dask is not installed)."""


class ClusterError(LfprobeError, OSError):
    """The cluster failed a bake (workers that cannot import lfprobe, or that kept dying)."""


@dataclass(frozen=True)
class CloudSpec:
    """What a worker needs to load exactly the cloud the client loaded, and bake from it."""

    paths: tuple
    scanners: tuple
    columns: str
    cache_dir: str
    world_offset: tuple
    settings: tuple  # (name, value) pairs of the native bake settings
    # One 4×4 transform per file (Blender's scan objects), or none: the files as they are.
    file_matrices: tuple = ()
    # The spatial cloud the client wrote (path and key), which tasks read in parts; "": none,
    # each worker loads the whole cloud.
    spatial_path: str = ""
    spatial_key: str = ""


def _load_cloud(spec: CloudSpec, world_offset, progress: Progress = None):
    """The cloud to bake and its scans' records, as the client and every worker load it."""
    cloud, records = load_scans_and_sources(
        list(spec.paths), [list(s) if s is not None else None for s in spec.scanners], spec.columns,
        spec.cache_dir, world_offset=world_offset, progress=progress)
    if spec.file_matrices:
        files = file_of_each_scan(records, list(spec.paths))
        cloud = transform_scans(cloud, [spec.file_matrices[f] for f in files])
    return cloud, records


# Per worker process: the cloud its last tasks baked from, ready to bake (one at a time, so a
# worker that serves several bakes holds one cloud).
_prepared: dict = {}
_prepared_lock = threading.Lock()


def _prepared_source(spec: CloudSpec):
    with _prepared_lock:
        source = _prepared.get(spec)
        if source is None:
            _prepared.clear()
            cloud, _records = _load_cloud(spec, list(spec.world_offset))
            source = native.load().start_prepare_cloud_bake(cloud, dict(spec.settings),
                                                            cache_dir=spec.cache_dir).run(None)
            _prepared[spec] = source
        return source


def bake_probe_batch(spec_fields: dict, positions: list, indices: list, staging: str) -> dict:
    """A cluster task (run through core/cluster_task.py): bakes the probes `indices` into
    `staging`. spec_fields: a CloudSpec's fields. Returns the staged records
    (finish_probe_set_staging's input) and this worker's figures."""
    spec = CloudSpec(**spec_fields)
    if spec.spatial_path:
        return _bake_from_spatial_cloud(spec, positions, indices, staging)
    started = time.perf_counter()
    fresh = spec not in _prepared
    before = _private_memory_bytes()
    source = _prepared_source(spec)
    prepared = time.perf_counter()
    job = native.load().start_bake_staged_probes(source, positions, list(indices), staging)
    # The staging folder's removal is the client's cancel: stop between texel batches too.
    staged = job.run(lambda _fraction, _stage: os.path.isdir(staging))
    return {
        "staged": staged,
        "worker_pid": os.getpid(),
        "prepare_seconds": (prepared - started) if fresh else 0.0,
        "normals_seconds": source.normals_seconds if fresh else 0.0,
        "hierarchy_seconds": source.hierarchy_seconds if fresh else 0.0,
        "prepared_from_cache": bool(source.from_cache),
        "bake_seconds": time.perf_counter() - prepared,
        "bytes_read": _bytes_read(spec, source) if fresh else 0,
        "peak_memory_bytes": _peak_memory_bytes(),
        # The memory the worker owns itself (not shared with other processes) before it loaded
        # this cloud (the interpreter, Dask, lfprobe) and after it (the cloud ready to bake).
        "base_memory_bytes": before if fresh else 0,
        "cloud_memory_bytes": (_private_memory_bytes() - before) if fresh else 0,
        "read_in_parts": False,
        "file_bytes": 0,
    }


def _bake_from_spatial_cloud(spec: CloudSpec, positions: list, indices: list, staging: str) -> dict:
    """A task that maps the spatial cloud and bakes from the parts its probes' cuts read. Opened
    per task (it reads a header and a table), so that what the mapping holds afterwards is this
    task's reading."""
    _native = native.load()
    started = time.perf_counter()
    before = _private_memory_bytes()
    cloud = _native.open_spatial_cloud(spec.spatial_path, spec.spatial_key)
    opened = time.perf_counter()
    job = _native.start_bake_staged_probes(cloud, positions, list(indices), staging, dict(spec.settings))
    staged = job.run(lambda _fraction, _stage: os.path.isdir(staging))
    result = {
        "staged": staged,
        "worker_pid": os.getpid(),
        "prepare_seconds": opened - started,
        "normals_seconds": 0.0,
        "hierarchy_seconds": 0.0,
        "prepared_from_cache": True,
        "bake_seconds": time.perf_counter() - opened,
        # The file's pages this task touched: what it read of the cloud (its resident part of
        # the mapping; pages the kernel mapped in around a fault from its cache count too).
        "bytes_read": cloud.resident_bytes or 0,
        "peak_memory_bytes": _peak_memory_bytes(),
        "base_memory_bytes": before,
        # The task's own memory for the cloud: the pages it read and the cuts it gathered.
        "cloud_memory_bytes": max(0, _private_memory_bytes() - before),
        "read_in_parts": True,
        "file_bytes": cloud.file_bytes,
    }
    del cloud
    return result


def _peak_memory_bytes() -> int:
    """This process's peak resident memory so far (Linux reports KiB). A worker forked from a
    large process counts the pages it shares with it too."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def _private_memory_bytes() -> int:
    """The resident memory this process does not share (Linux: /proc/self/smaps_rollup); 0 where
    that cannot be read."""
    try:
        with open("/proc/self/smaps_rollup", encoding="ascii") as stream:
            fields = dict(line.split(":", 1) for line in stream if ":" in line)
        return sum(int(fields[k].split()[0]) * 1024 for k in ("Private_Clean", "Private_Dirty"))
    except (OSError, KeyError, ValueError):
        return 0


def _bytes_read(spec: CloudSpec, source) -> int:
    """What a worker reads to get the cloud: each scan's parse-cache entry where the cache holds
    one, else the scan file itself (E57 and LAS/LAZ are read through their libraries, uncached),
    and the prepared-cloud entry where it read one."""
    total = os.path.getsize(source.cache_entry) if source.from_cache and source.cache_entry else 0
    for path in spec.paths:
        entry = native.load().scan_cache_entry_path(path, spec.columns, spec.cache_dir) if spec.cache_dir else ""
        total += os.path.getsize(entry if entry and os.path.isfile(entry) else path)
    return total


class _Cluster:
    """A Dask client on a running scheduler, or on a local cluster of worker processes that it
    owns and closes."""

    def __init__(self, scheduler: Optional[str], workers: Optional[int]):
        try:
            from distributed import Client, LocalCluster
        except ImportError as error:
            raise SchedulerUnreachableError(
                "baking on a cluster needs Dask's distributed package (Debian: apt-get install "
                f"python3-distributed; PyPI: pip install distributed): {error}") from None
        # The task function travels by value: a worker may not know this process's package name.
        import cloudpickle

        cloudpickle.register_pickle_by_value(cluster_task)
        self.local = None
        if scheduler:
            try:
                self.client = Client(scheduler, timeout=CONNECT_TIMEOUT_SECONDS, set_as_default=False)
            except (OSError, TimeoutError, ValueError) as error:
                raise SchedulerUnreachableError(
                    f"cannot reach the Dask scheduler at {scheduler!r} ({error}); start one with "
                    "`dask scheduler` and give its address (tcp://HOST:8786)") from None
        else:
            count = int(workers or 0)
            if count < 1:
                raise InputError("--workers needs a whole number of at least 1")
            # One thread per worker: each task's bake uses every core itself.
            self.local = LocalCluster(n_workers=count, threads_per_worker=1, processes=True,
                                      dashboard_address=None, silence_logs=logging.ERROR)
            self.client = Client(self.local, set_as_default=False)

    def worker_count(self) -> int:
        return len(self.client.scheduler_info().get("workers", {}))

    def close(self) -> None:
        self.client.close()
        if self.local is not None:
            self.local.close()


def bake_scans_on_cluster(
    scan_paths: Sequence[str],
    out_dir: str,
    placement: ProbePlacementSpec,
    options: BakeOptions,
    scanners: Sequence = (),
    columns: str = "",
    cache_dir: Optional[str] = None,
    world_offset: Optional[Sequence[float]] = None,
    file_matrices: Sequence = (),
    scheduler: Optional[str] = None,
    workers: Optional[int] = None,
    probes_per_task: int = 1,
    progress: Progress = None,
    read_in_parts: bool = True,
) -> dict:
    """Scan files → probe set folder, the probes baked on a Dask cluster: `scheduler` (an address
    such as tcp://host:8786) or a local cluster of `workers` processes. file_matrices: one 4×4
    transform per file that moves its points (Blender's scan objects), or none. Returns the bake summary
    (as bake_from_scans) with a "cluster" section: workers, tasks, seconds per probe, what the
    workers read and the scheduler's overhead. read_in_parts: with a cache folder, tasks map the
    spatial cloud the client writes and read only what their probes need (False: every worker
    loads the whole cloud, for comparison)."""
    if options.plan is not None:
        raise InputError("a cluster bake bakes every probe at one resolution: plan first "
                         "(./lfprobe place) and bake the planned positions, or bake --auto locally")
    if probes_per_task < 1:
        raise InputError("--probes-per-task needs a whole number of at least 1")
    placement.validate()
    _native = native.load()
    started = time.perf_counter()
    cluster = _Cluster(scheduler, workers)
    try:
        cache = default_cache_dir() if cache_dir is None else cache_dir
        settings = {"resolution": int(options.resolution), "splat_scale": float(options.splat_scale),
                    "hole_fill_texels": int(options.hole_fill_texels),
                    "normal_neighbours": int(options.normal_neighbours),
                    "lod_texels": float(options.lod_texels),
                    "lod_colour_tolerance": float(options.lod_colour_tolerance),
                    "splat_edge_margin": float(options.splat_edge_margin),
                    "splat_core_scale": float(options.splat_core_scale)}
        spec = CloudSpec(
            paths=tuple(os.path.abspath(str(p)) for p in scan_paths),
            scanners=tuple(tuple(map(float, s)) if s is not None else None for s in scanners),
            columns=columns or "",
            cache_dir=os.path.abspath(cache) if cache else "",
            world_offset=(),
            settings=tuple(sorted(settings.items())),
            file_matrices=tuple(tuple(tuple(float(v) for v in row) for row in m) for m in file_matrices),
        )
        cloud, records = _load_cloud(spec, None if world_offset is None else list(world_offset), progress)
        spec = dataclasses.replace(spec, world_offset=tuple(float(v) for v in cloud.world_offset))
        plan = _native.cloud_bake_manifest(cloud, **placement.native_kwargs(),
                                           sources_json=json.dumps(list(describe_records(records))),
                                           settings=settings)
        points = len(cloud)
        load_seconds = time.perf_counter() - started
        prepare_started = time.perf_counter()
        spatial_seconds = 0.0
        if spec.cache_dir:
            # Prepared once here into the shared cache, the cloud's normals, spacing and
            # hierarchy are read by every worker instead of computed by each.
            source = _native.start_prepare_cloud_bake(cloud, settings, cache_dir=spec.cache_dir).run(progress)
            spatial_started = time.perf_counter()
            entry = _native.start_write_spatial_cloud(source, spec.cache_dir).run(progress) if read_in_parts else None
            spatial_seconds = time.perf_counter() - spatial_started
            if entry is not None:
                spec = dataclasses.replace(spec, spatial_path=entry["path"], spatial_key=entry["key"])
            del source
        prepare_seconds = time.perf_counter() - prepare_started
        del cloud  # the workers load their own; the client keeps no cloud during the bake
        summary = _run_tasks(cluster, out_dir, spec, plan, probes_per_task, progress)
    finally:
        cluster.close()
    summary["points"] = points
    summary["world_offset"] = list(spec.world_offset)
    summary["cluster"]["client_load_seconds"] = load_seconds
    summary["cluster"]["client_prepare_seconds"] = prepare_seconds
    summary["cluster"]["client_spatial_cloud_seconds"] = spatial_seconds
    summary["cluster"]["wall_seconds"] = time.perf_counter() - started
    apply_storage(out_dir, summary, options)
    return summary


def _run_tasks(cluster: _Cluster, out_dir: str, spec: CloudSpec, plan: dict, probes_per_task: int,
               progress: Progress) -> dict:
    _native = native.load()
    positions = [list(p) for p in plan["positions"]]
    total = len(positions)
    batches = [list(range(i, min(i + probes_per_task, total))) for i in range(0, total, probes_per_task)]
    staging = _native.open_probe_set_staging(out_dir)
    futures = []
    try:
        started = time.perf_counter()
        fields = dataclasses.asdict(spec)
        futures = [cluster.client.submit(cluster_task.run_bake_task, fields, positions, batch, staging,
                                         pure=False) for batch in batches]
        staged, results, done = [], [], 0
        pending = list(futures)
        while pending:
            # Polled, not waited on: the progress callback is how Blender's Esc and the
            # terminal's Ctrl-C reach a bake, so it must run while tasks are under way.
            finished = [f for f in pending if f.done()]
            for future in finished:
                pending.remove(future)
                result = _task_result(future)
                results.append(result)
                staged.extend(result["staged"])
                done += len(result["staged"])
            _report(progress, done, total)
            if not finished:
                time.sleep(POLL_SECONDS)
        tasks_seconds = time.perf_counter() - started
        summary = _native.finish_probe_set_staging(out_dir, plan["manifest"], staged)
    except BaseException:
        _call_off(cluster, futures, out_dir)
        raise
    summary["folder"] = out_dir
    summary.pop("write_seconds", None)  # the workers' bake_seconds hold their writes
    summary.update(_figures(results, total, len(batches), tasks_seconds, cluster))
    return summary


def _task_result(future):
    """A finished task's result; its error as lfprobe's where the cluster, not the input, failed."""
    try:
        return future.result()
    except ImportError as error:  # the worker was started without lfprobe on its path
        raise ClusterError(str(error)) from None
    except Exception as error:
        if type(error).__name__ == "KilledWorker":  # Dask gave up after workers died running it
            raise ClusterError(f"the cluster lost the workers running a bake task ({error}); the set "
                               "was not written") from None
        raise


def _report(progress: Progress, done: int, total: int) -> None:
    if progress is None:
        return
    if progress(done / total, f"baking on the cluster: {done} of {total} probes") is False:
        raise native.cancelled_type()("bake cancelled")


def _call_off(cluster: _Cluster, futures: list, out_dir: str) -> None:
    """Cancels the tasks and removes the staging folder; a task still running stops at its next
    probe (or texel batch) and cannot write into the folder once it is gone, but a rename under
    way may land, so the folder is removed again until the tasks are over."""
    _native = native.load()
    try:
        cluster.client.cancel(futures, force=True)
    except Exception:  # the cluster may be what failed; the folder goes all the same
        pass
    _native.discard_probe_set_staging(out_dir)
    deadline = time.monotonic() + CANCEL_GRACE_SECONDS
    while time.monotonic() < deadline:
        try:
            busy = any(cluster.client.processing().values())
        except Exception:
            busy = False
        if not busy:
            break
        time.sleep(0.05)
        _native.discard_probe_set_staging(out_dir)
    _native.discard_probe_set_staging(out_dir)


def _figures(results: list, probes: int, tasks: int, tasks_seconds: float, cluster: _Cluster) -> dict:
    workers = {r["worker_pid"] for r in results}
    bake = sum(r["bake_seconds"] for r in results)
    prepare = [r["prepare_seconds"] for r in results if r["prepare_seconds"] > 0]
    busy = bake + sum(prepare)
    slots = max(1, cluster.worker_count())
    # What the wall clock of the task phase held beyond the workers' own work, per task.
    overhead = max(0.0, tasks_seconds * min(slots, len(workers) or 1) - busy) / max(1, tasks)
    return {
        "probe_count": probes,
        "normals_seconds": max([r["normals_seconds"] for r in results] or [0.0]),
        "hierarchy_seconds": max([r["hierarchy_seconds"] for r in results] or [0.0]),
        "bake_seconds": bake,
        "cluster": {
            "workers": slots,
            "workers_used": len(workers),
            "tasks": tasks,
            "tasks_seconds": tasks_seconds,
            "probes_per_second": probes / tasks_seconds if tasks_seconds > 0 else 0.0,
            "seconds_per_probe": bake / probes if probes else 0.0,
            "prepare_seconds_per_worker": (sum(prepare) / len(prepare)) if prepare else 0.0,
            # Workers whose cloud came ready from the prepared-cloud cache (the client's).
            "workers_reading_the_prepared_cloud": len({r["worker_pid"] for r in results
                                                       if r["prepared_from_cache"]}),
            "bytes_read_per_worker": max([r["bytes_read"] for r in results] or [0]),
            "peak_memory_per_worker": max([r["peak_memory_bytes"] for r in results] or [0]),
            "base_memory_per_worker": max([r["base_memory_bytes"] for r in results] or [0]),
            "cloud_memory_per_worker": max([r["cloud_memory_bytes"] for r in results] or [0]),
            # Tasks that read the spatial cloud in parts, the file's size and the most one task read.
            "tasks_reading_in_parts": sum(1 for r in results if r.get("read_in_parts")),
            "spatial_cloud_bytes": max([r.get("file_bytes", 0) for r in results] or [0]),
            "bytes_read_per_task": max([r["bytes_read"] for r in results if r.get("read_in_parts")] or [0]),
            "overhead_seconds_per_task": overhead,
        },
    }
