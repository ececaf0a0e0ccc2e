"""The scene's trace settings (``scene.lfprobe_render``): which baked grid F12, the viewport
and Compare trace, and how (probe order, thickness and fallback, samples, filter, blending,
threads)."""

from __future__ import annotations

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, PointerProperty

from ...core import defaults
from .. import grid as grid_module


def _grid_poll(_settings, obj):
    return grid_module.is_grid(obj)


def _redraw_viewports(_settings, context):
    # Trace settings are not part of the depsgraph: tag the views so that they refine again.
    for area in getattr(context.screen, "areas", ()):
        if area.type == "VIEW_3D":
            area.tag_redraw()


class LFProbeRenderSettings(bpy.types.PropertyGroup):
    grid: PointerProperty(
        name="Probe Grid",
        type=bpy.types.Object,
        poll=_grid_poll,
        description="The baked probe grid to trace (empty: the first baked grid, by name)",
        update=_redraw_viewports,
    )
    mode: EnumProperty(
        name="Probe Order",
        items=(
            ("auto", "Auto", "Walk the grid's cells for a grid set, nearest probes first otherwise"),
            ("nearest", "Nearest", "Try the probes nearest the ray first"),
            ("grid", "Grid Walk", "Walk the cells the ray crosses (3D DDA) and try their corner probes"),
        ),
        default=defaults.trace("mode"),
        update=_redraw_viewports,
    )
    thickness: FloatProperty(
        name="Thickness",
        description="How far behind the surface a probe saw a ray still counts as hitting it",
        min=0.0,
        soft_max=0.2,
        default=defaults.trace("thickness"),
        unit="LENGTH",
        precision=3,
        update=_redraw_viewports,
    )
    fallback_thickness: FloatProperty(
        name="Fallback",
        description="A ray that no probe answers meets the surface it stopped behind if it came this "
                    "close to it: a near object's edge that one scan station saw (at most the "
                    "Thickness: never)",
        min=0.0,
        soft_max=0.2,
        default=defaults.trace("fallback_thickness"),
        unit="LENGTH",
        precision=3,
        update=_redraw_viewports,
    )
    threads: IntProperty(
        name="Threads",
        description="CPU cores to trace with (0: all); the image is the same for any count",
        min=0,
        soft_max=64,
        default=0,
        update=_redraw_viewports,
    )
    samples: IntProperty(
        name="Pixel Samples",
        description="F12 and Compare: n×n rays per pixel on a stratified grid, their colour and coverage "
                    "averaged (anti-aliasing; depth and passes from the pixel centre). 1: one ray through "
                    "each pixel centre. The viewport traces one ray per pixel",
        min=1,
        max=8,
        default=2,
    )
    radiance_filter: EnumProperty(
        name="Radiance Filter",
        items=(
            ("bilinear", "Bilinear", "Interpolate between the texels around a hit that lie on the same surface"),
            ("nearest", "Nearest", "The colour of the one texel the ray met (the paper's lookup)"),
            ("footprint", "Footprint",
             "As bilinear, and where a pixel spans several texels, the probe's prefiltered radiance at the "
             "pixel's width: anti-aliases one ray per pixel, as texture LOD does"),
            ("bicubic", "Bicubic",
             "Catmull-Rom over the 4×4 texels around a hit where all lie on its surface, else bilinear: "
             "sharper than bilinear, which blurs texels that already average their footprint"),
        ),
        default=defaults.trace("filter"),
        update=_redraw_viewports,
    )
    blend: IntProperty(
        name="Blend Probes",
        description="Probes a hit's colour is blended from, each weighted by how finely it sees the point "
                    "(1: the first probe that answers alone)",
        min=1,
        max=8,
        default=defaults.trace("blend"),
        update=_redraw_viewports,
    )
    fill_holes: BoolProperty(
        name="Fill Holes",
        description="Colour holes of pixels that no probe could answer (UNKNOWN) from the pixels around "
                    "them, up to 5% of the image's width across; wider unknown regions stay black, and "
                    "the UNKNOWN pass still marks every such pixel. Off: UNKNOWN pixels are black",
        default=True,
        update=_redraw_viewports,
    )
