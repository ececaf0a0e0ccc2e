"""Compare: the probe-traced view of the active camera against Embree ground truth of chosen
reference meshes. This module gathers the camera, grid, trace settings and reference meshes
from the scene; lfprobe.core.compare.CompareReport renders, measures and writes the report
folder (camera.json, ground_truth.exr, probes.exr, their PNG previews, error_flip.png and
compare.json), whose previews are then shown in the Image Editor.
"""

from __future__ import annotations

import os

import bpy
from bpy.props import BoolProperty, IntProperty, StringProperty

from ...core.compare import DEFAULT_PPD, CompareReport, check_samples_per_pixel
from ...core.errors import InputError
from .. import probe_view
from .job_modal import NativeJobOperator
from .menu_registration import classes_with_menu_entry
from ..mesh_export import native_mesh_from_objects

IMAGE_NAMES = {"ground_truth_preview": "LFP Ground Truth", "probes_preview": "LFP Probes", "error": "LFP FLIP Error"}


class CompareError(InputError):
    """A compare that cannot run as asked (the message says why)."""


def reference_objects(context_objects, collection_name: str = "") -> list:
    """The mesh objects of the named collection (with its children), else the given objects'
    meshes (the selection)."""
    if collection_name:
        collection = bpy.data.collections.get(collection_name)
        if collection is None:
            raise CompareError(f"no collection named '{collection_name}'")
        objects = collection.all_objects
    else:
        objects = context_objects
    meshes = [obj for obj in objects if obj.type == "MESH" and not obj.lfprobe_scan.is_scan]
    if not meshes:
        where = f"collection '{collection_name}'" if collection_name else "the selection"
        raise CompareError(f"no reference meshes in {where}: select the meshes of the room "
                           "(scan clouds are not references)")
    return meshes


def default_report_dir() -> str:
    if not bpy.data.filepath:
        raise CompareError("save the .blend first (the report goes next to it), or give an output folder")
    stem = os.path.splitext(os.path.basename(bpy.data.filepath))[0]
    return bpy.path.abspath(f"//{stem}_compare")


class ComparePlan:
    """Everything a compare needs, gathered from the scene before any rendering starts, so
    that bad input is reported before time is spent; core.compare.CompareReport renders,
    measures and writes the report."""

    def __init__(self, scene, depsgraph, references, out_dir: str, camera_obj=None, grid_name: str = "",
                 spp: int = 1, ppd: float = DEFAULT_PPD):
        check_samples_per_pixel(spp)
        self.target = probe_view.trace_target(scene, grid_name, camera_obj=camera_obj, depsgraph=depsgraph)
        self.trace = self.target.trace
        self.references = [obj.name for obj in references]
        self.mesh = native_mesh_from_objects(references, depsgraph, world_offset=self.target.offset,
                                             name="compare references")
        self.report = CompareReport(out_dir, self.target.camera, spp=spp, ppd=ppd)
        self.paths = self.report.paths
        self.report.write_camera()

    def start_ground_truth(self):
        return self.report.start_ground_truth(self.mesh, threads=self.trace["threads"])

    def finish(self, gt_stats: dict) -> dict:
        """Traces the probes, measures against the ground truth, writes the report."""
        probe_stats = self.report.render_probes(self.target.load_field(), self.trace)
        return self.report.measure(gt_stats, probe_stats, {
            "grid": self.target.grid_name,
            "probe_set": self.target.folder,
            "reference_objects": self.references,
            "trace": self.trace,
        })


def run_compare(scene, depsgraph, references, out_dir: str, **options) -> dict:
    """Compare to the end in one call (the batch CLI)."""
    plan = ComparePlan(scene, depsgraph, references, out_dir, **options)
    gt_stats = plan.start_ground_truth().run(None)
    return plan.finish(gt_stats)


def summary_line(result: dict) -> str:
    def fmt(key, spec, unit=""):
        value = result.get(key)
        return "n/a" if value is None else f"{value:{spec}}{unit}"

    psnr = "inf" if result.get("psnr") == float("inf") else fmt("psnr", ".2f", " dB")
    line = (f"PSNR {psnr}, SSIM {fmt('ssim', '.4f')}, FLIP {fmt('flip', '.4f')}, "
            f"depth AbsRel {fmt('depth_absrel', '.4f')}, hole rate {fmt('hole_rate', '.3%')}, "
            f"false hits {fmt('false_hit_rate', '.3%')}")
    if result.get("guessed_pixels"):
        # Where no scan saw: the share of the view the probes guessed, and of the error there.
        line += (f", guessed surfaces {fmt('guessed_pixels', '.2%')} of the pixels "
                 f"({fmt('guessed_error_share', '.0%')} of the error)")
    return line


def load_report_images(paths: dict) -> list:
    """Loads (or reloads) the ground truth, probe and error previews into bpy.data.images
    (PNG: Blender reads the native EXRs' analysis channels as an unknown multilayer layout)."""
    images = []
    for key in ("ground_truth_preview", "probes_preview", "error"):
        path = paths[key]
        image = next((i for i in bpy.data.images if bpy.path.abspath(i.filepath) == path), None)
        if image is None:
            image = bpy.data.images.load(path)
        else:
            image.reload()
        image.name = IMAGE_NAMES[key]
        images.append(image)
    return images


def show_in_image_editor(context, image) -> bool:
    """Shows `image` in an Image Editor of the current screen, or in a new window; False
    when there is no window (background)."""
    if bpy.app.background or context.window is None:
        return False
    for area in context.screen.areas:
        if area.type == "IMAGE_EDITOR":
            area.spaces.active.image = image
            return True
    windows_before = set(context.window_manager.windows[:])
    bpy.ops.wm.window_new()
    new_windows = [w for w in context.window_manager.windows if w not in windows_before]
    if not new_windows:
        return False
    area = max(new_windows[0].screen.areas, key=lambda a: a.width * a.height)
    area.type = "IMAGE_EDITOR"
    area.spaces.active.image = image
    return True


class LFPROBE_OT_compare(NativeJobOperator, bpy.types.Operator):
    """Render ground truth of the reference meshes with Embree from the active camera, trace
    the probes from the same camera, measure the error and open the images"""

    bl_idname = "lfprobe.compare"
    bl_label = "Compare with Ground Truth"
    bl_options = {"REGISTER"}
    job_label = "Ground truth"

    collection: StringProperty(
        name="Reference Collection",
        description="Meshes of this collection are the reference (empty: the selected meshes)",
        default="",
    )
    directory: StringProperty(
        name="Report Folder",
        description="Where the report is written (empty: <blend name>_compare next to the .blend)",
        subtype="DIR_PATH",
        default="",
    )
    spp: IntProperty(name="Samples per Pixel",
                     description="Samples per pixel of the ground truth and of the probe render alike (matched "
                                 "filtering): 1 or a square",
                     min=1, soft_max=64, default=16)
    open_images: BoolProperty(name="Open Images", description="Show the images in an Image Editor",
                              default=True)

    _plan = None

    @classmethod
    def poll(cls, context):
        return context.scene is not None

    def execute(self, context):
        return self.run_job(context)

    def start_job(self, context):
        scene = context.scene
        try:
            references = reference_objects(context.selected_objects, self.collection)
            out_dir = bpy.path.abspath(self.directory) if self.directory else default_report_dir()
            self._plan = ComparePlan(scene, context.evaluated_depsgraph_get(), references, out_dir,
                                     spp=self.spp)
            return self._plan.start_ground_truth()
        except (InputError, OSError) as error:
            self.report({"ERROR"}, f"Compare: {error}")
            return None
        except Exception as error:  # native input errors (e.g. a mesh Embree refuses)
            self.report({"ERROR"}, f"Compare: {type(error).__name__}: {error}")
            return None

    def finish_job(self, context, result):
        plan = self._plan
        try:
            report = plan.finish(result)
        except Exception as error:
            self.report({"ERROR"}, f"Compare: {type(error).__name__}: {error}")
            return {"CANCELLED"}
        images = load_report_images(plan.paths)
        if self.open_images:
            show_in_image_editor(context, images[1])
        self.report({"INFO"}, f"Compare: {summary_line(report)}; report in {plan.paths['report']}")
        return {"FINISHED"}

    def cleanup_job(self, context):
        self._plan = None


def _menu_item(self, _context):
    self.layout.operator(LFPROBE_OT_compare.bl_idname, icon="IMAGE_REFERENCE")


register, unregister = classes_with_menu_entry((LFPROBE_OT_compare,), "TOPBAR_MT_render", _menu_item)
