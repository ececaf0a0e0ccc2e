#!/usr/bin/python3
"""Says where two runs of tools/reference_outputs.sh (or two report folders) differ, timings
aside: every EXR's channels bit for bit and its metadata JSON, every probe set's files byte for
byte, report.json's values, and the report's view images (PNG) byte for byte.

usage: /usr/bin/python3 tools/diff_outputs.py BEFORE AFTER     (exit status 1 when anything differs)

Open3D's Poisson reconstruction (the report's "Poisson mesh" peer) runs on threads and is not
deterministic: its rows and pictures differ between two runs of the same code, so they are
counted apart ("vary between any two runs") and do not make the exit status 1. So do the
demo's Blender files (.blend: Blender stamps them) and a grid object's random id in a manifest.
"""
import json
import math
import re
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "addon"))

# Keys and CSV columns whose values are clock readings or chosen by them (the fastest Embree
# packet size), and the findings' sentences, which quote times (their figures are compared
# where the report stores them).
TIMING = re.compile(
    r"seconds|per_second|_ms|ms_|speedup|fps|time|wall|elapsed|date|started|over_embree|"
    r"embree_packet|findings", re.I)
# Files written with the time in them, or plots of timings.
SKIP_FILES = re.compile(r"^(report\.html|report\.log|speed_.*\.png|peers_ms\.png|.*\.blend1?)$")
# Values that differ between two runs of the same code: the Poisson peer's (Open3D's threads)
# and the random id Blender's grid object carries into its probe set's manifest.
VARIES_FILES = re.compile(r"^triplet_poisson_.*\.png$")
VARIES_KEYS = re.compile(r"^/peers/poisson/|/blender_grid/id$")


def flatten(value, path=""):
    if isinstance(value, dict):
        for k, v in value.items():
            yield from flatten(v, f"{path}/{k}")
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield from flatten(v, f"{path}[{i}]")
    else:
        yield path, value


def same_value(a, b):
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    if isinstance(a, str) and isinstance(b, str) and "/" in a and "/" in b:
        return Path(a).name == Path(b).name  # a file of the run: the runs' folders differ
    return a == b


def poisson_rows(document) -> set:
    """Indices of report.json's peer rows that are the Poisson mesh's."""
    rows = document.get("peers", {}).get("rows", []) if isinstance(document, dict) else []
    return {i for i, r in enumerate(rows) if str(r.get("method", "")).startswith("Poisson")}


def diff_json(a, b, label, varies):
    fa = {k: v for k, v in flatten(a) if not TIMING.search(k)}
    fb = {k: v for k, v in flatten(b) if not TIMING.search(k)}
    poisson = poisson_rows(a) | poisson_rows(b)
    out = []
    for k in sorted(set(fa) | set(fb)):
        row = re.match(r"^/peers/rows\[(\d+)\]/", k)
        known = VARIES_KEYS.search(k) or (row and int(row.group(1)) in poisson)
        if k not in fa or k not in fb:
            line = f"{label}: {k} only in {'after' if k not in fa else 'before'}"
        elif not same_value(fa[k], fb[k]):
            line = f"{label}: {k}: {fa[k]!r} -> {fb[k]!r}"
        else:
            continue
        (varies if known else out).append(line)
    return out


def diff_csv(pa, pb, label, varies):
    import csv

    ra = list(csv.DictReader(pa.open(newline="")))
    rb = list(csv.DictReader(pb.open(newline="")))
    if len(ra) != len(rb):
        return [f"{label}: {len(ra)} rows -> {len(rb)}"]
    out = []
    for i, (x, y) in enumerate(zip(ra, rb)):
        known = str(x.get("method", "")).startswith("Poisson")
        for k in sorted(set(x) | set(y)):
            if not TIMING.search(k) and not same_value(x.get(k), y.get(k)):
                (varies if known else out).append(f"{label}: row {i} {k}: {x.get(k)!r} -> {y.get(k)!r}")
    return out


def diff_exr(pa, pb, label):
    from lfprobe import _native
    import numpy as np

    a, b = _native.read_image(str(pa)), _native.read_image(str(pb))
    out = []
    for key in ("rgba", "depth", "normal", "status", "probe", "steps"):
        x, y = np.asarray(a[key]), np.asarray(b[key])
        if x.shape != y.shape or x.tobytes() != y.tobytes():
            n = int(np.sum(x != y)) if x.shape == y.shape else -1
            out.append(f"{label}: channel {key} differs ({n} values)")
    ma = json.loads(a["metadata"]) if a["metadata"] else {}
    mb = json.loads(b["metadata"]) if b["metadata"] else {}
    out += diff_json(ma, mb, f"{label} metadata", out)
    return out


def main(argv):
    if len(argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    before, after = Path(argv[1]), Path(argv[2])
    files_a = {p.relative_to(before) for p in before.rglob("*") if p.is_file()}
    files_b = {p.relative_to(after) for p in after.rglob("*") if p.is_file()}
    problems = [f"only before: {p}" for p in sorted(files_a - files_b)]
    problems += [f"only after: {p}" for p in sorted(files_b - files_a)]
    compared = 0
    varies = []
    for rel in sorted(files_a & files_b):
        pa, pb = before / rel, after / rel
        if SKIP_FILES.match(rel.name):
            continue
        compared += 1
        if rel.suffix == ".exr" and rel.parts[0] != "mesh_probe" and "probe_" not in rel.name:
            problems += diff_exr(pa, pb, str(rel))
        elif rel.suffix == ".csv":
            problems += diff_csv(pa, pb, str(rel), varies)
        elif rel.suffix == ".json":
            problems += diff_json(json.loads(pa.read_text()), json.loads(pb.read_text()), str(rel),
                                  varies)
        elif pa.read_bytes() != pb.read_bytes():
            (varies if VARIES_FILES.match(rel.name) else problems).append(f"{rel}: bytes differ")
    for line in problems:
        print(line)
    if varies:
        print(f"{len(varies)} values that vary between any two runs (the Poisson peer, Blender's ids) "
              "differ; not counted:")
        for line in varies:
            print(f"  {line}")
    print(f"{compared} files compared, {len(problems)} differences")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
