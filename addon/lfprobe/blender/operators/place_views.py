"""Add Probes for Views: probes where the views need them (lfprobe.core.adaptive in the add-on).

The grid is baked as Bake bakes it (the same sources, resolution, planning and storage:
bake.GridBake), then a probe is added at the eye of the view that traces the most UNKNOWN pixels, again and
again, until every view is at most the grid's Target UNKNOWN, the next probe would take the
set over its Memory Budget, or Max Added Probes were added. The views are the selected cameras
or the scene camera over the frame range every Frame Step frames, exported as the renderer
sees them (camera_export, in the bake's world frame). Like Bake it runs modal in the UI (a
progress bar, Esc cancels) and synchronously under ``blender -b``; the set is made in the
staging folder and renamed into the grid's probe folder, so an error or a cancel leaves the
previous set as it was. What was added goes onto the grid (placement_json) for the panel and
the overlay."""

import json
import os
import shutil

import bpy
from bpy.props import CollectionProperty, StringProperty

from ...core import adaptive, native
from ...core.atomic_write import replace_folder
from ...core.cloud_transform import to_local
from ...core.errors import InputError
from ...core.probe_set import read_manifest
from . import bake
from .. import camera_export
from .. import grid as grid_module
from . import job_modal
from .. import probe_view
from ..properties.camera_name import LFProbeCameraName
from ..scene_objects import object_of_type

# The short words for adaptive.STOP_REASONS that the panel's one line has room for.
STOP_WORDS = {
    "target": "target met",
    "budget": "memory budget reached",
    "max_added": "Max Added Probes reached",
    "eyes_used": "every view's eye has a probe",
}


class ViewsError(InputError):
    """No views to place probes for (the message says what to select or set)."""


def view_cameras(context, grid, offset, names=()) -> list:
    """The camera dicts (world frame: world = offset + Blender position) of the views to serve:
    the cameras named, else as the grid's Views says: the selected cameras at the current
    frame, or the scene camera at every Frame Step-th frame of the scene's range (the current
    frame is restored afterwards). Raises ViewsError or camera_export.CameraExportError."""
    scene = context.scene
    if names:
        objects = [object_of_type(scene, name, "CAMERA", ViewsError, quote=repr) for name in names]
    elif grid.views_from == "SELECTED":
        objects = sorted((obj for obj in context.selected_objects if obj.type == "CAMERA"), key=lambda o: o.name)
        if not objects:
            raise ViewsError("no camera is selected: select the cameras whose views need probes "
                             "(or set Views to Scene Camera Path)")
    else:
        return _camera_path(context, int(grid.frame_step), offset)
    depsgraph = context.evaluated_depsgraph_get()
    return [camera_export.camera_dict(scene, obj, offset, depsgraph=depsgraph) for obj in objects]


def _camera_path(context, step: int, offset) -> list:
    scene = context.scene
    if scene.camera is None:
        raise ViewsError(f"scene {scene.name!r} has no camera: make the camera whose path needs "
                         "probes the scene camera (or set Views to Selected Cameras)")
    frames = range(scene.frame_start, scene.frame_end + 1, max(1, step))
    if not frames:
        raise ViewsError(f"scene {scene.name!r}: its frame range {scene.frame_start}–{scene.frame_end} is empty")
    current, subframe = scene.frame_current, scene.frame_subframe
    cameras = []
    try:
        for frame in frames:
            scene.frame_set(frame)
            camera_obj = scene.camera  # timeline markers may switch the camera
            camera = camera_export.camera_dict(scene, camera_obj, offset,
                                               depsgraph=context.evaluated_depsgraph_get())
            camera["name"] = f"{camera_obj.name} frame {frame}"
            cameras.append(camera)
    finally:
        scene.frame_set(current, subframe=subframe)
    return cameras


def placement_record(result, cameras: list, offset, target_unknown: float, budget_mib: float) -> dict:
    """What goes onto the grid (placement_json) from an adaptive.AdaptiveResult: the added
    probes in Blender's frame, the worst and mean view's UNKNOWN rate before and after, the
    memory of the whole set and why it stopped."""
    first, last = result.iterations[0], result.iterations[-1]
    return {
        "views": [camera.get("name", "") for camera in cameras],
        "base_probes": result.base_probes,
        "added": [{
            "position": to_local(added["position"], offset),
            "view": cameras[added["view"]].get("name", ""),
            "resolution": int(added["resolution"]),
            "memory_bytes": int(added["memory_bytes"]),
            "unknown_rate_before": float(added["unknown_rate_before"]),
        } for added in result.added],
        "unknown_before": float(first["max_unknown_rate"]),
        "unknown_after": float(last["max_unknown_rate"]),
        "mean_unknown_before": float(first["mean_unknown_rate"]),
        "mean_unknown_after": float(last["mean_unknown_rate"]),
        "unknown_per_view": [float(r) for r in last["unknown_rate_per_view"]],
        "memory_bytes": int(result.memory_bytes),
        "stop": result.stop,
        "stopped_because": result.stopped_because,
        "target_unknown": float(target_unknown),
        "budget_mib": float(budget_mib),
    }


def summary_line(placement: dict, colour: str = "") -> str:
    """One line for the panel (which names the overlay's `colour` of the added probes), the
    operator's report and the batch CLI."""
    added, views = len(placement.get("added", [])), len(placement.get("views", []))
    stop = placement.get("stop", "")
    marked = f" ({colour})" if colour else ""
    return (f"{added} probe{'' if added == 1 else 's'} added{marked} for {views} view{'' if views == 1 else 's'}: "
            f"UNKNOWN {placement.get('unknown_before', 0.0):.1%} → {placement.get('unknown_after', 0.0):.1%} "
            f"(worst view), {placement.get('memory_bytes', 0) / 2**20:.2f} MiB, {STOP_WORDS.get(stop, stop)}")


class LFPROBE_OT_place_for_views(bake.GridJobOperator, bpy.types.Operator):
    """Bake the probe grid, then add probes at the eyes of the views that trace the most UNKNOWN
    pixels until the target or the memory budget is met (Esc cancels)"""

    bl_idname = "object.lfprobe_place_for_views"
    bl_label = "Add Probes for Views"
    bl_options = {"REGISTER"}
    job_label = bake.GRID_JOB_LABELS[1]

    grid: StringProperty(name="Grid", description="Name of the grid object (empty: the active object)", default="")
    cameras: CollectionProperty(
        type=LFProbeCameraName,
        name="Cameras",
        description="Camera objects whose views to serve (empty: as the grid's Views says)",
        options={"HIDDEN", "SKIP_SAVE"},
    )

    def start_job(self, context):
        self._staging = None
        try:
            native.load()
            grid_obj = bake.grid_object(context, self.grid)
            inputs = bake.GridBake(context, grid_obj)
            if inputs.meshes:
                raise bake.BakeInputError(
                    f"grid {grid_obj.name!r} bakes from meshes, but the probes added for views are "
                    "baked from scan points: use scan clouds as its sources")
            grid = grid_obj.lfprobe_grid
            cameras = view_cameras(context, grid, inputs.offset, [item.name for item in self.cameras])
            trace = probe_view.trace_settings(context.scene)
        except (InputError, native.NativeModuleError) as error:
            self.report({"ERROR"}, f"Add probes for views: {error}")
            return None
        self._inputs = inputs
        self._cameras = cameras
        self._target, self._budget_mib = float(grid.target_unknown), float(grid.budget_mib)
        self._place = dict(
            target_unknown=self._target,
            budget_bytes=adaptive.budget_from_mib(self._budget_mib) if self._budget_mib > 0 else None,
            max_added=int(grid.max_added),
            trace={"mode": trace["mode"], "thickness": trace["thickness"]},
            threads=trace["threads"],
            log=print if bpy.app.background else None,
        )
        self._staging = inputs.staging
        self._remove_staging()  # left by a crashed Blender
        self._step = "load"
        return inputs.start_load()

    def finish_job(self, context, result):
        inputs = self._inputs
        if self._step == "load":
            cloud, sources = inputs.cloud_and_sources(result)
            self._step = "place"
            # The thread gets plain values only: bpy data is not to be touched off the main thread.
            cameras, staging, options, placement = self._cameras, self._staging, inputs.options, inputs.placement
            base_grid = {"min": placement.grid_min, "max": placement.grid_max, "counts": placement.counts}
            # Every bake of the placement records the grid's Storage: the views are traced, and the
            # budget counted, as the finished set will load.
            settings = dict(self._place, resolution=options.resolution, plan=options.plan,
                            splat_scale=options.splat_scale, hole_fill_texels=options.hole_fill_texels,
                            storage=options.storage, distance_step=options.distance_step)
            return job_modal.ThreadJob(
                lambda report: adaptive.place_adaptively(cloud, cameras, staging, base_grid=base_grid,
                                                         sources=sources, progress=report, **settings),
                name="lfprobe adaptive placement",
            )
        inputs.bind(self._staging)
        replace_folder(self._staging, inputs.folder)
        self._staging = None
        manifest = read_manifest(inputs.folder)
        record = placement_record(result, self._cameras, inputs.offset, self._target, self._budget_mib)
        grid_obj = bpy.data.objects.get(inputs.grid_name)
        if grid_obj is None or not grid_module.is_grid(grid_obj):
            self.report({"WARNING"}, f"Placed into {inputs.folder}, but grid {inputs.grid_name!r} was removed meanwhile")
            return {"FINISHED"}
        grid = grid_obj.lfprobe_grid
        inputs.mark_baked(grid_obj, manifest, base_probes=result.base_probes)
        grid.placement_json = json.dumps(record)
        self.report({"INFO"}, f"Grid {grid_obj.name!r}: {summary_line(record)}; "
                              f"{len(manifest['probes'])} probes in {inputs.folder}")
        return {"FINISHED"}

    def _remove_staging(self):
        for folder in (self._staging, self._staging.rstrip(os.sep) + ".adding"):
            shutil.rmtree(folder, ignore_errors=True)

    def cleanup_job(self, context):
        if getattr(self, "_staging", None):
            self._remove_staging()
            self._staging = None


_CLASSES = (LFProbeCameraName, LFPROBE_OT_place_for_views)


# Blender's own helper: registers in order, unregisters in reverse.
register, unregister = bpy.utils.register_classes_factory(_CLASSES)
