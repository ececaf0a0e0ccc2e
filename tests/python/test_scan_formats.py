"""E57 and LAS/LAZ import (core/scan_formats.py), mixing them with the native formats and merged
exports of several stations (core/scan_merge.py), on the shared scans."""

import json
import os

import numpy as np
import pytest

from conftest import run_cli
from lfprobe.core import pipeline, scan_formats
from lfprobe.core.errors import InputError


def _library(name):
    try:
        return scan_formats.library(name, "the test")
    except scan_formats.MissingLibraryError as error:
        pytest.skip(str(error))


def _scan(shared_data, name):
    return os.path.join(shared_data, "scans", name)


def test_e57_reads_the_same_points_as_the_pts_export(native, shared_data):
    e57 = _scan(shared_data, "pumpAVisualReferenceImage.e57")
    _library("pye57")
    cloud, records = pipeline.load_scans_and_sources([e57], cache_dir="")
    pts = native.load_scans([_scan(shared_data, "pumpA.pts")], cache_dir="")
    assert len(cloud) == len(pts) == 155201
    assert np.abs(cloud.positions.astype(np.float64) - pts.positions).max() < 1e-3  # within 1 mm
    assert np.abs(cloud.colors - pts.colors).max() < 1e-5  # same 8-bit sRGB decoding
    assert cloud.scans[0]["scanner"] == (0.0, 0.0, 0.0)  # the station: identity pose at the origin
    assert records[0].metadata["station_name"] == "pumpA" and records[0].scanner == [0.0, 0.0, 0.0]
    arrays = scan_formats.read_e57(e57)[0]
    assert arrays.intensities is not None and len(arrays.intensities) == 155201


def _write_e57(path, stations):
    """An E57 of several posed stations written by pye57: each (local xyz, rgb uint8, rotation
    quaternion wxyz, translation)."""
    pye57 = _library("pye57")
    with pye57.E57(str(path), mode="w") as out:
        for local, rgb, rotation, translation in stations:
            data = {"cartesianX": local[:, 0].copy(), "cartesianY": local[:, 1].copy(),
                    "cartesianZ": local[:, 2].copy(), "intensity": np.linspace(0, 1, len(local)),
                    "colorRed": rgb[:, 0].copy(), "colorGreen": rgb[:, 1].copy(), "colorBlue": rgb[:, 2].copy()}
            out.write_scan_raw(data, rotation=np.array(rotation, float), translation=np.array(translation, float))


def test_e57_stations_are_posed_georeferenced_and_kept_apart(tmp_path):
    rng = np.random.default_rng(1)
    local = rng.uniform(-5, 5, size=(500, 3))
    rgb = rng.integers(0, 256, size=(500, 3)).astype(np.uint8)
    utm = np.array([512000.0, 5400000.0, 230.0])
    quarter = [np.cos(np.pi / 4), 0, 0, np.sin(np.pi / 4)]  # 90° about Z: (x, y) → (−y, x)
    path = tmp_path / "two_stations.e57"
    _write_e57(path, [(local, rgb, [1, 0, 0, 0], utm), (local, rgb, quarter, utm + [3.0, 0, 0])])
    cloud, records = pipeline.load_scans_and_sources([str(path)], cache_dir="")
    offset = np.array(cloud.world_offset)
    assert len(cloud) == 1000 and np.all(np.bincount(cloud.scan_index) == 500)
    assert np.all(offset == np.round(offset)) and np.abs(offset - utm).max() < 10
    world = cloud.positions.astype(np.float64) + offset
    expected = np.vstack([local + utm, np.column_stack([-local[:, 1], local[:, 0], local[:, 2]]) + utm + [3, 0, 0]])
    assert np.abs(world - expected).max() < 1e-4  # georeferenced, float32 only after the offset
    assert np.allclose(np.array(cloud.scans[1]["scanner"]) + offset, utm + [3, 0, 0])
    assert [r.metadata["station"] for r in records] == [0, 1]


def test_las_and_laz_read_back_within_their_scale(native, shared_data, tmp_path):
    laspy = _library("laspy")
    _library("lazrs")
    source = native.load_scans([_scan(shared_data, "autzen_trim_xyzrgb.xyz")], cache_dir="")
    world = source.positions.astype(np.float64) + np.array(source.world_offset)
    encoded = np.round(np.clip(np.asarray(source.colors, float), 0, 1) ** (1 / 2.2) * 65535).astype(np.uint16)
    wkt = 'PROJCS["NAD83 / Oregon GIC Lambert (ft)",GEOGCS["NAD83"]]'
    for suffix in ("las", "laz"):
        header = laspy.LasHeader(point_format=3, version="1.2")
        header.scales = np.array([0.01, 0.01, 0.01])
        header.offsets = np.floor(world.min(axis=0))
        header.vlrs.append(laspy.vlrs.known.WktCoordinateSystemVlr(wkt))
        las = laspy.LasData(header)
        las.x, las.y, las.z = world[:, 0], world[:, 1], world[:, 2]
        las.red, las.green, las.blue = encoded[:, 0], encoded[:, 1], encoded[:, 2]
        las.intensity = np.arange(len(world)) % 1000
        path = tmp_path / f"autzen.{suffix}"
        las.write(str(path))
        cloud, records = pipeline.load_scans_and_sources([str(path)], cache_dir="")
        back = cloud.positions.astype(np.float64) + np.array(cloud.world_offset)
        assert len(cloud) == 110000
        assert np.abs(back - world).max() <= 0.005 + 1e-3  # half the 0.01 scale, plus float32 local
        assert np.abs(cloud.colors - scan_formats.srgb_decode(encoded / 65535.0)).max() < 1e-6
        assert "Oregon" in records[0].metadata["crs"] and records[0].metadata["format"] == suffix
        arrays = scan_formats.read_las(str(path))
        assert arrays.intensities[1234] == 234


def test_an_e57_mixes_with_an_xyz_one_scan_index_each(shared_data):
    _library("pye57")
    paths = [_scan(shared_data, "pumpAVisualReferenceImage.e57"), _scan(shared_data, "pumpA_xyzrgb.xyz")]
    cloud, records = pipeline.load_scans_and_sources(paths, scanners=[None, [0, 0, 0]], cache_dir="")
    assert len(cloud) == 2 * 155201 and list(np.bincount(cloud.scan_index)) == [155201, 155201]
    first, second = cloud.positions[cloud.scan_index == 0], cloud.positions[cloud.scan_index == 1]
    assert np.abs(first - second).max() < 1e-3
    assert [r.path for r in records] == paths and records[1].scanner == [0.0, 0.0, 0.0]


def test_a_truncated_e57_is_an_input_error_naming_the_file(shared_data, tmp_path):
    _library("pye57")
    data = open(_scan(shared_data, "pumpAVisualReferenceImage.e57"), "rb").read()
    broken = tmp_path / "truncated.e57"
    broken.write_bytes(data[: len(data) // 2])
    with pytest.raises(InputError, match="truncated.e57"):
        pipeline.load_scans([str(broken)], cache_dir="")
    result = run_cli("bake", "--scan", broken, "--probe", 0, 0, 0, "--res", 16, "--out", tmp_path / "out", "--quiet")
    assert result.returncode == 2 and "truncated.e57" in result.stderr and "Traceback" not in result.stderr


def test_a_las_whose_header_lies_about_its_point_count_is_an_input_error(tmp_path):
    laspy = _library("laspy")
    las = laspy.LasData(laspy.LasHeader(point_format=3, version="1.2"))
    las.x, las.y, las.z = np.arange(100.0), np.zeros(100), np.zeros(100)
    path = tmp_path / "lying.las"
    las.write(str(path))
    raw = bytearray(path.read_bytes())
    raw[107:111] = (1000).to_bytes(4, "little")  # LAS 1.2 legacy point count: 1000 instead of 100
    path.write_bytes(bytes(raw))
    with pytest.raises(InputError, match="lying.las"):
        pipeline.load_scans([str(path)], cache_dir="")


def test_a_missing_library_says_what_to_install():
    with pytest.raises(scan_formats.MissingLibraryError, match="tools/scan_deps.sh"):
        scan_formats.library("lfprobe_no_such_library", "reading a test file")


def _simulate(native, mesh, at, path, step=1.0):
    native.start_simulate_scan(mesh, str(path), list(at), step_deg=step, noise_mm=0.0, vertical_fov=300.0,
                               seed=1).run()


def test_a_merged_export_gives_the_bake_of_its_separate_stations(native, shared_data, tmp_path):
    """Two stations simulated in the Cornell box, baked from their two files (a scanner each)
    and from one merged file with two --scanner positions (nearest station, then the station
    column): the same coverage and depth within 0.5 %, the same normals."""
    mesh = native.load_mesh(os.path.join(shared_data, "meshes", "cornell_box", "CornellBox-Original.obj")) \
        if os.path.exists(os.path.join(shared_data, "meshes", "cornell_box", "CornellBox-Original.obj")) else None
    if mesh is None:
        objs = [f for f in os.listdir(os.path.join(shared_data, "meshes", "cornell_box")) if f.endswith(".obj")]
        mesh = native.load_mesh(os.path.join(shared_data, "meshes", "cornell_box", objs[0]))
    low, high = np.array(mesh.bounds[0]), np.array(mesh.bounds[1])
    centre = 0.5 * (low + high)
    size = high - low
    # In the open space at the front of the box (Y up, open towards +Z), clear of the blocks.
    front = centre + [0, 0, 0.25 * size[2]]
    stations = [front - [0.2 * size[0], 0, 0], front + [0.2 * size[0], 0.1 * size[1], 0]]
    files = [tmp_path / "a.xyz", tmp_path / "b.xyz"]
    for at, path in zip(stations, files):
        _simulate(native, mesh, at, path)
    merged = tmp_path / "merged.xyz"
    with_column = tmp_path / "merged_station.xyz"
    rows = [l for l in files[0].read_text().splitlines() if l and l[0] in "-0123456789."]
    rows_b = [l for l in files[1].read_text().splitlines() if l and l[0] in "-0123456789."]
    merged.write_text("\n".join(rows + rows_b) + "\n")
    with_column.write_text("\n".join([r + " 1" for r in rows] + [r + " 2" for r in rows_b]) + "\n")
    width = len(rows[0].split())
    columns = "x y z r g b" if width == 6 else "x y z"
    probes = ["--probe", *front, "--probe", *(front + [0, 0.15 * size[1], 0.1 * size[2]])]
    scanners = [a for s in stations for a in ["--scanner", *s]]

    def bake(name, scans, *extra):
        run_cli("bake", "--scan", *scans, *scanners, *probes, "--res", 64, "--out", tmp_path / name,
                "--no-cache", "--quiet", *extra, check=True)
        manifest = json.loads((tmp_path / name / "manifest.json").read_text())
        return manifest, [native.read_probe(str(tmp_path / name / p["file"])) for p in manifest["probes"]]

    separate, separate_maps = bake("separate", files)
    for name, extra in (("column", ("--columns", columns + " station")), ("nearest", ())):
        scan = merged if name == "nearest" else with_column
        manifest, maps = bake(name, [scan], *extra)
        assert [s["scanner"] for s in manifest["sources"]] == [s["scanner"] for s in separate["sources"]]
        if name == "column":
            assert [s["points"] for s in manifest["sources"]] == [len(rows), len(rows_b)]
        for ref, got in zip(separate_maps, maps):
            surface_ref = ref["state"] == ref["state"].flat[np.argmax(np.isfinite(ref["distance"]).ravel())]
            both = np.isfinite(ref["distance"]) & np.isfinite(got["distance"])
            covered_ref, covered = np.isfinite(ref["distance"]).mean(), np.isfinite(got["distance"]).mean()
            assert abs(covered - covered_ref) <= 0.005 * covered_ref, name
            depth_error = np.abs(got["distance"][both] - ref["distance"][both]) / ref["distance"][both]
            assert np.mean(depth_error) <= 0.005, name
            dots = np.sum(ref["normal"][both] * got["normal"][both], axis=-1)
            assert np.mean(dots > 0.9) >= 0.99, name  # normals face the same (right) station
            assert surface_ref.any()


def test_simulated_scans_streamed_as_a_cloud_are_the_cloud_their_files_give(native, shared_data, tmp_path):
    """start_simulate_scans hands the scans over as one cloud with no file between: the same
    points, colours, scans and frame as start_simulate_scan's files read back, but for the files'
    6 decimals."""
    folder = os.path.join(shared_data, "meshes", "cornell_box")
    mesh = native.load_mesh(os.path.join(folder, sorted(f for f in os.listdir(folder) if f.endswith(".obj"))[0]))
    low, high = np.array(mesh.bounds[0]), np.array(mesh.bounds[1])
    centre, size = 0.5 * (low + high), high - low
    stations = [list(centre + [-0.2 * size[0], 0, 0.25 * size[2]]), list(centre + [0.2 * size[0], 0, 0.2 * size[2]])]
    files = []
    for k, at in enumerate(stations):
        files.append(str(tmp_path / f"scan{k}.xyz"))
        native.start_simulate_scan(mesh, files[-1], at, step_deg=2.0, noise_mm=1.0, seed=k + 1).run()
    from_files = pipeline.load_scans(files, stations, cache_dir="")
    streamed = native.start_simulate_scans(mesh, stations, step_deg=2.0, noise_mm=1.0).run()
    cloud = streamed["cloud"]
    assert [s["points"] for s in streamed["stats"]] == [s["points"] for s in from_files.scans]
    assert cloud.world_offset == from_files.world_offset
    assert np.array_equal(cloud.scan_index, from_files.scan_index)
    assert np.array_equal(cloud.colors, from_files.colors)
    assert np.abs(cloud.positions - from_files.positions).max() < 2e-6
    for a, b in zip(cloud.scans, from_files.scans):
        assert np.allclose(a["scanner"], b["scanner"], atol=1e-6)
