"""The Python face of the native core: arrays in and out, errors as exceptions, long work with
the GIL released, progress and cancellation."""

import json
import threading
import time

import numpy as np
import pytest


def box_cloud(native, spacing=0.05):
    """Points on the walls of a 4 × 3 × 2.5 m box, scanner at its centre."""
    lo, hi = np.array([-2.0, -1.5, 0.0]), np.array([2.0, 1.5, 2.5])
    chunks = []
    for axis in range(3):
        u, v = (axis + 1) % 3, (axis + 2) % 3
        gu = np.arange(lo[u], hi[u], spacing)
        gv = np.arange(lo[v], hi[v], spacing)
        uu, vv = np.meshgrid(gu, gv, indexing="ij")
        for w in (lo[axis], hi[axis]):
            p = np.zeros((uu.size, 3))
            p[:, axis] = w
            p[:, u] = uu.ravel()
            p[:, v] = vv.ravel()
            chunks.append(p)
    positions = np.concatenate(chunks).astype(np.float32)
    colors = np.tile(np.array([[0.2, 0.4, 0.6]], np.float32), (len(positions), 1))
    return native.PointCloud.from_arrays(positions, colors, scanners=[[0.0, 0.0, 1.25]])


def test_oct_encode_decode_round_trip_and_errors(native):
    rng = np.random.default_rng(0)
    d = rng.normal(size=(1000, 3)).astype(np.float32)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    back = native.oct_decode(native.oct_encode(d))
    assert np.max(np.abs(back - d)) < 1e-5
    with pytest.raises(ValueError, match="finite non-zero direction"):
        native.oct_encode(np.array([[np.nan, 0, 1]], np.float32))
    with pytest.raises(ValueError):
        native.oct_encode(np.zeros((1, 3), np.float32))
    with pytest.raises(ValueError, match=r"shape \(n, 3\)"):
        native.oct_encode(np.zeros((4, 2), np.float32))


def test_point_cloud_arrays_are_views_of_the_native_cloud(native):
    cloud = box_cloud(native, 0.25)
    positions = cloud.positions
    assert positions.dtype == np.float32 and positions.shape == (len(cloud), 3)
    assert cloud.colors.shape == (len(cloud), 3)
    assert cloud.normals is None and cloud.intensities is None
    assert cloud.scans[0]["scanner"] == (0.0, 0.0, 1.25)
    del cloud  # the arrays keep the cloud alive
    assert np.isfinite(positions).all()
    with pytest.raises(ValueError, match="NaN"):
        native.PointCloud.from_arrays(np.array([[0, 0, np.inf]], np.float32))


def test_bake_releases_the_gil_reports_progress_and_reads_back(native, tmp_path):
    cloud = box_cloud(native, 0.02)  # enough work (~1 s) for several progress polls
    ticks = []
    stop = threading.Event()

    def python_keeps_running():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.005)

    seen = []
    worker = threading.Thread(target=python_keeps_running)
    worker.start()
    try:
        summary = native.bake_probe_set(
            cloud, str(tmp_path / "set"), resolution=256,
            positions=[[0, 0, 1.25], [1, 0.5, 1.0], [-1, -0.5, 2.0], [0.5, 0.5, 0.5]] * 4,
            progress=lambda fraction, stage: seen.append((fraction, stage)),
        )
    finally:
        stop.set()
        worker.join()
    assert summary["probe_count"] == 16
    assert len(ticks) > 10, "a Python thread must run while the native bake works"
    # Polled every 0.1 s: at least one report while working, and the final one.
    assert len(seen) >= 2 and seen[-1] == (1.0, "done")
    assert all(0.0 <= f <= 1.0 and isinstance(s, str) and s for f, s in seen)
    probe = native.read_probe(str(tmp_path / "set" / "probe_00000.exr"))
    assert probe["distance"].shape == (256, 256)
    assert probe["coverage"]["surface"] + probe["coverage"]["inferred"] > 0.99
    # Straight up from the box's centre the ceiling is 1.25 m away.
    u, v = native.oct_encode(np.array([[0, 0, 1]], np.float32))[0]
    assert probe["distance"][int(v * 256), int(u * 256)] == pytest.approx(1.25, abs=0.01)
    levels = native.coarse_min_distance(probe["distance"])
    assert levels[0].shape == (128, 128)
    d = np.nan_to_num(probe["distance"], nan=0.0)
    assert (levels[0] <= d.reshape(128, 2, 128, 2).min(axis=(1, 3))).all()


def test_cancel_from_the_progress_callback(native, tmp_path):
    cloud = box_cloud(native)
    with pytest.raises(native.Cancelled):
        native.bake_probe_set(cloud, str(tmp_path / "set"), resolution=128,
                              positions=[[0, 0, 1]] * 50, progress=lambda f, s: False)
    assert not (tmp_path / "set" / "manifest.json").exists()


def test_job_runs_in_the_background_and_can_be_cancelled(native, tmp_path):
    cloud = box_cloud(native)
    job = native.start_bake_probe_set(cloud, str(tmp_path / "set"), resolution=128,
                                      positions=[[0, 0, 1]] * 200)
    assert not job.done
    job.cancel()
    assert job.wait(30.0)
    with pytest.raises(native.Cancelled):
        job.result()


def test_callback_exception_stops_the_work_and_propagates(native, tmp_path):
    cloud = box_cloud(native)

    def boom(fraction, stage):
        raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        native.bake_probe_set(cloud, str(tmp_path / "set"), resolution=64,
                              positions=[[0, 0, 1]] * 50, progress=boom)


def test_bad_bake_arguments_are_value_errors(native, tmp_path):
    cloud = box_cloud(native, 0.5)
    with pytest.raises(ValueError, match="resolution"):
        native.bake_probe_set(cloud, str(tmp_path / "a"), resolution=1, positions=[[0, 0, 1]])
    with pytest.raises(ValueError, match="no probe positions"):
        native.bake_probe_set(cloud, str(tmp_path / "b"), resolution=16)
    with pytest.raises(ValueError, match="grid"):
        native.bake_probe_set(cloud, str(tmp_path / "c"), resolution=16, grid_min=[0, 0, 0])
    with pytest.raises(ValueError, match="counts"):
        native.bake_probe_set(cloud, str(tmp_path / "d"), resolution=16, grid_min=[0, 0, 0],
                              grid_max=[1, 1, 1], counts=[0, 1, 1])


def test_plan_options_reach_the_splat_settings_of_the_planned_bake(native, tmp_path):
    """A planned bake takes splat_plane_reach among its options, checks it as a plain bake does,
    and records every splat setting in the manifest as a plain bake does."""
    cloud = box_cloud(native)
    probe = [[0.0, 0.0, 1.25]]
    with pytest.raises(ValueError, match="splat_plane_reach must be a positive"):
        native.start_plan_probes(cloud, positions=probe, options={"splat_plane_reach": 0.0}).run()
    native.start_bake_planned_probe_set(cloud, str(tmp_path / "planned"), positions=probe,
                                        options={"splat_plane_reach": 3.0}).run()
    native.bake_probe_set(cloud, str(tmp_path / "plain"), resolution=64, positions=probe)
    planned, plain = (json.loads((tmp_path / name / "manifest.json").read_text())["bake"]
                      for name in ("planned", "plain"))
    assert planned["splat_plane_reach"] == 3.0 and plain["splat_plane_reach"] == 2.0
    splat_keys = {"splat_scale", "splat_plane_reach", "max_splat_radius_texels", "hole_fill_texels",
                  "min_distance", "lod_texels", "face_the_probe"}
    assert splat_keys <= set(planned) and splat_keys <= set(plain)


def test_lod_texels_reaches_the_bake_and_its_manifest(native, tmp_path):
    """lod_texels (the point hierarchy's cut) is an option of the plain and the planned bake,
    recorded in the manifest, and checked like the other splat settings."""
    cloud = box_cloud(native)
    probe = [[0.0, 0.0, 1.25]]
    summary = native.bake_probe_set(cloud, str(tmp_path / "every_point"), resolution=64,
                                    positions=probe, lod_texels=0.0)
    assert summary["hierarchy_seconds"] < 1e-3  # no hierarchy is built
    native.start_bake_planned_probe_set(cloud, str(tmp_path / "planned"), positions=probe,
                                        options={"lod_texels": 2.0}).run()
    for name, expected in (("every_point", 0.0), ("planned", 2.0)):
        bake = json.loads((tmp_path / name / "manifest.json").read_text())["bake"]
        assert bake["lod_texels"] == expected
    with pytest.raises(ValueError, match="lod_texels must be a finite number"):
        native.bake_probe_set(cloud, str(tmp_path / "bad"), resolution=64, positions=probe,
                              lod_texels=float("nan"))


def test_lod_colour_tolerance_reaches_the_bake_and_its_manifest(native, tmp_path):
    """lod_colour_tolerance (wider cells where their children agree) is an option of the plain and
    the planned bake, off by default, recorded in the manifest and checked."""
    assert native.DEFAULTS["bake"]["lod_colour_tolerance"] == 0.0
    cloud = box_cloud(native)
    probe = [[0.0, 0.0, 1.25]]
    native.bake_probe_set(cloud, str(tmp_path / "plain"), resolution=64, positions=probe,
                          lod_colour_tolerance=0.01)
    native.start_bake_planned_probe_set(cloud, str(tmp_path / "planned"), positions=probe,
                                        options={"lod_colour_tolerance": 0.02}).run()
    for name, expected in (("plain", 0.01), ("planned", 0.02)):
        bake = json.loads((tmp_path / name / "manifest.json").read_text())["bake"]
        assert bake["lod_colour_tolerance"] == pytest.approx(expected)
    with pytest.raises(ValueError, match="lod_colour_tolerance must be a finite colour difference"):
        native.bake_probe_set(cloud, str(tmp_path / "bad"), resolution=64, positions=probe,
                              lod_colour_tolerance=-1.0)


def test_clouds_from_arrays_keep_intensities_and_scan_paths(native):
    """An array cloud (E57/LAS readers, the add-on's moved scans) keeps the scanner's intensity
    and the file of each scan, and refuses what does not fit."""
    positions = np.arange(12, dtype=np.float32).reshape(4, 3)
    cloud = native.PointCloud.from_arrays(positions, intensities=np.array([1, 2, 3, 4], np.float32),
                                          scan_index=np.array([0, 1, 1, 0], np.uint32),
                                          scanners=[None, [0.0, 0.0, 0.0]], scan_paths=["a.e57", "b.las"])
    assert list(cloud.intensities) == [1, 2, 3, 4]
    assert [s["path"] for s in cloud.scans] == ["a.e57", "b.las"]
    with pytest.raises(ValueError, match="intensities: NaN"):
        native.PointCloud.from_arrays(positions, intensities=np.array([1, np.nan, 3, 4], np.float32))
    with pytest.raises(ValueError, match="intensities: expected shape"):
        native.PointCloud.from_arrays(positions, intensities=np.ones(3, np.float32))
    with pytest.raises(ValueError, match="one path per scan"):
        native.PointCloud.from_arrays(positions, scan_paths=["a", "b"])


def test_local_geometry_gives_the_bakes_normals_and_reads_the_bakes_cache(native, tmp_path):
    """The Poisson peer's normals: a box's wall normals face its scanner (inward), the spacing is
    the grid's; after a bake with a cache the geometry is read from the bake's entry, the same
    arrays, and nothing new is written."""
    cloud = box_cloud(native, 0.05)
    fresh = native.start_local_geometry(cloud).run()
    normals, spacing = fresh["normals"], fresh["spacing"]
    assert normals.shape == (len(cloud), 3) and normals.dtype == np.float32 and fresh["oriented"].all()
    to_scanner = np.array([0.0, 0.0, 1.25], np.float32) - cloud.positions
    assert (np.einsum("ij,ij->i", normals, to_scanner) > 0).all()
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-5)
    assert 0.04 < float(np.median(spacing)) < 0.08
    cache = tmp_path / "cache"
    native.bake_probe_set(cloud, str(tmp_path / "set"), resolution=32, positions=[[0.0, 0.0, 1.25]],
                          cache_dir=str(cache))
    entries = sorted(p.name for p in cache.iterdir())
    cached = native.start_local_geometry(cloud, cache_dir=str(cache)).run()
    assert sorted(p.name for p in cache.iterdir()) == entries
    np.testing.assert_array_equal(cached["normals"], normals)
    np.testing.assert_array_equal(cached["spacing"], spacing)


def test_grid_positions_are_the_bakes_with_a_one_probe_axis_at_the_centre(native):
    from lfprobe.core import defaults
    from lfprobe.core.report.scene import grid_positions

    positions = native.grid_positions([0.0, 0.0, 1.0], [2.0, 4.0, 3.0], [3, 1, 2])
    assert positions.shape == (6, 3)
    # x fastest, then z (y has one probe: at the box's centre, where the bake puts it)
    assert positions[:, 0].tolist() == [0.0, 1.0, 2.0, 0.0, 1.0, 2.0]
    assert set(positions[:, 1].tolist()) == {2.0}
    assert positions[:, 2].tolist() == [1.0, 1.0, 1.0, 3.0, 3.0, 3.0]
    assert grid_positions([0.0, 0.0, 1.0], [2.0, 4.0, 3.0], [3, 1, 2]) == positions.tolist()
    # The defaults every caller reads are the native settings' own.
    assert defaults.trace("thickness") == 0.0025 and defaults.bake("splat_scale") == 0.8
    assert defaults.trace("fallback_thickness") == 0.02
    assert defaults.bake("resolution") == 512 and defaults.trace("blend") == 4


def test_a_lazily_opened_field_reads_probes_when_traced(native, tmp_path):
    """ProbeField.load(lazy=True), as Blender's F12 and viewport open a set: nothing but the
    manifest is read until a ray reaches a probe, and the image is the eager load's."""
    cloud = box_cloud(native)
    native.bake_probe_set(cloud, str(tmp_path / "set"), resolution=32, grid_min=[-0.5, -0.5, 1.0],
                          grid_max=[0.5, 0.5, 1.5], counts=[2, 2, 2])
    lazy = native.ProbeField.load(str(tmp_path / "set"), lazy=True)
    eager = native.ProbeField.load(str(tmp_path / "set"))
    assert (lazy.probe_count, lazy.loaded_probe_count, lazy.memory_bytes) == (8, 0, 0)
    assert eager.loaded_probe_count == 8
    camera = json.dumps({"type": "PERSP", "resolution": [24, 16], "lens": 20.0, "sensor_width": 36.0,
                         "matrix_world": [[1, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 1.25], [0, 0, 0, 1]]})
    image_lazy, _ = lazy.render(camera, threads=2)
    image_eager, _ = eager.render(camera, threads=2)
    assert 0 < lazy.loaded_probe_count <= 8
    for channel in ("rgba", "status"):
        np.testing.assert_array_equal(image_lazy[channel], image_eager[channel])
