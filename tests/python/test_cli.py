"""./lfprobe bake and ./lfprobe info end to end, on the real scans in ../shared/data."""

import json
import os
import signal
import subprocess
import time

import numpy as np
import pytest

from conftest import ROOT, run_cli


def test_bake_and_info_on_the_pump_room_scan(shared_data, tmp_path):
    scan = os.path.join(shared_data, "scans", "pumpA_xyzrgb.xyz")
    out = tmp_path / "pump"
    result = run_cli("bake", "--scan", scan, "--scanner", 0, 0, 0, "--grid-min", -1, -1, -0.5,
                     "--grid-max", 1, 1, -0.5, "--counts", 2, 3, 1, "--res", 64, "--out", out,
                     "--cache", tmp_path / "cache", "--quiet", check=True)
    assert "baked 6 probe(s) at 64²" in result.stdout
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["format"] == "lfprobe-probe-set" and manifest["format_version"] == 1
    assert manifest["layout"] == "grid" and manifest["grid"]["counts"] == [2, 3, 1]
    assert len(manifest["probes"]) == 6
    source = manifest["sources"][0]
    assert source["points"] == 155201 and len(source["sha256"]) == 64
    assert source["scanner"] == [0.0, 0.0, 0.0]
    info = run_cli("info", out, check=True).stdout
    assert "probes: 6" in info and "resolution(s): 64" in info
    as_json = json.loads(run_cli("info", out, "--json", check=True).stdout)
    assert as_json["probe_count"] == 6
    assert as_json["disk_bytes"] > 0 and as_json["memory_bytes_per_probe"] > 64 * 64 * 18
    assert set(as_json["coverage"]) == {"surface", "inferred", "empty", "unknown"}


def test_a_rebake_reads_the_prepared_cloud_and_writes_the_same_probes(shared_data, tmp_path):
    """The cloud's normals, spacing and point hierarchy are cached beside the parsed scan: a
    second bake of the same scan (here at another grid) reads them and bakes what computing
    them gives, byte for byte; a planned bake reads them too; --no-cache writes none."""
    scan = os.path.join(shared_data, "scans", "pumpA_xyzrgb.xyz")
    cache = tmp_path / "cache"

    def bake(out, *extra):
        result = run_cli("bake", "--scan", scan, "--scanner", 0, 0, 0, "--grid-min", -1, -1, -0.5,
                         "--grid-max", 1, 1, -0.5, "--counts", 2, 1, 1, "--res", 32, "--out", out,
                         "--json", *extra, check=True)
        return json.loads(result.stdout)

    first = bake(tmp_path / "a", "--cache", cache)
    assert first["prepared_from_cache"] is False
    assert len(list(cache.glob("prepared-*.lfpprep"))) == 1
    second = bake(tmp_path / "b", "--cache", cache)
    assert second["prepared_from_cache"] is True
    uncached = bake(tmp_path / "c", "--no-cache")
    assert uncached["prepared_from_cache"] is False
    for name in ("probe_00000.exr", "probe_00001.exr"):
        assert (tmp_path / "b" / name).read_bytes() == (tmp_path / "c" / name).read_bytes()
    assert bake(tmp_path / "d", "--cache", cache, "--auto")["prepared_from_cache"] is True
    no_cache = tmp_path / "none"
    bake(tmp_path / "e", "--cache", no_cache, "--no-cache")
    assert not no_cache.exists() or not list(no_cache.glob("prepared-*"))


def test_pump_room_scan_at_its_scanner_covers_every_swept_direction(native, shared_data, tmp_path):
    """Baked at the scanner's own position, the directions the scanner swept have data.

    The scan (one station) covers an irregular window of directions, with no returns in
    between, so "swept" is measured from the scan itself: 1°×1° azimuth/elevation cells that
    hold points, eroded by one cell so the window's ragged edge does not count."""
    cloud = native.load_scans([os.path.join(shared_data, "scans", "pumpA_xyzrgb.xyz")],
                              scanners=[[0, 0, 0]], cache_dir="")
    p = cloud.positions.astype(np.float64)
    elevation = np.degrees(np.arcsin(p[:, 2] / np.linalg.norm(p, axis=1)))
    azimuth = np.degrees(np.arctan2(p[:, 1], p[:, 0]))

    def cell(az, el):
        return (az + 180).astype(int) % 360, np.clip((el + 90).astype(int), 0, 179)

    occupied = np.zeros((360, 180), bool)
    occupied[cell(azimuth, elevation)] = True
    interior = occupied.copy()
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            interior &= np.roll(np.roll(occupied, dx, 0), dy, 1)

    def coverage(res, splat_scale):
        folder = tmp_path / f"p{res}_{splat_scale}"
        native.bake_probe_set(cloud, str(folder), resolution=res, positions=[[0, 0, 0]],
                              splat_scale=splat_scale, hole_fill_texels=4 if splat_scale else 0)
        state = native.read_probe(str(folder / "probe_00000.exr"))["state"].reshape(-1)
        centres = (np.stack(np.meshgrid(np.arange(res), np.arange(res), indexing="xy"), -1) + 0.5) / res
        dirs = native.oct_decode(centres.reshape(-1, 2).astype(np.float32)).astype(np.float64)
        swept = interior[cell(np.degrees(np.arctan2(dirs[:, 1], dirs[:, 0])),
                              np.degrees(np.arcsin(np.clip(dirs[:, 2], -1, 1))))]
        return np.isin(state[swept], [2, 3]).mean(), swept.sum()  # SURFACE or INFERRED

    for res in (256, 1024):
        covered, texels = coverage(res, 0.8)
        print(f"pump room at its scanner, {res}²: {texels} swept texels, coverage {100 * covered:.2f}%")
        assert covered > 0.99
    # Without splats the same scan is a sieve at 1024² (the paper's aliasing).
    bare, _ = coverage(1024, 0.0)
    print(f"  without splats at 1024²: {100 * bare:.2f}%")
    assert bare < 0.9


def test_georeferenced_lidar_keeps_millimetre_precision(native, shared_data):
    path = os.path.join(shared_data, "scans", "autzen_trim_xyzrgb.xyz")
    cloud = native.load_scans([path], cache_dir="")
    offset = np.array(cloud.world_offset)
    assert np.abs(offset).max() > 1e5  # a real offset was chosen
    assert np.abs(cloud.positions).max() < 1e4
    truth = np.loadtxt(path, usecols=(0, 1, 2))
    world = cloud.positions.astype(np.float64) + offset
    error = np.abs(world - truth).max()
    print(f"autzen: offset {offset}, worst error after the offset {error:.2e} units")
    assert error < 1e-3


def test_bad_scan_gives_a_clear_error_and_no_probe_set(tmp_path):
    bad = tmp_path / "bad.xyz"
    bad.write_text("1 2 3 255 0 0\n4 5 six 0 255 0\n")
    out = tmp_path / "out"
    result = run_cli("bake", "--scan", bad, "--probe", 0, 0, 0, "--out", out, "--res", 16, "--no-cache")
    assert result.returncode == 2
    assert "bad.xyz" in result.stderr and ":2" in result.stderr and "six" in result.stderr
    assert not (out / "manifest.json").exists()
    missing = run_cli("bake", "--scan", tmp_path / "nope.xyz", "--probe", 0, 0, 0, "--out", out)
    assert missing.returncode != 0 and "nope.xyz" in missing.stderr
    no_probe = run_cli("bake", "--scan", bad, "--out", out)
    assert no_probe.returncode == 2 and "no probes" in no_probe.stderr
    not_a_set = run_cli("info", tmp_path)
    assert not_a_set.returncode == 2 and "manifest" in not_a_set.stderr


def _wall_scan(path, pitch):
    """A 4 × 4 m wall 3 m along x, sampled every `pitch` metres, as an "x y z r g b" scan."""
    g = np.arange(-2, 2, pitch)
    yy, zz = np.meshgrid(g, g)
    wall = np.column_stack([np.full(yy.size, 3.0), yy.ravel(), zz.ravel() + 1])
    np.savetxt(path, np.column_stack([wall, np.full((yy.size, 3), 128)]), fmt="%.3f")
    return path


@pytest.mark.parametrize("moment", ["staging opened", "writing probes"])
def test_killed_rebake_leaves_the_earlier_set_as_it_was(native, tmp_path, moment):
    """SIGKILL at two moments of a bake over an earlier set (as its staging folder appears; after
    some probes were written): the earlier set is untouched (the new one is staged in
    SET.partial and swapped in only when complete), the staging folder holds only complete probe
    files, and the next bake clears it."""
    scan = _wall_scan(tmp_path / "room.xyz", 0.02)
    out = tmp_path / "set"
    run_cli("bake", "--scan", scan, "--probe", 0, 0, 1, 0.5, 0, 1, "--res", 16, "--out", out,
            "--no-cache", "--quiet", check=True)
    earlier = {p.name: p.read_bytes() for p in out.iterdir()}
    staging = tmp_path / "set.partial"
    probes = [v for i in range(60) for v in (0.01 * i, 0, 1)]
    process = subprocess.Popen(
        [os.path.join(ROOT, "lfprobe"), "bake", "--scan", str(scan), "--probe", *map(str, probes),
         "--res", "512", "--out", str(out), "--no-cache", "--quiet"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.time() + 120
    waited_for = staging if moment == "staging opened" else staging / "probe_00002.exr"
    while not waited_for.exists() and time.time() < deadline:
        time.sleep(0.005)
    process.send_signal(signal.SIGKILL)
    process.wait()
    assert {p.name: p.read_bytes() for p in out.iterdir()} == earlier
    complete = sorted(staging.glob("probe_?????.exr"))
    if moment == "writing probes":
        assert complete, "the bake should have written some probes before the kill"
    for path in complete:
        assert native.read_probe(str(path))["resolution"] == 512
    run_cli("bake", "--scan", scan, "--probe", 0, 0, 1, "--res", 16, "--out", out, "--no-cache",
            "--quiet", check=True)
    assert not staging.exists()
    assert sorted(p.name for p in out.iterdir()) == ["known_space.bin", "manifest.json", "probe_00000.exr"]


@pytest.mark.parametrize("moment", ["staging opened", "writing probes"])
def test_interrupted_rebake_leaves_the_earlier_set_bit_for_bit(native, tmp_path, moment):
    """Ctrl-C (SIGINT) at two moments of a bake over an earlier set, as soon as its staging
    folder exists (the first probe baking) and after some probes were written: exit 130, the
    earlier set as it was, no staging folder or temporary left, and the next bake succeeds."""
    scan = _wall_scan(tmp_path / "room.xyz", 0.01)
    out = tmp_path / "set"
    run_cli("bake", "--scan", scan, "--probe", 0, 0, 1, "--res", 16, "--out", out, "--no-cache",
            "--quiet", check=True)
    earlier = {p.name: p.read_bytes() for p in out.iterdir()}
    staging = tmp_path / "set.partial"
    probes = [v for i in range(60) for v in (0.01 * i, 0, 1)]
    process = subprocess.Popen(
        [os.path.join(ROOT, "lfprobe"), "bake", "--scan", str(scan), "--probe", *map(str, probes),
         "--res", "512", "--out", str(out), "--no-cache", "--quiet"],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 120
    waited_for = staging if moment == "staging opened" else staging / "probe_00002.exr"
    while not waited_for.exists() and time.time() < deadline:
        time.sleep(0.005)
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=120)
    assert process.returncode == 130, stderr
    assert "cancelled" in stderr
    assert {p.name: p.read_bytes() for p in out.iterdir()} == earlier
    assert not staging.exists()
    assert not [p for p in tmp_path.iterdir() if ".tmp." in p.name]
    run_cli("bake", "--scan", scan, "--probe", 0, 0, 1, 0.5, 0, 1, "--res", 16, "--out", out,
            "--no-cache", "--quiet", check=True)
    assert sorted(p.name for p in out.iterdir()) == ["known_space.bin", "manifest.json", "probe_00000.exr",
                                                     "probe_00001.exr"]
