"""End to end: mesh → ground truth EXR, simulated scan, probe set baked from a mesh."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest

from conftest import SHARED_DATA
from lfprobe.core import cli, native
from lfprobe.core.pipeline import BakeOptions, ProbePlacementSpec, bake_from_mesh

DATA = os.path.join(SHARED_DATA, "meshes")
CORNELL = os.path.join(DATA, "cornell_box", "CornellBox-Original.obj")


def _camera(tmp_path):
    cam = {
        "type": "PERSP",
        # Blender camera at (0, 1, 3.5) looking down -Z (the box's open side), +Y up.
        "matrix_world": [[1, 0, 0, 0], [0, 1, 0, 1], [0, 0, 1, 3.5], [0, 0, 0, 1]],
        "resolution": [64, 48],
        "lens": 35.0,
    }
    path = tmp_path / "cam.json"
    path.write_text(json.dumps(cam))
    return str(path)


def test_load_mesh_and_ground_truth(tmp_path):
    _native = native.load()
    mesh = _native.load_mesh(CORNELL)
    assert mesh.triangle_count == 36
    (lo, hi) = mesh.bounds
    assert lo[1] == pytest.approx(0.0) and hi[1] == pytest.approx(1.99)
    out = str(tmp_path / "gt.exr")
    assert cli.main(["gt", "--mesh", CORNELL, "--camera", _camera(tmp_path), "--out", out,
                             "--spp", "4", "--threads", "2", "--quiet"]) == 0
    image = _native.read_image(out)
    assert image["width"] == 64
    assert (image["status"] == 1).mean() > 0.5
    stats = _native.embree_throughput(mesh, _camera(tmp_path), threads=1, repeats=1)
    assert stats["rays"] == 64 * 48 and stats["rays_per_second"] > 0


def test_scan_and_bake(tmp_path):
    _native = native.load()
    xyz = str(tmp_path / "scan.xyz")
    assert cli.main(["scan", "--mesh", CORNELL, "--at", "0", "1", "0", "--step-deg", "4",
                             "--out", xyz, "--quiet"]) == 0
    with open(xyz) as f:
        assert f.readline().startswith("# scanner 0.000000 1.000000 0.000000")
    cloud = _native.load_scans([xyz], cache_dir="")
    assert len(cloud) > 1000
    assert cloud.scans[0]["scanner"] is not None
    summary = bake_from_mesh(
        [CORNELL], str(tmp_path / "probes"), ProbePlacementSpec(positions=[(0.0, 1.0, 0.0)]),
        BakeOptions(resolution=32),
    )
    assert summary["probe_count"] == 1
    manifest = json.loads((tmp_path / "probes" / "manifest.json").read_text())
    assert manifest["bake"]["source"] == "mesh"
    assert manifest["sources"][0]["kind"] == "mesh"
    # Inside the closed box every texel sees a surface except through the open front.
    assert summary["mean_coverage"]["unknown"] == 0.0


def test_scan_partial_sweep(tmp_path):
    """--horizontal-fov/--horizontal-start: a partial sweep keeps its window of azimuth, says so
    in the file's header, and a bad window is refused with exit 2."""
    _native = native.load()
    full, part = str(tmp_path / "full.xyz"), str(tmp_path / "part.xyz")
    common = ["scan", "--mesh", CORNELL, "--at", "0", "1", "0", "--step-deg", "4", "--quiet"]
    assert cli.main(common + ["--out", full]) == 0
    assert cli.main(common + ["--out", part, "--horizontal-fov", "90",
                              "--horizontal-start", "-45"]) == 0
    with open(part) as f:
        header = [f.readline() for _ in range(3)]
    assert header[2].startswith("# partial sweep: horizontal fov 90 deg from azimuth -45 deg")
    xyz = _native.load_scans([part], cache_dir="")
    positions = xyz.positions.astype(float) + xyz.world_offset
    d = positions - [0.0, 1.0, 0.0]
    azimuth = np.degrees(np.arctan2(d[:, 1], d[:, 0]))
    side = np.hypot(d[:, 0], d[:, 1]) > 1e-6 * np.linalg.norm(d, axis=1)
    # Positions are written to the micrometre: their azimuths are exact to about 1e-4°.
    assert ((azimuth[side] >= -45.0 - 1e-3) & (azimuth[side] < 45.0)).all()
    assert 0.2 < len(xyz) / len(_native.load_scans([full], cache_dir="")) < 0.3
    assert cli.main(common + ["--out", str(tmp_path / "bad.xyz"), "--horizontal-fov", "0"]) == 2
    assert not (tmp_path / "bad.xyz").exists()


def test_scan_texture_filter(tmp_path):
    """scan --texture-filter: the same points either way; footprint colours (the default) are
    the texture's mean over each point's footprint, so on the lab room's textures at a coarse
    step they vary less from point to point than point samples do."""
    _native = native.load()
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    mesh = os.path.join(root, "blend", "lab_room", "lab_room.obj")
    common = ["scan", "--mesh", mesh, "--at", "1.5", "3.0", "1.1", "--step-deg", "1.5",
              "--noise-mm", "0", "--quiet"]
    area, point = str(tmp_path / "area.xyz"), str(tmp_path / "point.xyz")
    assert cli.main(common + ["--out", area]) == 0
    assert cli.main(common + ["--out", point, "--texture-filter", "point"]) == 0
    a = _native.load_scans([area], cache_dir="")
    p = _native.load_scans([point], cache_dir="")
    assert len(a) == len(p) > 10000
    np.testing.assert_array_equal(np.asarray(a.positions), np.asarray(p.positions))
    ca, cp = np.asarray(a.colors, np.float64), np.asarray(p.colors, np.float64)
    assert (ca != cp).any(axis=1).mean() > 0.2  # textured surfaces read differently
    # Neighbouring points along a scan row: filtered colours change less between them.
    assert np.abs(np.diff(ca, axis=0)).mean() < 0.9 * np.abs(np.diff(cp, axis=0)).mean()


def _georef_quad_obj(path, origin):
    """A 2 × 2 m wall facing -Y at y = origin.y + 3, written in world (UTM-sized) coordinates."""
    x, y, z = origin
    lines = [f"v {x + dx:.3f} {y + 3.0:.3f} {z + dz:.3f}" for dx, dz in
             ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    path.write_text("\n".join(lines) + "\nf 1 2 3 4\n")


def _camera_at(tmp_path, origin):
    # Blender camera at `origin` looking along +Y: rotate -Z onto +Y (90° about X).
    x, y, z = origin
    cam = {"type": "PERSP", "resolution": [32, 24], "lens": 50.0,
           "matrix_world": [[1, 0, 0, x], [0, 0, -1, y], [0, 1, 0, z], [0, 0, 0, 1]]}
    path = tmp_path / "cam_utm.json"
    path.write_text(json.dumps(cam))
    return str(path)


def test_georeferenced_mesh_keeps_depth_and_arrays_match_obj(tmp_path):
    """A mesh at x ≈ 5e5, y ≈ 5.4e6 renders depths right to < 1 mm (float32 alone: ±0.5 m),
    and the same wall handed over as arrays (as Blender does) renders the same image."""
    import numpy as np

    _native = native.load()
    origin = (512000.25, 5400000.5, 231.0)
    obj = tmp_path / "utm.obj"
    _georef_quad_obj(obj, origin)
    mesh = _native.load_mesh(str(obj))
    assert mesh.world_offset != (0.0, 0.0, 0.0)
    camera = _camera_at(tmp_path, origin)
    out_obj = str(tmp_path / "obj.exr")
    _native.start_ground_truth(mesh, camera, out_obj, threads=1).result()
    image = _native.read_image(out_obj)
    centre = image["depth"][12, 16]
    assert abs(centre - 3.0) < 1e-3, centre

    x, y, z = origin
    vertices = np.array([[x - 1, y + 3, z - 1], [x + 1, y + 3, z - 1], [x + 1, y + 3, z + 1],
                         [x - 1, y + 3, z + 1]], dtype=np.float64)
    arrays = _native.mesh_from_arrays(
        vertices, np.array([[0, 1, 2], [0, 2, 3]]),
        materials=[{"name": "wall", "base_color": (0.8, 0.8, 0.8)}], name="wall")
    out_arrays = str(tmp_path / "arrays.exr")
    _native.start_ground_truth(arrays, camera, out_arrays, threads=1).result()
    np.testing.assert_allclose(_native.read_image(out_arrays)["depth"], image["depth"], atol=1e-5)
    np.testing.assert_allclose(_native.read_image(out_arrays)["rgba"], image["rgba"], atol=1e-6)


def test_mesh_from_arrays_rejects_bad_input():
    import numpy as np

    _native = native.load()
    vertices = np.zeros((3, 3))
    with pytest.raises(ValueError, match="triangle 0 names vertex 7"):
        _native.mesh_from_arrays(vertices, np.array([[0, 1, 7]]))
    with pytest.raises(ValueError, match="vertices of shape"):
        _native.mesh_from_arrays(np.zeros((3, 2)), np.array([[0, 1, 2]]))
    with pytest.raises(ValueError, match="corner_uvs of shape"):
        _native.mesh_from_arrays(vertices, np.array([[0, 1, 2]]), corner_uvs=np.zeros((2, 2)))
    with pytest.raises(ValueError, match="not finite"):
        _native.mesh_from_arrays(np.full((3, 3), np.nan), np.array([[0, 1, 2]]))
    with pytest.raises(ValueError, match="material"):
        _native.mesh_from_arrays(vertices, np.array([[0, 1, 2]]), material=np.array([3]))
