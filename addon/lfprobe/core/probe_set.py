"""Reading a probe set folder (docs/DESIGN.md §3) without the native module: the manifest and the
facts `lfprobe info` prints."""

from __future__ import annotations

import json
import os
from typing import Optional

from .atomic_write import atomic_open

MANIFEST = "manifest.json"
PAPER_BYTES_PER_2048_PROBE = 24.375 * 1024 * 1024  # the paper's figure: 2048² + 128² maps


def read_manifest(folder: str) -> dict:
    path = os.path.join(folder, MANIFEST)
    if not os.path.isfile(path):
        raise FileNotFoundError(
            f"{path}: no probe set manifest (not a probe set, or its bake did not finish)"
        )
    with open(path, encoding="utf-8") as stream:
        try:
            manifest = json.load(stream)
        except json.JSONDecodeError as error:
            raise ValueError(f"{path}: invalid JSON: {error}") from error
        except RecursionError:
            # Python's own parser gives up first on JSON nested thousands deep; the native reader
            # refuses anything past 64.
            raise ValueError(f"{path}: JSON nested too deep (a manifest nests a few levels)") from None
    if manifest.get("format") != "lfprobe-probe-set":
        raise ValueError(f'{path}: not an lfprobe probe set (expected "format": "lfprobe-probe-set")')
    _check_as_a_render_would(folder)
    return manifest


def _check_as_a_render_would(folder: str) -> None:
    """The native reader's checks (format version, plain probe file names, counts, resolutions,
    the type of every field): what `info` or a report reads is what a render accepts, and a
    mistyped field is a clear error naming manifest.json, not a traceback. Skipped only where the
    native module cannot be loaded (then nothing can render the set either)."""
    from .native import NativeModuleError, load

    try:
        native = load()
    except NativeModuleError:
        return
    native.check_probe_set_manifest(folder)


def coarse_level_bytes(resolution: int, storage: Optional[dict] = None) -> int:
    """Bytes of the min-distance levels derived on load, halving to 1×1: float32, or 16-bit
    codes when the probes load with a distance step (the manifest's "storage")."""
    per_value = 2 if storage and storage.get("distance_step") else 4
    total = 0
    n = resolution
    while n > 1:
        n = (n + 1) // 2
        total += n * n * per_value
    return total


def summarize(folder: str) -> dict:
    """What a probe set holds: probes, resolutions, coverage and memory, as plain data."""
    manifest = read_manifest(folder)
    probes = manifest["probes"]
    disk = 0
    missing = []
    for probe in probes:
        path = os.path.join(folder, probe["file"])
        if os.path.isfile(path):
            disk += os.path.getsize(path)
        else:
            missing.append(probe["file"])
    resolutions = sorted({p["resolution"] for p in probes})
    storage = manifest.get("storage")
    memory = sum(p.get("memory_bytes", 0) + coarse_level_bytes(p["resolution"], storage) for p in probes)
    coverage = {}
    for key in ("surface", "inferred", "empty", "unknown"):
        values = [p.get("coverage", {}).get(key, 0.0) for p in probes]
        coverage[key] = sum(values) / len(values) if values else 0.0
    return {
        "folder": os.path.abspath(folder),
        "format_version": manifest.get("format_version"),
        "layout": manifest.get("layout"),
        "grid": manifest.get("grid"),
        "world_offset": manifest.get("world_offset"),
        "probe_count": len(probes),
        "resolutions": resolutions,
        "coverage": coverage,
        "memory_bytes": memory,
        "memory_bytes_per_probe": memory / len(probes) if probes else 0,
        "disk_bytes": disk,
        "disk_bytes_per_probe": disk / len(probes) if probes else 0,
        "missing_files": missing,
        "bake": manifest.get("bake", {}),
        "storage": manifest.get("storage"),
        "sources": manifest.get("sources", []),
        "probes": probes,
    }


def record_in_bake(folder: str, key: str, value) -> None:
    """Adds `key`: `value` to the set's "bake" record (what the bake was), rewriting the manifest
    atomically; the native reader keeps that record as it is."""
    manifest = read_manifest(folder)
    bake = manifest.get("bake")
    manifest["bake"] = dict(bake if isinstance(bake, dict) else {}, **{key: value})
    with atomic_open(os.path.join(folder, MANIFEST), "w") as stream:
        json.dump(manifest, stream, indent=2)
