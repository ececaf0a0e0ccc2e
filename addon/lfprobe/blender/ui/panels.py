"""Object properties panels: a scan cloud's facts (points, world offset, files, scanners) and
a probe grid's settings, sources, probe folder and bake state (with the memory its set loads
into, and Apply Storage), with Add Probes for Views in a sub-panel."""

from __future__ import annotations

import os
import textwrap

import bpy

from ...core import estimates, native, probe_storage
from .. import grid as grid_module
from ..operators import place_views


def _native_problem(layout) -> None:
    """Says in the panel when the native module cannot load (the operators would fail)."""
    try:
        native.load()
    except native.NativeModuleError as error:
        column = layout.column(align=True)
        column.alert = True
        for line in textwrap.wrap(str(error), 60):
            column.label(text=line)


def _format_offset(offset) -> str:
    return ", ".join(f"{v:.6f}".rstrip("0").rstrip(".") for v in offset)


class LFPROBE_PT_scan(bpy.types.Panel):
    bl_label = "Scan Cloud"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "object"

    @classmethod
    def poll(cls, context):
        obj = context.object
        return obj is not None and obj.type == "MESH" and obj.lfprobe_scan.is_scan

    def draw(self, context):
        props = context.object.lfprobe_scan
        layout = self.layout
        _native_problem(layout)
        column = layout.column(align=True)
        column.label(text=f"Points: {props.point_count:,} ({props.display_count:,} displayed)")
        offset = props.offset()
        column.label(text=f"World offset: {_format_offset(offset)}")
        if any(offset):
            column.label(text="World = offset + Blender position (georeferenced)", icon="INFO")
        box = layout.box()
        box.label(text="Files")
        scanners = props.scanners()
        for index, path in enumerate(props.paths()):
            row = box.row()
            row.label(text=os.path.basename(path), icon="FILE" if os.path.isfile(path) else "ERROR")
            scanner = scanners[index] if index < len(scanners) else None
            row.label(text="scanner " + (_format_offset(scanner) if scanner is not None else "unknown"))


class LFPROBE_UL_grid_sources(bpy.types.UIList):
    def draw_item(self, _context, layout, _data, item, _icon, _active_data, _active_property, _index=0, _flt_flag=0):
        obj = item.obj
        if obj is None:
            layout.label(text="(empty)", icon="ERROR")
        else:
            layout.label(text=obj.name, icon="POINTCLOUD_DATA" if obj.lfprobe_scan.is_scan else "MESH_DATA")


def _draw_storage(layout, obj) -> None:
    """The baked set's memory as its manifest says it loads, and Apply Storage when that is
    not the grid's Storage (changed since the bake, or by ./lfprobe store)."""
    folder = grid_module.probe_dir_abspath(obj)
    facts = probe_storage.loaded_storage(folder)
    if facts is None:
        layout.label(text=f"No probe set in {folder}", icon="ERROR")
        return
    layout.label(text=f"Loads {probe_storage.memory_text(facts)}", icon="MEMORY")
    if not probe_storage.storage_matches(facts, *obj.lfprobe_grid.storage_choice()):
        layout.label(text=f"The set loads {facts['name']}, not as Storage says", icon="INFO")
        layout.operator("object.lfprobe_grid_apply_storage", icon="FILE_REFRESH").grid = obj.name


class _GridPanel:
    """Where a probe grid's panels live: the Object properties of a grid."""

    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "object"

    @classmethod
    def poll(cls, context):
        return grid_module.is_grid(context.object)


class LFPROBE_PT_grid(_GridPanel, bpy.types.Panel):
    bl_label = "Light Field Probe Grid"

    def draw(self, context):
        obj = context.object
        grid = obj.lfprobe_grid
        layout = self.layout
        _native_problem(layout)
        layout.use_property_split = True
        try:
            grid_module.grid_box(obj)
        except grid_module.GridError as error:
            layout.label(text=str(error), icon="ERROR")
        layout.prop(grid, "counts")
        layout.prop(grid, "resolution")
        layout.prop(grid, "coarse_resolution")
        layout.prop(grid, "storage")
        if grid.storage == "COMPACT":
            layout.prop(grid, "distance_step")
        layout.prop(grid, "plan_from_data")
        layout.label(text="Sources")
        row = layout.row()
        row.template_list("LFPROBE_UL_grid_sources", "", grid, "sources", grid, "active_source_index", rows=3)
        buttons = row.column(align=True)
        buttons.operator("object.lfprobe_grid_source_add", icon="ADD", text="")
        buttons.operator("object.lfprobe_grid_source_remove", icon="REMOVE", text="")
        layout.operator("object.lfprobe_grid_fit", icon="FULLSCREEN_ENTER")
        layout.prop(grid, "probe_dir")
        if not grid.probe_dir:
            layout.label(text=f"Default: {grid_module.default_probe_dir(obj)}", icon="FILE_FOLDER")
        layout.operator("object.lfprobe_bake", icon="RENDER_STILL").grid = obj.name
        bound = grid_module.bound_set(obj)
        # After an undo the grid's copy of the coverage may be gone; the set's manifest has it.
        coverage = grid.coverage() or [p.get("coverage", {}) for p in (bound.manifest or {}).get("probes", [])]
        if bound.problem:
            for line in textwrap.wrap(bound.problem, 70):
                layout.label(text=line, icon="ERROR")
        elif bound.manifest is not None and coverage:
            known = sum(1.0 - c.get("unknown", 1.0) for c in coverage) / len(coverage)
            layout.label(text=f"Baked: {len(coverage)} probes, {100 * known:.0f}% of directions known", icon="CHECKMARK")
            _draw_storage(layout, obj)
            plan = grid.plan()
            if plan:
                moved = sum(1 for p in plan if p.get("moved"))
                dropped = sum(1 for p in plan if p.get("dropped"))
                sizes = sorted({int(p.get("resolution", 0)) for p in plan if not p.get("dropped")})
                size_text = f"{sizes[0]}²–{sizes[-1]}²" if sizes else "none kept"
                layout.label(text=f"Plan: {moved} moved (blue), {dropped} dropped (black), maps {size_text}",
                             icon="INFO")
            placement = grid.placement()
            if placement:
                layout.label(text=place_views.summary_line(placement, colour="magenta"), icon="INFO")
            counts = tuple(grid.counts)
            if len(coverage) != counts[0] * counts[1] * counts[2]:
                layout.label(text="The counts changed since the bake: bake again", icon="INFO")
        else:
            layout.label(text="Not baked")
        _draw_bake_estimate(layout, grid)


def _draw_lines(layout, text: str, warn: bool, icon: bool = True) -> None:
    """One label per line of `text` (a panel's labels do not wrap), the first with an icon."""
    for n, line in enumerate(text.split("\n")):
        layout.label(text=line, icon=("ERROR" if warn else "INFO") if icon and n == 0 else "NONE")


def _draw_bake_estimate(layout, grid) -> None:
    """What the next Bake will hold in memory, with a warning when that is a lot."""
    storage, distance_step = grid.storage_choice()
    try:
        bytes_per_texel = int(native.load().probe_storage(storage, distance_step=distance_step)["bytes_per_texel"])
    except native.NativeModuleError:
        return
    text, warn = estimates.bake_memory_text(tuple(grid.counts), int(grid.resolution), bytes_per_texel, storage)
    if grid.plan_from_data:
        text += "\n(Plan From Data may use less)"
    _draw_lines(layout, text, warn)
    if warn:
        _draw_lines(layout, "Fewer probes, a lower Resolution\nor Compact storage use less", False, icon=False)
    estimate = grid.estimate()
    if estimate.get("counts") == list(grid.counts) and estimate.get("probes"):
        text, warn = estimates.coverage_estimate_text(estimate)
        _draw_lines(layout, text, warn)
        if warn:
            _draw_lines(layout, "Probes far from every scanner see little:\nfewer probes, nearer the stations",
                        False, icon=False)
    layout.operator("object.lfprobe_grid_estimate", icon="VIEWZOOM").grid = grid.id_data.name


class LFPROBE_PT_grid_views(_GridPanel, bpy.types.Panel):
    bl_label = "Probes for Views"
    bl_parent_id = "LFPROBE_PT_grid"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        obj = context.object
        grid = obj.lfprobe_grid
        layout = self.layout
        layout.use_property_split = True
        layout.prop(grid, "views_from")
        if grid.views_from == "CAMERA_PATH":
            layout.prop(grid, "frame_step")
        layout.prop(grid, "target_unknown")
        layout.prop(grid, "budget_mib")
        layout.prop(grid, "max_added")
        layout.operator("object.lfprobe_place_for_views", icon="OUTLINER_OB_CAMERA").grid = obj.name
        placement = grid.placement()
        if placement and grid_module.bound_set(obj).usable:
            layout.label(text=f"Stopped: {placement.get('stopped_because', '')}")


_CLASSES = (LFPROBE_PT_scan, LFPROBE_UL_grid_sources, LFPROBE_PT_grid, LFPROBE_PT_grid_views)


# Blender's own helper: registers in order, unregisters in reverse.
register, unregister = bpy.utils.register_classes_factory(_CLASSES)
