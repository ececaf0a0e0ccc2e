"""The hard scene (blend/scenes/hard_scene.py) at a small size, end to end: generate it, simulate
two scans at a coarse step, bake a probe grid at low resolution, render views with the probes
and with Embree, and check the figures where probes are known to fail: the georeferenced
offset, NaN colours, HIT/MISS/UNKNOWN against ground truth, blinds leaking the facade behind
them, and a probe 1.5 cm from a pillar's face.

Bounds: each figure was measured on this configuration (see the report of issue 6) and the
bound set with a margin; the comments give the measured value."""

import json
import os
import sys

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, ROOT)

from blend.scenes import hard_scene  # noqa: E402
from blend.scenes.output import write_scene  # noqa: E402
from blend.scenes.scene_file import load_scene  # noqa: E402
from lfprobe.core import camera_json, metrics  # noqa: E402

STEP_DEG = 0.5  # scan step: 720 × 300 rays per scan
PROBE_RES = 128
VIEW_RES = (160, 120)
THREADS = 2
OFFSET = np.array(hard_scene.WORLD_OFFSET)


def local(p):
    return np.asarray(p, float) - OFFSET


def pixel_rays(camera: dict):
    """World ray directions (h, w, 3) through the pixel centres of a perspective camera JSON
    (Blender's model: sensor fit AUTO on the larger side, looking down local −Z, +Y up)."""
    w, h = camera["resolution"]
    size = max(w, h)
    f = camera["lens"] / camera["sensor_width"] * size
    xs = (np.arange(w) + 0.5 - w / 2) / f
    ys = -(np.arange(h) + 0.5 - h / 2) / f
    d = np.stack(np.broadcast_arrays(xs[None, :], ys[:, None], -np.ones((h, w))), axis=-1)
    m = np.asarray(camera["matrix_world"])[:3, :3]
    d = d @ m.T
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


@pytest.fixture(scope="module")
def case(native, tmp_path_factory):
    """Scene files, scans, probe set, and per view: camera, ground truth, probe render."""
    tmp = tmp_path_factory.mktemp("hard_scene")
    written = write_scene("hard_scene", str(tmp))
    scene = load_scene(written["scene"])
    mesh = native.load_mesh(scene["mesh_path"])
    scans = []
    for i, at in enumerate(scene["scanners"][:2]):  # the two scanners in the hall
        path = str(tmp / f"scan_{i}.xyz")
        native.start_simulate_scan(mesh, path, at, step_deg=STEP_DEG, noise_mm=scene["scan"]["noise_mm"],
                                   vertical_fov=scene["scan"]["vertical_fov"], seed=i + 1).run()
        scans.append(path)
    cloud = native.load_scans(scans, cache_dir="")
    probes = str(tmp / "probes")
    grid = scene["grid"]
    summary = native.bake_probe_set(cloud, probes, resolution=PROBE_RES, grid_min=grid["min"],
                                    grid_max=grid["max"], counts=grid["counts"])
    field = native.ProbeField.load(probes)
    views = {}
    for view in scene["views"]:
        if view["name"] == "corridor":
            continue  # outside what the hall scanners saw: not a figure to bound here
        camera = camera_json.camera_dict(view["position"], view["look_at"], VIEW_RES, view["lens"])
        cam_path = str(tmp / f"{view['name']}.json")
        camera_json.write_camera(cam_path, camera)
        gt_path = str(tmp / f"{view['name']}_gt.exr")
        native.start_ground_truth(mesh, cam_path, gt_path, threads=THREADS).run()
        image, _ = field.render(cam_path, mode="auto", threads=THREADS)
        views[view["name"]] = {"camera": camera, "gt": native.read_image(gt_path), "probe": image}
    with open(os.path.join(probes, "manifest.json"), encoding="utf-8") as stream:
        manifest = json.load(stream)
    return {"scene": scene, "manifest": manifest, "summary": summary, "views": views, "probes": probes,
            "native": native}


def test_world_offset_survives_to_the_manifest(case):
    scene, manifest = case["scene"], case["manifest"]
    assert scene["world_offset"] == list(hard_scene.WORLD_OFFSET)
    offset = np.array(manifest["world_offset"], float)
    # The offset is chosen by the native rule (cloud bounds centre, whole metres): it must be the
    # georeferenced origin's neighbourhood, not zero.
    assert np.all(np.abs(offset - OFFSET) < 20.0), offset
    grid = manifest["grid"]
    world_origin = offset + np.array(grid["origin"], float)
    assert np.allclose(world_origin, scene["grid"]["min"], atol=1e-3), (world_origin, scene["grid"]["min"])
    world_last = world_origin + np.array(grid["spacing"], float) * (np.array(grid["counts"]) - 1)
    assert np.allclose(world_last, scene["grid"]["max"], atol=1e-3)
    # Local positions are small numbers: float32 keeps sub-millimetre detail there.
    for probe in manifest["probes"]:
        assert np.all(np.abs(np.array(probe["position"], float)) < 50.0), probe["position"]


def test_rendered_colours_and_depths_are_finite(case):
    for name, v in case["views"].items():
        image = v["probe"]
        assert np.isfinite(image["rgba"]).all(), f"{name}: NaN or inf in the colour"
        hit = image["status"] == 1
        assert hit.any(), f"{name}: no probe hit at all"
        assert np.isfinite(image["depth"][hit]).all() and (image["depth"][hit] > 0).all(), name


# Measured with this configuration (scan step 0.5°, 128² probes, 160×120 views): hole rate
# 0.0002 / 0.0001 (blinds), 0.0036 (floor), 0.0041 (pillar); no false misses; depth AbsRel
# 0.170 / 0.135 (the blinds hide the facade, see below), 0.041 (floor), 0.026 (pillar).
HOLE_RATE_MAX = 0.02
FALSE_MISS_RATE_MAX = 0.005
DEPTH_ABSREL_MAX = {"blinds_at_probe": 0.30, "blinds_between_probes": 0.30, "glancing_floor": 0.08,
                    "beside_pillar": 0.06}


def test_status_and_depth_against_ground_truth(case):
    for name, absrel_max in DEPTH_ABSREL_MAX.items():
        v = case["views"][name]
        r = metrics.compare_images(v["gt"], v["probe"])
        summary = {k: r[k] for k in ("hole_rate", "false_miss_rate", "false_hit_rate", "depth_absrel")}
        assert r["hole_rate"] <= HOLE_RATE_MAX, (name, summary)
        assert r["false_miss_rate"] <= FALSE_MISS_RATE_MAX, (name, summary)
        assert r["depth_absrel"] is not None and r["depth_absrel"] <= absrel_max, (name, summary)


def _points(view: dict, which: str) -> np.ndarray:
    """Local positions of the hit points of the ground truth ('gt') or the probe render
    ('probe'), NaN where it did not hit."""
    cam = view["camera"]
    origin = local(np.asarray(cam["matrix_world"])[:3, 3])
    image = view[which]
    depth = np.where(image["status"] == 1, image["depth"], np.nan)
    return origin + pixel_rays(cam) * depth[..., None]


def test_blinds_do_not_leak(case):
    """Where ground truth sees a slat, the probes must not see through it (the facade, the
    sky). The converse does not hold at this size: the 3 cm gaps between slats are closed by
    the bake's hole filling, so where ground truth sees the sky through the gaps (measured:
    every such pixel is a false hit) the probes answer with the near surface, the blinds,
    never with something behind them (measured 97 % / 93 % on the blinds' plane)."""
    w = hard_scene.WINDOW
    for name in ("blinds_at_probe", "blinds_between_probes"):
        v = case["views"][name]
        p = _points(v, "gt")
        in_window = (p[..., 1] > w["y0"]) & (p[..., 1] < w["y1"]) & (p[..., 2] > w["z0"]) & (p[..., 2] < w["z1"])
        slat = in_window & (np.abs(p[..., 0] - hard_scene.BLINDS["x"]) < 0.03)
        gt_depth, depth, status = v["gt"]["depth"], v["probe"]["depth"], v["probe"]["status"]
        leak = slat & ((status == 0) | ((status == 1) & (depth > gt_depth + 0.25)))
        assert slat.sum() > 500, f"{name}: the view must show the blinds"
        assert leak.sum() / slat.sum() <= 0.005, f"{name}: {leak.sum()} of {slat.sum()} slat pixels leak"  # 0.0001
        sky = v["gt"]["status"] == 0
        assert sky.sum() > 500, f"{name}: the view must show the sky through the blinds"
        q = _points(v, "probe")
        on_blinds = sky & (np.abs(q[..., 0] - hard_scene.BLINDS["x"]) < 0.05)
        assert on_blinds.sum() / sky.sum() >= 0.85, f"{name}: {on_blinds.sum()} of {sky.sum()} sky pixels"


def test_probe_beside_the_pillar(case):
    """The probe 1.5 cm from the pillar's face holds that face at 1.5 cm (no hole, nothing from
    behind it), and a view next to it has few hits on a wrong surface."""
    native = case["native"]
    target = local(case["scene"]["probes_near"]["pillar_probe"])
    offset = np.array(case["manifest"]["world_offset"], float)

    def distance_to_target(probe):
        return np.linalg.norm(offset + np.array(probe["position"]) - OFFSET - target)

    probe = min(case["manifest"]["probes"], key=distance_to_target)
    assert distance_to_target(probe) < 1e-3
    maps = native.read_probe(os.path.join(case["probes"], probe["file"]))
    n = maps["resolution"]
    uv = (np.stack(np.meshgrid(np.arange(n), np.arange(n)), axis=-1).reshape(-1, 2) + 0.5) / n
    dirs = native.oct_decode(uv.astype(np.float32)).reshape(n, n, 3)
    # Texels within 45° of −x look at the pillar's face: exact distance gap / cos(angle).
    cos = -dirs[..., 0]
    cone = cos > np.cos(np.radians(45))
    expected = hard_scene.PILLAR_GAP / np.maximum(cos, 1e-6)
    dist = maps["distance"]
    right = cone & np.isfinite(dist) & (np.abs(dist - expected) < 0.01)
    assert right.sum() / cone.sum() >= 0.95, f"{right.sum()} of {cone.sum()} texels hold the face"  # 1.0
    v = case["views"]["beside_pillar"]
    both = (v["gt"]["status"] == 1) & (v["probe"]["status"] == 1)
    gt_depth, depth = v["gt"]["depth"], v["probe"]["depth"]
    wrong = both & (np.abs(depth - gt_depth) > np.maximum(0.05, 0.05 * gt_depth))
    assert wrong.sum() / both.sum() <= 0.15, f"{wrong.sum()} of {both.sum()} hits on a wrong surface"  # 0.078


def test_scene_files_are_deterministic_and_checked(tmp_path):
    """The generator writes the same bytes as the committed blend/hard_scene/ (which
    blend/hard_scene.blend references); a broken scene file is refused, naming its key."""
    written = write_scene("hard_scene", str(tmp_path))
    committed = os.path.join(ROOT, "blend", "hard_scene")
    for rel in ("hard_scene.obj", "hard_scene.mtl", "hard_scene.scene.json", "textures/bricks.png",
                "textures/slat.png"):
        with open(tmp_path / "hard_scene" / rel, "rb") as fresh, open(os.path.join(committed, rel), "rb") as old:
            assert fresh.read() == old.read(), f"blend/hard_scene/{rel} is stale: run python3 -m blend.scenes"
    assert written["triangles"] > 500
    with open(written["scene"], encoding="utf-8") as stream:
        scene = json.load(stream)
    del scene["grid"]["counts"]
    broken = tmp_path / "broken.scene.json"
    broken.write_text(json.dumps(scene), encoding="utf-8")
    with pytest.raises(ValueError, match=r"broken\.scene\.json: grid\.counts"):
        load_scene(str(broken))
