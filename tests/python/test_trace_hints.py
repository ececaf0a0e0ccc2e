"""Issue 18, item 8: a render that comes out all UNKNOWN says why it probably did."""

import json

from conftest import run_cli
from lfprobe.core.trace_hints import camera_of, unknown_hint


def _manifest(tmp_path):
    (tmp_path / "manifest.json").write_text(json.dumps({
        "world_offset": [100.0, 0.0, 0.0],
        "grid": {"origin": [0.0, 0.0, 0.0], "spacing": [1.0, 1.0, 1.0], "counts": [3, 3, 2]}}))
    return str(tmp_path)


def _camera_at(x, y, z):
    return {"matrix_world": [[1, 0, 0, x], [0, 1, 0, y], [0, 0, 1, z], [0, 0, 0, 1]]}


def test_hints_name_the_likely_cause(tmp_path):
    folder = _manifest(tmp_path)
    all_unknown = {"hits": 0, "misses": 0, "unknown": 100}
    outside = unknown_hint(all_unknown, _camera_at(0.0, 1.0, 0.5), folder)  # the grid is at x ≥ 100
    assert "outside the probe grid" in outside and "(100.00, 0.00, 0.00) to (102.00, 2.00, 1.00)" in outside
    inside = unknown_hint(all_unknown, _camera_at(101.0, 1.0, 0.5), folder)
    assert "never saw what this camera looks at" in inside
    assert unknown_hint({"hits": 2, "misses": 0, "unknown": 98}, _camera_at(0, 0, 0), folder) is None
    assert unknown_hint(all_unknown, {}, str(tmp_path / "none")).startswith("hint: 100.0%")
    assert camera_of(str(tmp_path / "missing.json")) == {}


def test_render_from_outside_the_grid_prints_the_hint(native, tmp_path):
    from test_native_api import box_cloud

    folder = tmp_path / "set"
    native.bake_probe_set(box_cloud(native), str(folder), resolution=16, grid_min=[-0.5, -0.5, 1.0],
                          grid_max=[0.5, 0.5, 1.5], counts=[2, 2, 2])
    camera = tmp_path / "cam.json"
    run_cli("camera", "--position", 40, 40, 40, "--look-at", 0, 0, 1, "--res", 8, 6, "--out", camera,
            check=True)
    result = run_cli("render", "--probes", folder, "--camera", camera, "--out", tmp_path / "v.exr",
                     "--quiet", check=True)
    assert "stands outside the probe grid" in result.stdout, result.stdout
