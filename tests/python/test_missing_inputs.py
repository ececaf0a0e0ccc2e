"""Issue 22, item 13: every input file the command line reads exits 2 when it is missing (or is
not a regular file), like every other bad input, and the message names the file. Each input
has its own test."""

import json
import os

import pytest

from conftest import run_cli


def _camera(path):
    path.write_text(json.dumps({"type": "PERSP", "resolution": [8, 6], "lens": 20.0,
                                "sensor_width": 36.0,
                                "matrix_world": [[1, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0.5],
                                                 [0, 0, 0, 1]]}))
    return path


def _triangle_obj(path, mtl_line=""):
    path.write_text(f"{mtl_line}\nv 0 2 0\nv 1 2 0\nv 0 2 1\nusemtl m\nf 1 2 3\n")
    return path


def _assert_bad_input(result, named):
    assert result.returncode == 2, (result.returncode, result.stderr)
    assert str(named) in result.stderr, result.stderr
    assert "Traceback" not in result.stderr


def test_a_missing_scan_exits_2(tmp_path):
    missing = tmp_path / "nowhere.xyz"
    _assert_bad_input(run_cli("bake", "--scan", missing, "--probe", 0, 0, 0, "--out", tmp_path / "out",
                              "--quiet"), missing)


def test_a_missing_mesh_exits_2(tmp_path):
    missing = tmp_path / "nowhere.obj"
    _assert_bad_input(run_cli("gt", "--mesh", missing, "--camera", _camera(tmp_path / "cam.json"),
                              "--out", tmp_path / "gt.exr"), missing)


def test_a_missing_material_library_exits_2(tmp_path):
    obj = _triangle_obj(tmp_path / "tri.obj", "mtllib nowhere.mtl")
    _assert_bad_input(run_cli("gt", "--mesh", obj, "--camera", _camera(tmp_path / "cam.json"),
                              "--out", tmp_path / "gt.exr"), "nowhere.mtl")


def test_a_missing_texture_exits_2(tmp_path):
    (tmp_path / "tri.mtl").write_text("newmtl m\nKd 1 1 1\nmap_Kd nowhere.png\n")
    obj = _triangle_obj(tmp_path / "tri.obj", "mtllib tri.mtl")
    _assert_bad_input(run_cli("gt", "--mesh", obj, "--camera", _camera(tmp_path / "cam.json"),
                              "--out", tmp_path / "gt.exr"), "nowhere.png")


@pytest.fixture
def baked_set(native, tmp_path):
    from test_native_api import box_cloud

    folder = tmp_path / "set"
    native.bake_probe_set(box_cloud(native), str(folder), resolution=16, positions=[[0.0, 0.0, 1.25]])
    return folder


def test_a_missing_camera_exits_2(baked_set, tmp_path):
    missing = tmp_path / "nowhere.json"
    _assert_bad_input(run_cli("render", "--probes", baked_set, "--camera", missing,
                              "--out", tmp_path / "view.exr"), missing)


def test_a_camera_that_is_a_folder_exits_2(baked_set, tmp_path):
    _assert_bad_input(run_cli("render", "--probes", baked_set, "--camera", tmp_path,
                              "--out", tmp_path / "view.exr"), tmp_path)


def test_a_missing_probe_file_exits_2(baked_set, tmp_path):
    probe = next(p for p in os.listdir(baked_set) if p.endswith(".exr"))
    os.remove(baked_set / probe)
    _assert_bad_input(run_cli("render", "--probes", baked_set, "--camera", _camera(tmp_path / "cam.json"),
                              "--out", tmp_path / "view.exr"), probe)


def test_a_missing_probe_set_exits_2(tmp_path):
    _assert_bad_input(run_cli("render", "--probes", tmp_path / "no_set", "--camera",
                              _camera(tmp_path / "cam.json"), "--out", tmp_path / "view.exr"),
                      tmp_path / "no_set")


def test_missing_files_are_file_not_found_errors_in_python(native, tmp_path):
    """The native error for a missing input is both FileNotFoundError and NativeIOError."""
    with pytest.raises(FileNotFoundError, match="nowhere.xyz"):
        native.load_scans([str(tmp_path / "nowhere.xyz")], cache_dir="")
    with pytest.raises(native.NativeIOError):
        native.ProbeField.load(str(tmp_path / "no_set"))
