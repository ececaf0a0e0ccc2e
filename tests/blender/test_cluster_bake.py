"""Baking on a Dask cluster from Blender: with a scheduler address in the add-on's preferences,
Bake hands the probes to `dask worker` processes (started here as a user would, with
PYTHONPATH=<lfprobe>/addon); the set equals the local bake's byte for byte, a moved scan object
included. The operator's scheduler (what the batch `bake --scheduler` passes) overrides the
preferences; one that cannot be reached is the operator's error and leaves the baked set as
it was."""

import json
import os
import shutil
import subprocess
import time

import bpy

import helpers


def _files(folder: str) -> dict:
    out = {}
    for name in sorted(os.listdir(folder)):
        with open(os.path.join(folder, name), "rb") as stream:
            out[name] = stream.read()
    return out


class _Cluster:
    """`dask scheduler` and one `dask worker` as processes of their own."""

    def __init__(self):
        if shutil.which("dask") is None:
            raise helpers.Skip("Dask's command line is not installed (python3-distributed)")
        folder = helpers.tmp_dir()
        scheduler_file = os.path.join(folder, "scheduler.json")
        env = dict(os.environ, PYTHONPATH=os.path.dirname(helpers.ADDON_DIR))
        quiet = dict(stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
        self.processes = [subprocess.Popen(["dask", "scheduler", "--scheduler-file", scheduler_file,
                                            "--port", "0", "--dashboard-address", ":0"], **quiet)]
        self.processes.append(subprocess.Popen(["dask", "worker", "--scheduler-file", scheduler_file,
                                                "--nthreads", "1", "--no-dashboard"], **quiet))
        deadline = time.monotonic() + 60
        while not os.path.exists(scheduler_file):
            assert time.monotonic() < deadline, "dask scheduler did not start"
            time.sleep(0.1)
        with open(scheduler_file) as stream:
            self.address = json.load(stream)["address"]
        from distributed import Client

        with Client(self.address, timeout=30, set_as_default=False) as client:
            client.wait_for_workers(1, timeout=60)

    def close(self):
        for process in reversed(self.processes):
            process.terminate()
        for process in self.processes:
            process.wait(timeout=30)


def _box_room_grid_moved():
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(helpers.tmp_dir(), "scene.blend"))
    path = os.path.join(helpers.tmp_dir(), "box_room.xyz")
    helpers.write_box_room_xyz(path, pitch=0.05)
    (scan,) = helpers.import_scans(path)
    bpy.ops.object.lfprobe_grid_add()
    grid_obj = bpy.context.active_object
    bpy.ops.object.lfprobe_grid_fit(margin=1.0, spacing=0.0)
    grid_obj.lfprobe_grid.counts = (2, 1, 1)
    grid_obj.lfprobe_grid.resolution = 32
    grid_obj.lfprobe_grid.plan_from_data = False  # planned bakes stay on this machine
    scan.location = (1.0, 0.0, 0.0)  # the workers must move the points as Blender shows them
    grid_obj.location.x += 1.0
    bpy.context.view_layer.update()
    return grid_obj


def test_bake_on_the_preferences_scheduler_equals_the_local_bake():
    grid_obj = _box_room_grid_moved()
    folder = helpers.addon("blender.grid").probe_dir_abspath(grid_obj)
    assert bpy.ops.object.lfprobe_bake() == {"FINISHED"}
    local = _files(folder)
    assert len(local) == 4  # two probes, their known space and the manifest

    cluster = _Cluster()
    try:
        preferences = helpers.addon("blender.preferences")
        bpy.context.preferences.addons[preferences.ADDON_PACKAGE].preferences.scheduler_address = cluster.address
        assert preferences.scheduler_address() == cluster.address
        assert bpy.ops.object.lfprobe_bake() == {"FINISHED"}
    finally:
        cluster.close()
    assert _files(folder) == local
    assert grid_obj.lfprobe_grid.baked
    leftovers = [n for n in os.listdir(os.path.dirname(folder)) if n.endswith((".partial", ".baking"))]
    assert leftovers == []

    # The operator's own scheduler (the batch bake's --scheduler) wins over the preferences'.
    helpers.addon("core.cluster_bake").CONNECT_TIMEOUT_SECONDS = 1.0
    try:
        helpers.expect_operator_error(lambda: bpy.ops.object.lfprobe_bake(scheduler="tcp://127.0.0.1:9"),
                                      "cannot reach the Dask scheduler at 'tcp://127.0.0.1:9'")
    finally:
        helpers.addon("core.cluster_bake").CONNECT_TIMEOUT_SECONDS = 10.0
    assert _files(folder) == local
    assert grid_obj.lfprobe_grid.baked


def test_plan_from_data_bakes_here_when_a_scheduler_is_set():
    """A planned bake is not handed to the cluster: with an (unreachable) scheduler in the
    preferences, Plan From Data bakes on this machine, with a warning, instead of failing."""
    grid_obj = _box_room_grid_moved()
    grid_obj.lfprobe_grid.plan_from_data = True
    preferences = helpers.addon("blender.preferences")
    prefs = bpy.context.preferences.addons[preferences.ADDON_PACKAGE].preferences
    prefs.scheduler_address = "tcp://127.0.0.1:9"
    try:
        assert bpy.ops.object.lfprobe_bake() == {"FINISHED"}
    finally:
        prefs.scheduler_address = ""
    assert grid_obj.lfprobe_grid.baked
