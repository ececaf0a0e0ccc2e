"""A traced scene for the render-side tests (engine, compare, batch CLI): the box room of
helpers.write_box_room_xyz baked once per test run with the bpy-free pipeline (not the
add-on's bake), a probe grid pointing at it, a camera and a reference mesh of the room."""

from __future__ import annotations

import json
import os
import subprocess

import bpy
from mathutils import Matrix

import helpers

GRID_MIN = (-1.0, -0.5, 1.0)
GRID_MAX = (1.0, 0.5, 1.5)
GRID_COUNTS = (2, 2, 2)
RESOLUTION = 64
CAMERA_POSITION = (0.3, 0.2, 1.3)
CAMERA_TARGET = (2.0, 1.0, 1.0)
IMAGE_SIZE = (64, 48)

_baked = {}


def baked_probe_set() -> str:
    """The probe set folder of the box room (2×2×2 probes, 64² texels), baked once."""
    if "folder" not in _baked:
        work = helpers.tmp_dir()
        scan = os.path.join(work, "room.xyz")
        helpers.write_box_room_xyz(scan, 0.05)
        pipeline = helpers.addon("core.pipeline")
        folder = os.path.join(work, "probes")
        placement = pipeline.ProbePlacementSpec(grid_min=GRID_MIN, grid_max=GRID_MAX, counts=GRID_COUNTS)
        pipeline.bake_from_scans([scan], folder, placement, pipeline.BakeOptions(resolution=RESOLUTION),
                                 cache_dir="")
        _baked["folder"], _baked["scan"] = folder, scan
    return _baked["folder"]


def box_room_scan() -> str:
    baked_probe_set()
    return _baked["scan"]


def add_grid(folder: str, name: str = "ProbeGrid", baked: bool = True):
    """A probe grid over GRID_MIN..GRID_MAX whose probe folder is `folder`."""
    scene = bpy.context.scene
    obj = bpy.data.objects.new(name, None)
    obj.empty_display_type = "CUBE"
    scene.collection.objects.link(obj)
    obj.location = [(lo + hi) / 2 for lo, hi in zip(GRID_MIN, GRID_MAX)]
    obj.scale = [max((hi - lo) / 2, 1e-4) for lo, hi in zip(GRID_MIN, GRID_MAX)]
    grid = obj.lfprobe_grid
    grid.is_grid = True
    grid.counts = GRID_COUNTS
    grid.resolution = RESOLUTION
    grid.probe_dir = folder
    grid.baked = baked
    return obj


def add_camera(name: str = "Camera", position=CAMERA_POSITION, target=CAMERA_TARGET, lens: float = 24.0):
    """A perspective camera aimed at `target`, made the scene camera; render size IMAGE_SIZE."""
    core_camera = helpers.addon("core.camera_json")
    scene = bpy.context.scene
    data = bpy.data.cameras.new(name)
    data.lens = lens
    data.clip_start = 0.01
    obj = bpy.data.objects.new(name, data)
    scene.collection.objects.link(obj)
    obj.matrix_world = Matrix(core_camera.look_at_matrix(position, target))
    scene.camera = obj
    scene.render.resolution_x, scene.render.resolution_y = IMAGE_SIZE
    scene.render.resolution_percentage = 100
    return obj


def add_room_mesh(name: str = "Room", color=(0.5, 0.4, 0.3, 1.0)):
    """The box room as a mesh (a cube scaled to BOX_ROOM_MIN..MAX) with a Principled material."""
    lo, hi = helpers.BOX_ROOM_MIN, helpers.BOX_ROOM_MAX
    mesh = bpy.data.meshes.new(name)
    corners = [(x, y, z) for z in (lo[2], hi[2]) for y in (lo[1], hi[1]) for x in (lo[0], hi[0])]
    faces = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    mesh.from_pydata(corners, [], faces)
    mesh.update()
    material = bpy.data.materials.new(f"{name} material")
    material.use_nodes = True
    bsdf = next(n for n in material.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
    bsdf.inputs["Base Color"].default_value = color
    mesh.materials.append(material)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def traced_scene():
    """Engine LFPROBE, a baked grid and a camera; returns (grid, camera)."""
    folder = baked_probe_set()
    bpy.context.scene.render.engine = "LFPROBE"
    return add_grid(folder), add_camera()


def blender_command(blend: str, *args: str, opened_first: bool = False) -> list:
    """The command line that runs the add-on's batch CLI on `blend` (cli.py -- --open BLEND ...):
    Blender's own binary, or, with the bpy wheel (no binary), the wheel's Python running cli.py.
    opened_first: the form that has Blender open the file before cli.py enables the add-on
    (blender -b BLEND -P cli.py -- ...; with the wheel, open_mainfile first)."""
    cli = os.path.join(helpers.ADDON_DIR, "cli.py")
    args = list(args) if opened_first else ["--open", blend, *args]
    if bpy.app.binary_path and not bpy.app.binary_path.endswith(("python", "python3")):
        return [bpy.app.binary_path, "-b", "--factory-startup", *([blend] if opened_first else []),
                "--python-exit-code", "1", "-P", cli, "--", *args]
    import sys

    script = (
        "import runpy, sys, bpy; "
        + (f"bpy.ops.wm.open_mainfile(filepath={blend!r}); " if opened_first else "")
        + f"sys.argv = [{cli!r}, '--', *{args!r}]; "
        f"runpy.run_path({cli!r}, run_name='__main__')"
    )
    return [sys.executable, "-c", script]


def run_batch(blend: str, *args: str, timeout: int = 300, opened_first: bool = False) -> subprocess.CompletedProcess:
    return subprocess.run(blender_command(blend, *args, opened_first=opened_first), capture_output=True, text=True,
                          timeout=timeout)


def lfprobe_cli(*args: str) -> subprocess.CompletedProcess:
    """The bpy-free ./lfprobe of the checkout (system Python 3.11)."""
    return subprocess.run([os.path.join(helpers.ROOT, "lfprobe"), *map(str, args)], capture_output=True,
                          text=True, timeout=300)


def write_json(path: str, value) -> str:
    with open(path, "w", encoding="utf-8") as stream:
        json.dump(value, stream)
    return path
