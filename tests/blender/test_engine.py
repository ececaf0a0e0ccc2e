"""The render engine "Light Field Probes": F12 through the engine gives the image that
`./lfprobe render` gives for the same camera JSON (bit for bit: every pass is float32 in
both, and the trace is deterministic), bad scenes give a clear error and leave the scene as
it was, the camera export and the viewport's progressive refinement."""

from __future__ import annotations

import json
import math
import os

import bpy
import numpy as np
from mathutils import Matrix

import helpers
import probe_scene
from exr_channels import read_exr_channels


def _f12(path: str) -> dict:
    """Renders the scene camera with F12 and returns the passes of the saved multilayer EXR."""
    scene = bpy.context.scene
    bpy.ops.render.render()
    settings = scene.render.image_settings
    if hasattr(settings, "media_type"):  # Blender 5.0 picks multilayer formats by media type
        settings.media_type = "MULTI_LAYER_IMAGE"
    settings.file_format = "OPEN_EXR_MULTILAYER"
    settings.color_depth = "32"
    settings.exr_codec = "NONE"
    bpy.data.images["Render Result"].save_render(path)
    channels = read_exr_channels(path)
    layer = bpy.context.view_layer.name
    return {name[len(layer) + 1:]: array for name, array in channels.items()}


def _native():
    return helpers.addon("core.native").load()


def test_f12_matches_the_cli_render_of_the_same_camera():
    grid, camera = probe_scene.traced_scene()
    work = helpers.tmp_dir()
    passes = _f12(os.path.join(work, "f12.exr"))

    camera_export = helpers.addon("blender.camera_export")
    camera_json = camera_export.camera_dict(bpy.context.scene, camera)
    cam_path = probe_scene.write_json(os.path.join(work, "camera.json"), camera_json)
    out = os.path.join(work, "cli.exr")
    # F12 takes the scene's Pixel Samples (n×n), the CLI the same as --spp.
    spp = str(bpy.context.scene.lfprobe_render.samples ** 2)
    result = probe_scene.lfprobe_cli("render", "--probes", grid.lfprobe_grid.probe_dir, "--camera", cam_path,
                                     "--out", out, "--quiet", "--spp", spp)
    assert result.returncode == 0, result.stderr
    cli = _native().read_image(out)

    h, w = cli["rgba"].shape[:2]
    assert (w, h) == probe_scene.IMAGE_SIZE
    assert (cli["status"] == 1).mean() > 0.95, "the view should mostly hit the room's walls"
    for index, channel in enumerate("RGBA"):
        assert np.array_equal(passes[f"Combined.{channel}"], cli["rgba"][..., index]), channel
    assert np.array_equal(passes["Depth.Z"], cli["depth"])
    assert np.array_equal(passes["LFP Status.X"], cli["status"].astype(np.float32))
    assert np.array_equal(passes["LFP Probe.X"], cli["probe"].astype(np.float32))
    assert np.array_equal(passes["LFP Steps.X"], cli["steps"].astype(np.float32))
    assert np.array_equal(passes["LFP Guessed.X"], cli["guessed"].astype(np.float32))


def test_grid_coarse_resolution_reaches_the_trace():
    """The grid's Coarse Resolution keeps fewer min-distance levels (less memory); the F12
    image keeps its colours and depths, the steps pass shows the different walk."""
    grid, _camera = probe_scene.traced_scene()
    work = helpers.tmp_dir()
    full = _f12(os.path.join(work, "all_levels.exr"))
    probe_view = helpers.addon("blender.probe_view")
    folder = probe_view.probe_folder(grid)
    grid.lfprobe_grid.coarse_resolution = 16
    shallow = _f12(os.path.join(work, "from_16.exr"))
    # The add-on opens sets lazily (a probe is read when a ray reaches it): compare whole loads.
    field = helpers.addon("core.native").load().ProbeField
    assert field.load(folder, coarse_resolution=16).memory_bytes < field.load(folder).memory_bytes
    assert np.array_equal(shallow["Combined.R"], full["Combined.R"])
    assert np.array_equal(shallow["Depth.Z"], full["Depth.Z"])
    assert not np.array_equal(shallow["LFP Steps.X"], full["LFP Steps.X"])


def test_depth_pass_is_written_when_the_view_layer_has_it_off():
    probe_scene.traced_scene()
    bpy.context.view_layer.use_pass_z = False
    passes = _f12(os.path.join(helpers.tmp_dir(), "f12.exr"))
    depth = passes["Depth.Z"]
    assert np.isfinite(depth).mean() > 0.95
    assert 0.5 < float(np.median(depth)) < 5.0  # metres to the room's walls


def _scene_snapshot():
    scene = bpy.context.scene
    return (sorted(o.name for o in scene.objects), scene.camera.name if scene.camera else None,
            scene.render.engine)


def test_no_camera_is_a_clear_error_and_the_scene_stays():
    probe_scene.traced_scene()
    bpy.context.scene.camera = None
    before = _scene_snapshot()
    # Blender refuses before the engine runs ("Cannot render, no camera").
    helpers.expect_operator_error(lambda: bpy.ops.render.render(), "no camera")
    assert _scene_snapshot() == before


def test_no_baked_grid_is_a_clear_error_and_the_scene_stays():
    bpy.context.scene.render.engine = "LFPROBE"
    probe_scene.add_camera()
    probe_scene.add_grid(os.path.join(helpers.tmp_dir(), "not_baked"), baked=False)
    before = _scene_snapshot()
    helpers.expect_operator_error(lambda: bpy.ops.render.render(), "no baked probe grid")
    assert _scene_snapshot() == before


def test_missing_probe_folder_is_a_clear_error():
    grid, _camera = probe_scene.traced_scene()
    missing = os.path.join(helpers.tmp_dir(), "gone")
    grid.lfprobe_grid.probe_dir = missing
    helpers.expect_operator_error(lambda: bpy.ops.render.render(), "does not exist", missing)
    # A folder without a manifest (an unfinished bake) is named as such.
    os.makedirs(missing)
    helpers.expect_operator_error(lambda: bpy.ops.render.render(), "manifest")
    # The scene renders again once the grid points at its probes.
    grid.lfprobe_grid.probe_dir = probe_scene.baked_probe_set()
    bpy.ops.render.render()


def test_orthographic_camera_is_refused():
    _grid, camera = probe_scene.traced_scene()
    camera.data.type = "ORTHO"
    helpers.expect_operator_error(lambda: bpy.ops.render.render(), "orthographic")


def test_camera_export_reads_blender_settings():
    camera_export = helpers.addon("blender.camera_export")
    scene = bpy.context.scene
    camera = probe_scene.add_camera(lens=35.0)
    scene.render.resolution_x, scene.render.resolution_y = 1000, 500
    scene.render.resolution_percentage = 33
    scene.render.pixel_aspect_x = 2.0
    camera.data.sensor_fit = "VERTICAL"
    camera.data.shift_x, camera.data.shift_y = 0.1, -0.05
    d = camera_export.camera_dict(scene, camera, world_offset=(1000.0, 2000.0, 0.5))
    assert d["type"] == "PERSP" and d["resolution"] == [330, 165]
    assert d["sensor_fit"] == "VERTICAL" and d["pixel_aspect_x"] == 2.0
    assert math.isclose(d["shift_x"], 0.1, rel_tol=1e-6) and math.isclose(d["shift_y"], -0.05, rel_tol=1e-6)
    expected = np.array(camera.matrix_world)
    rows = np.array(d["matrix_world"])
    assert np.allclose(rows[:3, :3], expected[:3, :3])
    assert np.allclose(rows[:3, 3], expected[:3, 3] + np.array([1000.0, 2000.0, 0.5]))

    camera.data.type = "PANO"
    owner = camera.data if hasattr(camera.data, "panorama_type") else camera.data.cycles
    owner.panorama_type = "EQUIRECTANGULAR"
    owner.latitude_min, owner.latitude_max = -0.5, 1.0
    d = camera_export.camera_dict(scene, camera)
    assert d["type"] == "PANO_EQUIRECT"
    assert math.isclose(d["latitude_min"], -0.5, rel_tol=1e-6) and math.isclose(d["latitude_max"], 1.0, rel_tol=1e-6)
    owner.panorama_type = "MIRRORBALL"
    try:
        camera_export.camera_dict(scene, camera)
    except camera_export.CameraExportError as error:
        assert "MIRRORBALL" in str(error)
    else:
        raise AssertionError("a mirror-ball panorama must be refused")


class _ViewRegion:
    """What the engine reads of a 3D viewport's RegionView3D."""

    def __init__(self, view_matrix, window_matrix):
        self.view_matrix = view_matrix
        self.window_matrix = window_matrix
        self.is_perspective = True


def test_viewport_camera_and_refinement_match_the_camera_render():
    """A viewport looking through the camera (its view and projection matrices) traces the
    camera's image: the viewport camera is written with another sensor fit and lens, so the
    rays agree to float precision, not bit for bit; refinement ends on the full-size image."""
    grid, camera = probe_scene.traced_scene()
    camera_export = helpers.addon("blender.camera_export")
    viewport = helpers.addon("blender.engine.viewport")
    probe_view = helpers.addon("blender.probe_view")
    scene = bpy.context.scene
    depsgraph = bpy.context.evaluated_depsgraph_get()
    w, h = probe_scene.IMAGE_SIZE
    window = camera.calc_matrix_camera(depsgraph, x=w, y=h)
    region = _ViewRegion(camera.matrix_world.inverted(), window)
    view_camera = camera_export.viewport_camera_dict(region, w, h)

    field = probe_view.load_field(probe_view.probe_folder(grid))
    expected, _ = field.render(json.dumps(camera_export.camera_dict(scene, camera)))
    updates = []
    view = viewport.ProgressiveView(lambda: updates.append(1), band_rays=500)
    try:
        assert view.request(field, view_camera, w, h, {"threads": 1}, key=("view", 1))
        assert not view.request(field, view_camera, w, h, {"threads": 1}, key=("view", 1))
        assert view.wait_final(60), view.error()
        latest = view.latest()
        levels = [t.level for t in view.stats().levels]
    finally:
        view.stop()
    assert levels == list(viewport.LEVELS)
    assert latest.final and latest.rgba.shape == (h, w, 4)
    hit = expected["status"] == 1
    close = np.abs(latest.rgba - expected["rgba"]).max(axis=2) < 1e-3
    assert close[hit].mean() > 0.98, f"{close[hit].mean():.3f} of the hit pixels agree"
    assert len(updates) >= len(levels)


def test_engine_settings_choose_the_grid():
    grid, _camera = probe_scene.traced_scene()
    probe_view = helpers.addon("blender.probe_view")
    other = probe_scene.add_grid(probe_scene.baked_probe_set(), name="AnotherGrid", baked=True)
    scene = bpy.context.scene
    assert probe_view.grid_to_trace(scene) == other  # "AnotherGrid" sorts first
    scene.lfprobe_render.grid = grid
    assert probe_view.grid_to_trace(scene) == grid
    scene.lfprobe_render.mode = "nearest"
    scene.lfprobe_render.threads = 1
    assert probe_view.trace_settings(scene) == {"mode": "nearest", "thickness": scene.lfprobe_render.thickness,
                                                "fallback_thickness": scene.lfprobe_render.fallback_thickness,
                                                "threads": 1, "filter": "bilinear", "blend": 4, "hole_fill": -1}
    scene.lfprobe_render.radiance_filter = "nearest"
    scene.lfprobe_render.blend = 1
    scene.lfprobe_render.fill_holes = False
    assert probe_view.trace_settings(scene)["hole_fill"] == 0  # UNKNOWN pixels black
    scene.lfprobe_render.samples = 3
    assert probe_view.trace_settings(scene)["filter"] == "nearest" and probe_view.trace_settings(scene)["blend"] == 1
    assert probe_view.pixel_samples(scene) == 9
    bpy.ops.render.render()  # nearest-first tracing renders too


def test_settings_default_to_the_native_cores_defaults():
    # Blender needs a property's default when the class is made, before the native module
    # is loaded, so the add-on writes them; they must be the core's own.
    defaults = helpers.addon("core.native").load().DEFAULTS
    render = bpy.context.scene.lfprobe_render.bl_rna.properties
    assert math.isclose(render["thickness"].default, defaults["trace"]["thickness"], rel_tol=1e-6)
    assert math.isclose(render["fallback_thickness"].default, defaults["trace"]["fallback_thickness"],
                        rel_tol=1e-6)
    assert render["mode"].default == defaults["trace"]["mode"]
    assert render["radiance_filter"].default == defaults["trace"]["filter"]
    assert render["blend"].default == defaults["trace"]["blend"]
    grid = helpers.addon("blender.properties").LFProbeGridProperties.bl_rna.properties
    assert grid["resolution"].default == defaults["bake"]["resolution"]


def test_f12_states_its_cost_before_it_runs():
    """The render panel's estimate: the rays F12 traces, and after a first render the time at
    that render's rate; the grid panel's: what the next Bake holds in memory."""
    grid, _camera = probe_scene.traced_scene()
    estimates = helpers.addon("core.estimates")
    estimates._last_rays_per_second = None
    scene = bpy.context.scene
    render, samples = scene.render, scene.lfprobe_render.samples
    text, _warn = estimates.render_time_text(render.resolution_x, render.resolution_y,
                                             render.resolution_percentage, samples)
    assert "after a first render" in text
    _f12(os.path.join(helpers.tmp_dir(), "f12.exr"))
    rate = estimates.last_render_rate()
    assert rate and rate > 0
    text, warn = estimates.render_time_text(1920, 1080, 100, 8)
    assert f"{rate / 1e6:.2f} M rays/s" in text and "132.7 M rays" in text
    assert warn == (1920 * 1080 * 64 / rate > estimates.RENDER_WARNING_SECONDS)
    # The bake estimate takes the storage's bytes a texel from the native core.
    full = _native().probe_storage("full")["bytes_per_texel"]
    compact = _native().probe_storage("compact")["bytes_per_texel"]
    assert (full, compact) == (18, 7)
    g = grid.lfprobe_grid
    text, _warn = estimates.bake_memory_text(tuple(g.counts), g.resolution, full, "full")
    probes = g.counts[0] * g.counts[1] * g.counts[2]
    assert f"{probes} probes at {g.resolution}²" in text
