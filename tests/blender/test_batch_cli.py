"""The headless batch CLI end to end, as a pipeline runs it: a saved scene with an imported
scan, a probe grid and a camera is baked, rendered and compared by `blender -b -P
addon/lfprobe/cli.py -- --open scene.blend ...` in a separate Blender; bad input gives a clear
message and a non-zero exit; a scene rendering with the engine opens without Blender reporting
the engine missing."""

from __future__ import annotations

import json
import os

import bpy

import helpers
import probe_scene


def _saved_scene(folder: str) -> str:
    """Box-room scan imported through the add-on, a 2×2×2 grid over it, a camera, the room
    as a reference mesh; saved as scene.blend in `folder`."""
    scan = os.path.join(folder, "room.xyz")
    helpers.write_box_room_xyz(scan, 0.05)
    (cloud,) = helpers.import_scans(scan)
    grid = probe_scene.add_grid("//probes", baked=False)
    grid.lfprobe_grid.sources.add().obj = cloud
    probe_scene.add_camera()
    probe_scene.add_room_mesh()
    blend = os.path.join(folder, "scene.blend")
    bpy.ops.wm.save_as_mainfile(filepath=blend)
    return blend


def _check(result, *fragments):
    output = result.stdout + result.stderr
    for fragment in fragments:
        assert fragment in output, f"{fragment!r} not in the output:\n{output}"
    return output


def test_bake_render_compare_end_to_end():
    folder = helpers.tmp_dir()
    blend = _saved_scene(folder)

    # Rendering before baking: the grid has no probes yet.
    result = probe_scene.run_batch(blend, "render", "--out", os.path.join(folder, "early.exr"))
    assert result.returncode == 2, result.stdout + result.stderr
    _check(result, "no baked probe grid")

    result = probe_scene.run_batch(blend, "bake")
    assert result.returncode == 0, result.stdout + result.stderr
    _check(result, "baked grid 'ProbeGrid'", "saved")
    assert os.path.isfile(os.path.join(folder, "probes", "manifest.json"))

    out = os.path.join(folder, "view.exr")
    cam_json = os.path.join(folder, "camera.json")
    result = probe_scene.run_batch(blend, "render", "--out", out, "--camera-json", cam_json, "--threads", "1",
                                   "--fallback-thickness", "0.03")
    assert result.returncode == 0, result.stdout + result.stderr
    _check(result, "rays/s")
    native = helpers.addon("core.native").load()
    image = native.read_image(out)
    assert image["rgba"].shape[:2] == probe_scene.IMAGE_SIZE[::-1]
    assert (image["status"] == 1).mean() > 0.95
    # The same camera file through the bpy-free CLI, at the saved scene's samples per pixel (the
    # default Pixel Samples, 2×2), gives the same image.
    cli_out = os.path.join(folder, "cli.exr")
    cli = probe_scene.lfprobe_cli("render", "--probes", os.path.join(folder, "probes"), "--camera", cam_json,
                                  "--out", cli_out, "--threads", "1", "--spp", "4", "--fallback-thickness", "0.03")
    assert cli.returncode == 0, cli.stderr
    again = native.read_image(cli_out)
    assert (again["rgba"] == image["rgba"]).all() and (again["status"] == image["status"]).all()

    report_dir = os.path.join(folder, "report")
    result = probe_scene.run_batch(blend, "compare", "--reference", "Room", "--out", report_dir)
    assert result.returncode == 0, result.stdout + result.stderr
    _check(result, "PSNR", "depth AbsRel")
    with open(os.path.join(report_dir, "compare.json"), encoding="utf-8") as stream:
        report = json.load(stream)
    assert report["depth_absrel"] < 0.01 and report["hole_rate"] < 0.02


def test_bad_input_exits_non_zero_with_a_message():
    folder = helpers.tmp_dir()
    blend = _saved_scene(folder)
    cases = [
        (("render", "--camera", "Nope", "--out", os.path.join(folder, "x.exr")), "no object named 'Nope'"),
        (("render", "--camera", "Room", "--out", os.path.join(folder, "x.exr")), "not a camera"),
        (("compare", "--reference", "Missing", "--out", os.path.join(folder, "r")), "no object named 'Missing'"),
        (("bake", "--grid", "Camera"), "no probe grid named 'Camera'"),
    ]
    for args, fragment in cases:
        result = probe_scene.run_batch(blend, *args)
        assert result.returncode == 2, (args, result.stdout + result.stderr)
        _check(result, fragment)
    # A grid whose scan file went missing: the bake's own report, and exit 2.
    os.remove(os.path.join(folder, "room.xyz"))
    result = probe_scene.run_batch(blend, "bake")
    assert result.returncode == 2, result.stdout + result.stderr
    _check(result, "room.xyz", "missing")
    # Unknown subcommands and options are argparse's: exit 2 with usage.
    result = probe_scene.run_batch(blend, "paint")
    assert result.returncode == 2
    _check(result, "usage:")
    # --open of a .blend that is not there, or of a file that is no .blend.
    not_blend = os.path.join(folder, "not_a.blend")
    with open(not_blend, "w", encoding="utf-8") as stream:
        stream.write("not a blend file\n")
    for path, fragment in ((os.path.join(folder, "nope.blend"), "no such .blend"), (not_blend, "cannot open")):
        result = probe_scene.run_batch(path, "bake")
        assert result.returncode == 2, (path, result.stdout + result.stderr)
        _check(result, fragment, os.path.basename(path))


def test_a_scene_rendering_with_the_engine_opens_without_engine_not_available():
    """The .blend of a scene set to the engine LFPROBE, opened by --open once the add-on is
    enabled: no "Engine 'LFPROBE' not available" before the command's output. Opened by Blender
    before cli.py (blender -b scene.blend -P cli.py), Blender prints it: the control."""
    probe_scene.traced_scene()
    assert bpy.context.scene.render.engine == "LFPROBE"
    folder = helpers.tmp_dir()
    blend = os.path.join(folder, "engine.blend")
    bpy.ops.wm.save_as_mainfile(filepath=blend)
    message = "Engine 'LFPROBE' not available"
    for opened_first in (False, True):
        out = os.path.join(folder, f"view_{opened_first}.exr")
        result = probe_scene.run_batch(blend, "render", "--out", out, opened_first=opened_first)
        assert result.returncode == 0, result.stdout + result.stderr
        output = _check(result, "rays/s")
        assert (message in output) == opened_first, (opened_first, output)
        assert os.path.isfile(out)


def test_import_sets_up_a_grid_that_bakes_and_compares_by_collection():
    """`import` brings scans into a saved scene with a grid fitted to them (or an existing box
    Empty made the grid); `bake` then works on the saved file, and `compare` takes a
    collection of reference meshes. Missing scans are refused with exit status 2."""
    folder = helpers.tmp_dir()
    probe_scene.add_camera()
    room = probe_scene.add_room_mesh()
    references = bpy.data.collections.new("reference")
    bpy.context.scene.collection.children.link(references)
    references.objects.link(room)
    box = bpy.data.objects.new("probe_box", None)
    box.empty_display_type = "CUBE"
    box.location = (0.0, 0.0, 1.25)
    box.scale = (1.0, 0.75, 0.5)
    box["counts"] = [3, 2, 2]
    bpy.context.scene.collection.objects.link(box)
    blend = os.path.join(folder, "empty_scene.blend")
    bpy.ops.wm.save_as_mainfile(filepath=blend)
    scan = os.path.join(folder, "room.xyz")
    helpers.write_box_room_xyz(scan, 0.05)

    missing = probe_scene.run_batch(blend, "import", "--scan", os.path.join(folder, "nope.xyz"))
    assert missing.returncode == 2
    _check(missing, "nope.xyz")

    with_grid = os.path.join(folder, "with_grid.blend")
    result = probe_scene.run_batch(blend, "import", "--scan", scan, "--grid-from", "probe_box",
                                   "--resolution", "32", "--save-as", with_grid)
    assert result.returncode == 0, result.stdout + result.stderr
    _check(result, "imported", "grid 'probe_box': 3×2×2 probes at 32²", "saved")
    result = probe_scene.run_batch(with_grid, "bake")
    assert result.returncode == 0, result.stdout + result.stderr
    manifest = json.load(open(os.path.join(folder, "with_grid_probe_box_probes", "manifest.json")))
    assert len(manifest["probes"]) == 12
    result = probe_scene.run_batch(with_grid, "compare", "--reference-collection", "reference",
                                   "--out", os.path.join(folder, "cmp"))
    assert result.returncode == 0, result.stdout + result.stderr
    _check(result, "PSNR")

    # Without --counts the batch import fits the grid as Fit Grid does in the UI, with the same
    # defaults: the box room (4 × 3 × 2.5 m) less 0.25 m, probes at most 1 m apart.
    defaults = probe_scene.run_batch(blend, "import", "--scan", scan, "--resolution", "32",
                                     "--save-as", os.path.join(folder, "defaults.blend"))
    assert defaults.returncode == 0, defaults.stdout + defaults.stderr
    _check(defaults, "5×4×3 probes at 32²")
    bpy.ops.wm.open_mainfile(filepath=blend)
    helpers.import_scans(scan)
    bpy.ops.object.lfprobe_grid_add()
    assert bpy.ops.object.lfprobe_grid_fit() == {"FINISHED"}
    assert tuple(bpy.context.view_layer.objects.active.lfprobe_grid.counts) == (5, 4, 3)

    fitted = os.path.join(folder, "fitted.blend")
    result = probe_scene.run_batch(blend, "import", "--scan", scan, "--counts", "2", "2", "1",
                                   "--resolution", "32", "--save-as", fitted)
    assert result.returncode == 0, result.stdout + result.stderr
    _check(result, "2×2×1 probes at 32²")
