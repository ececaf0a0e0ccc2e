"""What a scene is traced through, gathered into a core TraceTarget (`trace_target`): which
baked grid, where its probe set lies, the frame offset between Blender and the probe set's
world, the camera and the render settings. The render engine (F12 and viewport), compare and
the batch CLI all start here; bpy is only read, never changed.
"""

from __future__ import annotations

import os

from ..core import defaults
from ..core.probe_set import read_manifest
from ..core.trace_target import TraceSetupError, TraceTarget, load_field  # noqa: F401  (importable here)
from . import camera_export
from . import grid as grid_module
from . import scan_object

MODES = ("auto", "nearest", "grid")


def render_settings(scene):
    return scene.lfprobe_render


def grid_to_trace(scene, name: str = ""):
    """The grid to trace: the one named, else the scene's lfprobe_render.grid, else the
    first baked grid (name order). Raises GridError when there is none."""
    if name:
        obj = scene.objects.get(name)
        if obj is None:
            raise grid_module.GridError(f"no object named '{name}' in scene '{scene.name}'")
        if not grid_module.is_grid(obj):
            raise grid_module.GridError(f"object '{name}' is not a light field probe grid")
        return obj
    chosen = render_settings(scene).grid
    if chosen is not None:
        if not grid_module.is_grid(chosen):
            raise grid_module.GridError(f"the render settings' grid '{chosen.name}' is not a light field probe grid")
        return chosen
    baked = grid_module.baked_grids(scene)
    if not baked:
        # A grid that was baked but whose set is gone or not its own: its own error says which.
        once_baked = sorted((obj for obj in scene.objects if grid_module.is_grid(obj)
                             and (obj.lfprobe_grid.baked or grid_module.bound_set(obj).problem)),
                            key=lambda obj: obj.name)
        if once_baked:
            return once_baked[0]
        raise grid_module.GridError(
            f"scene '{scene.name}' has no baked probe grid: add a probe grid "
            "(Add > Light Field Probe Grid) and bake it"
        )
    return baked[0]


def probe_folder(grid_obj) -> str:
    """The grid's probe set folder; raises TraceSetupError when no finished set baked for this
    grid is there."""
    folder = grid_module.probe_dir_abspath(grid_obj)
    if not os.path.isdir(folder):
        raise TraceSetupError(
            f"grid '{grid_obj.name}': its probe folder {folder} does not exist; bake the grid "
            "(or set its Probe Folder to a baked probe set)"
        )
    bound = grid_module.bound_set(grid_obj)
    if bound.manifest is None:
        try:
            read_manifest(folder)  # for the reason: missing, or not a probe set
        except (FileNotFoundError, ValueError) as error:
            raise TraceSetupError(f"grid '{grid_obj.name}': {error}; bake the grid again") from error
    if bound.problem:
        raise TraceSetupError(bound.problem)
    return folder


def frame_offset(scene, grid_obj=None) -> tuple:
    """World = offset + Blender position. The offset is the one of the grid's scan sources
    (the frame its probe set was baked in), else the scene's scan clouds', else zero."""
    if grid_obj is not None:
        for source in grid_obj.lfprobe_grid.sources:
            obj = source.obj
            if obj is not None and obj.type == "MESH" and obj.lfprobe_scan.is_scan:
                return obj.lfprobe_scan.offset()
    offset = scan_object.frame_offset(scene)
    return tuple(offset) if offset is not None else (0.0, 0.0, 0.0)


def coarse_resolution(grid_obj) -> int:
    """The grid's coarsest min-distance level kept when its probes are loaded (0: all)."""
    return int(grid_obj.lfprobe_grid.coarse_resolution) if grid_obj is not None else 0


def trace_settings(scene) -> dict:
    """The scene's trace settings as keyword arguments of ProbeField.render."""
    settings = render_settings(scene)
    return {"mode": settings.mode.lower(), "thickness": float(settings.thickness),
            "fallback_thickness": float(settings.fallback_thickness), "threads": int(settings.threads),
            "filter": settings.radiance_filter, "blend": int(settings.blend),
            "hole_fill": defaults.trace("hole_fill") if settings.fill_holes else 0}


def pixel_samples(scene) -> int:
    """Rays per pixel of a final render (F12, Compare, the batch render): the scene's n×n."""
    n = int(render_settings(scene).samples)
    return n * n


def trace_target(scene, grid_name: str = "", camera_obj=None, depsgraph=None, viewport=None) -> TraceTarget:
    """What tracing the scene takes: the grid named (else the render settings', else the first
    baked), its probe set, the frame offset, the camera (`camera_obj`, default the scene camera,
    evaluated in `depsgraph`; or the 3D view `viewport` = (region_data, width, height)) and the
    scene's trace settings. Raises GridError, TraceSetupError or CameraExportError."""
    grid_obj = grid_to_trace(scene, grid_name)
    folder = probe_folder(grid_obj)
    offset = frame_offset(scene, grid_obj)
    if viewport is not None:
        region_data, width, height = viewport
        camera = camera_export.viewport_camera_dict(region_data, width, height, offset)
    else:
        camera = camera_export.camera_dict(scene, camera_obj, offset, depsgraph=depsgraph)
    return TraceTarget(grid_name=grid_obj.name, folder=folder, coarse_resolution=coarse_resolution(grid_obj),
                       offset=tuple(offset), camera=camera, trace=trace_settings(scene), spp=pixel_samples(scene))
