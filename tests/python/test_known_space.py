"""A partial scan's probes carry their known space, and a render that uses it to stop asking
probes that cannot answer gives the image of asking every probe on (docs/DESIGN.md §4 "Rays that
no probe can answer"): the lab room from one station over a 90° window of azimuth, the scene's
grid at low resolution, its four views."""

import json
import os

import numpy as np

from lfprobe.core.camera_json import camera_dict

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
LAB_SCENE = os.path.join(ROOT, "blend", "lab_room", "lab_room.scene.json")


def _partial_scan_probes(native, tmp_path):
    """(the scene, the probe folder): the lab room scanned from its first station over a 90°
    window of azimuth at 1°, baked into the scene's grid at 128²."""
    with open(LAB_SCENE, encoding="utf-8") as f:
        scene = json.load(f)
    mesh = os.path.join(os.path.dirname(LAB_SCENE), scene["mesh"])
    xyz = str(tmp_path / "station.xyz")
    native.start_simulate_scan(mesh, xyz, [float(v) for v in scene["scanners"][0]], step_deg=1.0,
                               noise_mm=scene["scan"]["noise_mm"],
                               vertical_fov=scene["scan"]["vertical_fov"], horizontal_fov=90.0,
                               horizontal_start=45.0).run()
    cloud = native.load_scans([xyz], cache_dir="")
    folder = str(tmp_path / "probes")
    native.bake_probe_set(cloud, folder, resolution=128, grid_min=scene["grid"]["min"],
                          grid_max=scene["grid"]["max"], counts=scene["grid"]["counts"])
    return scene, folder


def test_a_partial_scan_renders_the_same_image_asking_fewer_probes(native, tmp_path):
    scene, folder = _partial_scan_probes(native, tmp_path)
    with open(os.path.join(folder, "manifest.json"), encoding="utf-8") as f:
        assert json.load(f)["known_space"] == "known_space.bin"
    assert os.path.isfile(os.path.join(folder, "known_space.bin"))
    assert not [name for name in os.listdir(folder) if name.endswith(".known")]

    field = native.ProbeField.load(folder, lazy=True)
    fewer = 0
    for view in scene["views"]:
        text = json.dumps(camera_dict(view["position"], view["look_at"], (160, 100),
                                      lens=view["lens"]))
        image, stats = field.render(text, threads=2)
        asked_on, stats_on = field.render(text, threads=2, stop_where_no_probe_can_answer=False)
        for channel in ("rgba", "status", "depth", "normal", "probe"):
            assert np.array_equal(image[channel], asked_on[channel], equal_nan=True), \
                (view["name"], channel)
        assert stats["mean_probes"] <= stats_on["mean_probes"], view["name"]
        fewer += stats["mean_probes"] < 0.8 * stats_on["mean_probes"]
    assert fewer >= 1  # a 90° sweep leaves views whose rays mostly no probe can answer


def test_the_hole_fill_colours_narrow_holes_keeps_every_status_and_leaves_the_unscanned_side_black(native, tmp_path):
    """The same partial scan through `render --hole-fill-px`: UNKNOWN pixels keep their status
    with the fill on or off, pixels whose samples all HIT are untouched, narrow holes get a
    colour, and the unscanned side (far wider than 5 % of the view) stays black."""
    from conftest import run_cli
    from lfprobe.core.image_files import read_any_image

    scene, folder = _partial_scan_probes(native, tmp_path)
    filled_any = left_any = 0
    for view in scene["views"]:
        camera = str(tmp_path / f"{view['name']}.json")
        with open(camera, "w", encoding="utf-8") as f:
            json.dump(camera_dict(view["position"], view["look_at"], (160, 100), lens=view["lens"]), f)
        images = {}
        for label, extra in (("off", ["--hole-fill-px", "0"]), ("on", []), ("first", ["--keep-inferred-hits"])):
            out = str(tmp_path / f"{view['name']}_{label}.exr")
            result = run_cli("render", "--probes", folder, "--camera", camera, "--out", out, "--spp", "4",
                             "--json", *extra, check=True)
            images[label] = (read_any_image(out), json.loads(result.stdout))
        (off, stats_off), (on, stats_on) = images["off"], images["on"]
        # The first-hit rule changes which probe answers a guessed texel, never whether a pixel
        # is UNKNOWN here: a guess answers where no probe measured the point either way.
        assert np.array_equal(images["first"][0]["status"] == 2, on["status"] == 2), view["name"]
        assert np.array_equal(off["status"], on["status"]) and stats_off["holes_filled"] == 0
        whole = off["rgba"][..., 3] == 1.0
        assert np.array_equal(off["rgba"][whole], on["rgba"][whole]), view["name"]
        changed = np.any(off["rgba"] != on["rgba"], axis=-1)
        assert changed.sum() >= stats_on["holes_filled"], view["name"]
        no_hit = off["rgba"][..., 3] == 0.0
        still_black = no_hit & ~changed
        assert still_black.sum() == stats_on["holes_left"], view["name"]
        filled_any += stats_on["holes_filled"]
        left_any += stats_on["holes_left"]
    assert filled_any > 0 and left_any > 0, (filled_any, left_any)
