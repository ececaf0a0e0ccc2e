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


def test_a_partial_scan_renders_the_same_image_asking_fewer_probes(native, tmp_path):
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
