"""The grid's Storage: a Compact bake records "compact" in the set's manifest (7 bytes a texel)
and F12 loads it so, giving the image `./lfprobe render` gives from the same manifest; Apply
Storage switches a baked set between full and compact without touching its probe files; Add
Probes for Views traces and counts its budget in the grid's storage; the batch CLI's
`bake --storage compact` stores the choice on the grid and bakes with it."""

from __future__ import annotations

import json
import os

import bpy
import numpy as np

import helpers
import probe_scene
from test_engine import _f12
from test_place_views import _cameras, _draw_panels, _room, _select

RESOLUTION = 32
COMPACT_STORAGE = {"radiance": "srgb8", "normal": "oct16", "confidence": False}


def _baked_box_room(storage: str = "FULL"):
    """A saved scene with the box room scan, a 2×2×1 grid at RESOLUTION over the middle of the
    room with the given Storage, baked by the operator; returns (grid object, probe folder)."""
    folder = helpers.tmp_dir()
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(folder, "scene.blend"))
    path = os.path.join(folder, "room.xyz")
    helpers.write_box_room_xyz(path, pitch=0.05)
    (scan,) = helpers.import_scans(path)
    bpy.ops.object.lfprobe_grid_add()
    grid_obj = bpy.context.active_object
    assert bpy.ops.object.lfprobe_grid_fit(margin=1.0, spacing=0.0) == {"FINISHED"}
    grid = grid_obj.lfprobe_grid
    grid.counts, grid.resolution, grid.storage = (2, 2, 1), RESOLUTION, storage
    assert bpy.ops.object.lfprobe_bake(grid=grid_obj.name) == {"FINISHED"}
    return grid_obj, helpers.addon("blender.grid").probe_dir_abspath(grid_obj)


def _manifest(folder: str) -> dict:
    return helpers.addon("core.probe_set").read_manifest(folder)


def _assert_storage(folder: str, bytes_per_texel: int, **expected) -> dict:
    manifest = _manifest(folder)
    for key, value in expected.items():
        assert manifest["storage"][key] == value, (key, manifest["storage"])
    for probe in manifest["probes"]:
        assert probe["memory_bytes"] == probe["resolution"] ** 2 * bytes_per_texel, probe
    return manifest


def _file_bytes(folder: str) -> dict:
    """Every probe file's bytes, by name."""
    names = sorted(n for n in os.listdir(folder) if n.endswith(".exr"))
    assert names
    return {name: open(os.path.join(folder, name), "rb").read() for name in names}


def test_compact_bake_loads_compact_and_f12_matches_the_cli():
    grid_obj, folder = _baked_box_room("COMPACT")
    manifest = _assert_storage(folder, 7, distance_step=0.001, **COMPACT_STORAGE)
    assert len(manifest["probes"]) == 4
    drawn = _draw_panels(grid_obj)
    assert {"storage", "distance_step"} <= set(drawn["props"])
    line = next(text for text in drawn["labels"] if text.startswith("Loads "))
    assert "(compact: 7 bytes a texel, 1 mm distance steps)" in line, line
    assert "object.lfprobe_grid_apply_storage" not in drawn["operators"]  # the set is as Storage says

    bpy.context.scene.render.engine = "LFPROBE"
    camera = probe_scene.add_camera()
    work = helpers.tmp_dir()
    passes = _f12(os.path.join(work, "f12.exr"))
    probe_view = helpers.addon("blender.probe_view")
    assert probe_view.load_field(folder).storage["bytes_per_texel"] == 7
    # Blender's frame is the set's (the scan has no world offset): the camera file is the same.
    cam_path = probe_scene.write_json(os.path.join(work, "camera.json"),
                                      helpers.addon("blender.camera_export").camera_dict(bpy.context.scene, camera))
    native = helpers.addon("core.native").load()
    images = {}
    for storage in ("manifest", "full"):
        out = os.path.join(work, f"cli_{storage}.exr")
        result = probe_scene.lfprobe_cli("render", "--probes", folder, "--camera", cam_path, "--out", out,
                                         "--storage", storage, "--quiet",
                                         "--spp", str(bpy.context.scene.lfprobe_render.samples ** 2))
        assert result.returncode == 0, result.stderr
        images[storage] = native.read_image(out)
    cli = images["manifest"]
    assert (cli["status"] == 1).mean() > 0.95, "the view should mostly hit the room's walls"
    for index, channel in enumerate("RGBA"):
        assert np.array_equal(passes[f"Combined.{channel}"], cli["rgba"][..., index]), channel
    assert np.array_equal(passes["Depth.Z"], cli["depth"])
    assert np.array_equal(passes["LFP Status.X"], cli["status"].astype(np.float32))
    # The same probes held at full precision give other depths (1 mm steps against float32):
    # F12 did load them compact.
    assert not np.array_equal(passes["Depth.Z"], images["full"]["depth"])
    hit = (cli["status"] == 1) & (images["full"]["status"] == 1)
    assert hit.mean() > 0.9 and np.percentile(np.abs(cli["depth"] - images["full"]["depth"])[hit], 99) < 0.01


def test_apply_storage_switches_a_baked_set_without_touching_its_files():
    grid_obj, folder = _baked_box_room("FULL")
    grid = grid_obj.lfprobe_grid
    _assert_storage(folder, 18, radiance="half", normal="half", distance_step=0.0, confidence=True)
    files = _file_bytes(folder)
    full_memory = helpers.addon("core.probe_set").summarize(folder)["memory_bytes"]
    probe_view = helpers.addon("blender.probe_view")
    assert probe_view.load_field(folder).storage["bytes_per_texel"] == 18

    grid.storage, grid.distance_step = "COMPACT", 0.002
    drawn = _draw_panels(grid_obj)
    assert "object.lfprobe_grid_apply_storage" in drawn["operators"]
    assert any(text.startswith("The set loads full") for text in drawn["labels"]), drawn["labels"]
    assert bpy.ops.object.lfprobe_grid_apply_storage(grid=grid_obj.name) == {"FINISHED"}
    _assert_storage(folder, 7, distance_step=0.002, **COMPACT_STORAGE)
    assert _file_bytes(folder) == files
    compact_memory = helpers.addon("core.probe_set").summarize(folder)["memory_bytes"]
    assert compact_memory < full_memory / 2
    assert probe_view.load_field(folder).storage["bytes_per_texel"] == 7  # the engine's cache reloads
    drawn = _draw_panels(grid_obj)
    assert "object.lfprobe_grid_apply_storage" not in drawn["operators"]
    assert any(f"{compact_memory / 2**20:.2f} MiB in memory (compact: 7 bytes a texel, 2 mm" in text
               for text in drawn["labels"]), drawn["labels"]
    # Another step is another storage: offered again.
    grid.distance_step = 0.001
    assert "object.lfprobe_grid_apply_storage" in _draw_panels(grid_obj)["operators"]

    grid.storage = "FULL"
    bpy.context.view_layer.objects.active = grid_obj
    assert bpy.ops.object.lfprobe_grid_apply_storage() == {"FINISHED"}
    _assert_storage(folder, 18, radiance="half", normal="half", distance_step=0.0, confidence=True)
    assert _file_bytes(folder) == files
    assert helpers.addon("core.probe_set").summarize(folder)["memory_bytes"] == full_memory

    # A grid without a baked set: a clear error, nothing written.
    bpy.ops.object.lfprobe_grid_add()
    helpers.expect_operator_error(lambda: bpy.ops.object.lfprobe_grid_apply_storage(), "no baked probe set",
                                  "bake it first")


def test_mesh_bake_records_the_storage():
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(helpers.tmp_dir(), "scene.blend"))
    bpy.ops.mesh.primitive_cube_add(size=4.0)
    cube = bpy.context.active_object
    bpy.ops.object.lfprobe_grid_add()
    grid_obj = bpy.context.active_object
    cube.select_set(True)
    assert bpy.ops.object.lfprobe_grid_source_add() == {"FINISHED"}
    grid_obj.scale = (0.5, 0.5, 0.5)
    grid = grid_obj.lfprobe_grid
    grid.counts, grid.resolution, grid.storage = (2, 1, 1), 16, "COMPACT"
    bpy.context.view_layer.update()
    assert bpy.ops.object.lfprobe_bake() == {"FINISHED"}
    _assert_storage(helpers.addon("blender.grid").probe_dir_abspath(grid_obj), 7, **COMPACT_STORAGE)


def test_probes_for_views_trace_and_budget_in_the_grids_storage():
    _folder, _scan, grid_obj = _room()
    hidden, opened = _cameras()
    grid_obj.lfprobe_grid.storage = "COMPACT"
    _select(hidden, opened, active=grid_obj)
    assert bpy.ops.object.lfprobe_place_for_views() == {"FINISHED"}
    folder = helpers.addon("blender.grid").probe_dir_abspath(grid_obj)
    manifest = _assert_storage(folder, 7, distance_step=0.001, **COMPACT_STORAGE)
    assert len(manifest["probes"]) == 3  # the grid's two and one at the hidden camera's eye
    placement = grid_obj.lfprobe_grid.placement()
    assert placement["added"][0]["memory_bytes"] < 64**2 * 18
    field = helpers.addon("core.native").load().ProbeField.load(folder)
    assert field.storage["bytes_per_texel"] == 7
    assert placement["memory_bytes"] == field.memory_bytes


def test_batch_cli_bake_storage_compact():
    folder = helpers.tmp_dir()
    scan = os.path.join(folder, "room.xyz")
    helpers.write_box_room_xyz(scan, 0.1)
    (cloud,) = helpers.import_scans(scan)
    grid_obj = probe_scene.add_grid("//probes", baked=False)
    grid_obj.lfprobe_grid.sources.add().obj = cloud
    grid_obj.lfprobe_grid.resolution = RESOLUTION
    blend = os.path.join(folder, "scene.blend")
    bpy.ops.wm.save_as_mainfile(filepath=blend)

    result = probe_scene.run_batch(blend, "bake", "--storage", "compact", "--distance-step", "0.002")
    output = result.stdout + result.stderr
    assert result.returncode == 0, output
    assert "baked grid 'ProbeGrid'" in output and "(compact: 7 bytes a texel, 2 mm distance steps)" in output, output
    probes = os.path.join(folder, "probes")
    _assert_storage(probes, 7, distance_step=0.002, **COMPACT_STORAGE)
    bpy.ops.wm.open_mainfile(filepath=blend)
    grid = bpy.data.objects["ProbeGrid"].lfprobe_grid
    assert grid.baked and grid.storage == "COMPACT" and abs(grid.distance_step - 0.002) < 1e-9

    # Left out, the grid's own setting (now compact) holds; a bad step is refused before any work.
    manifest_before = json.load(open(os.path.join(probes, "manifest.json")))
    result = probe_scene.run_batch(blend, "bake", "--distance-step", "0")
    assert result.returncode == 2 and "--distance-step must be from 0.0001 to 1 metres" in result.stderr, result.stderr
    assert json.load(open(os.path.join(probes, "manifest.json"))) == manifest_before
    result = probe_scene.run_batch(blend, "bake", "--no-save")
    assert result.returncode == 0, result.stdout + result.stderr
    _assert_storage(probes, 7, distance_step=0.002, **COMPACT_STORAGE)
