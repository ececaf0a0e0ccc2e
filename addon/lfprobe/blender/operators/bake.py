"""Bake a probe grid: gathers the grid's sources (the full clouds of scan objects through the
parse cache, or meshes through mesh_export), runs the native bake off the main thread (modal
in the UI: progress bar, Esc cancels; synchronous in ``blender -b``) into a temporary folder
beside the probe folder and renames it into place, so a cancelled or failed bake leaves the
previous probe set as it was. Per-probe coverage from the manifest goes onto the grid. The
set's manifest records the grid's Storage (how the probes load into memory); Apply Storage
changes it on a baked set without a rebake, as the probe files keep full precision."""

import json
import os
import shutil

import bpy
from bpy.props import StringProperty

from ...core import cluster_bake, estimates, native, pipeline
from ...core.atomic_write import replace_folder
from ...core.cloud_transform import to_world, transform_scans
from ...core.errors import InputError
from ...core import probe_storage
from ...core.probe_set import read_manifest, record_in_bake
from ...core.scan_formats import is_library_format
from ...core.scan_merge import describe_records, file_of_each_scan, loaded_with_records
from .. import grid as grid_module
from .. import preferences
from .. import scan_object
from . import job_modal
from .job_modal import NativeJobOperator, ThreadJob


class BakeInputError(InputError):
    """The grid cannot be baked as it is; the message says why and what to do."""


# The jobs that write a grid's probe folder (Bake, Add Probes for Views): one at a time, as two
# would share the cores and could write the same folder.
GRID_JOB_LABELS = ("Probe bake", "Adding probes for views")


def grid_job_running() -> bool:
    return any(label in job_modal.running_labels for label in GRID_JOB_LABELS)


def grid_object(context, name: str = ""):
    """The probe grid named `name`, else the active object; GridError when it is not a grid."""
    if name:
        obj = bpy.data.objects.get(name)
        if obj is None:
            raise grid_module.GridError(f"no object named {name!r}")
    else:
        obj = context.active_object
        if obj is None:
            raise grid_module.GridError("no active object: select a probe grid to bake")
    if not grid_module.is_grid(obj):
        raise grid_module.GridError(f"{obj.name!r} is not a probe grid")
    return obj


def gather_sources(grid_obj):
    """(scan objects, mesh objects) the grid bakes from, checked."""
    scans, meshes = [], []
    for index, source in enumerate(grid_obj.lfprobe_grid.sources):
        obj = source.obj
        if obj is None:
            raise BakeInputError(f"grid {grid_obj.name!r}: source {index + 1} is empty (pick an object or remove it)")
        if obj.type != "MESH":
            raise BakeInputError(f"grid {grid_obj.name!r}: source {obj.name!r} is a {obj.type}, not a scan cloud or mesh")
        (scans if obj.lfprobe_scan.is_scan else meshes).append(obj)
    if not scans and not meshes:
        raise BakeInputError(
            f"grid {grid_obj.name!r} has no sources: add scan clouds or meshes to bake from "
            "(select them and the grid, then Add Selected as Sources)"
        )
    if scans and meshes:
        raise BakeInputError(
            f"grid {grid_obj.name!r} mixes scan clouds ({scans[0].name!r}) and meshes ({meshes[0].name!r}): "
            "a probe set is baked from scans or from meshes, not both"
        )
    for obj in scans:
        for path in obj.lfprobe_scan.paths():
            if not os.path.isfile(path):
                raise BakeInputError(f"scan cloud {obj.name!r}: its file {path} is missing (the full cloud is read from it)")
    return scans, meshes


def shared_scan_offset(scans) -> tuple:
    """The local frame the scan objects share (an error when they do not)."""
    offset = scans[0].lfprobe_scan.offset()
    for obj in scans[1:]:
        if obj.lfprobe_scan.offset() != offset:
            raise BakeInputError(
                f"scan clouds {scans[0].name!r} and {obj.name!r} have different world offsets "
                f"({offset} and {obj.lfprobe_scan.offset()}): they are not in one frame"
            )
    return offset


def probe_folder(grid_obj) -> str:
    """The grid's probe folder, absolute; a path relative to an unsaved .blend is an error."""
    path = grid_obj.lfprobe_grid.probe_dir or grid_module.default_probe_dir(grid_obj)
    if path.startswith("//") and not bpy.data.filepath:
        raise BakeInputError(
            f"grid {grid_obj.name!r}: the probe folder {path} is relative to the .blend file, "
            "which is not saved yet: save the .blend first, or set an absolute probe folder"
        )
    return grid_module.probe_dir_abspath(grid_obj)


class GridBake:
    """What baking a grid takes, read from the grid and checked before any work starts (Bake and
    Add Probes for Views share it): the sources, the probe folder and its staging folder, the
    frame (world = offset + Blender position: the scans' frame, else the scene's for meshes),
    the grid in world coordinates and the bake options. Raises BakeInputError or GridError."""

    def __init__(self, context, grid_obj):
        low, high = grid_module.grid_box(grid_obj)
        self.scans, self.meshes = gather_sources(grid_obj)
        grid_module.claim_probe_folder(grid_obj)
        self.folder = probe_folder(grid_obj)
        # The folder stays the grid's after a rename or Save As: the default becomes explicit.
        self.probe_dir = grid_obj.lfprobe_grid.probe_dir or grid_module.default_probe_dir(grid_obj)
        self.grid_record = grid_module.grid_record(grid_obj)
        frame = shared_scan_offset(self.scans) if self.scans else scan_object.frame_offset(context.scene)
        self.grid_name = grid_obj.name
        self.staging = self.folder.rstrip(os.sep) + ".baking"
        self.offset = tuple(float(v) for v in (frame if frame is not None else (0.0, 0.0, 0.0)))
        grid = grid_obj.lfprobe_grid
        self.placement = pipeline.ProbePlacementSpec(
            grid_min=to_world(low, self.offset), grid_max=to_world(high, self.offset), counts=list(grid.counts)
        )
        storage, distance_step = grid.storage_choice()
        self.options = pipeline.BakeOptions(resolution=grid.resolution, storage=storage, distance_step=distance_step)
        if grid.plan_from_data and self.scans:
            # The grid's resolution is the largest a planned probe may get.
            self.options.plan = {"auto_resolution": True, "max_resolution": int(grid.resolution),
                                 "min_resolution": min(64, int(grid.resolution))}
        # Read on the main thread: the jobs' threads must not touch bpy.
        self.cache_dir = preferences.scan_cache_dir(context)
        self.paths = [p for obj in self.scans for p in obj.lfprobe_scan.paths()]
        self.scanners = [s for obj in self.scans for s in obj.lfprobe_scan.scanners()]
        # Each file's transform: the matrix of the scan object it belongs to.
        self.file_matrices = [[list(row) for row in obj.matrix_world] for obj in self.scans
                              for _ in obj.lfprobe_scan.paths()]

    def start_load(self):
        """The job that reads the scans' full clouds: the native one (through the parse cache),
        or, with E57 or LAS/LAZ files among them, core's loader on a thread of its own."""
        # Scanner positions travel with the files (headers, E57 poses) or were given at import.
        cache = self.cache_dir
        if any(is_library_format(p) for p in self.paths):
            paths, scanners, offset = list(self.paths), list(self.scanners), list(self.offset)
            if len(scanners) != len(paths):
                scanners = []
            return ThreadJob(lambda report: pipeline.load_scans_and_sources(
                paths, scanners, world_offset=offset, cache_dir=cache, progress=report))
        given = (self.scanners if len(self.scanners) == len(self.paths) and all(s is not None for s in self.scanners)
                 else [])
        return native.load().start_load_scans(
            self.paths, scanners=given, world_offset=list(self.offset), cache_dir=cache
        )

    def start_cluster_bake(self, out_dir: str, scheduler: str):
        """The job that bakes the grid's probes on the Dask scheduler at `scheduler` into
        `out_dir`: the workers read the scans' files through the parse cache and move each by
        its scan object's transform, as cloud_and_sources does here."""
        paths, scanners, offset = list(self.paths), list(self.scanners), list(self.offset)
        if len(scanners) != len(paths) or any(s is None for s in scanners):
            scanners = []
        matrices, placement, options, cache = list(self.file_matrices), self.placement, self.options, self.cache_dir
        return ThreadJob(lambda report: cluster_bake.bake_scans_on_cluster(
            paths, out_dir, placement, options, scanners=scanners, cache_dir=cache,
            world_offset=offset, file_matrices=matrices, scheduler=scheduler, progress=report))

    def cloud_and_sources(self, loaded):
        """(the cloud to bake, moved by the scan objects' transforms; the manifest's sources)."""
        loaded, records = loaded_with_records(loaded, self.paths)
        files = file_of_each_scan(records, self.paths)
        cloud = transform_scans(loaded, [self.file_matrices[f] for f in files])
        return cloud, describe_records(records)

    def bind(self, staging: str) -> None:
        """Records in the staged set the grid it is baked for (grid.bound_set checks it)."""
        record_in_bake(staging, grid_module.GRID_RECORD, self.grid_record)

    def mark_baked(self, grid_obj, manifest: dict, base_probes: int = -1) -> None:
        grid = grid_obj.lfprobe_grid
        if not grid.probe_dir:
            grid.probe_dir = self.probe_dir
        show_baked_set(grid, manifest, base_probes)


def show_baked_set(grid, manifest: dict, base_probes: int = -1) -> None:
    """Marks the grid as baked with the coverage and plan of its grid probes (the first
    `base_probes` of the manifest, all when negative); probes added for views, if any, are the
    caller's to record (placement_json), and a plain bake clears them."""
    probes = manifest["probes"] if base_probes < 0 else manifest["probes"][:base_probes]
    grid.coverage_json = json.dumps([p.get("coverage", {}) for p in probes])
    grid.plan_json = json.dumps(manifest.get("bake", {}).get("plan", []))
    grid.placement_json = "{}"
    grid.baked = True


def memory_text(folder: str) -> str:
    """What the grid's panel and reports say about how the set in `folder` loads (probe_storage.memory_text)."""
    return probe_storage.memory_text(probe_storage.loaded_storage(folder))


class GridJobOperator(NativeJobOperator):
    """An operator that runs one job on a grid (Bake, Add Probes for Views): one such job at a
    time, modal in the UI and synchronous in the background (NativeJobOperator)."""

    @classmethod
    def poll(cls, context):
        return not grid_job_running()

    def execute(self, context):
        return self.run_job(context)


class LFPROBE_OT_bake(GridJobOperator, bpy.types.Operator):
    """Bake the probe grid's light field probes from its sources (Esc cancels)"""

    bl_idname = "object.lfprobe_bake"
    bl_label = "Bake Probes"
    bl_options = {"REGISTER"}
    job_label = GRID_JOB_LABELS[0]

    grid: StringProperty(name="Grid", description="Name of the grid object (empty: the active object)", default="")
    scheduler: StringProperty(
        name="Scheduler",
        description="Dask scheduler to bake the probes on (empty: the add-on preferences' address, "
        "and with none there, this machine)",
        default="",
    )

    def start_job(self, context):
        self._staging = None
        try:
            native.load()
            inputs = GridBake(context, grid_object(context, self.grid))
        except (InputError, native.NativeModuleError) as error:
            self.report({"ERROR"}, f"Probe bake: {error}")
            return None
        self._inputs = inputs
        self._staging = inputs.staging
        shutil.rmtree(self._staging, ignore_errors=True)  # left by a crashed Blender
        if inputs.meshes:
            # A mesh bakes exactly at the grid's resolution: planning reads scan points.
            return self._start_mesh_bake(context, inputs.meshes)
        scheduler = self.scheduler.strip() or preferences.scheduler_address(context)
        if scheduler and inputs.options.plan is not None:
            # Planned bakes (per-probe resolutions, moves) are not handed to a cluster yet.
            self.report({"WARNING"}, "Probe bake: Plan From Data bakes on this machine, not on the "
                                     "Dask scheduler (turn it off to bake there)")
        elif scheduler:
            self._step = "bake"
            return inputs.start_cluster_bake(self._staging, scheduler)
        self._step = "load"
        return inputs.start_load()

    def _start_mesh_bake(self, context, meshes):
        from .. import mesh_export  # Blender meshes → native Mesh

        _native = native.load()
        inputs = self._inputs
        try:
            mesh = mesh_export.native_mesh_from_objects(
                meshes, context.evaluated_depsgraph_get(), world_offset=list(inputs.offset)
            )
        except mesh_export.MeshExportError as error:
            self.report({"ERROR"}, f"Probe bake: {error}")
            return None
        self._step = "bake"
        sources = [{"kind": "blender-mesh", "objects": [obj.name for obj in meshes], "triangles": int(mesh.triangle_count)}]
        return _native.start_bake_probe_set_from_mesh(
            mesh,
            self._staging,
            resolution=inputs.options.resolution,
            grid_min=inputs.placement.grid_min,
            grid_max=inputs.placement.grid_max,
            counts=inputs.placement.counts,
            sources_json=json.dumps(sources),
        )

    def finish_job(self, context, result):
        inputs = self._inputs
        if self._step == "load":
            cloud, sources = inputs.cloud_and_sources(result)
            self._step = "bake"
            return pipeline.bake_from_cloud(
                cloud, self._staging, inputs.placement, inputs.options, sources, start_only=True,
                cache_dir=inputs.cache_dir,
            )
        # The jobs ran with start_only, which leaves the storage to the caller: recorded while
        # the set is still staged, so the folder never holds a set that loads otherwise.
        pipeline.apply_storage(self._staging, result, inputs.options)
        inputs.bind(self._staging)
        replace_folder(self._staging, inputs.folder)
        self._staging = None
        manifest = read_manifest(inputs.folder)
        grid_obj = bpy.data.objects.get(inputs.grid_name)
        if grid_obj is None or not grid_module.is_grid(grid_obj):
            self.report({"WARNING"}, f"Baked into {inputs.folder}, but grid {inputs.grid_name!r} was removed meanwhile")
            return {"FINISHED"}
        inputs.mark_baked(grid_obj, manifest)
        mean = result.get("mean_coverage", {})
        self.report(
            {"INFO"},
            f"Baked {len(manifest['probes'])} probes into {inputs.folder}: "
            f"{100 * mean.get('surface', 0):.0f}% surface, {100 * mean.get('unknown', 0):.0f}% unknown; "
            f"{memory_text(inputs.folder)}",
        )
        return {"FINISHED"}

    def cleanup_job(self, context):
        if getattr(self, "_staging", None):
            shutil.rmtree(self._staging, ignore_errors=True)
            self._staging = None


class LFPROBE_OT_grid_apply_storage(bpy.types.Operator):
    """Make the grid's baked probe set load as its Storage says (rewrites the set's manifest;
    the probe files keep full precision, so no rebake is needed)"""

    bl_idname = "object.lfprobe_grid_apply_storage"
    bl_label = "Apply Storage"
    # No UNDO: the manifest on disk is what changes, and undo would not bring it back.
    bl_options = {"REGISTER"}

    grid: StringProperty(name="Grid", description="Name of the grid object (empty: the active object)", default="")

    @classmethod
    def poll(cls, context):
        return not grid_job_running()  # a bake or placement may be about to replace the folder

    def execute(self, context):
        try:
            _native = native.load()
            grid_obj = grid_object(context, self.grid)
            folder = probe_folder(grid_obj)
        except (InputError, native.NativeModuleError) as error:
            self.report({"ERROR"}, f"Apply storage: {error}")
            return {"CANCELLED"}
        before = probe_storage.loaded_storage(folder)
        if before is None:
            self.report({"ERROR"}, f"Apply storage: grid {grid_obj.name!r} has no baked probe set in {folder}: "
                                   "bake it first")
            return {"CANCELLED"}
        storage, distance_step = grid_obj.lfprobe_grid.storage_choice()
        try:
            _native.set_probe_set_storage(folder, storage, distance_step=distance_step)
        except (_native.InputError, _native.NativeIOError, OSError) as error:
            self.report({"ERROR"}, f"Apply storage: {error}")
            return {"CANCELLED"}
        self.report({"INFO"}, f"Grid {grid_obj.name!r}: {memory_text(folder)}, "
                              f"was {before['memory_bytes'] / 2**20:.2f} MiB ({before['name']})")
        return {"FINISHED"}


class LFPROBE_OT_grid_estimate(NativeJobOperator, bpy.types.Operator):
    """Estimate how much of each probe's surroundings the grid's scans cover, before baking: a
    coarse bake at every probe (the classification of Plan From Data), nothing written"""

    bl_idname = "object.lfprobe_grid_estimate"
    bl_label = "Estimate Coverage"
    bl_options = {"REGISTER"}
    job_label = "Estimating coverage"

    grid: StringProperty(name="Grid", description="Name of the grid object (empty: the active object)", default="")

    @classmethod
    def poll(cls, context):
        return not grid_job_running() and cls.job_label not in job_modal.running_labels

    def execute(self, context):
        return self.run_job(context)

    def start_job(self, context):
        try:
            native.load()
            grid_obj = grid_object(context, self.grid)
            low, high = grid_module.grid_box(grid_obj)
            scans, meshes = gather_sources(grid_obj)
            if meshes:
                raise BakeInputError(f"grid {grid_obj.name!r}: Estimate Coverage works from scan clouds; "
                                     "a mesh is exact where it has geometry")
            offset = tuple(float(v) for v in shared_scan_offset(scans) or (0.0, 0.0, 0.0))
        except (InputError, native.NativeModuleError) as error:
            self.report({"ERROR"}, f"Estimate coverage: {error}")
            return None
        grid = grid_obj.lfprobe_grid
        self._grid_name, self._counts, self._resolution = grid_obj.name, list(grid.counts), int(grid.resolution)
        placement = pipeline.ProbePlacementSpec(grid_min=to_world(low, offset), grid_max=to_world(high, offset),
                                                counts=list(grid.counts))
        paths = [p for obj in scans for p in obj.lfprobe_scan.paths()]
        scanners = [s for obj in scans for s in obj.lfprobe_scan.scanners()]
        if len(scanners) != len(paths) or any(s is None for s in scanners):
            scanners = []
        matrices = [[list(row) for row in obj.matrix_world] for obj in scans for _ in obj.lfprobe_scan.paths()]
        cache = preferences.scan_cache_dir(context)  # read here: the job's thread must not touch bpy
        # Classification only: every probe where the grid puts it, none moved or dropped.
        options = {"classify": True, "max_move": 0.0, "drop": False, "auto_resolution": False,
                   "resolution": self._resolution}

        def work(report):
            cloud, records = pipeline.load_scans_and_sources(paths, scanners, world_offset=list(offset),
                                                             cache_dir=cache, progress=report)
            files = file_of_each_scan(records, paths)
            cloud = transform_scans(cloud, [matrices[f] for f in files])
            return pipeline.plan_probes(cloud, placement, options, progress=report)

        return ThreadJob(work, name="lfprobe coverage estimate")

    def finish_job(self, context, result):
        grid_obj = bpy.data.objects.get(self._grid_name)
        if grid_obj is None:
            return {"CANCELLED"}
        estimate = estimates.coverage_estimate(result)
        estimate.update(counts=self._counts, resolution=self._resolution,
                        unknown=[float(p.get("classification", {}).get("unknown", 1.0)) for p in result])
        grid_obj.lfprobe_grid.estimate_json = json.dumps(estimate)
        text, _warn = estimates.coverage_estimate_text(estimate)
        self.report({"INFO"}, f"Grid {grid_obj.name!r}: {text.replace(chr(10), ', ')}")
        return {"FINISHED"}


_CLASSES = (LFPROBE_OT_bake, LFPROBE_OT_grid_apply_storage, LFPROBE_OT_grid_estimate)


# Blender's own helper: registers in order, unregisters in reverse.
register, unregister = bpy.utils.register_classes_factory(_CLASSES)
