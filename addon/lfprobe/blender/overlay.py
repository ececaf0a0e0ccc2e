"""The viewport overlay of probe grids: each probe as a point coloured by its coverage after
baking (green: every direction measured, red: mostly unknown; grey before baking; planned
probes moved blue, dropped black; probes added for views magenta) and the grid's cell lines,
drawn over the scene (the probes sit inside rooms, behind the walls).
register() also starts the coloured drawing of scan clouds (scan_display). The geometry is plain numpy (testable headless); drawing uses only the
gpu module calls that Blender 3.4 and 5.x share, with builtin shader names picked at run time."""

from __future__ import annotations

import bpy
import numpy as np

from . import grid as grid_module
from . import scan_display
from .draw_handler import ViewportDrawHandler

UNBAKED_COLOUR = (0.75, 0.75, 0.75, 1.0)
LINE_COLOUR = (0.55, 0.75, 1.0, 0.35)
POINT_SIZE = 8.0

_batch_cache: dict = {}


def coverage_colours(coverage: list, probe_count: int) -> np.ndarray:
    """RGBA per probe: from red (nothing known) to green (every direction surface, inferred or
    empty); grey when there is no coverage for each probe."""
    colours = np.tile(np.asarray(UNBAKED_COLOUR, dtype=np.float32), (probe_count, 1))
    if len(coverage) != probe_count:
        return colours
    unknown = np.array([float(c.get("unknown", 1.0)) for c in coverage], dtype=np.float32)
    known = np.clip(1.0 - unknown, 0.0, 1.0)
    colours[:, 0] = 1.0 - known
    colours[:, 1] = known
    colours[:, 2] = 0.1
    return colours


# Planned probes (Plan From Data) by what the plan found: moved ones and dropped ones stand
# out from the coverage colours of the probes kept where they were.
MOVED_COLOUR = (0.2, 0.6, 1.0, 1.0)
DROPPED_COLOUR = (0.15, 0.15, 0.15, 1.0)


def plan_colours(colours: np.ndarray, plan: list) -> np.ndarray:
    """Coverage colours with moved probes in blue and dropped probes in near-black."""
    if len(plan) != len(colours):
        return colours
    out = colours.copy()
    for i, probe in enumerate(plan):
        if probe.get("dropped"):
            out[i] = DROPPED_COLOUR
        elif probe.get("moved"):
            out[i] = MOVED_COLOUR
    return out


# Probes that Add Probes for Views put at the eyes of views (place_views.py): not on the grid,
# and in none of the coverage colours (whose blue stays low) nor the plan's.
ADDED_COLOUR = (1.0, 0.2, 1.0, 1.0)


def added_probes(obj) -> np.ndarray:
    """Positions (n, 3) in Blender's frame of the probes added for views, from the grid's
    placement record."""
    added = obj.lfprobe_grid.placement().get("added", [])
    return np.array([a["position"] for a in added], dtype=np.float64).reshape(-1, 3)


def cell_lines(obj) -> np.ndarray:
    """Line segment end points (2k, 3) of the grid's cells: every row of probes along each axis."""
    positions = grid_module.probe_positions(obj)
    nx, ny, nz = (int(c) for c in obj.lfprobe_grid.counts)
    lattice = positions.reshape(nz, ny, nx, 3)
    segments = []
    if nx > 1:
        segments.append(np.stack([lattice[:, :, 0], lattice[:, :, -1]], axis=-2).reshape(-1, 3))
    if ny > 1:
        segments.append(np.stack([lattice[:, 0, :], lattice[:, -1, :]], axis=-2).reshape(-1, 3))
    if nz > 1:
        segments.append(np.stack([lattice[0], lattice[-1]], axis=-2).reshape(-1, 3))
    return np.concatenate(segments) if segments else np.zeros((0, 3))


def overlay_geometry(obj):
    """(probe positions (n, 3), probe colours (n, 4), line end points (2k, 3)) as float32: the
    grid's probes first, then the probes added for views."""
    positions = grid_module.probe_positions(obj)
    colours = plan_colours(coverage_colours(obj.lfprobe_grid.coverage(), len(positions)),
                           obj.lfprobe_grid.plan())
    added = added_probes(obj)
    positions = np.concatenate([positions, added])
    colours = np.concatenate([colours, np.tile(np.asarray(ADDED_COLOUR, dtype=np.float32), (len(added), 1))])
    return positions.astype(np.float32), colours.astype(np.float32), cell_lines(obj).astype(np.float32)


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
