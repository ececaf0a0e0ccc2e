"""The add-on's interactive paths, in a real Blender window (Blender 3.4.1 under Xvfb; the bpy
wheel has no windows): the modal import and bake keep the UI running (timers keep firing
while the native work runs), show progress and finish; Esc cancels a bake and leaves the
previous probe set; the overlay draws with this Blender's GPU module.

    xvfb-run -a -s "-screen 0 1280x800x24" blender --factory-startup --enable-event-simulate \
        -P tests/blender/run_ui.py

Prints PASS/FAIL per check and exits non-zero when any fails; a Python error inside a
panel's draw() only prints a traceback, so the caller also fails the run on "Traceback"."""

import os
import sys
import time
import traceback

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import helpers  # noqa: E402

TIMEOUT = 120.0
results = []


def _window_context():
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    region = next(r for r in area.regions if r.type == "WINDOW")
    return dict(window=window, area=area, region=region)


def _invoke(operator, **properties):
    with bpy.context.temp_override(**_window_context()):
        return operator("INVOKE_DEFAULT", **properties)


def _check(name, condition, detail=""):
    results.append((name, bool(condition)))
    print(("PASS " if condition else "FAIL ") + name + (f": {detail}" if detail and not condition else ""))
    sys.stdout.flush()


def scenario():
    """A generator: each yield hands control back to Blender's event loop for a while."""
    helpers.enable_addon()
    folder = helpers.tmp_dir()
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(folder, "ui.blend"))
    scan_path = os.path.join(folder, "room.xyz")
    helpers.write_box_room_xyz(scan_path, pitch=0.02)

    # Modal import: the operator returns at once and the object appears later.
    ticks = []  # times at which a UI timer ran

    def tick():
        ticks.append(time.monotonic())
        return 0.02

    bpy.app.timers.register(tick)
    jobs = helpers.addon("blender.operators.job_modal").running_labels
    with bpy.context.temp_override(**_window_context()):
        started = bpy.ops.import_scene.lfprobe_scan(
            "EXEC_DEFAULT", directory=folder, files=[{"name": "room.xyz"}]
        )
    _check("import runs modal", started == {"RUNNING_MODAL"}, started)
    deadline = time.monotonic() + TIMEOUT
    while "room" not in bpy.data.objects and time.monotonic() < deadline:
        yield 0.05
    scan = bpy.data.objects.get("room")
    _check("modal import finishes", scan is not None and scan.lfprobe_scan.point_count > 100_000)

    # Modal bake: timers keep firing (the UI is responsive) and the bake lands.
    bpy.ops.object.select_all(action="DESELECT")
    scan.select_set(True)
    bpy.context.view_layer.objects.active = scan
    with bpy.context.temp_override(**_window_context()):
        bpy.ops.object.lfprobe_grid_add()
        grid_obj = bpy.context.view_layer.objects.active
        bpy.ops.object.lfprobe_grid_fit(margin=0.5, spacing=0.0)
    grid_obj.lfprobe_grid.counts = (3, 2, 2)
    grid_obj.lfprobe_grid.resolution = 256
    started = _invoke(bpy.ops.object.lfprobe_bake, grid=grid_obj.name)
    begun = time.monotonic()
    _check("bake runs modal", started == {"RUNNING_MODAL"} and jobs == ["Probe bake"], (started, jobs))
    while jobs and time.monotonic() - begun < TIMEOUT:
        yield 0.05
    seconds = time.monotonic() - begun
    _check("modal bake finishes with coverage", grid_obj.lfprobe_grid.baked and len(grid_obj.lfprobe_grid.coverage()) == 12)
    # The main loop keeps running: no gap between UI timer runs comes near the bake's length.
    during = [t for t in ticks if begun <= t <= begun + seconds]
    gaps = [b - a for a, b in zip([begun] + during, during + [begun + seconds])]
    _check("UI stays responsive while baking", len(during) >= 3 and max(gaps) < 0.5 * seconds,
           f"{len(during)} timer runs in {seconds:.1f} s, longest gap {max(gaps):.2f} s")
    print(f"  modal bake: {seconds:.1f} s, {len(during)} UI timer runs meanwhile, longest gap {max(gaps):.2f} s")
    probe_dir = helpers.addon("blender.grid").probe_dir_abspath(grid_obj)
    manifest_before = open(os.path.join(probe_dir, "manifest.json")).read()

    # Esc cancels: the previous probe set stays, nothing half-written is left.
    grid_obj.lfprobe_grid.resolution = 1024
    grid_obj.lfprobe_grid.counts = (4, 3, 3)
    _invoke(bpy.ops.object.lfprobe_bake, grid=grid_obj.name)
    yield 1.0
    window = bpy.context.window_manager.windows[0]
    escaped = time.monotonic()
    window.event_simulate(type="ESC", value="PRESS")
    window.event_simulate(type="ESC", value="RELEASE")
    while jobs and time.monotonic() - escaped < TIMEOUT:
        yield 0.05
    stopped = time.monotonic() - escaped
    print(f"  Esc: the bake stopped {stopped:.2f} s later")
    staging = probe_dir.rstrip(os.sep) + ".baking"
    _check("Esc cancels the bake", not jobs and stopped < 10.0 and not os.path.exists(staging),
           f"stopped after {stopped:.1f} s; staging left: {os.path.exists(staging)}")
    _check("a cancelled bake keeps the previous probe set",
           open(os.path.join(probe_dir, "manifest.json")).read() == manifest_before)

    # Disabling the add-on during a bake stops the bake (no job left running, no staging
    # folder), and enabled again it bakes.
    _invoke(bpy.ops.object.lfprobe_bake, grid=grid_obj.name)
    yield 1.0
    baking = list(jobs)
    helpers.disable_addon()
    yield 0.3
    _check("disabling the add-on stops a running bake",
           baking == ["Probe bake"] and not jobs and not os.path.exists(staging),
           f"running before {baking}, after {jobs}; staging left: {os.path.exists(staging)}")
    helpers.enable_addon()
    jobs = helpers.addon("blender.operators.job_modal").running_labels
    grid_obj.lfprobe_grid.resolution = 64
    grid_obj.lfprobe_grid.counts = (2, 2, 1)
    with bpy.context.temp_override(**_window_context()):
        can_bake = bpy.ops.object.lfprobe_bake.poll()
    started = _invoke(bpy.ops.object.lfprobe_bake, grid=grid_obj.name)
    deadline = time.monotonic() + TIMEOUT
    while jobs and time.monotonic() < deadline:
        yield 0.05
    _check("enabled again, the add-on bakes", can_bake and started == {"RUNNING_MODAL"}
           and len(grid_obj.lfprobe_grid.coverage()) == 4, (can_bake, started))

    # The overlay draws the grid with this Blender's builtin shaders.
    overlay = helpers.addon("blender.ui.overlay")
    overlay._batch_cache.clear()
    helpers.addon("blender.ui.scan_display")._batch_cache.clear()
    with bpy.context.temp_override(**_window_context()):
        bpy.ops.wm.redraw_timer(type="DRAW_WIN", iterations=1)
    _check("overlay draws the grid", grid_obj.name in overlay._batch_cache)
    _check("the scan is drawn in its colours", scan.name in helpers.addon("blender.ui.scan_display")._batch_cache)
    # The panels draw (a Python error in a draw() only prints a traceback: the wrapper,
    # tools/blender_tests.sh, fails the run on any traceback in the output).
    window = bpy.context.window_manager.windows[0]
    properties = next(a for a in window.screen.areas if a.type == "PROPERTIES")
    properties.spaces.active.context = "OBJECT"
    for active in (grid_obj, scan):
        bpy.context.view_layer.objects.active = active
        properties.tag_redraw()
        with bpy.context.temp_override(**_window_context()):
            bpy.ops.wm.redraw_timer(type="DRAW_WIN", iterations=1)
    bpy.context.view_layer.objects.active = grid_obj

    shot = os.environ.get("LFPROBE_UI_SCREENSHOT")  # to look at: the overlay over the scan
    if shot:
        context = _window_context()
        with bpy.context.temp_override(**context):
            bpy.ops.view3d.view_all()
        for _ in range(5):
            yield 0.3
        with bpy.context.temp_override(**context):
            bpy.ops.wm.redraw_timer(type="DRAW_WIN_SWAP", iterations=1)
            bpy.ops.screen.screenshot(filepath=shot)


def drive(steps):
    def tick():
        try:
            return next(steps)
        except StopIteration:
            finish()
        except Exception:
            traceback.print_exc()
            results.append(("scenario", False))
            finish()
        return None
    return tick


def finish():
    failed = [name for name, ok in results if not ok]
    print(f"{len(results) - len(failed)} passed, {len(failed)} failed")
    sys.stdout.flush()
    os._exit(1 if failed or not results else 0)  # from a timer: the only way to set the exit code


bpy.context.preferences.view.show_splash = False
bpy.app.timers.register(drive(scenario()), first_interval=1.0)
