"""Scan clouds in the viewport: each scan object's display subsample drawn as points in the
scan's own colours, in every shading mode and in both Blender versions (Blender 3.4's solid
mode cannot colour point clouds by attribute, and its EEVEE does not draw them). The Geometry
Nodes points stay for final renders (Cycles, EEVEE Next); overlay.register() registers this."""

from __future__ import annotations

import bpy
import numpy as np

from ...core.colour import srgb_encode
from ..properties import COLOR_ATTRIBUTE
from .draw_handler import ViewportDrawHandler

POINT_SIZE = 2.0

_batch_cache: dict = {}


def display_arrays(obj):
    """(positions (n, 3) float32 in the object's frame, sRGB-encoded RGBA (n, 4) float32): the
    viewport draws in display space, the attribute holds linear colour."""
    mesh = obj.data
    n = len(mesh.vertices)
    positions = np.empty(n * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", positions)
    colours = np.ones(n * 4, dtype=np.float32)
    attribute = mesh.attributes.get(COLOR_ATTRIBUTE)
    if attribute is not None and attribute.data_type == "FLOAT_COLOR" and attribute.domain == "POINT":
        attribute.data.foreach_get("color", colours)
    colours = colours.reshape(n, 4)
    colours[:, :3] = srgb_encode(colours[:, :3], dtype=np.float32)
    return positions.reshape(n, 3), colours


def _shader():
    import gpu

    for name in ("POINT_FLAT_COLOR", "3D_FLAT_COLOR"):  # 4.x/5.x, then 3.4
        try:
            return gpu.shader.from_builtin(name)
        except ValueError:
            continue
    raise RuntimeError("no builtin flat-colour point shader in this Blender")


def _batch(obj):
    from gpu_extras.batch import batch_for_shader

    mesh = obj.data
    key = (mesh.name, len(mesh.vertices), obj.lfprobe_scan.display_count)
    cached = _batch_cache.get(obj.name)
    if cached is not None and cached[0] == key:
        return cached[1]
    positions, colours = display_arrays(obj)
    shader = _shader()
    batch = (shader, batch_for_shader(shader, "POINTS", {"pos": positions, "color": colours}))
    _batch_cache[obj.name] = (key, batch)
    return batch


def _draw():
    import gpu

    scene = getattr(bpy.context, "scene", None)
    if scene is None:
        return
    space = getattr(bpy.context, "space_data", None)
    shading = getattr(space, "shading", None)
    if shading is not None and shading.type == "RENDERED" and scene.render.engine == "LFPROBE":
        return  # the trace through the probes is the picture; the cloud would cover it
    scans = [o for o in scene.objects if o.type == "MESH" and o.lfprobe_scan.is_scan and o.visible_get()]
    if not scans:
        return
    gpu.state.depth_test_set("LESS_EQUAL")
    gpu.state.depth_mask_set(True)
    gpu.state.point_size_set(POINT_SIZE)
    try:
        for obj in scans:
            shader, batch = _batch(obj)
            with gpu.matrix.push_pop():
                gpu.matrix.multiply_matrix(obj.matrix_world)
                shader.bind()
                batch.draw(shader)
    finally:
        gpu.state.point_size_set(1.0)
        gpu.state.depth_mask_set(False)
        gpu.state.depth_test_set("NONE")


_draw_handler = ViewportDrawHandler(_draw)


def register():
    _draw_handler.add()


def unregister():
    _draw_handler.remove()
    _batch_cache.clear()
