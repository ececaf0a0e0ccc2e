"""Takes the README's screenshots of the add-on in a real Blender window, and measures how
fast the Rendered viewport refines.

    xvfb-run -s "-screen 0 1600x1000x24" blender --factory-startup -P tools/screenshots.py [-- OUT_DIR]

Builds a small scene (the real pump-room scan from ../shared/data, a probe grid fitted to it,
a low-resolution bake into a temporary folder, a camera), then, once the window has drawn,
writes into docs/screenshots/ (or OUT_DIR): panel_scan.png and panel_grid.png (the Object
properties of the scan cloud and the grid), overlay.png (the 3D viewport with the grid's
probe overlay), render_settings.png (the engine's render panel), viewport_rendered.png (the
viewport traced through the probes) and window.png; prints the viewport's refinement time per
level; quits. Exit status 0 when every screenshot was written, 1 otherwise.
"""

import os
import sys
import tempfile
import time
import traceback

import addon_utils
import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED = os.environ.get("LFPROBE_SHARED_DATA", os.path.join(ROOT, "..", "shared", "data"))
SCAN = os.path.join(SHARED, "scans", "pumpA_xyzrgb.xyz")
OUT = os.path.abspath(sys.argv[sys.argv.index("--") + 1]) if "--" in sys.argv[:-1] else \
    os.path.join(ROOT, "docs", "screenshots")
PROBE_RESOLUTION = 128
REFINE_TIMEOUT = 120.0  # seconds any one step may wait (import, bake, refinement)

_work = tempfile.mkdtemp(prefix="lfprobe-screenshots-")
_state = {"step": 0, "written": [], "failed": False, "waited": 0.0}


def _enable_addon():
    sys.path.insert(0, os.path.join(ROOT, "addon"))
    addon_utils.enable("lfprobe", default_set=False, handle_error=lambda error: (_ for _ in ()).throw(error))
    return sys.modules["lfprobe"]


def _window():
    # Timers run without a window in the context: the one window of this session.
    return bpy.context.window_manager.windows[0]


def _area(kind):
    screen = _window().screen
    return max((a for a in screen.areas if a.type == kind), key=lambda a: a.width * a.height, default=None)


def _region(area, kind="WINDOW"):
    return next(r for r in area.regions if r.type == kind)


def _override(area):
    return bpy.context.temp_override(window=_window(), screen=_window().screen, area=area, region=_region(area))


def _shoot_area(area, name):
    path = os.path.join(OUT, name)
    with _override(area):
        bpy.ops.screen.screenshot_area(filepath=path)
    _state["written"].append(path)
    print(f"screenshots: wrote {path}")


def _synchronous():
    """Without a window in the context the add-on's import and bake run to the end at once
    (as in blender -b) instead of modally: the screenshots need their results, not their
    progress bars."""
    return bpy.context.temp_override(window=None)


def _start_import():
    """Imports the pump-room scan into a saved, otherwise empty scene (the camera stays)."""
    _enable_addon()
    for obj in list(bpy.data.objects):
        if obj.type != "CAMERA":
            bpy.data.objects.remove(obj)
    blend = os.path.join(_work, "pump_room.blend")
    bpy.ops.wm.save_as_mainfile(filepath=blend)
    with _synchronous():
        bpy.ops.wm.open_mainfile(filepath=blend)  # also closes the splash screen
    with _synchronous():
        bpy.ops.import_scene.lfprobe_scan(directory=os.path.dirname(SCAN), files=[{"name": os.path.basename(SCAN)}])


def _scan_object():
    return next((o for o in bpy.data.objects if o.type == "MESH" and o.lfprobe_scan.is_scan), None)


def _start_bake(scan):
    """A grid fitted to the scan, baked at a low resolution, and a camera inside the room."""
    for obj in bpy.context.view_layer.objects:
        obj.select_set(False)
    scan.select_set(True)
    bpy.context.view_layer.objects.active = scan
    with _override(_area("VIEW_3D")):
        bpy.ops.object.lfprobe_grid_add()
    grid = next(o for o in bpy.data.objects if o.type == "EMPTY" and o.lfprobe_grid.is_grid)
    grid.lfprobe_grid.resolution = PROBE_RESOLUTION
    bpy.context.view_layer.objects.active = grid
    # A single-station scan is seen best near its scanner (the origin): a small grid there.
    grid.location, grid.scale = (0.0, 0.0, 0.0), (0.6, 0.6, 0.3)
    grid.lfprobe_grid.counts = (2, 2, 2)  # the grid took the selected scan as its source
    with _synchronous():
        bpy.ops.object.lfprobe_bake(grid=grid.name)
    camera = bpy.context.scene.camera
    camera.location = (0.0, 0.0, 0.0)
    camera.rotation_euler = (1.2, 0.0, 2.4)
    camera.data.lens = 20.0
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = 960, 540
    scene.lfprobe_render.grid = grid
    return scan, grid


def _step_panels(scan, grid):
    view3d = _area("VIEW_3D")
    space = view3d.spaces.active
    space.shading.type = "SOLID"
    for obj in bpy.context.view_layer.objects:
        obj.select_set(False)
    grid.select_set(True)
    bpy.context.view_layer.objects.active = grid
    with _override(view3d):
        bpy.ops.view3d.view_all()
    properties = _area("PROPERTIES")
    properties.spaces.active.context = "OBJECT"
    # The grid's panel sits below Transform and the others: scroll down to it.
    with _override(properties):
        for _ in range(6):
            bpy.ops.view2d.scroll_down(page=True)


def _step_scan_panel(scan):
    bpy.context.view_layer.objects.active = scan
    _area("PROPERTIES").spaces.active.context = "OBJECT"


def _start_rendered_view():
    scene = bpy.context.scene
    scene.render.engine = "LFPROBE"
    _area("PROPERTIES").spaces.active.context = "RENDER"
    view3d = _area("VIEW_3D")
    space = view3d.spaces.active
    space.region_3d.view_perspective = "CAMERA"
    space.overlay.show_overlays = False
    space.shading.type = "RENDERED"
    _state["render_started"] = time.perf_counter()


def _refined() -> bool:
    engine = sys.modules["lfprobe.blender.engine"]
    stats = engine.viewport_stats()
    return stats is not None and len(stats.levels) == 4


def _report_refinement():
    engine = sys.modules["lfprobe.blender.engine"]
    stats = engine.viewport_stats()
    print("screenshots: viewport refinement (level = downscale factor; trace time, time since the view changed)")
    for t in stats.levels:
        print(f"  1/{t.level}: {t.width}×{t.height} traced in {t.seconds * 1000:.0f} ms, "
              f"on screen {t.since_request * 1000:.0f} ms after the request")


def _wait(what: str) -> float:
    """Polls again soon; gives up after REFINE_TIMEOUT seconds on one step."""
    _state["waited"] += 0.2
    if _state["waited"] > REFINE_TIMEOUT:
        raise TimeoutError(f"gave up waiting for {what}")
    return 0.2


def _tick():
    """One step per timer call, so that the window redraws between steps."""
    step = _state["step"]
    try:
        if step == 0:
            _start_import()
        elif step == 1:
            if _scan_object() is None:
                return _wait("the scan import")
            _state["scene"] = _start_bake(_scan_object())
        elif step == 2:
            if not _state["scene"][1].lfprobe_grid.baked:
                return _wait("the bake")
            _step_panels(*_state["scene"])
        elif step == 3:
            _shoot_area(_area("PROPERTIES"), "panel_grid.png")
            _shoot_area(_area("VIEW_3D"), "overlay.png")
            _step_scan_panel(_state["scene"][0])
        elif step == 4:
            _shoot_area(_area("PROPERTIES"), "panel_scan.png")
            _start_rendered_view()
        elif step == 5:
            if not _refined():
                _area("VIEW_3D").tag_redraw()
                return _wait("the Rendered viewport's refinement")
            _report_refinement()
        elif step == 6:
            _shoot_area(_area("VIEW_3D"), "viewport_rendered.png")
            _shoot_area(_area("PROPERTIES"), "render_settings.png")
            path = os.path.join(OUT, "window.png")
            with bpy.context.temp_override(window=_window(), screen=_window().screen):
                bpy.ops.screen.screenshot(filepath=path)
            _state["written"].append(path)
            print(f"screenshots: wrote {path}")
        else:
            _finish()
            return None
    except Exception:
        traceback.print_exc()
        _state["failed"] = True
        _finish()
        return None
    _state["step"] += 1
    _state["waited"] = 0.0
    return 1.0  # seconds for the window to redraw before the next step


def _finish():
    ok = not _state["failed"] and len(_state["written"]) == 6
    print(f"screenshots: {'done' if ok else 'FAILED'}, {len(_state['written'])} written to {OUT}")
    sys.stdout.flush()
    os._exit(0 if ok else 1)  # quit_blender would ask nothing, but cannot carry an exit status


if bpy.app.background:
    print("screenshots: needs a window (run under xvfb-run without -b)", file=sys.stderr)
    sys.exit(2)
if not os.path.isfile(SCAN):
    print(f"screenshots: the scan {SCAN} is missing (set LFPROBE_SHARED_DATA)", file=sys.stderr)
    sys.exit(2)
os.makedirs(OUT, exist_ok=True)
bpy.app.timers.register(_tick, first_interval=2.0, persistent=True)
