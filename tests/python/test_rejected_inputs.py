"""Issue 22, item 13: inputs the command line used to accept or answer wrongly. Each is refused
with exit 2 and a message naming the input (no traceback), or, where the run can still succeed
(a parse cache that cannot be written), goes on with a warning. One test per listed input."""

import json
import os
import resource
import subprocess
import threading

import pytest

from conftest import ROOT, run_cli, write_box_room_xyz
from test_missing_inputs import _assert_bad_input, _camera


@pytest.fixture
def baked_set(native, tmp_path):
    from test_native_api import box_cloud

    folder = tmp_path / "set"
    native.bake_probe_set(box_cloud(native), str(folder), resolution=16, positions=[[0.0, 0.0, 1.25]])
    return folder


@pytest.mark.parametrize("name, text", [
    ("garbage", "garbage\x01\x02 not an obj\n"),
    ("empty", ""),
    ("comments_only", "# exported by nothing\n# no faces\n"),
])
def test_an_obj_without_faces_exits_2(tmp_path, name, text):
    mesh = tmp_path / f"{name}.obj"
    mesh.write_text(text)
    result = run_cli("gt", "--mesh", mesh, "--camera", _camera(tmp_path / "cam.json"),
                     "--out", tmp_path / "gt.exr")
    _assert_bad_input(result, mesh)
    assert "no faces" in result.stderr
    assert not (tmp_path / "gt.exr").exists()


@pytest.mark.parametrize("option", ["--thickness", "--fallback-thickness"])
@pytest.mark.parametrize("thickness", ["nan", "inf", "-inf", "-0.5"])
def test_a_thickness_that_is_not_a_finite_length_exits_2(baked_set, tmp_path, option, thickness):
    result = run_cli("render", "--probes", baked_set, "--camera", _camera(tmp_path / "cam.json"),
                     "--out", tmp_path / "view.exr", f"{option}={thickness}")
    _assert_bad_input(result, "thickness")
    assert not (tmp_path / "view.exr").exists()


def test_a_negative_bound_on_probes_per_ray_exits_2(baked_set, tmp_path):
    result = run_cli("render", "--probes", baked_set, "--camera", _camera(tmp_path / "cam.json"),
                     "--out", tmp_path / "view.exr", "--max-probes-per-ray=-1")
    _assert_bad_input(result, "max_probes_per_ray")
    assert not (tmp_path / "view.exr").exists()


def _manifest_with(folder, change):
    path = folder / "manifest.json"
    manifest = json.loads(path.read_text())
    change(manifest)
    path.write_text(json.dumps(manifest))


@pytest.mark.parametrize("name, change, expected", [
    ("format_version_2", lambda m: m.update(format_version=2), "format_version 2"),
    ("file_outside_the_set", lambda m: m["probes"][0].update(file="../elsewhere/probe_00000.exr"),
     "plain file name"),
    ("resolution_a_string", lambda m: m["probes"][0].update(resolution="big"), "resolution"),
    ("probes_not_a_list", lambda m: m.update(probes=5), "probes"),
    ("coverage_a_list", lambda m: m["probes"][0].update(coverage=[1]), "manifest.json"),
    ("storage_a_number", lambda m: m.update(storage=7), "storage"),
    ("memory_bytes_a_string", lambda m: m["probes"][0].update(memory_bytes="a"), "manifest.json"),
    ("file_a_number", lambda m: m["probes"][0].update(file=3), "manifest.json"),
])
def test_info_refuses_the_manifests_render_refuses(baked_set, name, change, expected):
    _manifest_with(baked_set, change)
    result = run_cli("info", baked_set)
    _assert_bad_input(result, "manifest.json")
    assert expected in result.stderr


def test_info_refuses_a_manifest_nested_200000_deep(baked_set):
    path = baked_set / "manifest.json"
    text = path.read_text().replace('"bake": {', '"bake": ' + "[" * 200_000 + "]" * 200_000 + ', "x": {', 1)
    path.write_text(text)
    result = run_cli("info", baked_set)
    _assert_bad_input(result, "manifest.json")
    assert "nested" in result.stderr


def test_a_fifo_named_as_scan_exits_2_without_waiting_for_a_writer(tmp_path):
    fifo = tmp_path / "scan.xyz"
    os.mkfifo(fifo)
    try:
        result = run_cli("bake", "--scan", fifo, "--out", tmp_path / "set", "--probe", 0, 0, 1,
                         "--res", 16, timeout=60)
    finally:
        # Should the reader block after all, a writer lets it go so the test fails instead of
        # hanging.
        def release():
            with open(fifo, "w"):
                pass

        threading.Thread(target=release, daemon=True).start()
    _assert_bad_input(result, fifo)
    assert "not a regular file" in result.stderr


def _with_file_size_limit(limit_bytes):
    """A child whose writes past limit_bytes fail with EFBIG, as on a full disk (Python ignores
    SIGXFSZ, so write() reports the error instead of the process being killed)."""
    return lambda: resource.setrlimit(resource.RLIMIT_FSIZE, (limit_bytes, limit_bytes))


def _cli(*args, limit_bytes):
    return subprocess.run([os.path.join(ROOT, "lfprobe"), *map(str, args)], capture_output=True,
                          text=True, timeout=600, preexec_fn=_with_file_size_limit(limit_bytes))


def test_a_full_disk_leaves_no_truncated_error_map(baked_set, tmp_path):
    camera = tmp_path / "cam.json"
    camera.write_text(json.dumps({"type": "PERSP", "resolution": [96, 64], "lens": 20.0,
                                  "matrix_world": [[1, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 1.25],
                                                   [0, 0, 0, 1]]}))
    for name, thickness in (("a.exr", "0.02"), ("b.exr", "0.2")):
        run_cli("render", "--probes", baked_set, "--camera", camera, "--out", tmp_path / name,
                "--thickness", thickness, check=True)
    error_map = tmp_path / "error.png"
    result = _cli("compare", tmp_path / "a.exr", tmp_path / "b.exr", "--error-map", error_map,
                  limit_bytes=50)
    assert result.returncode == 1, (result.returncode, result.stderr)
    assert "error.png" in result.stderr and "Traceback" not in result.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.exr", "b.exr", "cam.json", "set"]


def test_a_parse_cache_that_cannot_be_written_is_a_warning(tmp_path):
    scan = tmp_path / "room.xyz"
    write_box_room_xyz(scan, 0.1)  # a cache entry of about 140 KB, over the 64 KiB a file may take
    cache = tmp_path / "cache"
    result = _cli("bake", "--scan", scan, "--cache", cache, "--out", tmp_path / "set", "--probe",
                  0, 0, 1.2, "--res", 16, limit_bytes=64 * 1024)
    assert result.returncode == 0, result.stderr
    assert "lfprobe: warning:" in result.stderr and "parse cache could not be written" in result.stderr
    assert (tmp_path / "set" / "manifest.json").is_file()
    assert os.listdir(cache) == []  # no entry, no temporary
