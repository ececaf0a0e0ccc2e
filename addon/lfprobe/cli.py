"""Headless batch entry of the Blender add-on: import scans, bake, add probes for views, render and
compare a saved scene.

    blender -b scene.blend --python-exit-code 1 -P <add-on>/cli.py -- import --scan FILE... [--grid-from EMPTY] --save-as OUT.blend
    blender -b scene.blend --python-exit-code 1 -P <add-on>/cli.py -- bake [--grid NAME] [--storage full|compact]
    blender -b scene.blend --python-exit-code 1 -P <add-on>/cli.py -- place (--views CAMERA... | --camera-path)
    blender -b scene.blend --python-exit-code 1 -P <add-on>/cli.py -- render [--camera NAME] --out IMG.exr
    blender -b scene.blend --python-exit-code 1 -P <add-on>/cli.py -- compare --reference OBJ... --out DIR

The add-on is used as it is enabled in Blender (legacy add-on or extension), or else imported
from the folder this file lies in (whose parent is put on sys.path) and enabled for this run
only. Exit status: 0 success, 2 bad input (the message says what and where), 1 other
failures, 130 cancelled. Run inside Blender only; the bpy-free command line is ./lfprobe.
"""

from __future__ import annotations

import argparse
import importlib
import json
import os
import sys

EXIT_OK, EXIT_FAILURE, EXIT_BAD_INPUT, EXIT_CANCELLED = 0, 1, 2, 130


class BatchError(Exception):
    """A failure with its exit status; the message is what the user reads."""

    def __init__(self, message: str, status: int = EXIT_BAD_INPUT):
        super().__init__(message)
        self.status = status


def _add_on_package():
    """The add-on's package, enabled: an already enabled copy, else the one holding this file."""
    import addon_utils
    import bpy

    for name in bpy.context.preferences.addons.keys():
        if name == "lfprobe" or name.endswith(".lfprobe"):
            return importlib.import_module(name)
    package_dir = os.path.dirname(os.path.abspath(__file__))
    parent = os.path.dirname(package_dir)
    if parent not in sys.path:
        sys.path.insert(0, parent)
    package_name = os.path.basename(package_dir)
    errors = []
    module = addon_utils.enable(package_name, default_set=False, handle_error=errors.append)
    if module is None:
        detail = f": {errors[0]}" if errors else ""
        raise BatchError(f"cannot enable the lfprobe add-on from {package_dir}{detail}", EXIT_FAILURE)
    return module


def _blender_module(package, name: str):
    return importlib.import_module(f"{package.__name__}.blender.{name}")


def _scene_objects():
    return _blender_module(_add_on_package(), "scene_objects")


def _scene(name: str):
    import bpy

    if not name:
        return bpy.context.scene
    scene = bpy.data.scenes.get(name)
    if scene is None:
        raise BatchError(f"no scene named '{name}' in {bpy.data.filepath or 'the unsaved file'}")
    return scene


def _camera(scene, name: str):
    if not name:
        if scene.camera is None:
            raise BatchError(f"scene '{scene.name}' has no active camera: pass --camera NAME")
        return scene.camera
    return _scene_objects().object_of_type(scene, name, "CAMERA", BatchError)


def _depsgraph(scene):
    """The evaluated depsgraph of the scene (animated or constrained cameras and meshes)."""
    import bpy

    if scene == bpy.context.scene:
        return bpy.context.evaluated_depsgraph_get()
    depsgraph = scene.view_layers[0].depsgraph
    depsgraph.update()
    return depsgraph


def _cmd_import(package, args) -> int:
    """Imports scans and gives the scene a probe grid baking from them: an existing box Empty
    (--grid-from, e.g. the demo scenes' probe_grid with its "counts") or a new grid fitted to
    the scans."""
    import bpy

    grid_module = _blender_module(package, "grid")
    scene = _scene(args.scene)
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
        if not grid.probe_dir:
            grid.probe_dir = grid_module.default_probe_dir(grid_obj)
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


def _grids(grid_module, scene, name):
    """The grid named `name` (GridError when there is none), or every grid of the scene by name."""
    if name:
        grid_obj = scene.objects.get(name)
        if grid_obj is None or not grid_module.is_grid(grid_obj):
            raise grid_module.GridError(f"no probe grid named '{name}' in scene '{scene.name}'")
        return [grid_obj]
    return sorted((o for o in scene.objects if grid_module.is_grid(o)), key=lambda o: o.name)


def _save_unless_told_not(args, note: str = "") -> None:
    """Saves the open .blend after a batch step, unless --no-save."""
    import bpy

    if args.no_save:
        return
    if not bpy.data.filepath:
        raise BatchError("the scene is not saved to a .blend: pass --no-save or open a saved .blend")
    bpy.ops.wm.save_mainfile()
    print(f"lfprobe: saved {bpy.data.filepath}{note}")


def _store_storage_options(grid, args) -> None:
    """--storage and --distance-step onto the grid (saved with it), as the panel would set them."""
    if args.distance_step is not None:
        # The property would clamp a step out of its range without a word.
        limits = grid.bl_rna.properties["distance_step"]
        if not limits.hard_min <= args.distance_step <= limits.hard_max:
            raise BatchError(f"--distance-step must be from {limits.hard_min:g} to {limits.hard_max:g} metres, "
                             f"got {args.distance_step}")
        grid.distance_step = args.distance_step
    if args.storage:
        grid.storage = args.storage.upper()


def _cmd_bake(package, args) -> int:
    import bpy

    grid_module = _blender_module(package, "grid")
    bake = _blender_module(package, "operators.bake")
    scene = _scene(args.scene)
    grids = _grids(grid_module, scene, args.grid)
    if not grids:
        raise BatchError(f"scene '{scene.name}' has no probe grid to bake")
    for grid_obj in grids:
        _store_storage_options(grid_obj.lfprobe_grid, args)
        try:
            result = bpy.ops.object.lfprobe_bake(grid=grid_obj.name)
        except RuntimeError as error:  # the operator's ERROR report
            raise BatchError(str(error).strip(), EXIT_BAD_INPUT) from error
        if result != {"FINISHED"}:
            raise BatchError(f"baking grid '{grid_obj.name}' was cancelled", EXIT_CANCELLED)
        folder = grid_module.probe_dir_abspath(grid_obj)
        print(f"lfprobe: baked grid '{grid_obj.name}' into {folder}: loads {bake.memory_text(folder)}")
    _save_unless_told_not(args, " (grids marked as baked)")
    return EXIT_OK


def _cmd_place(package, args) -> int:
    """Add Probes for Views on a grid: bakes it, adds probes at the eyes of the views that trace
    the most UNKNOWN until the target or budget, and saves the .blend (the grid's settings and
    its record of the added probes)."""
    import bpy

    grid_module = _blender_module(package, "grid")
    place_views = _blender_module(package, "operators.place_views")
    scene = _scene(args.scene)
    grids = _grids(grid_module, scene, args.grid)
    if len(grids) != 1:
        raise BatchError(f"scene '{scene.name}' has {len(grids) or 'no'} probe grid{'' if len(grids) == 1 else 's'}"
                         + (": pass --grid NAME" if grids else " to add probes to"))
    grid_obj = grids[0]
    for name in args.views or ():
        _camera(scene, name)  # names the missing object or non-camera before any work
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
    _store_storage_options(grid, args)
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
    _save_unless_told_not(args)
    return EXIT_OK


def _cmd_render(package, args) -> int:
    probe_view = _blender_module(package, "probe_view")
    scene = _scene(args.scene)
    camera_obj = _camera(scene, args.camera)
    target = probe_view.trace_target(scene, args.grid, camera_obj=camera_obj, depsgraph=_depsgraph(scene))
    trace = dict(target.trace, spp=target.spp)
    for option in ("mode", "thickness", "threads", "spp", "filter", "blend"):
        value = getattr(args, option)
        if value is not None:
            trace[option] = value
    out = os.path.abspath(args.out)
    if not os.path.isdir(os.path.dirname(out)):
        raise BatchError(f"--out {args.out}: the folder {os.path.dirname(out)} does not exist")
    if args.camera_json:
        importlib.import_module(f"{package.__name__}.core.camera_json").write_camera(args.camera_json, target.camera)
    _image, stats = target.load_field().render(json.dumps(target.camera), output=out, **trace)
    rays = max(int(stats["rays"]), 1)
    pixels = max(int(stats["hits"] + stats["misses"] + stats["unknown"]), 1)
    print(f"lfprobe: rendered {out} from camera '{camera_obj.name}' through grid '{target.grid_name}': "
          f"{rays:,} rays in {stats['seconds'] * 1000:.1f} ms ({stats['rays_per_second'] / 1e6:.2f} M rays/s), "
          f"pixels HIT {100 * stats['hits'] / pixels:.2f}%, UNKNOWN {100 * stats['unknown'] / pixels:.2f}%")
    return EXIT_OK


def _cmd_compare(package, args) -> int:
    import bpy

    compare = _blender_module(package, "operators.compare")
    scene = _scene(args.scene)
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
        references.append(_scene_objects().object_of_type(
            scene, name, "MESH", lambda message: BatchError(f"--reference: {message}")))
    camera_obj = _camera(scene, args.camera)
    result = compare.run_compare(scene, _depsgraph(scene), references, os.path.abspath(args.out),
                                 camera_obj=camera_obj, grid_name=args.grid, spp=args.spp, ppd=args.ppd)
    print(f"lfprobe: compare {compare.summary_line(result)}")
    print(f"lfprobe: ground truth {result['ref_render_seconds'] * 1000:.1f} ms, probes "
          f"{result['test_render_seconds'] * 1000:.1f} ms; report in {os.path.dirname(result['reference'])}")
    return EXIT_OK


def _add_storage_arguments(parser) -> None:
    parser.add_argument("--storage", choices=["full", "compact"], default=None,
                        help="how the probes load into memory (the files keep full precision): full "
                             "(18 bytes a texel) or compact (7: 8-bit sRGB radiance, 16-bit distance, "
                             "8+8-bit normals, no confidence); default: the grid's Storage")
    parser.add_argument("--distance-step", type=float, default=None, metavar="M",
                        help="compact: the distance quantum in metres (default: the grid's, 0.001)")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="blender -b scene.blend --python-exit-code 1 -P cli.py --",
        description="Bake, render and compare the light field probes of a saved Blender scene.")
    parser.add_argument("--scene", default="", help="scene to use (default: the file's active scene)")
    sub = parser.add_subparsers(dest="command", required=True)

    imp = sub.add_parser("import", help="import scans and set up a probe grid baking from them; save")
    imp.add_argument("--scan", nargs="+", required=True, metavar="FILE", help=".xyz/.pts/.ply scans")
    imp.add_argument("--grid-from", default="", metavar="EMPTY",
                     help="make this box Empty the grid (its 'counts' property is used), "
                          "instead of a new grid fitted to the scans")
    imp.add_argument("--counts", nargs=3, type=int, metavar=("NX", "NY", "NZ"))
    imp.add_argument("--resolution", type=int, default=0, help="probe map resolution (default: the grid's)")
    imp.add_argument("--plan", action="store_true", help="Plan From Data: per-probe resolution, moves, drops")
    imp.add_argument("--margin", type=float, default=0.25, help="new grid: metres inside the scans' bounds")
    imp.add_argument("--spacing", type=float, default=0.0, help="new grid: largest probe spacing (0: keep counts)")
    imp.add_argument("--save-as", metavar="FILE.blend", help="save here (default: over the opened .blend)")
    imp.set_defaults(run=_cmd_import)

    bake = sub.add_parser("bake", help="bake the scene's probe grids and save the .blend")
    bake.add_argument("--grid", default="", metavar="NAME", help="bake only this grid (default: every grid)")
    bake.add_argument("--no-save", action="store_true", help="do not save the .blend afterwards")
    _add_storage_arguments(bake)
    bake.set_defaults(run=_cmd_bake)

    place = sub.add_parser(
        "place", help="bake a grid and add probes where views trace UNKNOWN; save the .blend",
        description="Add Probes for Views: bakes the grid, then adds a probe at the eye of the view "
                    "with the most UNKNOWN pixels, again and again, until every view is at most "
                    "--target-unknown UNKNOWN, the next probe would exceed --budget-mib, or "
                    "--max-added probes were added. Options left out keep the grid's settings.")
    views = place.add_mutually_exclusive_group(required=True)
    views.add_argument("--views", nargs="+", metavar="CAMERA", help="camera objects whose views to serve")
    views.add_argument("--camera-path", action="store_true",
                       help="the scene camera over the scene's frame range, a view every --frame-step frames")
    place.add_argument("--frame-step", type=int, default=None, metavar="K", help="with --camera-path: every K frames")
    place.add_argument("--grid", default="", metavar="NAME", help="probe grid (default: the scene's only grid)")
    place.add_argument("--target-unknown", type=float, default=None, metavar="F",
                       help="stop when every view has at most this fraction of UNKNOWN pixels (grid default 0.01)")
    place.add_argument("--budget-mib", type=float, default=None, metavar="M",
                       help="memory budget of the whole probe set in MiB (0: none)")
    place.add_argument("--max-added", type=int, default=None, metavar="N", help="most probes added")
    place.add_argument("--no-save", action="store_true", help="do not save the .blend afterwards")
    _add_storage_arguments(place)
    place.set_defaults(run=_cmd_place)

    render = sub.add_parser("render", help="trace a camera's view through the baked probes into an EXR")
    render.add_argument("--camera", default="", metavar="NAME", help="camera object (default: the scene camera)")
    render.add_argument("--out", required=True, metavar="IMG.exr",
                        help="image to write (the EXR of ./lfprobe render: RGBA, Z, N, status, probe, steps)")
    render.add_argument("--grid", default="", metavar="NAME",
                        help="probe grid (default: the render settings' grid, else the first baked one)")
    render.add_argument("--mode", choices=["auto", "nearest", "grid"], default=None,
                        help="probe order (default: the scene's render setting)")
    render.add_argument("--thickness", type=float, default=None, help="surface thickness in metres")
    render.add_argument("--threads", type=int, default=None, help="cores (0: all); the image is the same")
    render.add_argument("--spp", type=int, default=None, metavar="N",
                        help="samples per pixel, 1 or a square (default: the scene's Pixel Samples squared)")
    render.add_argument("--filter", choices=["nearest", "bilinear"], default=None,
                        help="a hit's colour: its texel, or interpolated on the same surface (default: the scene's)")
    render.add_argument("--blend", type=int, default=None, metavar="N",
                        help="probes a hit's colour is blended from, 1-8 (default: the scene's)")
    render.add_argument("--camera-json", metavar="CAM.json", help="also write the camera file used")
    render.set_defaults(run=_cmd_render)

    compare = sub.add_parser("compare", help="ground truth of reference meshes vs the probes, with metrics")
    compare.add_argument("--reference", nargs="+", metavar="OBJ", help="reference mesh objects")
    compare.add_argument("--reference-collection", metavar="NAME",
                         help="every mesh of this collection (and its children) as the reference")
    compare.add_argument("--out", required=True, metavar="DIR", help="report folder (created)")
    compare.add_argument("--camera", default="", metavar="NAME", help="camera object (default: the scene camera)")
    compare.add_argument("--grid", default="", metavar="NAME", help="probe grid (default as for render)")
    compare.add_argument("--spp", type=int, default=16,
                         help="samples per pixel of the ground truth and the probe render alike (1 or a square)")
    compare.add_argument("--ppd", type=float, default=67.0, help="FLIP pixels per degree")
    compare.set_defaults(run=_cmd_compare)
    return parser


def _arguments(argv) -> list:
    return argv[argv.index("--") + 1:] if "--" in argv else []


def main(argv=None) -> int:
    args = build_parser().parse_args(_arguments(sys.argv if argv is None else argv))
    try:
        package = _add_on_package()
        # Every error the add-on reports about its input (GridError, TraceSetupError, ...).
        user_errors = (importlib.import_module(f"{package.__name__}.core.errors").InputError,)
        native = importlib.import_module(f"{package.__name__}.core.native").load()
    except BatchError as error:
        print(f"lfprobe: error: {error}", file=sys.stderr)
        return error.status
    except ImportError as error:
        print(f"lfprobe: error: {error}", file=sys.stderr)
        return EXIT_FAILURE
    try:
        return args.run(package, args)
    except BatchError as error:
        print(f"lfprobe: error: {error}", file=sys.stderr)
        return error.status
    except user_errors + (native.InputError, FileNotFoundError) as error:
        print(f"lfprobe: error: {error}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except native.Cancelled:
        print("lfprobe: cancelled", file=sys.stderr)
        return EXIT_CANCELLED
    except (native.NativeIOError, OSError) as error:
        print(f"lfprobe: error: {error}", file=sys.stderr)
        return EXIT_FAILURE


if __name__ == "__main__":
    sys.stdout.flush()
    status = main()
    sys.stdout.flush()
    sys.stderr.flush()
    if status:
        sys.exit(status)
