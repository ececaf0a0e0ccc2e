"""Probe grids, placed like EEVEE's irradiance volumes: an Empty whose cube [-1, 1]^3,
moved and scaled (never rotated), is the grid's box; the corner probes sit on its corners.
Operators add a grid, fit it to a scan cloud, and edit its list of sources."""

import math
import os

import bpy
import numpy as np
from bpy.props import FloatProperty, IntProperty
from mathutils import Vector

from ..core import native
from ..core.errors import InputError
from .menu_registration import classes_with_menu_entry


ROTATION_TOLERANCE = 1e-6


class GridError(InputError):
    """A grid that cannot be baked or drawn as it is (the message says why)."""


def is_grid(obj) -> bool:
    return obj is not None and obj.type == "EMPTY" and obj.lfprobe_grid.is_grid


def grid_box(obj) -> tuple:
    """(min corner, max corner) of the grid's box in Blender's frame. Raises GridError for a
    rotated grid (the probes' maps are axis-aligned) or a flat one."""
    matrix = obj.matrix_world
    location, rotation, scale = matrix.decompose()
    angle = rotation.to_axis_angle()[1]
    if abs(angle) > ROTATION_TOLERANCE:
        raise GridError(
            f"grid {obj.name!r} is rotated by {math.degrees(angle):.3g}°: probe grids must stay "
            "axis-aligned (clear its rotation, Alt+R)"
        )
    low = np.array([location[i] - abs(scale[i]) for i in range(3)], dtype=float)
    high = np.array([location[i] + abs(scale[i]) for i in range(3)], dtype=float)
    counts = tuple(obj.lfprobe_grid.counts)
    for axis in range(3):
        if high[axis] - low[axis] <= 0 and counts[axis] > 1:
            raise GridError(f"grid {obj.name!r} has zero size along {'XYZ'[axis]} but {counts[axis]} probes there")
    return low, high


def probe_positions(obj) -> np.ndarray:
    """The probes of the grid in Blender's frame, x fastest then y then z, where the bake puts
    them (the native core's computation)."""
    low, high = grid_box(obj)
    counts = [int(c) for c in obj.lfprobe_grid.counts]
    return native.load().grid_positions([float(v) for v in low], [float(v) for v in high], counts)


def default_probe_dir(obj) -> str:
    return f"//{bpy.path.clean_name(obj.name)}_probes"


def probe_dir_abspath(grid_obj) -> str:
    """The grid's probe folder as an absolute path ("//" is the folder of the .blend)."""
    path = grid_obj.lfprobe_grid.probe_dir or default_probe_dir(grid_obj)
    return os.path.normpath(bpy.path.abspath(path))


def baked_grids(scene) -> list:
    """The scene's grids that have a finished probe set, in name order."""
    return sorted(
        (obj for obj in scene.objects if is_grid(obj) and obj.lfprobe_grid.baked),
        key=lambda obj: obj.name,
    )


def counts_for_spacing(size, spacing: float) -> tuple:
    """Probes per axis so that neighbours are at most `spacing` apart (at least one per axis)."""
    return tuple(max(1, int(math.ceil(float(s) / spacing - 1e-9)) + 1) if s > 0 else 1 for s in size)


def _active_grid(context):
    obj = context.active_object
    return obj if is_grid(obj) else None


class LFPROBE_OT_grid_add(bpy.types.Operator):
    """Add a light field probe grid (an Empty whose box sets the extent)"""

    bl_idname = "object.lfprobe_grid_add"
    bl_label = "Light Field Probe Grid"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        obj = bpy.data.objects.new("ProbeGrid", None)
        obj.empty_display_type = "CUBE"
        obj.empty_display_size = 1.0
        obj.location = context.scene.cursor.location
        (context.collection or context.scene.collection).objects.link(obj)
        grid = obj.lfprobe_grid
        grid.is_grid = True
        grid.probe_dir = default_probe_dir(obj)
        # Bake from the selected scan clouds, as a start.
        for candidate in context.selected_objects:
            if candidate.type == "MESH" and candidate.lfprobe_scan.is_scan:
                grid.sources.add().obj = candidate
        for other in context.view_layer.objects:
            other.select_set(False)
        obj.select_set(True)
        context.view_layer.objects.active = obj
        return {"FINISHED"}


class LFPROBE_OT_grid_fit(bpy.types.Operator):
    """Fit the active probe grid to the full bounds of a scan cloud (the grid's first scan
    source, else the selected scan cloud) and choose its counts from a spacing"""

    bl_idname = "object.lfprobe_grid_fit"
    bl_label = "Fit Grid to Scan"
    bl_options = {"REGISTER", "UNDO"}

    margin: FloatProperty(
        name="Margin",
        description="Keep the probes this far inside the cloud's bounds (walls are not good probe places)",
        min=0.0,
        default=0.25,
        unit="LENGTH",
    )
    spacing: FloatProperty(
        name="Spacing",
        description="Largest distance between neighbouring probes (0 keeps the counts)",
        min=0.0,
        default=1.0,
        unit="LENGTH",
    )

    @classmethod
    def poll(cls, context):
        return _active_grid(context) is not None

    def _scan(self, context, grid_obj):
        for source in grid_obj.lfprobe_grid.sources:
            if source.obj is not None and source.obj.lfprobe_scan.is_scan:
                return source.obj
        for obj in context.selected_objects:
            if obj.type == "MESH" and obj.lfprobe_scan.is_scan:
                return obj
        return None

    def execute(self, context):
        grid_obj = _active_grid(context)
        scan = self._scan(context, grid_obj)
        if scan is None:
            self.report({"ERROR"}, f"Fit grid: {grid_obj.name!r} has no scan cloud source and none is selected")
            return {"CANCELLED"}
        props = scan.lfprobe_scan
        matrix = scan.matrix_world
        corners = np.array(
            [matrix @ Vector((x, y, z))
             for x in (props.bounds_min[0], props.bounds_max[0])
             for y in (props.bounds_min[1], props.bounds_max[1])
             for z in (props.bounds_min[2], props.bounds_max[2])],
            dtype=float,
        )
        low, high = corners.min(axis=0) + self.margin, corners.max(axis=0) - self.margin
        centre = (corners.min(axis=0) + corners.max(axis=0)) / 2
        # A margin larger than half the cloud collapses that axis onto its centre.
        low, high = np.where(low < high, low, centre), np.where(low < high, high, centre)
        grid_obj.rotation_euler = (0.0, 0.0, 0.0)
        if grid_obj.rotation_mode == "QUATERNION":
            grid_obj.rotation_quaternion = (1.0, 0.0, 0.0, 0.0)
        grid_obj.location = tuple((low + high) / 2)
        grid_obj.scale = tuple(np.maximum((high - low) / 2, 1e-4))
        if self.spacing > 0:
            grid_obj.lfprobe_grid.counts = counts_for_spacing(high - low, self.spacing)
        if not any(s.obj == scan for s in grid_obj.lfprobe_grid.sources):
            grid_obj.lfprobe_grid.sources.add().obj = scan
        counts = tuple(grid_obj.lfprobe_grid.counts)
        self.report({"INFO"}, f"Grid {grid_obj.name!r} fitted to {scan.name!r}: {counts[0]}×{counts[1]}×{counts[2]} probes")
        return {"FINISHED"}


class LFPROBE_OT_grid_source_add(bpy.types.Operator):
    """Add the selected scan clouds and meshes to the active grid's sources"""

    bl_idname = "object.lfprobe_grid_source_add"
    bl_label = "Add Selected as Sources"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _active_grid(context) is not None

    def execute(self, context):
        grid = _active_grid(context).lfprobe_grid
        present = {s.obj for s in grid.sources}
        added = 0
        for obj in context.selected_objects:
            if obj.type == "MESH" and obj not in present:
                grid.sources.add().obj = obj
                added += 1
        if not added:
            self.report({"WARNING"}, "Select scan clouds or meshes (besides the grid) to add them as sources")
            return {"CANCELLED"}
        return {"FINISHED"}


class LFPROBE_OT_grid_source_remove(bpy.types.Operator):
    """Remove the highlighted source from the active grid"""

    bl_idname = "object.lfprobe_grid_source_remove"
    bl_label = "Remove Source"
    bl_options = {"REGISTER", "UNDO"}

    index: IntProperty(default=-1, options={"SKIP_SAVE"})

    @classmethod
    def poll(cls, context):
        grid_obj = _active_grid(context)
        return grid_obj is not None and len(grid_obj.lfprobe_grid.sources) > 0

    def execute(self, context):
        grid = _active_grid(context).lfprobe_grid
        index = self.index if self.index >= 0 else grid.active_source_index
        if not 0 <= index < len(grid.sources):
            return {"CANCELLED"}
        grid.sources.remove(index)
        grid.active_source_index = min(index, len(grid.sources) - 1)
        return {"FINISHED"}


def icon(*names: str) -> str:
    """The first of `names` that this Blender has (4.1 renamed the light probe icons)."""
    known = bpy.types.UILayout.bl_rna.functions["operator"].parameters["icon"].enum_items.keys()
    return next((name for name in names if name in known), "NONE")


def _menu_add(self, _context):
    self.layout.operator(LFPROBE_OT_grid_add.bl_idname, icon=icon("LIGHTPROBE_VOLUME", "LIGHTPROBE_GRID"))


_CLASSES = (LFPROBE_OT_grid_add, LFPROBE_OT_grid_fit, LFPROBE_OT_grid_source_add, LFPROBE_OT_grid_source_remove)


register, unregister = classes_with_menu_entry(_CLASSES, "VIEW3D_MT_add", _menu_add)
