"""Esc stops F12 (Blender 3.4.1 in a window under Xvfb): a render through the probes that would
take minutes (1920×1080, 8×8 rays a pixel) ends within a second of a real Esc key press, sent
through the X server (xdotool, XTEST) as a user's keyboard would; Blender's event simulation
cannot test this, as simulated events never reach the render job's break flag.

    xvfb-run -a -s "-screen 0 1280x800x24" blender --factory-startup -P tests/blender/run_f12_esc.py

Prints PASS/FAIL and exits non-zero when the check fails."""

import os
import subprocess
import sys
import time
import traceback

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import helpers  # noqa: E402

TIMEOUT = 120.0


def _window_context():
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    region = next(r for r in area.regions if r.type == "WINDOW")
    return dict(window=window, area=area, region=region)


def _wait_for_jobs():
    jobs = helpers.addon("blender.operators.job_modal").running_labels
    deadline = time.monotonic() + TIMEOUT
    while jobs and time.monotonic() < deadline:
        yield 0.1


def scenario(results):
    helpers.enable_addon()
    folder = helpers.tmp_dir()
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(folder, "f12.blend"))
    helpers.write_box_room_xyz(os.path.join(folder, "room.xyz"), pitch=0.05)
    with bpy.context.temp_override(**_window_context()):
        bpy.ops.import_scene.lfprobe_scan("EXEC_DEFAULT", directory=folder, files=[{"name": "room.xyz"}])
    yield from _wait_for_jobs()
    scan = bpy.data.objects["room"]
    bpy.ops.object.select_all(action="DESELECT")
    scan.select_set(True)
    bpy.context.view_layer.objects.active = scan
    bpy.ops.object.lfprobe_grid_add()
    grid_obj = bpy.context.view_layer.objects.active
    bpy.ops.object.lfprobe_grid_fit(margin=0.5, spacing=0.0)
    grid_obj.lfprobe_grid.counts = (2, 2, 1)
    grid_obj.lfprobe_grid.resolution = 64
    with bpy.context.temp_override(**_window_context()):
        bpy.ops.object.lfprobe_bake("INVOKE_DEFAULT", grid=grid_obj.name)
    yield from _wait_for_jobs()

    scene = bpy.context.scene
    bpy.ops.object.camera_add(location=grid_obj.location, rotation=(1.4, 0.0, 0.3))
    scene.camera = bpy.context.view_layer.objects.active
    scene.render.engine = "LFPROBE"
    scene.render.resolution_x, scene.render.resolution_y = 1920, 1080
    scene.render.resolution_percentage = 100
    scene.lfprobe_render.samples = 8
    bpy.context.preferences.view.render_display_type = "NONE"
    ended = []
    handler = lambda *_args: ended.append(time.monotonic())  # noqa: E731
    bpy.app.handlers.render_cancel.append(handler)
    with bpy.context.temp_override(**_window_context()):
        bpy.ops.render.render("INVOKE_DEFAULT")
    yield 1.5
    running = bpy.app.is_job_running("RENDER")
    subprocess.run(["xdotool", "mousemove", "640", "400"], check=True)
    pressed = time.monotonic()
    subprocess.run(["xdotool", "key", "Escape"], check=True)
    while bpy.app.is_job_running("RENDER") and time.monotonic() - pressed < TIMEOUT:
        yield 0.02
    stopped = (ended[0] if ended else time.monotonic()) - pressed
    print(f"  F12: the render was cancelled {stopped:.2f} s after Esc")
    ok = running and bool(ended) and stopped < 1.0
    results.append(ok)
    print(("PASS" if ok else "FAIL") + " Esc stops F12 within a second"
          + ("" if ok else f": rendering when Esc came {running}, cancelled {bool(ended)}, {stopped:.2f} s"))


def main():
    results = []
    steps = scenario(results)

    def tick():
        try:
            return next(steps)
        except StopIteration:
            pass
        except Exception:
            traceback.print_exc()
            results.append(False)
        sys.stdout.flush()
        os._exit(0 if results and all(results) else 1)  # from a timer: the only way to set the exit code

    bpy.context.preferences.view.show_splash = False
    bpy.app.timers.register(tick, first_interval=1.0)


main()
