"""./lfprobe render, splat and camera end to end on a small generated room."""

import json

import numpy as np
import pytest

from conftest import run_cli, write_box_room_xyz


@pytest.fixture(scope="module")
def room(tmp_path_factory):
    """A 4 × 3 × 2.5 m box room as an .xyz scan (2 cm pitch) and a 2×2×1 probe grid baked from it."""
    folder = tmp_path_factory.mktemp("room")
    scan = folder / "room.xyz"
    write_box_room_xyz(scan, 0.02)
    probes = folder / "probes"
    run_cli("bake", "--scan", scan, "--scanner", 0, 0, 1.25, "--grid-min", -1, -0.5, 1.2,
            "--grid-max", 1, 0.5, 1.2, "--counts", 2, 2, 1, "--res", 128, "--out", probes,
            "--no-cache", "--quiet", check=True)
    camera = folder / "cam.json"
    run_cli("camera", "--position", 0, 0, 1.25, "--look-at", 2, 0, 1.25, "--res", 64, 48,
            "--lens", 20, "--out", camera, check=True)
    return {"scan": scan, "probes": probes, "camera": camera, "folder": folder}


def test_render_prints_speed_and_writes_the_view(native, room):
    out = room["folder"] / "view.exr"
    result = run_cli("render", "--probes", room["probes"], "--camera", room["camera"], "--out", out,
                     "--quiet", check=True)
    assert "M rays/s" in result.stdout and "texels" in result.stdout
    image = native.read_image(str(out))
    assert image["rgba"].shape == (48, 64, 4)
    assert (image["status"] == 1).mean() > 0.99  # HIT
    # The camera looks at the wall x = 2 from 2 m away, straight on at the centre.
    assert image["depth"][24, 32] == pytest.approx(2.0, rel=0.01)
    metadata = json.loads(image["metadata"])
    assert metadata["stats"]["rays"] == 64 * 48


def test_render_is_the_same_on_one_and_two_threads(native, room):
    images = []
    for threads in (1, 2):
        out = room["folder"] / f"t{threads}.exr"
        run_cli("render", "--probes", room["probes"], "--camera", room["camera"], "--out", out,
                "--threads", threads, "--quiet", check=True)
        images.append(native.read_image(str(out)))
    for key in ("rgba", "depth", "normal", "status", "probe", "steps"):
        assert np.array_equal(images[0][key], images[1][key], equal_nan=True), key


def test_background_render_equals_render_and_cancels(native, room):
    """ProbeField.start_render (the engine's F12 path) gives render()'s image; cancel stops it."""
    field = native.ProbeField.load(str(room["probes"]))
    camera = room["camera"].read_text()
    image, stats = field.render(camera, threads=2)
    job = field.start_render(camera, threads=2)
    job_image, job_stats = job.result()
    assert job.fraction == 1.0
    for key in ("rgba", "depth", "status", "probe", "steps"):
        assert np.array_equal(job_image[key], image[key], equal_nan=True), key
    assert job_stats["hits"] == stats["hits"]
    big = json.loads(camera)
    big["resolution"] = [1600, 1200]
    job = field.start_render(json.dumps(big), threads=1)
    job.cancel()
    with pytest.raises(native.Cancelled):
        job.result()


def test_trace_throughput_times_the_image_rays_and_the_same_rays_from_their_answers(native, room):
    """trace_throughput: the camera's rays (the figure compared with Embree) count the image's
    hits; start="answer" starts each where its trace ended, and those meet the same surfaces."""
    field = native.ProbeField.load(str(room["probes"]))
    camera = room["camera"].read_text()
    _, stats = field.render(camera, threads=2)
    from_camera = field.trace_throughput(camera, threads=2, repeats=1)
    from_answer = field.trace_throughput(camera, threads=2, repeats=1, start="answer")
    assert from_camera["rays"] == from_answer["rays"] == stats["rays"]
    assert from_camera["hits"] == stats["hits"]
    assert from_answer["hits"] >= 0.99 * stats["hits"]
    assert from_camera["rays_per_second"] > 0 and from_answer["rays_per_second"] > 0
    with pytest.raises(ValueError, match='start must be "camera" or "answer"'):
        field.trace_throughput(camera, start="nowhere")
    # colour="texel": the answers a render with the paper's colour (nearest texel, no blending)
    # gives, timed without the default colour's further lookups.
    _, texel_stats = field.render(camera, threads=2, filter="nearest", blend=1)
    texel = field.trace_throughput(camera, threads=2, repeats=1, colour="texel")
    assert texel["rays"] == stats["rays"] and texel["hits"] == texel_stats["hits"]
    assert texel["rays_per_second"] > 0
    with pytest.raises(ValueError, match='colour must be "default" or "texel"'):
        field.trace_throughput(camera, colour="blended")


def test_splat_baseline_renders_the_same_camera(native, room):
    out = room["folder"] / "splat.exr"
    result = run_cli("splat", "--scan", room["scan"], "--scanner", 0, 0, 1.25, "--camera",
                     room["camera"], "--out", out, "--no-cache", "--quiet", check=True)
    assert "M points/s" in result.stdout and "pixels/s" in result.stdout
    image = native.read_image(str(out))
    assert (image["status"] == 1).mean() > 0.99
    assert image["depth"][24, 32] == pytest.approx(2.0, rel=0.02)


def test_render_errors_are_clear(room, tmp_path):
    bad = tmp_path / "bad_cam.json"
    bad.write_text(json.dumps({"type": "ORTHO"}))
    result = run_cli("render", "--probes", room["probes"], "--camera", bad, "--out", tmp_path / "x.exr")
    assert result.returncode == 2 and "bad_cam.json" in result.stderr and "type" in result.stderr
    assert not (tmp_path / "x.exr").exists()
    missing = run_cli("render", "--probes", tmp_path, "--camera", room["camera"], "--out", tmp_path / "y.exr")
    assert missing.returncode != 0 and "manifest" in missing.stderr


def test_hostile_cameras_are_clear_errors(room, tmp_path):
    """A camera whose keys are each valid but whose rays are not finite, and a camera file with
    bytes that are not UTF-8: exit 2 with a message (the second quoting the bytes), no crash."""
    tiny_lens = json.loads(room["camera"].read_text())
    tiny_lens["lens"] = 1e-300
    path = tmp_path / "tiny_lens.json"
    path.write_text(json.dumps(tiny_lens))
    for mode in ("grid", "nearest"):
        result = run_cli("render", "--probes", room["probes"], "--camera", path, "--mode", mode,
                         "--out", tmp_path / "x.exr", "--quiet")
        assert result.returncode == 2, result.stderr
        assert "rays are not finite" in result.stderr
    bad_bytes = tmp_path / "bad_bytes.json"
    bad_bytes.write_bytes(b'{"type": "PERSP", "lens": "\xff\xfe"}')
    result = run_cli("render", "--probes", room["probes"], "--camera", bad_bytes,
                     "--out", tmp_path / "y.exr", "--quiet")
    assert result.returncode == 2
    assert "bad_bytes.json" in result.stderr and "\\xff" in result.stderr
