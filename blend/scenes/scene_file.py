"""The `<name>.scene.json` contract shared by the demo scenes and the report:

    {"name", "title"?, "mesh", "scanners": [[x,y,z], ...],
     "scan": {"step_deg", "noise_mm", "vertical_fov"},
     "grid": {"min": [x,y,z], "max": [x,y,z], "counts": [nx,ny,nz]},
     "views": [{"name", "position", "look_at", "lens", "resolution": [w,h]}, ...],
     "walk"?: {"points": [[x,y,z], ...], "look_at", "frames", "lens"}}

World coordinates in metres, Z up; relative paths are relative to the JSON file. Optional
keys added here: "world_offset" (the scene's georeferenced origin, informative) and
"probes_near" (named probe-related points of interest for tests)."""

from __future__ import annotations

import json
import math
import os

from .files import write_atomic


def _vec(value, where: str, length: int = 3, integer: bool = False):
    if not isinstance(value, (list, tuple)) or len(value) != length:
        raise ValueError(f"{where}: expected a list of {length} numbers, got {value!r}")
    for v in value:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise ValueError(f"{where}: expected finite numbers, got {value!r}")
        if integer and (not float(v).is_integer() or v < 1):
            raise ValueError(f"{where}: expected whole numbers of at least 1, got {value!r}")
    return [int(v) for v in value] if integer else [float(v) for v in value]


def validate_scene(scene: dict, where: str) -> dict:
    """Checks a scene dict against the contract; raises ValueError naming `where` and the key."""
    if not isinstance(scene, dict):
        raise ValueError(f"{where}: expected a JSON object")
    for key in ("name", "mesh", "scanners", "scan", "grid", "views"):
        if key not in scene:
            raise ValueError(f"{where}: missing key '{key}'")
    if not isinstance(scene["name"], str) or not scene["name"]:
        raise ValueError(f"{where}: 'name' must be a non-empty string")
    if not isinstance(scene["mesh"], str) or not scene["mesh"]:
        raise ValueError(f"{where}: 'mesh' must be a file name")
    if not isinstance(scene["scanners"], list) or not scene["scanners"]:
        raise ValueError(f"{where}: 'scanners' must be a non-empty list of [x, y, z]")
    for i, s in enumerate(scene["scanners"]):
        _vec(s, f"{where}: scanners[{i}]")
    scan = scene["scan"]
    for key in ("step_deg", "noise_mm", "vertical_fov"):
        if not isinstance(scan, dict) or not isinstance(scan.get(key), (int, float)) or scan[key] < 0:
            raise ValueError(f"{where}: scan.{key} must be a non-negative number")
    grid = scene["grid"]
    if not isinstance(grid, dict):
        raise ValueError(f"{where}: 'grid' must be an object with min, max, counts")
    lo, hi = _vec(grid.get("min"), f"{where}: grid.min"), _vec(grid.get("max"), f"{where}: grid.max")
    _vec(grid.get("counts"), f"{where}: grid.counts", integer=True)
    if any(a > b for a, b in zip(lo, hi)):
        raise ValueError(f"{where}: grid.min {lo} must not exceed grid.max {hi}")
    if not isinstance(scene["views"], list) or not scene["views"]:
        raise ValueError(f"{where}: 'views' must be a non-empty list")
    for i, view in enumerate(scene["views"]):
        here = f"{where}: views[{i}]"
        if not isinstance(view, dict) or not isinstance(view.get("name"), str):
            raise ValueError(f"{here}: expected an object with a 'name'")
        _vec(view.get("position"), f"{here}.position")
        _vec(view.get("look_at"), f"{here}.look_at")
        _vec(view.get("resolution"), f"{here}.resolution", 2, integer=True)
        if not isinstance(view.get("lens"), (int, float)) or view["lens"] <= 0:
            raise ValueError(f"{here}.lens: expected a focal length in mm")
    walk = scene.get("walk")
    if walk is not None:
        if not isinstance(walk, dict) or not isinstance(walk.get("points"), list) or len(walk["points"]) < 2:
            raise ValueError(f"{where}: walk.points must list at least two [x, y, z]")
        for i, p in enumerate(walk["points"]):
            _vec(p, f"{where}: walk.points[{i}]")
        _vec(walk.get("look_at"), f"{where}: walk.look_at")
        if not isinstance(walk.get("frames"), int) or walk["frames"] < 2:
            raise ValueError(f"{where}: walk.frames must be a whole number of at least 2")
    return scene


def write_scene_json(path: str, scene: dict) -> None:
    validate_scene(scene, path)
    write_atomic(path, (json.dumps(scene, indent=2) + "\n").encode("utf-8"))


def load_scene(path: str) -> dict:
    """Reads and checks a scene file; adds 'mesh_path', the mesh's absolute path."""
    try:
        with open(path, encoding="utf-8") as stream:
            scene = json.load(stream)
    except FileNotFoundError:
        raise FileNotFoundError(f"{path}: scene file not found") from None
    except json.JSONDecodeError as error:
        raise ValueError(f"{path}: not valid JSON ({error})") from None
    validate_scene(scene, path)
    scene["mesh_path"] = os.path.join(os.path.dirname(os.path.abspath(path)), scene["mesh"])
    return scene
