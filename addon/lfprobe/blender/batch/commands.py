"""The batch commands (import, bake, place, render, compare) on the open .blend: each runs the
add-on's operators or gatherers as the UI would and prints what it did, raising BatchError
for what the user must fix."""

from __future__ import annotations

import json
import os

import bpy

from ...core.camera_json import write_camera
from ...core.trace_hints import unknown_hint
from .. import grid as grid_module
from .. import probe_view
from ..operators import bake, compare, place_views
from ..scene_objects import object_of_type
from .scene_access import (camera_named, evaluated_depsgraph, grids_named, save_unless_told_not, scene_named,
                           store_storage_options)
from .status import EXIT_BAD_INPUT, EXIT_CANCELLED, EXIT_OK, BatchError


def run_import(args) -> int:
    """Imports scans and gives the scene a probe grid baking from them: an existing box Empty
    (--grid-from, e.g. the demo scenes' probe_grid with its "counts") or a new grid fitted to
    the scans."""
    scene = scene_named(args.scene)
    paths = [os.path.abspath(p) for p in args.scan]
    for path in paths:
        if not os.path.isfile(path):
            raise BatchError(f"--scan: no file {path}")
    before = set(bpy.data.objects)
    for folder in sorted({os.path.dirname(p) for p in paths}):
        names = [os.path.basename(p) for p in paths if os.path.dirname(p) == folder]
        try:
            result = bpy.ops.import_scene.lfprobe_scan(directory=folder, files=[{"name": n} for n in names])
        except RuntimeError as error:  # the operator's ERROR report
            raise BatchError(str(error).strip()) from error
        if result != {"FINISHED"}:
            raise BatchError(f"importing {', '.join(names)} did not finish ({', '.join(result)})")
    scans = sorted((o for o in bpy.data.objects if o not in before), key=lambda o: o.name)
    print(f"lfprobe: imported {sum(o.lfprobe_scan.point_count for o in scans):,} points from "
          f"{len(paths)} file(s) into {len(scans)} object(s)")
    if args.grid_from:
        grid_obj = scene.objects.get(args.grid_from)
        if grid_obj is None or grid_obj.type != "EMPTY":
            raise BatchError(f"--grid-from: no Empty named '{args.grid_from}' in scene '{scene.name}'")
        grid = grid_obj.lfprobe_grid
        grid.is_grid = True
        if not grid.grid_id:
            grid.grid_id = grid_module.new_grid_id()
        stored = grid_obj.get("counts")
        if stored is not None and len(stored) == 3:
            grid.counts = [int(c) for c in stored]
        for scan in scans:
            grid.sources.add().obj = scan
    else:
        for obj in bpy.context.view_layer.objects:
            obj.select_set(obj in scans)
        bpy.ops.object.lfprobe_grid_add()
        grid_obj = bpy.context.view_layer.objects.active
        if bpy.ops.object.lfprobe_grid_fit(margin=args.margin, spacing=args.spacing) != {"FINISHED"}:
            raise BatchError("fitting the new grid to the scans failed")
        grid = grid_obj.lfprobe_grid
    try:
        grid_module.grid_box(grid_obj)
    except grid_module.GridError as error:
        raise BatchError(str(error)) from error
    if args.counts:
        grid.counts = args.counts
    if args.resolution:
        grid.resolution = args.resolution
    grid.plan_from_data = args.plan
    counts = tuple(grid.counts)
    print(f"lfprobe: grid '{grid_obj.name}': {counts[0]}×{counts[1]}×{counts[2]} probes at "
          f"{grid.resolution}²{' (planned from the data)' if grid.plan_from_data else ''}, "
          f"{len(grid.sources)} source(s)")
    target = os.path.abspath(args.save_as) if args.save_as else bpy.data.filepath
    if not target:
        raise BatchError("the scene is not saved to a .blend: pass --save-as FILE.blend")
    if not os.path.isdir(os.path.dirname(target)):
        raise BatchError(f"--save-as {args.save_as}: the folder {os.path.dirname(target)} does not exist")
    bpy.ops.wm.save_as_mainfile(filepath=target, relative_remap=True)
    print(f"lfprobe: saved {target}")
    return EXIT_OK


def run_bake(args) -> int:
    scene = scene_named(args.scene)
    grids = grids_named(scene, args.grid)
    if not grids:
        raise BatchError(f"scene '{scene.name}' has no probe grid to bake")
    for grid_obj in grids:
        store_storage_options(grid_obj.lfprobe_grid, args)
        try:
            result = bpy.ops.object.lfprobe_bake(grid=grid_obj.name, scheduler=args.scheduler)
        except RuntimeError as error:  # the operator's ERROR report
            raise BatchError(str(error).strip(), EXIT_BAD_INPUT) from error
        if result != {"FINISHED"}:
            raise BatchError(f"baking grid '{grid_obj.name}' was cancelled", EXIT_CANCELLED)
        folder = grid_module.probe_dir_abspath(grid_obj)
        print(f"lfprobe: baked grid '{grid_obj.name}' into {folder}: loads {bake.memory_text(folder)}")
    save_unless_told_not(args, " (grids marked as baked)")
    return EXIT_OK


def run_place(args) -> int:
    """Add Probes for Views on a grid: bakes it, adds probes at the eyes of the views that trace
    the most UNKNOWN until the target or budget, and saves the .blend (the grid's settings and
    its record of the added probes)."""
    scene = scene_named(args.scene)
    grids = grids_named(scene, args.grid)
    if len(grids) != 1:
        raise BatchError(f"scene '{scene.name}' has {len(grids) or 'no'} probe grid{'' if len(grids) == 1 else 's'}"
                         + (": pass --grid NAME" if grids else " to add probes to"))
    grid_obj = grids[0]
    for name in args.views or ():
        camera_named(scene, name)  # names the missing object or non-camera before any work
    if args.target_unknown is not None and not 0.0 <= args.target_unknown <= 1.0:
        raise BatchError(f"--target-unknown must be a fraction from 0 to 1, got {args.target_unknown}")
    if args.budget_mib is not None and not args.budget_mib >= 0.0:
        raise BatchError(f"--budget-mib must be 0 (no budget) or a positive number of MiB, got {args.budget_mib}")
    for option, value in (("--max-added", args.max_added), ("--frame-step", args.frame_step)):
        if value is not None and value < 1:
            raise BatchError(f"{option} must be at least 1, got {value}")
    grid = grid_obj.lfprobe_grid
    # Options given are stored on the grid (and saved with it), as the panel would set them.
    grid.views_from = "CAMERA_PATH" if args.camera_path else "SELECTED"
    for option in ("frame_step", "target_unknown", "budget_mib", "max_added"):
        value = getattr(args, option)
        if value is not None:
            setattr(grid, option, value)
    store_storage_options(grid, args)
    context = {} if scene == bpy.context.scene else {"scene": scene, "view_layer": scene.view_layers[0]}
    try:
        with bpy.context.temp_override(**context):
            result = bpy.ops.object.lfprobe_place_for_views(grid=grid_obj.name,
                                                            cameras=[{"name": n} for n in args.views or ()])
    except RuntimeError as error:  # the operator's ERROR report
        raise BatchError(str(error).strip(), EXIT_BAD_INPUT) from error
    if result != {"FINISHED"}:
        raise BatchError(f"adding probes to grid '{grid_obj.name}' was cancelled", EXIT_CANCELLED)
    print(f"lfprobe: grid '{grid_obj.name}': {place_views.summary_line(grid.placement())}")
    print(f"lfprobe: probe set in {grid_module.probe_dir_abspath(grid_obj)}")
    save_unless_told_not(args)
    return EXIT_OK


def run_render(args) -> int:
    scene = scene_named(args.scene)
    camera_obj = camera_named(scene, args.camera)
    target = probe_view.trace_target(scene, args.grid, camera_obj=camera_obj, depsgraph=evaluated_depsgraph(scene))
    trace = dict(target.trace, spp=target.spp)
    for option in ("mode", "thickness", "fallback_thickness", "threads", "spp", "filter", "blend", "hole_fill"):
        value = getattr(args, option)
        if value is not None:
            trace[option] = value
    out = os.path.abspath(args.out)
    if not os.path.isdir(os.path.dirname(out)):
        raise BatchError(f"--out {args.out}: the folder {os.path.dirname(out)} does not exist")
    if args.camera_json:
        write_camera(args.camera_json, target.camera)
    _image, stats = target.load_field().render(json.dumps(target.camera), output=out, **trace)
    rays = max(int(stats["rays"]), 1)
    pixels = max(int(stats["hits"] + stats["misses"] + stats["unknown"]), 1)
    print(f"lfprobe: rendered {out} from camera '{camera_obj.name}' through grid '{target.grid_name}': "
          f"{rays:,} rays in {stats['seconds'] * 1000:.1f} ms ({stats['rays_per_second'] / 1e6:.2f} M rays/s), "
          f"pixels HIT {100 * stats['hits'] / pixels:.2f}%, UNKNOWN {100 * stats['unknown'] / pixels:.2f}%")
    hint = unknown_hint(stats, target.camera, target.folder)
    if hint:
        print(f"lfprobe: {hint}")
    return EXIT_OK


def run_compare(args) -> int:
    scene = scene_named(args.scene)
    references = []
    if args.reference_collection:
        collection = bpy.data.collections.get(args.reference_collection)
        if collection is None:
            raise BatchError(f"--reference-collection: no collection named '{args.reference_collection}'")
        references = [o for o in collection.all_objects if o.type == "MESH"]
        if not references:
            raise BatchError(f"--reference-collection: '{collection.name}' holds no mesh")
    elif not args.reference:
        raise BatchError("compare needs --reference OBJ... or --reference-collection NAME")
    for name in args.reference or ():
        references.append(object_of_type(
            scene, name, "MESH", lambda message: BatchError(f"--reference: {message}")))
    camera_obj = camera_named(scene, args.camera)
    result = compare.run_compare(scene, evaluated_depsgraph(scene), references, os.path.abspath(args.out),
                                 camera_obj=camera_obj, grid_name=args.grid, spp=args.spp, ppd=args.ppd)
    print(f"lfprobe: compare {compare.summary_line(result)}")
    print(f"lfprobe: ground truth {result['ref_render_seconds'] * 1000:.1f} ms, probes "
          f"{result['test_render_seconds'] * 1000:.1f} ms; report in {os.path.dirname(result['reference'])}")
    return EXIT_OK
