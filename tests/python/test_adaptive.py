"""Adaptive probe placement (lfprobe.core.adaptive and `lfprobe place --views`): a box room with
a partition that hides a corner from the base probe; a camera in that corner traces UNKNOWN
until the greedy loop puts a probe at its eye; a memory budget stops the loop."""

import json

import numpy as np
import pytest

from conftest import run_cli

from lfprobe.core.adaptive import place_adaptively
from lfprobe.core.camera_json import camera_dict, write_camera
from lfprobe.core.probe_set import coarse_level_bytes, read_manifest

BASE_PROBE = [-1.0, 0.0, 1.25]
HIDDEN_EYE = [1.6, -0.8, 1.25]     # behind the partition, seen from the base probe
OPEN_EYE = [-1.2, 0.4, 1.25]       # in the open half, near the base probe


def _panel(axis, value, u_range, v_range, pitch):
    u_axis, v_axis = [a for a in range(3) if a != axis]
    uu, vv = np.meshgrid(np.arange(*u_range, pitch), np.arange(*v_range, pitch), indexing="ij")
    p = np.zeros((uu.size, 3))
    p[:, axis], p[:, u_axis], p[:, v_axis] = value, uu.ravel(), vv.ravel()
    return p


def write_partitioned_room(path, pitch=0.04):
    """A 4 × 3 × 2.5 m box room (x −2..2, y −1.5..1.5, z 0..2.5) with a 5 cm partition at
    x = 1 from the wall y = −1.5 to y = 0.3, every surface sampled (a merged, complete scan)."""
    lo, hi = np.array([-2.0, -1.5, 0.0]), np.array([2.0, 1.5, 2.5])
    chunks = []
    for axis in range(3):
        u, v = [a for a in range(3) if a != axis]
        for wall in (lo[axis], hi[axis]):
            chunks.append(_panel(axis, wall, (lo[u], hi[u]), (lo[v], hi[v]), pitch))
    for x in (1.0, 1.05):
        chunks.append(_panel(0, x, (-1.5, 0.3), (0.0, 2.5), pitch))
    chunks.append(_panel(1, 0.3, (1.0, 1.05 + 1e-9), (0.0, 2.5), pitch / 2))
    p = np.concatenate(chunks)
    rgb = np.column_stack([(p[:, 0] + 2) * 60, (p[:, 1] + 1.5) * 80, p[:, 2] * 100]).astype(int)
    np.savetxt(path, np.column_stack([p, rgb]), fmt=["%.4f"] * 3 + ["%d"] * 3, header="x y z r g b",
               comments="//")


@pytest.fixture(scope="module")
def room(tmp_path_factory):
    from lfprobe.core import pipeline

    folder = tmp_path_factory.mktemp("adaptive")
    scan = folder / "room.xyz"
    write_partitioned_room(scan)
    cloud = pipeline.load_scans([str(scan)], [BASE_PROBE], cache_dir="")
    cameras = [camera_dict(HIDDEN_EYE, [2.0, -0.8, 1.0], (48, 32), lens=20.0),
               camera_dict(OPEN_EYE, [-2.0, 0.4, 1.25], (48, 32), lens=20.0)]
    return {"folder": folder, "scan": scan, "cloud": cloud, "cameras": cameras}


def test_greedy_placement_fills_the_hidden_view(room, native):
    out = str(room["folder"] / "placed")
    result = place_adaptively(room["cloud"], room["cameras"], out, base_positions=[BASE_PROBE],
                              resolution=64, target_unknown=0.01, threads=2)
    first, last = result.iterations[0], result.iterations[-1]
    # The base probe sees the open half but not behind the partition.
    assert first["unknown_rate_per_view"][0] > 0.3, first
    assert first["unknown_rate_per_view"][1] <= 0.01, first
    assert [a["view"] for a in result.added] == [0]
    assert result.added[0]["position"] == pytest.approx(HIDDEN_EYE)
    assert last["max_unknown_rate"] <= 0.01 and "every view" in result.stopped_because
    assert last["probes"] == 2 and result.base_probes == 1
    # The merged set is an ordinary probe set: its manifest lists both EXRs, and it traces.
    manifest = read_manifest(out)
    assert manifest["layout"] == "positions" and len(manifest["probes"]) == 2
    assert manifest["bake"]["adaptive"][0]["view"] == 0
    field = native.ProbeField.load(out)
    assert field.probe_count == 2 and field.memory_bytes == last["memory_bytes"]
    image, _ = field.render(json.dumps(room["cameras"][0]), threads=2)
    assert (image["status"] == 1).mean() > 0.95
    # Its known space grew with it: both probes' (an incomplete one would be refused).
    assert manifest["known_space"] == "known_space.bin"
    for camera in room["cameras"]:
        lazy = native.ProbeField.load(out, lazy=True)
        text = json.dumps(camera)
        stopped, _ = lazy.render(text, threads=2)
        asked_on, _ = lazy.render(text, threads=2, stop_where_no_probe_can_answer=False)
        assert all((stopped[k] == asked_on[k]).all() for k in ("rgba", "status", "probe"))


def test_budget_stops_before_the_probe_that_does_not_fit(room):
    def run(name, budget):
        return place_adaptively(room["cloud"], room["cameras"], str(room["folder"] / name),
                                base_positions=[BASE_PROBE], resolution=64, target_unknown=0.01,
                                budget_bytes=budget, threads=2)

    free = run("unbounded", None)
    base, added = free.iterations[0]["memory_bytes"], free.added[0]["memory_bytes"]
    assert added > coarse_level_bytes(64)  # the maps and their coarse levels
    tight = run("budget", base + added / 2)
    assert tight.added == [] and "budget" in tight.stopped_because
    assert tight.iterations[-1]["max_unknown_rate"] > 0.3
    assert tight.memory_bytes == base
    exact = run("budget_exact", base + added)  # a probe that just fits is added
    assert len(exact.added) == 1 and exact.memory_bytes == base + added


def test_no_base_starts_from_the_worst_view(room):
    result = place_adaptively(room["cloud"], room["cameras"], str(room["folder"] / "empty"),
                              resolution=64, target_unknown=0.01, threads=2)
    assert result.iterations[0]["probes"] == 0 and result.iterations[0]["max_unknown_rate"] == 1.0
    assert len(result.added) == 2
    assert result.iterations[-1]["max_unknown_rate"] <= 0.01


def test_place_views_cli(room):
    cams = []
    for i, camera in enumerate(room["cameras"]):
        path = room["folder"] / f"cam_{i}.json"
        write_camera(str(path), camera)
        cams.append(path)
    probes = room["folder"] / "cli_probes"
    plan = room["folder"] / "adaptive.json"
    result = run_cli("place", "--scan", room["scan"], "--scanner", *BASE_PROBE, "--probe", *BASE_PROBE,
                     "--views", *cams, "--target-unknown", 0.01, "--res", 64, "--out-probes", probes,
                     "--out", plan, "--no-cache", "--quiet", check=True)
    assert "added 1 probe" in result.stdout, result.stdout
    data = json.loads(plan.read_text())
    assert data["added"][0]["position"] == pytest.approx(HIDDEN_EYE)
    assert len(read_manifest(str(probes))["probes"]) == 2
    # Compact storage: every probe baked on the way records it, so the budget counts 7 bytes a texel.
    compact = room["folder"] / "cli_compact"
    run_cli("place", "--scan", room["scan"], "--scanner", *BASE_PROBE, "--probe", *BASE_PROBE,
            "--views", *cams, "--target-unknown", 0.01, "--res", 64, "--out-probes", compact,
            "--storage", "compact", "--no-cache", "--quiet", check=True)
    manifest = read_manifest(str(compact))
    assert manifest["storage"]["radiance"] == "srgb8" and len(manifest["probes"]) == 2
    assert all(p["memory_bytes"] == 64 * 64 * 7 for p in manifest["probes"])
    # Errors the user can cause name what is wrong.
    bad = run_cli("place", "--scan", room["scan"], "--probe", *BASE_PROBE, "--views", room["folder"] / "nope.json",
                  "--out-probes", probes)
    assert bad.returncode == 2 and "nope.json" in bad.stderr and "Traceback" not in bad.stderr
    bad = run_cli("place", "--scan", room["scan"], "--probe", *BASE_PROBE, "--views", *cams)
    assert bad.returncode == 2 and "--out-probes" in bad.stderr
    bad = run_cli("place", "--scan", room["scan"], "--probe", *BASE_PROBE, "--views", *cams,
                  "--out-probes", probes, "--budget-mib", -1)
    assert bad.returncode == 2 and "--budget-mib" in bad.stderr


def test_planned_probes_take_the_resolution_the_data_supports(room):
    # 4 cm pitch seen from 0.4–4 m: the plan picks a resolution below the 256² cap.
    result = place_adaptively(room["cloud"], room["cameras"], str(room["folder"] / "planned"),
                              base_positions=[BASE_PROBE],
                              plan={"min_resolution": 16, "max_resolution": 256, "samples_per_spacing": 1.0},
                              target_unknown=0.01, threads=2)
    assert [a["view"] for a in result.added] == [0]
    assert 16 <= result.added[0]["resolution"] < 256
    assert result.iterations[-1]["max_unknown_rate"] <= 0.01
    manifest = read_manifest(str(room["folder"] / "planned"))
    assert manifest["bake"]["adaptive"][0]["bake"][0]["resolution"] == result.added[0]["resolution"]
