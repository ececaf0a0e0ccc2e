"""The batch command line's options (blender -b -P cli.py -- --open FILE.blend COMMAND ...)."""

from __future__ import annotations

import argparse

from ...core import defaults
from ...core.cli.arguments import finite_float
from ...core.grid_fit import FIT_MARGIN, FIT_SPACING
from . import commands


def _add_storage_arguments(parser) -> None:
    parser.add_argument("--storage", choices=["full", "compact"], default=None,
                        help="how the probes load into memory (the files keep full precision): full "
                             "(18 bytes a texel) or compact (7: 8-bit sRGB radiance, 16-bit distance, "
                             "8+8-bit normals, no confidence); default: the grid's Storage")
    parser.add_argument("--distance-step", type=finite_float, default=None, metavar="M",
                        help="compact: the distance quantum in metres (default: the grid's; a new grid's is "
                             f"{defaults.storage('distance_step'):g})")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="blender -b --python-exit-code 1 -P cli.py --",
        description="Bake, render and compare the light field probes of a saved Blender scene.")
    parser.add_argument("--open", default="", metavar="FILE.blend",
                        help="the .blend to work on, opened once the add-on is enabled (blender -b FILE.blend "
                             "-P cli.py opens it before, and Blender reports the engine LFPROBE of a scene "
                             "as not available)")
    parser.add_argument("--scene", default="", help="scene to use (default: the file's active scene)")
    sub = parser.add_subparsers(dest="command", required=True)

    imp = sub.add_parser("import", help="import scans and set up a probe grid baking from them; save")
    imp.add_argument("--scan", nargs="+", required=True, metavar="FILE", help=".xyz/.pts/.ply scans")
    imp.add_argument("--grid-from", default="", metavar="EMPTY",
                     help="make this box Empty the grid (its 'counts' property is used), "
                          "instead of a new grid fitted to the scans")
    imp.add_argument("--counts", nargs=3, type=int, metavar=("NX", "NY", "NZ"))
    imp.add_argument("--resolution", type=int, default=0, help="probe map resolution (default: the grid's)")
    plan = imp.add_mutually_exclusive_group()
    plan.add_argument("--plan", dest="plan", action="store_true", default=True,
                      help="Plan From Data: per-probe resolution, moves, drops (the default, as in the UI)")
    plan.add_argument("--no-plan", dest="plan", action="store_false",
                      help="every probe where the grid puts it, at --resolution")
    imp.add_argument("--margin", type=finite_float, default=FIT_MARGIN,
                     help=f"new grid: metres inside the scans' bounds (default {FIT_MARGIN}, as Fit Grid)")
    imp.add_argument("--spacing", type=finite_float, default=FIT_SPACING,
                     help=f"new grid: largest probe spacing (default {FIT_SPACING} m, as Fit Grid; 0: keep the "
                          "new grid's counts, 2×2×2)"),
    imp.add_argument("--save-as", metavar="FILE.blend", help="save here (default: over the opened .blend)")
    imp.set_defaults(run=commands.run_import)

    bake = sub.add_parser("bake", help="bake the scene's probe grids and save the .blend")
    bake.add_argument("--grid", default="", metavar="NAME", help="bake only this grid (default: every grid)")
    bake.add_argument("--no-save", action="store_true", help="do not save the .blend afterwards")
    bake.add_argument("--scheduler", default="", metavar="ADDRESS",
                      help="bake the probes on this running Dask scheduler (tcp://HOST:8786; default: "
                           "the add-on preferences' address, else this machine)")
    _add_storage_arguments(bake)
    bake.set_defaults(run=commands.run_bake)

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
    place.add_argument("--target-unknown", type=finite_float, default=None, metavar="F",
                       help="stop when every view has at most this fraction of UNKNOWN pixels (grid default 0.01)")
    place.add_argument("--budget-mib", type=finite_float, default=None, metavar="M",
                       help="memory budget of the whole probe set in MiB (0: none)")
    place.add_argument("--max-added", type=int, default=None, metavar="N", help="most probes added")
    place.add_argument("--no-save", action="store_true", help="do not save the .blend afterwards")
    _add_storage_arguments(place)
    place.set_defaults(run=commands.run_place)

    render = sub.add_parser("render", help="trace a camera's view through the baked probes into an EXR")
    render.add_argument("--camera", default="", metavar="NAME", help="camera object (default: the scene camera)")
    render.add_argument("--out", required=True, metavar="IMG.exr",
                        help="image to write (the EXR of ./lfprobe render: RGBA, Z, N, status, probe, steps)")
    render.add_argument("--grid", default="", metavar="NAME",
                        help="probe grid (default: the render settings' grid, else the first baked one)")
    render.add_argument("--mode", choices=["auto", "nearest", "grid"], default=None,
                        help="probe order (default: the scene's render setting)")
    render.add_argument("--thickness", type=finite_float, default=None, help="surface thickness in metres")
    render.add_argument("--fallback-thickness", type=finite_float, default=None, metavar="M",
                        help="a ray no probe answers meets the surface it stopped behind within M metres "
                             "(default: the scene's render setting)")
    render.add_argument("--threads", type=int, default=None, help="cores (0: all); the image is the same")
    render.add_argument("--spp", type=int, default=None, metavar="N",
                        help="samples per pixel, 1 or a square (default: the scene's Pixel Samples squared)")
    render.add_argument("--filter", choices=["nearest", "bilinear", "footprint", "bicubic"], default=None,
                        help="a hit's colour: its texel, interpolated on the same surface (bilinear, or bicubic: "
                             "Catmull-Rom, sharper), or averaged over the pixel's footprint (default: the scene's)")
    render.add_argument("--blend", type=int, default=None, metavar="N",
                        help="probes a hit's colour is blended from, 1-8 (default: the scene's)")
    render.add_argument("--hole-fill-px", dest="hole_fill", type=int, default=None, metavar="N",
                        help="UNKNOWN holes at most N pixels across coloured from the pixels around them, "
                             "their status kept (0: off; default: the scene's Fill Holes, 5%% of the width)")
    render.add_argument("--camera-json", metavar="CAM.json", help="also write the camera file used")
    render.set_defaults(run=commands.run_render)

    compare = sub.add_parser("compare", help="ground truth of reference meshes vs the probes, with metrics")
    compare.add_argument("--reference", nargs="+", metavar="OBJ", help="reference mesh objects")
    compare.add_argument("--reference-collection", metavar="NAME",
                         help="every mesh of this collection (and its children) as the reference")
    compare.add_argument("--out", required=True, metavar="DIR", help="report folder (created)")
    compare.add_argument("--camera", default="", metavar="NAME", help="camera object (default: the scene camera)")
    compare.add_argument("--grid", default="", metavar="NAME", help="probe grid (default as for render)")
    compare.add_argument("--spp", type=int, default=16,
                         help="samples per pixel of the ground truth and the probe render alike (1 or a square)")
    compare.add_argument("--ppd", type=finite_float, default=67.0, help="FLIP pixels per degree")
    compare.set_defaults(run=commands.run_compare)
    return parser
