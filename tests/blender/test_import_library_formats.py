"""File › Import and Bake with the library formats (E57 through pye57, core/scan_formats.py):
the shared pump-room E57 imports as the same points as its .pts export with its station as the
scanner, mixes with a native .xyz, and a grid bakes from it. Skipped where the libraries are not
installed (tools/scan_deps.sh)."""

import json
import os

import bpy
import numpy as np

import helpers

PUMP_POINTS = 155_201


def _needs_pye57():
    formats = helpers.addon("core.scan_formats")
    try:
        formats.library("pye57", "the test")
    except formats.MissingLibraryError as error:
        raise helpers.Skip(str(error))


def test_e57_imports_posed_with_its_station():
    _needs_pye57()
    path = helpers.shared_data("scans/pumpAVisualReferenceImage.e57")
    (obj,) = helpers.import_scans(path)
    props = obj.lfprobe_scan
    assert props.point_count == PUMP_POINTS and props.paths() == [os.path.abspath(path)]
    assert props.scanners() == [[0.0, 0.0, 0.0]]
    pts = helpers.addon("core.native").load().load_scans([helpers.shared_data("scans/pumpA.pts")], cache_dir="")
    co = np.empty(len(obj.data.vertices) * 3, dtype=np.float32)
    obj.data.vertices.foreach_get("co", co)
    assert len(co) == 3 * PUMP_POINTS  # under the display limit: every point, in file order
    assert np.abs(co.reshape(-1, 3) - pts.positions).max() < 1e-3


def test_e57_and_xyz_import_as_separate_objects_and_bake():
    _needs_pye57()
    e57 = helpers.shared_data("scans/pumpAVisualReferenceImage.e57")
    xyz = helpers.shared_data("scans/pumpA_xyzrgb.xyz")
    objects = helpers.import_scans(e57, xyz, separate_objects=True)
    assert sorted(o.lfprobe_scan.point_count for o in objects) == [PUMP_POINTS, PUMP_POINTS]
    folder = helpers.tmp_dir()
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(folder, "scene.blend"))
    bpy.ops.object.lfprobe_grid_add()
    grid_obj = bpy.context.active_object
    assert sorted(s.obj.name for s in grid_obj.lfprobe_grid.sources) == sorted(o.name for o in objects)  # the selection
    grid_obj.location = (0.0, 0.0, -0.5)
    grid_obj.scale = (0.5, 0.5, 0.1)
    grid_obj.lfprobe_grid.counts = (1, 1, 1)
    grid_obj.lfprobe_grid.resolution = 32
    assert bpy.ops.object.lfprobe_bake() == {"FINISHED"}
    probe_dir = os.path.join(folder, f"scene_{grid_obj.name}_probes")
    manifest = json.load(open(os.path.join(probe_dir, "manifest.json"), encoding="utf-8"))
    sources = manifest["sources"]
    assert sorted(s["points"] for s in sources) == [PUMP_POINTS, PUMP_POINTS], sources
    e57_source = [s for s in sources if s["path"].endswith(".e57")][0]
    assert e57_source["station_name"] == "pumpA" and e57_source["scanner"] == [0.0, 0.0, 0.0]
    assert manifest["probes"][0]["coverage"]["surface"] > 0.1
