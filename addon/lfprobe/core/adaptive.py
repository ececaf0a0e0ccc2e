"""Adaptive probe placement: probes where views need them (the paper's simulated probes).

A base placement (a grid, explicit positions, or nothing) is baked once; then, greedily, the
view with the most UNKNOWN pixels gets a probe at its eye, until every view's UNKNOWN rate is
at most a target or the next probe would not fit a memory budget. Each iteration bakes only
the new probe (a one-probe set) and merges it into the growing set by rewriting the manifest
with layout "positions", so the cost of an iteration is one probe's bake and one render per
view. Without ground truth, a hole is what the trace itself reports: an UNKNOWN pixel.
"""

from __future__ import annotations

import json
import math
import os
import shutil
from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional, Sequence

import numpy as np

from . import defaults, native
from .atomic_write import atomic_open
from .pipeline import BakeOptions, Progress, ProbePlacementSpec, bake_from_cloud
from .probe_set import MANIFEST, coarse_level_bytes, read_manifest

UNKNOWN = 2  # the render's status channel: 0 MISS, 1 HIT, 2 UNKNOWN
# Why the greedy loop stopped: every view at the target, the next probe over the budget, the
# limit of added probes reached, every view above the target already with a probe at its eye.
STOP_REASONS = ("target", "budget", "max_added", "eyes_used")
DEFAULT_TRACE = {"mode": defaults.trace("mode"), "thickness": defaults.trace("thickness")}
Log = Optional[Callable[[str], object]]


@dataclass
class AdaptiveResult:
    """What the greedy loop did: the probes it added (world positions), one record per
    iteration (probes, memory, UNKNOWN rate per view) and why it stopped: `stopped_because` in
    words, `stop` as one of STOP_REASONS (for a caller that words it its own way)."""
    folder: str
    base_probes: int
    added: List[Dict[str, object]] = field(default_factory=list)
    iterations: List[Dict[str, object]] = field(default_factory=list)
    stopped_because: str = ""
    stop: str = ""
    memory_bytes: int = 0
    bake_seconds: float = 0.0

    @property
    def added_positions(self) -> List[List[float]]:
        return [a["position"] for a in self.added]

    def as_dict(self) -> Dict[str, object]:
        return {"folder": self.folder, "base_probes": self.base_probes, "added": self.added,
                "iterations": self.iterations, "stopped_because": self.stopped_because, "stop": self.stop,
                "memory_bytes": self.memory_bytes, "bake_seconds": self.bake_seconds}


def camera_position(camera: dict) -> List[float]:
    """The eye of a camera dict (the translation column of matrix_world)."""
    try:
        m = camera["matrix_world"]
        return [float(m[0][3]), float(m[1][3]), float(m[2][3])]
    except (KeyError, IndexError, TypeError) as error:
        raise ValueError(f"camera: expected matrix_world as 4×4 rows ({error})") from error


def probe_memory_bytes(record: dict, storage: Optional[dict] = None) -> int:
    """Loaded bytes of one manifest probe record: its maps and the coarse levels derived on load
    (as lfprobe.core.probe_set.summarize counts them); storage: the manifest's "storage"."""
    return int(record.get("memory_bytes", 0)) + coarse_level_bytes(int(record["resolution"]), storage)


def unknown_rate(image: dict) -> float:
    status = np.asarray(image["status"])
    return float(np.count_nonzero(status == UNKNOWN)) / status.size if status.size else 0.0


def _write_manifest(folder: str, manifest: dict) -> None:
    path = os.path.join(folder, MANIFEST)
    with atomic_open(path) as stream:
        json.dump(manifest, stream, indent=2, sort_keys=True)


# The set's known space (native known_space.hpp's kKnownSpaceName), named by the manifest.
KNOWN_SPACE_FILE = "known_space.bin"


class _GrowingSet:
    """A probe set folder that probes are appended to (layout "positions")."""

    def __init__(self, folder: str, manifest: Optional[dict]):
        self.folder = folder
        self.manifest = manifest

    @property
    def probes(self) -> List[dict]:
        return [] if self.manifest is None else self.manifest["probes"]

    def memory_bytes(self) -> int:
        storage = None if self.manifest is None else self.manifest.get("storage")
        return sum(probe_memory_bytes(p, storage) for p in self.probes)

    def append(self, one_probe_folder: str, note: dict) -> None:
        """Moves the single probe of `one_probe_folder` into this set and rewrites the manifest."""
        added = read_manifest(one_probe_folder)
        record = dict(added["probes"][0])
        name = f"probe_{len(self.probes):05d}.exr"
        # A rename within one file system: the EXR appears whole; the manifest that lists it comes last.
        os.replace(os.path.join(one_probe_folder, record["file"]), os.path.join(self.folder, name))
        record["file"] = name
        # The set's known space grows by the probe's (written before the manifest that lists
        # the probe); a set that cannot have a whole one has none, and asks every probe on.
        known = native.load().append_known_space(self.folder, one_probe_folder, len(self.probes))
        if self.manifest is None:
            self.manifest = dict(added, probes=[], layout="positions")
            self.manifest.pop("grid", None)
            self.manifest["bake"] = dict(added.get("bake", {}), adaptive=[])
        elif [round(a, 9) for a in added["world_offset"]] != [round(a, 9) for a in self.manifest["world_offset"]]:
            raise ValueError(f"{one_probe_folder}: world offset {added['world_offset']} differs from the set's "
                             f"{self.manifest['world_offset']}")
        if self.manifest.get("layout") != "positions":
            # A grid with one more probe is no longer a grid: the trace tries probes nearest first.
            self.manifest["layout"] = "positions"
            self.manifest.pop("grid", None)
        self.manifest["probes"].append(record)
        if known:
            self.manifest["known_space"] = KNOWN_SPACE_FILE
        else:
            self.manifest.pop("known_space", None)
        self.manifest.setdefault("bake", {}).setdefault("adaptive", []).append(
            dict(note, file=name, resolution=record["resolution"], bake=added.get("bake", {}).get("plan")))
        _write_manifest(self.folder, self.manifest)


def place_adaptively(
    cloud,
    cameras: Sequence[dict],
    folder: str,
    base_positions: Sequence[Sequence[float]] = (),
    base_grid: Optional[Dict[str, Sequence]] = None,
    resolution: int = 256,
    plan: Optional[dict] = None,
    target_unknown: float = 0.01,
    budget_bytes: Optional[float] = None,
    max_added: int = 64,
    trace: Optional[dict] = None,
    threads: int = 0,
    splat_scale: float = 0.8,
    hole_fill_texels: Optional[int] = None,
    log: Log = None,
    sources: Sequence[dict] = (),
    progress: Progress = None,
    storage: Optional[str] = None,
    distance_step: float = 0.0,
) -> AdaptiveResult:
    """Greedy placement into `folder` (a probe set that ends up holding the base and the added
    probes). cameras: camera dicts (docs/DESIGN.md §3, world coordinates). base_grid: {"min", "max",
    "counts"}, or base_positions (world), or neither. resolution: the new probes' N, or with
    `plan` (options of start_bake_planned_probe_set) each new probe is planned from the data.
    Stops when every view's UNKNOWN rate is ≤ target_unknown, when the next probe would take the
    set over budget_bytes (loaded maps and coarse levels), after max_added probes, or when every
    view that is still above the target already has a probe at its eye. sources: the manifest's
    source records (lfprobe.core.sources.describe_scan). progress(fraction, stage) is called
    through every bake and between traces; when it returns False the work stops with
    Cancelled (folder is then left half made: the caller bakes into a staging folder).
    storage, distance_step: how the probes load (BakeOptions); every bake records it, so the
    views are traced and the budget counted as the finished set loads."""
    _native = native.load()
    if not cameras:
        raise ValueError("adaptive placement needs at least one view (camera)")
    if not 0.0 <= target_unknown <= 1.0:
        raise ValueError(f"target UNKNOWN rate must be between 0 and 1, got {target_unknown}")
    if budget_bytes is not None and budget_bytes <= 0:
        raise ValueError(f"memory budget must be positive, got {budget_bytes} bytes")
    if base_grid is not None and base_positions:
        raise ValueError("give a base grid or base positions, not both")
    trace = dict(DEFAULT_TRACE if trace is None else trace)
    texts = [json.dumps(c) for c in cameras]
    eyes = [camera_position(c) for c in cameras]
    if os.path.exists(folder):
        shutil.rmtree(folder)
    os.makedirs(folder)
    work = folder.rstrip(os.sep) + ".adding"
    options = BakeOptions(resolution=int(resolution), splat_scale=splat_scale,
                          hole_fill_texels=(defaults.bake("hole_fill_texels") if hole_fill_texels is None
                                            else hole_fill_texels),
                          plan=plan, storage=storage,
                          distance_step=distance_step)

    def step(fraction: float, stage: str):
        if progress is not None and progress(fraction, stage) is False:
            raise _native.Cancelled(f"adaptive placement cancelled ({stage})")
        return True

    def bake_into(target: str, positions=(), grid=None, stage: str = "") -> dict:
        grid = grid or {}
        placement = ProbePlacementSpec(positions=list(positions), grid_min=grid.get("min"),
                                       grid_max=grid.get("max"), counts=grid.get("counts"))
        # The native bake stops on the callback's False and raises Cancelled itself.
        relay = None if progress is None else (lambda f, s: progress(f, f"{stage}: {s}"))
        return bake_from_cloud(cloud, target, placement, options, sources, progress=relay)

    result = AdaptiveResult(folder=os.path.abspath(folder), base_probes=0)
    if base_grid is not None or base_positions:
        summary = bake_into(folder, base_positions, base_grid, stage="base probes")
        result.bake_seconds += summary["bake_seconds"] + summary.get("normals_seconds", 0.0)
        grown = _GrowingSet(folder, read_manifest(folder))
        result.base_probes = len(grown.probes)
    else:
        grown = _GrowingSet(folder, None)
    try:
        while True:
            field_ = _native.ProbeField.load(folder) if grown.probes else None
            rates, unknown_pixels, seconds = [], [], 0.0
            for index, (text, camera) in enumerate(zip(texts, cameras)):
                step(index / len(cameras), f"tracing {len(cameras)} view(s) through {len(grown.probes)} probe(s)")
                if field_ is None:  # nothing baked yet: every pixel is unknown
                    w, h = camera["resolution"]
                    rates.append(1.0)
                    unknown_pixels.append(int(w) * int(h))
                    continue
                image, stats = field_.render(text, threads=threads, **trace)
                seconds += stats["seconds"]
                rates.append(unknown_rate(image))
                unknown_pixels.append(int(np.count_nonzero(np.asarray(image["status"]) == UNKNOWN)))
            memory = grown.memory_bytes()
            result.iterations.append({
                "iteration": len(result.iterations), "probes": len(grown.probes), "memory_bytes": memory,
                "unknown_rate_per_view": rates, "mean_unknown_rate": sum(rates) / len(rates),
                "max_unknown_rate": max(rates), "render_seconds": seconds})
            result.memory_bytes = memory
            if log:
                log(f"  adaptive: {len(grown.probes)} probe(s), {memory / 2**20:.2f} MiB, UNKNOWN mean "
                    f"{100 * sum(rates) / len(rates):.2f} %, worst {100 * max(rates):.2f} %")
            del field_
            if max(rates) <= target_unknown:
                result.stopped_because = f"every view at most {target_unknown:.2%} UNKNOWN"
                result.stop = "target"
                break
            if len(result.added) >= max_added:
                result.stopped_because = f"{max_added} probes added (the limit)"
                result.stop = "max_added"
                break
            # The worst view whose eye has no probe yet: a probe at an eye that already has one
            # would change nothing.
            order = sorted(range(len(cameras)), key=lambda i: -unknown_pixels[i])
            worst = next((i for i in order if rates[i] > target_unknown
                          and not any(math.dist(eyes[i], a["eye"]) < 1e-6 for a in result.added)), None)
            if worst is None:
                result.stopped_because = "every view above the target already has a probe at its eye"
                result.stop = "eyes_used"
                break
            if os.path.exists(work):
                shutil.rmtree(work)
            summary = bake_into(work, [eyes[worst]], stage=f"probe {len(result.added) + 1} at the eye of view "
                                                            f"{worst + 1} ({rates[worst]:.1%} UNKNOWN)")
            candidate_set = read_manifest(work)
            candidate = candidate_set["probes"][0]
            cost = probe_memory_bytes(candidate, candidate_set.get("storage"))
            if budget_bytes is not None and memory + cost > budget_bytes:
                result.stopped_because = (f"the next probe ({cost / 2**20:.2f} MiB) would exceed the budget "
                                          f"({budget_bytes / 2**20:.2f} MiB; {memory / 2**20:.2f} MiB used)")
                result.stop = "budget"
                break
            result.bake_seconds += summary["bake_seconds"] + summary.get("normals_seconds", 0.0)
            # A planned probe may have been moved off a wall: record where it went (world).
            position = [o + c for o, c in zip(candidate_set["world_offset"], candidate["position"])]
            note = {"iteration": len(result.iterations) - 1, "view": worst, "eye": eyes[worst],
                    "position": position, "unknown_rate_before": rates[worst]}
            grown.append(work, note)
            result.added.append({**note, "resolution": candidate["resolution"], "memory_bytes": cost})
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return result


def budget_from_mib(mib: Optional[float]) -> Optional[float]:
    if mib is None:
        return None
    if not math.isfinite(mib) or mib <= 0:
        raise ValueError(f"--budget-mib must be a positive number of MiB, got {mib}")
    return mib * 1024.0 * 1024.0
