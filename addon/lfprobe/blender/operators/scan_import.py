"""File › Import › Scan Cloud (.xyz, .pts, .ply, .e57, .las, .laz): reads one or several scans
off the main thread, with the native readers (through lfprobe's parse cache) or, for E57 and
LAS/LAZ, through core's loader (core/scan_formats.py), and makes scan cloud objects. An E57's
stations stay apart in the cloud (one scan per station, posed, its station the scanner); its
object holds them all and the bake reads the stations' poses from the file again."""

import os

import bpy
from bpy.props import BoolProperty, CollectionProperty, FloatProperty, IntProperty, StringProperty
from bpy_extras.io_utils import ImportHelper

from ...core import native, pipeline
from ...core.scan_formats import ALL_EXTENSIONS, is_library_format
from ...core.scan_merge import file_of_each_scan, loaded_with_records
from ...core.scan_points import automatic_point_radius, file_of_each_point, file_scanners, in_shared_frame, object_groups, object_points
from .. import preferences
from .. import scan_object
from .job_modal import NativeJobOperator, ThreadJob
from .menu_registration import classes_with_menu_entry

SCAN_EXTENSIONS = ALL_EXTENSIONS
def _world_scanner(scanner, offset):
    if scanner is None:
        return None
    return [float(s) + float(o) for s, o in zip(scanner, offset)]


class LFPROBE_OT_import_scan(NativeJobOperator, ImportHelper, bpy.types.Operator):
    """Import laser scan point clouds (.xyz, .pts, .ply, .e57, .las, .laz) as scan cloud objects"""

    bl_idname = "import_scene.lfprobe_scan"
    bl_label = "Import Scan Cloud"
    # PRESET: the file browser's preset menu keeps a user's Columns, Display Limit and the rest.
    bl_options = {"REGISTER", "UNDO", "PRESET"}
    job_label = "Scan import"

    filename_ext = ".xyz"
    filter_glob: StringProperty(default="*.xyz;*.pts;*.ply;*.txt;*.asc;*.csv;*.e57;*.las;*.laz", options={"HIDDEN"})
    files: CollectionProperty(type=bpy.types.OperatorFileListElement, options={"HIDDEN", "SKIP_SAVE"})
    directory: StringProperty(subtype="DIR_PATH", options={"HIDDEN", "SKIP_SAVE"})

    display_limit: IntProperty(
        name="Display Limit",
        description="Most points shown in the viewport; the full cloud stays available to the baker",
        min=1000,
        default=2_000_000,
    )
    separate_objects: BoolProperty(
        name="One Object per File", description="Make an object per scan file instead of one merged cloud"
    )
    point_radius: FloatProperty(
        name="Point Radius",
        description="Radius of the displayed points (0 = half the mean spacing of the displayed points)",
        min=0.0,
        default=0.0,
        unit="LENGTH",
    )
    columns: StringProperty(
        name="Columns",
        description='Column names of text scans, e.g. "x y z i r g b" (empty: from the header or the count)',
        default="",
    )

    def invoke(self, context, event):
        if self.directory and len(self.files) > 0:
            # Files dropped on the viewport (the FileHandler below): no file browser.
            return self.execute(context)
        return ImportHelper.invoke(self, context, event)

    def _paths(self) -> list:
        names = [f.name for f in self.files if f.name]
        if names:
            return [os.path.join(self.directory, name) for name in names]
        return [self.filepath] if self.filepath else []

    def execute(self, context):
        return self.run_job(context)

    def start_job(self, context):
        paths = [bpy.path.abspath(p) for p in self._paths()]
        if not paths:
            self.report({"ERROR"}, "Scan import: no file given")
            return None
        for path in paths:
            if not os.path.isfile(path):
                self.report({"ERROR"}, f"Scan import: {path}: no such file")
                return None
            if not path.lower().endswith(SCAN_EXTENSIONS):
                self.report(
                    {"ERROR"},
                    f"Scan import: {path}: not a scan file (expected {', '.join(SCAN_EXTENSIONS)})",
                )
                return None
        try:
            _native = native.load()
        except native.NativeModuleError as error:
            self.report({"ERROR"}, str(error))
            return None
        self._import_paths = paths
        cache = preferences.scan_cache_dir(context)  # read here: the job's thread must not touch bpy
        if any(is_library_format(p) for p in paths):
            columns = self.columns
            return ThreadJob(lambda report: pipeline.load_scans_and_sources(
                paths, columns=columns, cache_dir=cache, progress=report))
        return _native.start_load_scans(paths, columns=self.columns, cache_dir=cache)

    def finish_job(self, context, loaded):
        paths = self._import_paths
        cloud, records = loaded_with_records(loaded, paths)
        files = file_of_each_scan(records, paths)
        collection = context.collection or context.scene.collection
        positions, offset, too_far = in_shared_frame(cloud.positions, cloud.world_offset,
                                                     scan_object.frame_offset(context.scene))
        if too_far:
            self.report(
                {"WARNING"},
                f"{os.path.basename(paths[0])}: far from the other scans' frame; "
                f"it keeps its own world offset {tuple(offset)}",
            )
        colors = cloud.colors
        # One scanner per file: a file of several stations (an E57) keeps None, its own poses.
        scans = [{"scanner": s} for s in file_scanners(cloud.scans, files, len(paths))]
        scan_index = None
        if self.separate_objects and len(paths) > 1:
            scan_index = file_of_each_point(files, cloud.scan_index)
        groups = object_groups(paths, scans, len(positions), scan_index)
        created = []
        for group_paths, members, scanners in groups:
            created.append(
                self._make_object(collection, group_paths, members, positions, colors, scanners, cloud, offset)
            )
        for obj in context.view_layer.objects:
            obj.select_set(False)
        for obj in created:
            obj.select_set(True)
        context.view_layer.objects.active = created[-1]
        total = sum(o.lfprobe_scan.point_count for o in created)
        shown = sum(o.lfprobe_scan.display_count for o in created)
        self.report({"INFO"}, f"Imported {total:,} points from {len(paths)} file(s); {shown:,} displayed")
        return {"FINISHED"}

    def _make_object(self, collection, paths, members, positions, colors, scanners, cloud, offset):
        bounds, shown, shown_colors = object_points(positions, colors, members, self.display_limit)
        radius = self.point_radius or automatic_point_radius(*bounds, len(shown))
        # Scanners are in the cloud's own frame; the object's frame may be the scene's.
        cloud_offset = cloud.world_offset
        name = os.path.splitext(os.path.basename(paths[0]))[0] + (" +%d" % (len(paths) - 1) if len(paths) > 1 else "")
        return scan_object.build_scan_object(
            name,
            shown,
            shown_colors,
            point_count=len(members),
            source_paths=paths,
            world_offset=offset,
            scanners=[_world_scanner(s, cloud_offset) for s in scanners],
            bounds=bounds,
            point_radius=radius,
            collection=collection,
        )


def _menu_import(self, _context):
    self.layout.operator(LFPROBE_OT_import_scan.bl_idname, text="Scan Cloud (.xyz, .pts, .ply, .e57, .las)")


_CLASSES = [LFPROBE_OT_import_scan]

if hasattr(bpy.types, "FileHandler"):  # Blender 4.1+: drag and drop

    class LFPROBE_FH_scan(bpy.types.FileHandler):
        """Scan files dropped on the 3D viewport or the outliner are imported as scan clouds"""

        bl_idname = "LFPROBE_FH_scan"
        bl_label = "Scan Cloud"
        bl_import_operator = LFPROBE_OT_import_scan.bl_idname
        bl_file_extensions = ";".join(ALL_EXTENSIONS)

        @classmethod
        def poll_drop(cls, context):
            return context.area is not None and context.area.type in {"VIEW_3D", "OUTLINER"}

    _CLASSES.append(LFPROBE_FH_scan)

register, unregister = classes_with_menu_entry(tuple(_CLASSES), "TOPBAR_MT_file_import", _menu_import)
