"""The scene file of the report (``<name>.scene.json``): a reference mesh, simulated scanner
positions and settings, a probe grid, named views and an optional camera walk.

Relative paths are relative to the JSON file. Every problem with a scene file is a ValueError
(or FileNotFoundError) whose message names the file, the key and what was expected.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from typing import List, Optional, Sequence

from .. import native
from ..camera_json import camera_dict

DEFAULT_SCAN = {"step_deg": 0.25, "noise_mm": 1.0, "vertical_fov": 300.0}
NAME_CHARACTERS = set("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-.")


def grid_positions(grid_min: Sequence[float], grid_max: Sequence[float], counts: Sequence[int]) -> List[List[float]]:
    """Probe positions of a grid as the bake places them, x fastest (the corner probes on the box
    corners, an axis with one probe at the box's centre): the native core's computation."""
    return native.load().grid_positions(list(grid_min), list(grid_max), [int(c) for c in counts]).tolist()


@dataclass
class View:
    name: str
    position: List[float]
    look_at: List[float]
    lens: float = 24.0
    resolution: List[int] = field(default_factory=lambda: [320, 240])

    def camera(self, max_width: Optional[int] = None, position: Optional[Sequence[float]] = None) -> dict:
        """The camera JSON dict (docs/DESIGN.md §3) of this view; max_width scales the resolution
        down keeping its aspect; position moves the eye keeping the viewing direction."""
        w, h = self.resolution
        if max_width is not None and w > max_width:
            h = max(12, int(round(h * max_width / w)))
            w = max_width
        eye = list(self.position) if position is None else [float(c) for c in position]
        target = [t - p + e for t, p, e in zip(self.look_at, self.position, eye)]
        return camera_dict(eye, target, (w, h), lens=self.lens)


@dataclass
class Scene:
    path: str
    name: str
    title: str
    mesh: str
    scanners: List[List[float]]
    scan: dict
    grid_min: List[float]
    grid_max: List[float]
    grid_counts: List[int]
    views: List[View]
    walk: Optional[dict] = None

    def probe_positions(self) -> List[List[float]]:
        """World positions of the scene grid's probes."""
        return grid_positions(self.grid_min, self.grid_max, self.grid_counts)

    def walk_views(self, frames: Optional[int] = None) -> List[View]:
        """The walk as views: `frames` eyes (the scene's own count unless given) evenly spaced
        along the polyline of `points`."""
        if not self.walk:
            return []
        points = self.walk["points"]
        frames = self.walk["frames"] if frames is None else frames
        lengths = [math.dist(a, b) for a, b in zip(points, points[1:])]
        total = sum(lengths)
        views = []
        for k in range(frames):
            s = total * k / (frames - 1) if frames > 1 else 0.0
            segment = 0
            while segment < len(lengths) - 1 and s > lengths[segment]:
                s -= lengths[segment]
                segment += 1
            a, b = points[segment], points[min(segment + 1, len(points) - 1)]
            f = s / lengths[segment] if lengths and lengths[segment] > 0 else 0.0
            eye = [a[i] + (b[i] - a[i]) * f for i in range(3)]
            res = self.walk.get("resolution", self.views[0].resolution)
            views.append(View(f"walk_{k:03d}", eye, list(self.walk["look_at"]), self.walk["lens"], list(res)))
        return views


class _Checker:
    """Validates values with messages that name the file and the key."""

    def __init__(self, path: str):
        self.path = path

    def fail(self, key: str, expected: str, got=None):
        detail = "" if got is None else f", got {json.dumps(got) if not isinstance(got, str) else repr(got)}"
        raise ValueError(f"{self.path}: {key}: expected {expected}{detail}")

    def number(self, value, key: str, positive: bool = False) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            self.fail(key, "a finite number", value)
        if positive and value <= 0:
            self.fail(key, "a positive number", value)
        return float(value)

    def vec3(self, value, key: str) -> List[float]:
        if not isinstance(value, (list, tuple)) or len(value) != 3:
            self.fail(key, "[x, y, z] (three numbers, metres, world coordinates)", value)
        return [self.number(v, f"{key}[{i}]") for i, v in enumerate(value)]

    def counts(self, value, key: str) -> List[int]:
        if (not isinstance(value, (list, tuple)) or len(value) != 3
                or any(isinstance(v, bool) or not isinstance(v, int) or v < 1 for v in value)):
            self.fail(key, "[nx, ny, nz] (three whole numbers of at least 1)", value)
        return [int(v) for v in value]

    def resolution(self, value, key: str) -> List[int]:
        if (not isinstance(value, (list, tuple)) or len(value) != 2
                or any(isinstance(v, bool) or not isinstance(v, int) or v < 16 or v > 16384 for v in value)):
            self.fail(key, "[width, height] (whole numbers from 16 to 16384)", value)
        return [int(v) for v in value]

    def name(self, value, key: str) -> str:
        if not isinstance(value, str) or not value or not set(value) <= NAME_CHARACTERS:
            self.fail(key, "a short id of letters, digits, '_', '-' or '.' (it is used in file names)", value)
        return value


def _view(check: _Checker, raw, key: str) -> View:
    if not isinstance(raw, dict):
        check.fail(key, "an object with name, position, look_at, lens, resolution", raw)
    for required in ("name", "position", "look_at"):
        if required not in raw:
            check.fail(f"{key}.{required}", "a value (the key is missing)")
    view = View(
        name=check.name(raw["name"], f"{key}.name"),
        position=check.vec3(raw["position"], f"{key}.position"),
        look_at=check.vec3(raw["look_at"], f"{key}.look_at"),
        lens=check.number(raw.get("lens", 24.0), f"{key}.lens", positive=True),
        resolution=check.resolution(raw.get("resolution", [320, 240]), f"{key}.resolution"),
    )
    if view.position == view.look_at:
        check.fail(f"{key}.look_at", "a point other than the position", raw["look_at"])
    return view


def load_scene(path: str) -> Scene:
    """Reads and validates a scene file; the mesh path comes back absolute."""
    if not os.path.isfile(path):
        raise FileNotFoundError(f"no such scene file: {path}")
    try:
        with open(path, encoding="utf-8") as stream:
            raw = json.load(stream)
    except json.JSONDecodeError as error:
        raise ValueError(f"{path}: not valid JSON: {error}") from error
    except UnicodeDecodeError as error:
        raise ValueError(f"{path}: not UTF-8 text: {error}") from error
    check = _Checker(path)
    if not isinstance(raw, dict):
        check.fail("(top level)", "a JSON object", type(raw).__name__)
    for required in ("name", "mesh", "scanners", "grid", "views"):
        if required not in raw:
            check.fail(required, "a value (the key is missing)")
    name = check.name(raw["name"], "name")
    if not isinstance(raw["mesh"], str) or not raw["mesh"]:
        check.fail("mesh", "a mesh file path (.obj or .ply)", raw["mesh"])
    mesh = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(path)), raw["mesh"]))
    if not mesh.lower().endswith((".obj", ".ply")):
        check.fail("mesh", "an .obj or .ply file", raw["mesh"])
    if not os.path.isfile(mesh):
        raise FileNotFoundError(f"{path}: mesh: no such file {mesh}")
    if not isinstance(raw["scanners"], list) or not raw["scanners"]:
        check.fail("scanners", "a non-empty list of [x, y, z] scanner positions", raw["scanners"])
    scanners = [check.vec3(s, f"scanners[{i}]") for i, s in enumerate(raw["scanners"])]
    scan_raw = raw.get("scan", {})
    if not isinstance(scan_raw, dict):
        check.fail("scan", "an object with step_deg, noise_mm, vertical_fov", scan_raw)
    scan = dict(DEFAULT_SCAN)
    for key in DEFAULT_SCAN:
        if key in scan_raw:
            scan[key] = check.number(scan_raw[key], f"scan.{key}", positive=key != "noise_mm")
    if scan["noise_mm"] < 0:
        check.fail("scan.noise_mm", "a number of at least 0", scan["noise_mm"])
    if not 0 < scan["vertical_fov"] <= 360:
        check.fail("scan.vertical_fov", "degrees in (0, 360]", scan["vertical_fov"])
    grid = raw["grid"]
    if not isinstance(grid, dict) or any(k not in grid for k in ("min", "max", "counts")):
        check.fail("grid", 'an object {"min": [x,y,z], "max": [x,y,z], "counts": [nx,ny,nz]}', grid)
    grid_min, grid_max = check.vec3(grid["min"], "grid.min"), check.vec3(grid["max"], "grid.max")
    counts = check.counts(grid["counts"], "grid.counts")
    if any(lo > hi for lo, hi in zip(grid_min, grid_max)):
        check.fail("grid.max", "a corner at least grid.min on every axis", grid["max"])
    if not isinstance(raw["views"], list) or not raw["views"]:
        check.fail("views", "a non-empty list of views", raw["views"])
    views = [_view(check, v, f"views[{i}]") for i, v in enumerate(raw["views"])]
    names = [v.name for v in views]
    if len(set(names)) != len(names):
        check.fail("views", "views with different names", names)
    walk = raw.get("walk")
    if walk is not None:
        if not isinstance(walk, dict) or "points" not in walk or "look_at" not in walk:
            check.fail("walk", 'an object {"points": [[x,y,z], ...], "look_at": [x,y,z], "frames": n, "lens": mm}', walk)
        if not isinstance(walk["points"], list) or len(walk["points"]) < 1:
            check.fail("walk.points", "a non-empty list of [x, y, z]", walk["points"])
        frames = walk.get("frames", 12)
        if isinstance(frames, bool) or not isinstance(frames, int) or frames < 1:
            check.fail("walk.frames", "a whole number of at least 1", frames)
        for i, point in enumerate(walk["points"]):
            if check.vec3(point, f"walk.points[{i}]") == check.vec3(walk["look_at"], "walk.look_at"):
                check.fail(f"walk.points[{i}]", "a point other than walk.look_at (the camera looks at it)", point)
        walk = {
            "points": [check.vec3(p, f"walk.points[{i}]") for i, p in enumerate(walk["points"])],
            "look_at": check.vec3(walk["look_at"], "walk.look_at"),
            "frames": frames,
            "lens": check.number(walk.get("lens", 24.0), "walk.lens", positive=True),
            **({"resolution": check.resolution(walk["resolution"], "walk.resolution")}
               if "resolution" in walk else {}),
        }
    title = raw.get("title", name)
    if not isinstance(title, str):
        check.fail("title", "a string", title)
    return Scene(os.path.abspath(path), name, title, mesh, scanners, scan, grid_min, grid_max,
                 counts, views, walk)
