"""End to end: mesh → ground truth EXR, simulated scan, probe set baked from a mesh."""

from __future__ import annotations

import json
import os

import pytest

from lfprobe.core import cli, cli_mesh, native
from lfprobe.core.pipeline import BakeOptions, ProbePlacementSpec

DATA = os.path.join(os.path.dirname(__file__), "..", "..", "..", "shared", "data", "meshes")
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
    summary = cli_mesh.bake_from_mesh(
        [CORNELL], str(tmp_path / "probes"), ProbePlacementSpec(positions=[(0.0, 1.0, 0.0)]),
        BakeOptions(resolution=32),
    )
    assert summary["probe_count"] == 1
    manifest = json.loads((tmp_path / "probes" / "manifest.json").read_text())
    assert manifest["bake"]["source"] == "mesh"
    assert manifest["sources"][0]["kind"] == "mesh"
    # Inside the closed box every texel sees a surface except through the open front.
    assert summary["mean_coverage"]["unknown"] == 0.0
