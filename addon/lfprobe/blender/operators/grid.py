"""Probe grid operators: add a grid (Add menu), fit it to a scan cloud, add and remove its
scan sources."""

import bpy
from bpy.props import FloatProperty, IntProperty
from mathutils import Vector

from ...core.grid_fit import FIT_MARGIN, FIT_SPACING, box_location_and_scale, counts_for_spacing, fitted_box
from ..grid import is_grid, new_grid_id
from .menu_registration import classes_with_menu_entry


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
        grid.grid_id = new_grid_id()  # the probe folder stays the default until the first bake
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
        default=FIT_MARGIN,
        unit="LENGTH",
    )
    spacing: FloatProperty(
        name="Spacing",
        description="Largest distance between neighbouring probes (0 keeps the counts)",
        min=0.0,
        default=FIT_SPACING,
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
        corners = [matrix @ Vector((x, y, z))
                   for x in (props.bounds_min[0], props.bounds_max[0])
                   for y in (props.bounds_min[1], props.bounds_max[1])
                   for z in (props.bounds_min[2], props.bounds_max[2])]
        low, high = fitted_box(corners, self.margin)
        grid_obj.rotation_euler = (0.0, 0.0, 0.0)
        if grid_obj.rotation_mode == "QUATERNION":
            grid_obj.rotation_quaternion = (1.0, 0.0, 0.0, 0.0)
        grid_obj.location, grid_obj.scale = box_location_and_scale(low, high)
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
