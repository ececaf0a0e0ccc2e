"""The render engine's panel in the Render properties: the scene's trace settings."""

from __future__ import annotations

import bpy

from ...core import estimates
from .. import grid as grid_module
from ..engine.render_engine import LFProbeRenderEngine


class RENDER_PT_lfprobe_trace(bpy.types.Panel):
    bl_label = "Light Field Probes"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"
    COMPAT_ENGINES = {LFProbeRenderEngine.bl_idname}

    @classmethod
    def poll(cls, context):
        return context.engine in cls.COMPAT_ENGINES

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        settings = context.scene.lfprobe_render
        layout.prop(settings, "grid")
        if settings.grid is None:
            baked = grid_module.baked_grids(context.scene)
            layout.label(text=f"Tracing: {baked[0].name}" if baked else "No baked probe grid",
                         icon="INFO" if baked else "ERROR")
        layout.prop(settings, "mode")
        layout.prop(settings, "thickness")
        layout.prop(settings, "fallback_thickness")
        layout.prop(settings, "samples")
        layout.prop(settings, "radiance_filter")
        layout.prop(settings, "blend")
        layout.prop(settings, "fill_holes")
        layout.prop(settings, "threads")
        render = context.scene.render
        text, warn = estimates.render_time_text(render.resolution_x, render.resolution_y,
                                                render.resolution_percentage, settings.samples)
        for n, line in enumerate(text.split("\n")):  # a panel's labels do not wrap
            layout.label(text=line, icon=("ERROR" if warn else "INFO") if n == 0 else "NONE")
        if warn:
            layout.label(text="Lower the resolution % or Pixel Samples")
            layout.label(text="for a quicker preview")
