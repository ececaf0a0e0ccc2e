"""The render engine's panel in the Render properties: the scene's trace settings."""

from __future__ import annotations

import bpy

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
        layout.prop(settings, "samples")
        layout.prop(settings, "radiance_filter")
        layout.prop(settings, "blend")
        layout.prop(settings, "threads")
