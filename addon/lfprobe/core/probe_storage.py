"""How a probe set loads into memory, read from its manifest's "storage" dict (written by the
native set_probe_set_storage; see native probe_storage.hpp): its name (full, compact, custom),
a line describing it, and the memory the set takes."""

from __future__ import annotations

import os
from typing import Optional

from .probe_set import MANIFEST, summarize


def storage_name(storage: Optional[dict]) -> str:
    """"full", "compact" or "custom" for a manifest's "storage" dict (none: full, as it loads)."""
    storage = storage or {}
    radiance, normal = storage.get("radiance", "half"), storage.get("normal", "half")
    step, confidence = float(storage.get("distance_step") or 0.0), storage.get("confidence", True)
    if radiance == "half" and normal == "half" and step == 0.0 and confidence:
        return "full"
    if radiance == "srgb8" and normal == "oct16" and step > 0.0 and not confidence:
        return "compact"
    return "custom"


def describe(storage: dict) -> str:
    """One line for a manifest's "storage" dict."""
    step = storage.get("distance_step") or 0.0
    if storage.get("radiance") == "half" and storage.get("normal") == "half" and not step:
        return "full (half RGBA, float32 distance, half normals)"
    distance = f"16-bit distance in {step * 1000:g} mm steps" if step else "float32 distance"
    parts = [f"{storage.get('radiance')} radiance", distance, f"{storage.get('normal')} normals"]
    if not storage.get("confidence", True):
        parts.append("no confidence")
    text = ", ".join(parts)
    if "bytes_per_texel" in storage:
        text += f" ({storage['bytes_per_texel']} bytes a texel)"
    return text


# A panel asks on every redraw: one summary per folder, read again when its manifest changes.
_loaded_storage: dict = {}


def loaded_storage(folder: str) -> Optional[dict]:
    """How the finished probe set in `folder` loads, from its manifest: {"memory_bytes" (maps and
    coarse levels), "storage" (the manifest's dict), "name" (storage_name), "bytes_per_texel",
    "distance_step"}; None when there is no readable set."""
    try:
        stat = os.stat(os.path.join(folder, MANIFEST))
    except OSError:
        return None
    stamp = (stat.st_mtime_ns, stat.st_size, stat.st_ino)  # a rewrite renames a new file in
    cached = _loaded_storage.get(folder)
    if cached is not None and cached[0] == stamp:
        return cached[1]
    try:
        info = summarize(folder)
    except (OSError, ValueError, KeyError, TypeError):
        return None
    probe = info["probes"][0] if info["probes"] else None
    facts = {
        "memory_bytes": int(info["memory_bytes"]),
        "storage": info["storage"] or {},
        "name": storage_name(info["storage"]),
        # The manifest's per-probe bytes are its maps alone: N² texels of this many bytes.
        "bytes_per_texel": round(int(probe.get("memory_bytes", 0)) / int(probe["resolution"]) ** 2) if probe else 0,
        "distance_step": float((info["storage"] or {}).get("distance_step") or 0.0),
    }
    _loaded_storage[folder] = (stamp, facts)
    return facts


def memory_text(facts: Optional[dict]) -> str:
    """E.g. "1.23 MiB in memory (compact: 7 bytes a texel, 1 mm distance steps)" for
    loaded_storage's facts."""
    if facts is None:
        return "no probe set"
    detail = f"{facts['bytes_per_texel']} bytes a texel"
    if facts["distance_step"] > 0.0:
        detail += f", {facts['distance_step'] * 1000:g} mm distance steps"
    return f"{facts['memory_bytes'] / 2**20:.2f} MiB in memory ({facts['name']}: {detail})"


def storage_matches(facts: Optional[dict], storage: str, distance_step: float) -> bool:
    """Whether the set described by `facts` (loaded_storage) loads as `storage` ("full" or
    "compact" with `distance_step`) says."""
    if facts is None:
        return True
    if facts["name"] != storage:
        return False
    return storage == "full" or abs(facts["distance_step"] - distance_step) <= 1e-6 * distance_step
