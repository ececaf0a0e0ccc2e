"""The render engine "Light Field Probes": F12 and the Rendered viewport trace the scene's
baked probe grid (never its geometry).

F12 traces the active camera at the render size and writes Combined (RGBA: linear colour,
coverage), Depth (distance along the ray, +inf where nothing is hit, as the native EXR's Z)
and four trace passes: "LFP Status" (0 MISS, 1 HIT, 2 UNKNOWN), "LFP Probe" (the probe that
answered, −1 none), "LFP Steps" (texels visited) and "LFP Guessed" (1 where the pixel shows a
hole-filled texel: a surface no scan saw, guessed from around it; where a scan station would
help). The image is the one `./lfprobe render` writes for the same camera JSON.

The viewport refines progressively in a worker thread (viewport.py) and draws the latest
level as a texture, sRGB-encoded here (the scene's view transform is not applied to it).
"""

from __future__ import annotations

import json
import traceback

import bpy
import numpy as np

from ...core import estimates
from ...core.colour import srgb_display_rgba
from ...core.errors import InputError
from .. import probe_view
from .viewport import ProgressiveView

TRACE_PASSES = (("LFP Status", "status"), ("LFP Probe", "probe"), ("LFP Steps", "steps"),
                ("LFP Guessed", "guessed"))


def _to_bottom_up(array: np.ndarray, channels: int) -> np.ndarray:
    """A native image (top row first) as a render pass's rect (bottom row first, (h·w, c))."""
    flipped = np.ascontiguousarray(array[::-1], dtype=np.float32)
    return flipped.reshape(-1, channels)


def _set_pass(render_pass, rows: np.ndarray) -> None:
    """Copies (h·w, c) float32 rows into a render pass in one call: foreach_set takes the rows
    as they are in Blender 3.4 and flat in Blender 4+; assigning `rect` walks the pixels one by
    one from Python (0.58 s for 960×540 RGBA, against 2 ms)."""
    for values in (rows, rows.reshape(-1)):
        try:
            render_pass.rect.foreach_set(values)
            return
        except (TypeError, AttributeError):
            continue
    render_pass.rect = rows


_last_drawn_view = [None]  # the ProgressiveView a viewport drew last (for viewport_stats)


def viewport_stats():
    """Refinement timings (viewport.RefineStats) of the viewport drawn last, or None: what
    tools/screenshots.py reports as the viewport's refinement speed."""
    view = _last_drawn_view[0]
    return view.stats() if view is not None else None


class LFProbeRenderEngine(bpy.types.RenderEngine):
    bl_idname = "LFPROBE"
    bl_label = "Light Field Probes"
    bl_use_preview = False
    bl_use_eevee_viewport = True  # Material Preview shading stays EEVEE's

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._view = None
        self._texture = None
        self._texture_image = None
        self._view_error = None

    def __del__(self):
        view = getattr(self, "_view", None)
        if view is not None:
            view.stop()
            if _last_drawn_view[0] is view:
                _last_drawn_view[0] = None

    # F12 ------------------------------------------------------------------------------

    def update_render_passes(self, scene=None, renderlayer=None):
        self.register_pass(scene, renderlayer, "Combined", 4, "RGBA", "COLOR")
        self.register_pass(scene, renderlayer, "Depth", 1, "Z", "VALUE")
        for name, _key in TRACE_PASSES:
            self.register_pass(scene, renderlayer, name, 1, "X", "VALUE")

    def render(self, depsgraph):
        scene = depsgraph.scene
        try:
            image = self._trace_frame(scene, depsgraph)
        except InputError as error:
            self._fail(str(error))
            return
        except Exception as error:  # a native error, or a bug: reported, never raised into Blender
            traceback.print_exc()
            self._fail(f"{type(error).__name__}: {error}")
            return
        self._write_result(depsgraph, image)

    def _trace_frame(self, scene, depsgraph):
        target = probe_view.trace_target(scene, depsgraph=depsgraph)
        self.update_stats("", f"Light Field Probes: loading {target.grid_name}")
        field = target.load_field()
        if self.test_break():
            return None
        width, height = target.camera["resolution"]
        self.update_stats("", f"Light Field Probes: tracing {width}×{height} through {field.probe_count} probes")
        # In the background, so that Esc (test_break) stops the trace mid-frame.
        job = field.start_render(json.dumps(target.camera), spp=target.spp, **target.trace)
        while not job.wait(0.1):
            if self.test_break():
                job.cancel()
                job.wait()
                return None
            self.update_progress(job.fraction)
        image, stats = job.result()
        estimates.record_render_rate(stats["rays_per_second"])  # the next F12's time estimate
        pixels = max(int(stats["hits"] + stats["misses"] + stats["unknown"]), 1)
        self.update_stats("", f"Light Field Probes: {stats['seconds'] * 1000:.0f} ms, "
                              f"{stats['rays_per_second'] / 1e6:.2f} M rays/s, HIT {100 * stats['hits'] / pixels:.1f}%"
                              + (f" (guessed {100 * stats['guessed'] / pixels:.1f}%: see LFP Guessed)"
                                 if stats.get("guessed") else ""))
        return image

    def _write_result(self, depsgraph, image) -> None:
        if image is None:
            return
        height, width = image["rgba"].shape[:2]
        layer_name = depsgraph.view_layer.name
        for name, _key in TRACE_PASSES:
            self.add_pass(name, 1, "X", layer=layer_name)
        if not depsgraph.view_layer.use_pass_z:
            self.add_pass("Depth", 1, "Z", layer=layer_name)
        result = self.begin_result(0, 0, width, height, layer=layer_name)
        try:
            layer = result.layers[0]
            _set_pass(layer.passes["Combined"], _to_bottom_up(image["rgba"], 4))
            _set_pass(layer.passes["Depth"], _to_bottom_up(image["depth"], 1))
            for name, key in TRACE_PASSES:
                _set_pass(layer.passes[name], _to_bottom_up(image[key].astype(np.float32), 1))
        finally:
            self.end_result(result)

    def _fail(self, message: str) -> None:
        self.report({"ERROR"}, f"Light Field Probes: {message}")
        if hasattr(self, "error_set"):
            self.error_set(f"Light Field Probes: {message}")
        self.update_stats("", f"Light Field Probes: {message}")

    # Viewport ---------------------------------------------------------------------------

    def view_update(self, context, depsgraph):
        # A changed grid (moved, re-baked) shows through the draw's request key; nothing here
        # needs the depsgraph, but the redraw tells view_draw to look again.
        self.tag_redraw()

    def view_draw(self, context, depsgraph):
        scene = depsgraph.scene
        region, region_data = context.region, context.region_data
        width, height = region.width, region.height
        if self._view is None:
            self._view = ProgressiveView(self.tag_redraw)
        try:
            self._request_view(scene, region_data, width, height)
            self._view_error = None
        except InputError as error:
            self._view_error = str(error)
        message = self._view_error or self._view.error()
        if message:
            self.update_stats("", f"Light Field Probes: {message}")
            return
        latest = self._view.latest()
        if latest is None:
            return
        _last_drawn_view[0] = self._view
        self._draw_image(scene, latest, width, height)
        timings = self._view.stats().levels
        if timings:
            last = timings[-1]
            state = "done" if latest.final else "refining"
            self.update_stats("", f"Light Field Probes: {state}, 1/{last.level} size in "
                                  f"{last.since_request * 1000:.0f} ms")

    def _request_view(self, scene, region_data, width, height) -> None:
        target = probe_view.trace_target(scene, viewport=(region_data, width, height))
        field = target.load_field()
        key = (json.dumps(target.camera, sort_keys=True), id(field), tuple(sorted(target.trace.items())))
        self._view.request(field, target.camera, width, height, target.trace, key)

    def _draw_image(self, scene, view_image, width, height) -> None:
        import gpu
        from gpu_extras.presets import draw_texture_2d

        if self._texture_image is not view_image:
            # Bottom row first, as a GPU texture is filled.
            pixels = np.ascontiguousarray(srgb_display_rgba(view_image.rgba)[::-1])
            h, w = pixels.shape[:2]
            buffer = gpu.types.Buffer("FLOAT", w * h * 4, pixels.ravel())
            self._texture = gpu.types.GPUTexture((w, h), format="RGBA16F", data=buffer)
            self._texture_image = view_image
        gpu.state.blend_set("ALPHA_PREMULT")
        draw_texture_2d(self._texture, (0, 0), width, height)
        gpu.state.blend_set("NONE")
