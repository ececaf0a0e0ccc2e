"""What the batch commands look up in the open .blend (scene, camera, grids, depsgraph) and how
they store options and save, with BatchError for what is missing."""

from __future__ import annotations

import os

import bpy

from .. import grid as grid_module
from ..scene_objects import object_of_type
from .status import BatchError


def open_blend(path: str) -> None:
    """Opens the .blend of --open. The add-on is enabled by then, so Blender knows the render
    engine LFPROBE while it loads the file; opened by Blender's own command line, before cli.py
    runs, a scene rendering with it makes Blender print "Engine 'LFPROBE' not available"."""
    if not os.path.isfile(path):
        raise BatchError(f"no such .blend: {path}")
    try:
        bpy.ops.wm.open_mainfile(filepath=os.path.abspath(path), load_ui=False)
    except RuntimeError as error:
        raise BatchError(f"cannot open {path}: {error}") from error


def scene_named(name: str):
    """The scene called name, or the active scene for an empty name."""
    if not name:
        return bpy.context.scene
    scene = bpy.data.scenes.get(name)
    if scene is None:
        raise BatchError(f"no scene named '{name}' in {bpy.data.filepath or 'the unsaved file'}")
    return scene


def camera_named(scene, name: str):
    """The camera object called name, or the scene camera for an empty name."""
    if not name:
        if scene.camera is None:
            raise BatchError(f"scene '{scene.name}' has no active camera: pass --camera NAME")
        return scene.camera
    return object_of_type(scene, name, "CAMERA", BatchError)


def evaluated_depsgraph(scene):
    """The evaluated depsgraph of the scene (animated or constrained cameras and meshes)."""
    if scene == bpy.context.scene:
        return bpy.context.evaluated_depsgraph_get()
    depsgraph = scene.view_layers[0].depsgraph
    depsgraph.update()
    return depsgraph


def grids_named(scene, name):
    """The grid named `name` (GridError when there is none), or every grid of the scene by name."""
    if name:
        grid_obj = scene.objects.get(name)
        if grid_obj is None or not grid_module.is_grid(grid_obj):
            raise grid_module.GridError(f"no probe grid named '{name}' in scene '{scene.name}'")
        return [grid_obj]
    return sorted((o for o in scene.objects if grid_module.is_grid(o)), key=lambda o: o.name)


def save_unless_told_not(args, note: str = "") -> None:
    """Saves the open .blend after a batch step, unless --no-save."""
    if args.no_save:
        return
    if not bpy.data.filepath:
        raise BatchError("the scene is not saved to a .blend: pass --no-save or open a saved .blend")
    bpy.ops.wm.save_mainfile()
    print(f"lfprobe: saved {bpy.data.filepath}{note}")


def store_storage_options(grid, args) -> None:
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
