"""The render engine "Light Field Probes" (render_engine.py: F12 and the Rendered viewport,
which refines progressively through viewport.py), registered with its scene settings
(properties/render_settings.py) and its Render panel (ui/render_panel.py)."""

from __future__ import annotations

import bpy
from bpy.props import PointerProperty

from ...core.trace_target import forget_fields
from ..properties.render_settings import LFProbeRenderSettings
from .render_engine import TRACE_PASSES, LFProbeRenderEngine, viewport_stats  # noqa: F401  (the engine's names)
from ..ui.render_panel import RENDER_PT_lfprobe_trace

# Blender's own panels that apply to any engine (output, dimensions, camera lens, ...) list
# the engines they show for, with "BLENDER_RENDER" standing for external engines.
_SHARED_PANEL_EXCLUDE = {"RENDER_PT_color_management", "RENDER_PT_simplify"}


def _shared_panels():
    for panel in bpy.types.Panel.__subclasses__():
        engines = getattr(panel, "COMPAT_ENGINES", None)
        if engines is not None and "BLENDER_RENDER" in engines and panel.__name__ not in _SHARED_PANEL_EXCLUDE:
            yield panel


_CLASSES = (LFProbeRenderSettings, LFProbeRenderEngine, RENDER_PT_lfprobe_trace)


_register_classes, _unregister_classes = bpy.utils.register_classes_factory(_CLASSES)


def register():
    _register_classes()
    bpy.types.Scene.lfprobe_render = PointerProperty(type=LFProbeRenderSettings)
    for panel in _shared_panels():
        panel.COMPAT_ENGINES.add(LFProbeRenderEngine.bl_idname)


def unregister():
    for panel in _shared_panels():
        panel.COMPAT_ENGINES.discard(LFProbeRenderEngine.bl_idname)
    del bpy.types.Scene.lfprobe_render
    _unregister_classes()
    forget_fields()
