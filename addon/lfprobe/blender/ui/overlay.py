"""The viewport overlay of probe grids: each probe as a point coloured by its coverage after
baking (green: every direction measured, red: mostly unknown; grey before baking; planned
probes moved blue, dropped black; probes added for views magenta) and the grid's cell lines,
drawn over the scene (the probes sit inside rooms, behind the walls).
register() also starts the coloured drawing of scan clouds (scan_display). The geometry comes from
core.grid_overlay (plain arrays, testable without Blender); drawing uses only the
gpu module calls that Blender 3.4 and 5.x share, with builtin shader names picked at run time."""

from __future__ import annotations

import bpy
import numpy as np

from ...core import grid_overlay
from .. import grid as grid_module
from . import scan_display
from .draw_handler import ViewportDrawHandler

LINE_COLOUR = (0.55, 0.75, 1.0, 0.35)
POINT_SIZE = 8.0

_batch_cache: dict = {}


def overlay_geometry(obj):
    """(probe positions (n, 3), probe colours (n, 4), line end points (2k, 3)) as float32 of a
    grid object (core.grid_overlay computes them from the grid's settings)."""
    grid = obj.lfprobe_grid
    return grid_overlay.overlay_geometry(grid_module.probe_positions(obj), tuple(grid.counts), grid.coverage(),
                                         grid.plan(), grid.placement())


def _builtin_shader(*names):
    import gpu

    for name in names:
        try:
            return gpu.shader.from_builtin(name)
        except ValueError:
            continue
    raise RuntimeError(f"none of the builtin shaders {names} exists in this Blender")


def _batches(obj):
    from gpu_extras.batch import batch_for_shader

    grid = obj.lfprobe_grid
    key = (tuple(map(tuple, obj.matrix_world)), tuple(grid.counts), grid.coverage_json, grid.plan_json,
           grid.placement_json)
    cached = _batch_cache.get(obj.name)
    if cached is not None and cached[0] == key:
        return cached[1]
    positions, colours, lines = overlay_geometry(obj)
    point_shader = _builtin_shader("POINT_FLAT_COLOR", "3D_FLAT_COLOR")
    line_shader = _builtin_shader("FLAT_COLOR", "3D_FLAT_COLOR")
    line_colours = np.tile(np.asarray(LINE_COLOUR, dtype=np.float32), (len(lines), 1))
    batches = (
        (point_shader, batch_for_shader(point_shader, "POINTS", {"pos": positions, "color": colours})),
        (line_shader, batch_for_shader(line_shader, "LINES", {"pos": lines, "color": line_colours})),
    )
    _batch_cache[obj.name] = (key, batches)
    return batches


def _draw():
    import gpu

    context = bpy.context
    scene = getattr(context, "scene", None)
    if scene is None:
        return
    grids = [obj for obj in scene.objects if grid_module.is_grid(obj) and obj.visible_get()]
    if not grids:
        return
    gpu.state.blend_set("ALPHA")
    gpu.state.depth_test_set("NONE")
    gpu.state.point_size_set(POINT_SIZE)
    try:
        for obj in grids:
            try:
                (point_shader, points), (line_shader, lines) = _batches(obj)
            except grid_module.GridError:
                continue  # a rotated grid: the panel says why; nothing sensible to draw
            line_shader.bind()
            lines.draw(line_shader)
            point_shader.bind()
            points.draw(point_shader)
    finally:
        gpu.state.point_size_set(1.0)
        gpu.state.blend_set("NONE")


_draw_handler = ViewportDrawHandler(_draw)


def is_drawing() -> bool:
    return _draw_handler.active


def register():
    scan_display.register()
    _draw_handler.add()


def unregister():
    _draw_handler.remove()
    _batch_cache.clear()
    scan_display.unregister()
