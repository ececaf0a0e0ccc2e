"""`lfprobe place` and `lfprobe bake --auto`: resolution from the data, probes moved off walls
where that lets them see more, the plan in the manifest, and the planned set traced like any
other."""

import json

import pytest

from conftest import run_cli, write_box_room_xyz


@pytest.fixture(scope="module")
def room(tmp_path_factory):
    folder = tmp_path_factory.mktemp("place")
    scan = folder / "room.xyz"
    write_box_room_xyz(scan, 0.04)
    return {"scan": scan, "folder": folder}


def test_place_moves_a_probe_off_the_wall_and_sizes_by_density(room):
    plan_path = room["folder"] / "plan.json"
    # Probe 1 sits 1 mm from the wall x = 2; probe 0 stands in the open.
    result = run_cli("place", "--scan", room["scan"], "--scanner", 0, 0, 1.25,
                     "--probe", 0, 0, 1.25, 1.999, 0, 1.25, "--no-cache", "--out", plan_path,
                     "--quiet", check=True)
    assert "too_close→useful (moved" in result.stdout
    plan = json.loads(plan_path.read_text())
    open_probe, wall_probe = plan["probes"]
    assert open_probe["class"] == "useful" and not open_probe["moved"]
    assert wall_probe["found"] == "too_close" and wall_probe["moved"]
    assert wall_probe["position"][0] < 1.999
    # 4 cm pitch seen from ~1.5–2 m: N ≈ 3.54 · r / s ≈ 130–180 at one texel per point, and
    # 2.5 times that at the default 2.5 texels per point spacing: the 384 or 512 step.
    assert 100 < open_probe["data_resolution"] < 260
    assert open_probe["resolution"] in (256, 384, 512)
    one_per_point = json.loads(run_cli("place", "--scan", room["scan"], "--scanner", 0, 0, 1.25,
                                       "--probe", 0, 0, 1.25, "--no-cache", "--samples-per-spacing", 1,
                                       "--json", "--quiet", check=True).stdout)
    assert one_per_point["probes"][0]["resolution"] in (96, 128, 192)
    # Capping the texel footprint at 10 cm lowers it.
    capped = json.loads(run_cli("place", "--scan", room["scan"], "--scanner", 0, 0, 1.25,
                                "--probe", 0, 0, 1.25, "--no-cache", "--footprint", 0.1,
                                "--min-res", 16, "--json", "--quiet", check=True).stdout)
    assert capped["probes"][0]["resolution"] < open_probe["resolution"]


def test_bake_auto_writes_the_plan_and_renders(room, native):
    probes = room["folder"] / "auto"
    run_cli("bake", "--scan", room["scan"], "--scanner", 0, 0, 1.25, "--grid-min", -1, -0.5, 1.2,
            "--grid-max", 1.999, 0.5, 1.2, "--counts", 2, 2, 1, "--auto", "--no-cache",
            "--out", probes, "--quiet", check=True)
    manifest = json.loads((probes / "manifest.json").read_text())
    plan = manifest["bake"]["plan"]
    assert len(plan) == 4 == len(manifest["probes"])
    for record, planned in zip(manifest["probes"], plan):
        assert record["resolution"] == planned["resolution"]
        assert record["position"] == pytest.approx(planned["position"])
    # The two probes at x = 1.999 are too close to the wall; a move would not let them see more
    # (the wall is scanned right up to them), so they are kept where they are, not dropped.
    wall = [p for p in plan if p["original"][0] > 1.99]
    assert len(wall) == 2
    for p in wall:
        assert p["found"] == "too_close" and not p["dropped"]
        assert p["moved"] or p["class"] == "too_close"
        assert p["moved"] or p["classification"]["unknown"] < 0.01
    # --auto models only what the data carries in memory too: compact storage unless told otherwise
    assert manifest["storage"] == {"radiance": "srgb8", "normal": "oct16", "distance_step": 0.001,
                                   "confidence": False}
    camera = room["folder"] / "cam.json"
    run_cli("camera", "--position", 0, 0, 1.25, "--look-at", -2, 0, 1.25, "--res", 48, 32,
            "--out", camera, check=True)
    out = room["folder"] / "auto.exr"
    run_cli("render", "--probes", probes, "--camera", camera, "--out", out, "--quiet", check=True)
    image = native.read_image(str(out))
    assert (image["status"] == 1).mean() > 0.95


def test_bake_auto_refuses_meshes(room, tmp_path):
    result = run_cli("bake", "--mesh", "x.obj", "--probe", 0, 0, 1, "--auto",
                     "--out", tmp_path / "p")
    assert result.returncode == 2 and "--auto" in result.stderr
