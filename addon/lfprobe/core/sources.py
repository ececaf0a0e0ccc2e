"""Identifying the inputs of a bake, so a probe set records exactly what it was made from."""

from __future__ import annotations

import hashlib
import os


def file_sha256(path: str, chunk: int = 1 << 22) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as stream:
        while True:
            block = stream.read(chunk)
            if not block:
                break
            digest.update(block)
    return digest.hexdigest()


def describe_scan(path: str, points: int, scanner, sha256: str | None = None) -> dict:
    """The manifest's record of one scan file (sha256: the file's hash when already known, as
    for the second station of an E57)."""
    return {
        "kind": "scan",
        "path": os.path.abspath(path),
        "bytes": os.path.getsize(path),
        "sha256": sha256 or file_sha256(path),
        "points": int(points),
        "scanner": list(scanner) if scanner is not None else None,
    }


def default_cache_dir() -> str:
    """Where parsed scans are cached: $LFPROBE_CACHE, else the XDG cache folder."""
    if os.environ.get("LFPROBE_CACHE"):
        return os.environ["LFPROBE_CACHE"]
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "lfprobe", "scans")


def describe_mesh(path: str, triangles: int) -> dict:
    """The manifest's record of one mesh file (like sources.describe_scan)."""
    return {
        "kind": "mesh",
        "path": os.path.abspath(path),
        "bytes": os.path.getsize(path),
        "sha256": file_sha256(str(path)),
        "triangles": int(triangles),
    }
