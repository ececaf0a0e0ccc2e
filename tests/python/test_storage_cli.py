"""Storage sized to the data, end to end: bake --storage, store, render --storage, info, and
ProbeField.load(storage=...) on a small generated room."""

import json

import numpy as np
import pytest

from conftest import run_cli, write_box_room_xyz


@pytest.fixture(scope="module")
def room(tmp_path_factory):
    folder = tmp_path_factory.mktemp("storage_room")
    scan = folder / "room.xyz"
    write_box_room_xyz(scan, 0.02)
    camera = folder / "cam.json"
    run_cli("camera", "--position", 0.3, 0.2, 1.1, "--look-at", 2, -1, 1.0, "--res", 64, 48,
            "--lens", 20, "--out", camera, check=True)
    return {"scan": scan, "camera": camera, "folder": folder}


def _bake(room, name, *extra):
    probes = room["folder"] / name
    result = run_cli("bake", "--scan", room["scan"], "--scanner", 0, 0, 1.25, "--grid-min", -1, -0.5, 1.2,
                     "--grid-max", 1, 0.5, 1.2, "--counts", 2, 2, 1, "--res", 64, "--out", probes,
                     "--no-cache", "--quiet", *extra, check=True)
    return probes, result


def _render(native, room, probes, name, *extra):
    out = room["folder"] / name
    run_cli("render", "--probes", probes, "--camera", room["camera"], "--out", out, "--quiet", *extra,
            check=True)
    return native.read_image(str(out))


def test_bake_compact_records_the_storage_and_renders_like_full(native, room):
    full, _ = _bake(room, "full")
    compact, result = _bake(room, "compact", "--storage", "compact", "--distance-step", 0.002)
    assert "storage: srgb8 radiance, 16-bit distance in 2 mm steps" in result.stdout
    manifest = json.loads((compact / "manifest.json").read_text())
    assert manifest["storage"] == {"radiance": "srgb8", "normal": "oct16", "distance_step": 0.002,
                                   "confidence": False}
    assert all(p["memory_bytes"] == 64 * 64 * 7 for p in manifest["probes"])
    assert json.loads((full / "manifest.json").read_text())["storage"]["radiance"] == "half"
    # The EXR files are the same: storage is how they load, not what they hold.
    assert (full / "probe_00000.exr").read_bytes() == (compact / "probe_00000.exr").read_bytes()

    a = _render(native, room, full, "full.exr")
    b = _render(native, room, compact, "compact.exr")
    assert json.loads(b["metadata"])["storage"]["distance_step"] == 0.002
    assert json.loads(a["metadata"])["memory_bytes"] > 2 * json.loads(b["metadata"])["memory_bytes"]
    hits = (a["status"] == 1) & (b["status"] == 1)
    assert (a["status"] == b["status"]).mean() > 0.99
    assert hits.mean() > 0.9
    assert np.median(np.abs(a["depth"][hits] - b["depth"][hits])) <= 0.001 + 1e-6
    # Colours within 8-bit sRGB on nearly every pixel (another texel at a silhouette otherwise).
    close = np.abs(a["rgba"][..., :3] - b["rgba"][..., :3]).max(axis=-1) < 0.0045
    assert close[hits].mean() > 0.98

    # render --storage overrides the manifest either way; the full load of the compact set is
    # the full set's image bit for bit.
    c = _render(native, room, compact, "forced_full.exr", "--storage", "full")
    for key in ("rgba", "depth", "status", "probe", "steps"):
        assert np.array_equal(a[key], c[key], equal_nan=True), key


def test_store_switches_a_baked_set_and_info_reports_it(native, room):
    probes, _ = _bake(room, "switched")
    before = json.loads(run_cli("info", probes, "--json", check=True).stdout)
    result = run_cli("store", probes, "compact", check=True)
    assert "loads as srgb8 radiance" in result.stdout
    after = json.loads(run_cli("info", probes, "--json", check=True).stdout)
    assert after["storage"]["distance_step"] == 0.001
    # 18 → 7 bytes a texel on the fine maps, float32 → 16-bit coarse levels.
    from lfprobe.core.probe_set import coarse_level_bytes
    assert before["memory_bytes"] - after["memory_bytes"] == 4 * (64 * 64 * 11 + coarse_level_bytes(64) // 2)
    field = native.ProbeField.load(str(probes))
    assert field.storage["bytes_per_texel"] == 7
    assert native.ProbeField.load(str(probes), storage="full").storage["bytes_per_texel"] == 18
    assert "storage in memory: srgb8" in run_cli("info", probes, check=True).stdout
    run_cli("store", probes, "full", check=True)
    assert native.ProbeField.load(str(probes)).memory_bytes == \
        native.ProbeField.load(str(probes), storage="full").memory_bytes


def test_bad_storage_is_a_clear_error(native, room):
    probes, _ = _bake(room, "bad")
    with pytest.raises(ValueError, match="storage"):
        native.ProbeField.load(str(probes), storage="tiny")
    with pytest.raises(ValueError, match="distance step"):
        native.ProbeField.load(str(probes), storage="compact", distance_step=-1.0)
    with pytest.raises(ValueError, match="storage.radiance"):
        native.ProbeField.load(str(probes), storage={"radiance": "rgb4"})
    manifest = json.loads((probes / "manifest.json").read_text())
    manifest["storage"] = {"radiance": "srgb8", "distance_step": "x"}
    (probes / "manifest.json").write_text(json.dumps(manifest))
    result = run_cli("render", "--probes", probes, "--camera", room["camera"], "--out",
                     room["folder"] / "bad.exr", "--quiet")
    assert result.returncode == 2 and "storage" in result.stderr
