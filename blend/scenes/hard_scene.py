"""The hard scene, for stability and error analysis. In local coordinates (world = WORLD_OFFSET +
local, a georeferenced origin as UTM data has): a long hall (x 0..3.5, y 0..9, z 0..2.6) with a
finely tiled floor seen at glancing angles, a window in the x = 3.5 wall behind venetian blinds
(5 mm thick slats with gaps; outside, a brick facade and open sky, so some rays escape), a
radiator with thin fins, a narrow corridor (0.9 m, x −1.0..−0.1) behind the x = 0 wall reached
through a door frame with an open door, and a pillar whose face is 1.5 cm from two probes of
the grid (x = 0.6, y = 3.3)."""

from __future__ import annotations

import math

import numpy as np

from . import textures as tex
from .mesh_builder import MeshBuilder

SEED = 61
WORLD_OFFSET = (512000.0, 5400000.0, 230.0)
HALL = (3.5, 9.0, 2.6)
WINDOW = {"y0": 1.0, "y1": 2.6, "z0": 0.8, "z1": 2.2, "depth": 0.2}
BLINDS = {"x": 3.43, "width": 0.05, "thickness": 0.005, "pitch": 0.06, "tilt_deg": 30.0}
CORRIDOR = {"x0": -1.0, "x1": -0.1, "y0": 4.0, "y1": 9.0, "height": 2.4}
DOOR = {"y0": 6.0, "y1": 6.85, "top": 2.05}
PILLAR_GAP = 0.015  # the pillar's face is this far from the probes at x = 0.6, y = 3.3
GRID = {"min": (0.6, 0.9, 1.2), "max": (2.9, 8.1, 1.6), "counts": (2, 4, 2)}


def world(p) -> list:
    return [float(a + o) for a, o in zip(p, WORLD_OFFSET)]


def slat_count() -> int:
    return int((WINDOW["z1"] - WINDOW["z0"] - 0.06) / BLINDS["pitch"])


def _materials(b: MeshBuilder, rng) -> None:
    b.texture("fine_tiles", tex.floor_tiles(rng, 256, tiles=4, base=(0.55, 0.50, 0.45), grout=(0.2, 0.2, 0.2)))
    b.texture("plaster", tex.plaster(rng))
    b.texture("bricks", tex.bricks(rng))
    b.texture("slat", tex.slat_metal(rng))
    b.texture("wood", tex.wood(rng, 256, planks=2))
    b.texture("concrete", tex.plaster(rng, color=(0.55, 0.55, 0.53)))
    b.texture("poster", tex.poster(rng))
    for name in ("fine_tiles", "plaster", "bricks", "slat", "wood", "concrete", "poster"):
        b.material(name, texture=name)
    for name, colour in (
        ("frame_white", (0.80, 0.80, 0.78)),
        ("radiator", (0.85, 0.85, 0.82)),
        ("ground", (0.20, 0.22, 0.18)),
        ("cord", (0.6, 0.6, 0.55)),
        ("ceiling", (0.85, 0.85, 0.85)),
    ):
        b.material(name, colour)


def _hall(b: MeshBuilder) -> None:
    w, d, h = HALL
    b.quad("hall_floor", "fine_tiles", (w / 2, d / 2, 0), (1, 0, 0), (0, 1, 0), w / 2, d / 2, uv_scale=0.4)
    b.quad("hall_ceiling", "ceiling", (w / 2, d / 2, h), (1, 0, 0), (0, -1, 0), w / 2, d / 2)
    b.wall("hall_wall_south", "plaster", (w, 0, 0), (-1, 0, 0), (0, 0, 1), w, h, uv_scale=1.5)
    b.wall("hall_wall_north", "plaster", (0, d, 0), (1, 0, 0), (0, 0, 1), w, h, uv_scale=1.5)
    # x = 0 wall toward the corridor, with the door opening; wall u runs along +y.
    b.wall("hall_wall_west", "plaster", (0, 0, 0), (0, 1, 0), (0, 0, 1), d, h,
           openings=[(DOOR["y0"], DOOR["y1"], 0.0, DOOR["top"])], uv_scale=1.5)
    # x = 3.5 wall with the window; wall u runs from y = 9 down.
    b.wall("hall_wall_east", "plaster", (w, d, 0), (0, -1, 0), (0, 0, 1), d, h,
           openings=[(d - WINDOW["y1"], d - WINDOW["y0"], WINDOW["z0"], WINDOW["z1"])], uv_scale=1.5)
    b.box("poster", "frame_white", (0.0, 1.2, 1.1), (0.006, 1.9, 2.1), faces={"+x": ("poster", (0, 0, 1, 1))},
          skip=("-x",))


def _window_and_outside(b: MeshBuilder) -> None:
    x, y0, y1, z0, z1, dep = HALL[0], WINDOW["y0"], WINDOW["y1"], WINDOW["z0"], WINDOW["z1"], WINDOW["depth"]
    yc, zc = (y0 + y1) / 2, (z0 + z1) / 2
    b.quad("window_reveal", "plaster", (x + dep / 2, yc, z1), (0, 1, 0), (1, 0, 0), (y1 - y0) / 2, dep / 2)
    b.quad("window_reveal", "plaster", (x + dep / 2, yc, z0), (0, 1, 0), (-1, 0, 0), (y1 - y0) / 2, dep / 2)
    b.quad("window_reveal", "plaster", (x + dep / 2, y0, zc), (1, 0, 0), (0, 0, 1), dep / 2, (z1 - z0) / 2)
    b.quad("window_reveal", "plaster", (x + dep / 2, y1, zc), (-1, 0, 0), (0, 0, 1), dep / 2, (z1 - z0) / 2)
    # The outer face of the wall, seen from outside through nothing but the opening itself.
    b.wall("facade_own", "concrete", (x + dep, 0, 0), (0, 1, 0), (0, 0, 1), HALL[1], HALL[2] + 0.4,
           openings=[(y0, y1, z0, z1)])
    # Outside: ground and a brick facade across the street; no roof, so rays escape to the sky.
    b.quad("outside_ground", "ground", (6.0, HALL[1] / 2, -0.05), (1, 0, 0), (0, 1, 0), 2.3, 9.0)
    b.quad("outside_facade", "bricks", (8.3, HALL[1] / 2, 1.45), (0, -1, 0), (0, 0, 1), 9.0, 1.5, uv_scale=2.0)


def _blinds(b: MeshBuilder) -> None:
    """Venetian blinds across the window opening: slats 5 mm thick, 5 cm wide, tilted, 6 cm
    apart, hung from a head rail on two ladder cords."""
    y0, y1 = WINDOW["y0"] + 0.02, WINDOW["y1"] - 0.02
    tilt = math.radians(BLINDS["tilt_deg"])
    across = np.array([math.cos(tilt), 0.0, math.sin(tilt)])  # slat width, rising toward outside
    normal = np.array([-math.sin(tilt), 0.0, math.cos(tilt)])
    for k in range(slat_count()):
        z = WINDOW["z0"] + 0.05 + k * BLINDS["pitch"]
        b.oriented_box("blind_slats", "slat", (BLINDS["x"], (y0 + y1) / 2, z), [(0, 1, 0), across, normal],
                       ((y1 - y0) / 2, BLINDS["width"] / 2, BLINDS["thickness"] / 2), uv_scale=0.3)
    top = WINDOW["z0"] + 0.05 + slat_count() * BLINDS["pitch"]
    b.box("blind_rail", "frame_white", (BLINDS["x"] - 0.025, y0, top), (BLINDS["x"] + 0.025, y1, top + 0.04))
    for y in (y0 + 0.25, y1 - 0.25):
        for dx in (-0.022, 0.022):
            b.tube("blind_cords", "cord", [(BLINDS["x"] + dx, y, WINDOW["z0"] + 0.03), (BLINDS["x"] + dx, y, top)],
                   0.001, 4)


def _radiator(b: MeshBuilder) -> None:
    for k in range(40):  # fins 3 mm thick, 3.5 cm apart
        y = WINDOW["y0"] + 0.1 + k * 0.035
        b.box("radiator", "radiator", (3.3, y, 0.15), (3.42, y + 0.003, 0.7))
    b.cylinder("radiator", "radiator", (3.36, WINDOW["y0"] + 0.08, 0.2), 0.012, 1.44, 8, axis=(0, 1, 0))


def _corridor(b: MeshBuilder) -> None:
    c = CORRIDOR
    width, length = c["x1"] - c["x0"], c["y1"] - c["y0"]
    xc, yc = (c["x0"] + c["x1"]) / 2, (c["y0"] + c["y1"]) / 2
    b.quad("corridor_floor", "fine_tiles", (xc, yc, 0), (1, 0, 0), (0, 1, 0), width / 2, length / 2, uv_scale=0.4)
    b.quad("corridor_ceiling", "ceiling", (xc, yc, c["height"]), (1, 0, 0), (0, -1, 0), width / 2, length / 2)
    b.wall("corridor_wall_west", "plaster", (c["x0"], c["y0"], 0), (0, 1, 0), (0, 0, 1), length, c["height"])
    # The corridor side of the wall shared with the hall (10 cm thick), with the door opening.
    b.wall("corridor_wall_east", "plaster", (c["x1"], c["y1"], 0), (0, -1, 0), (0, 0, 1), length, c["height"],
           openings=[(c["y1"] - DOOR["y1"], c["y1"] - DOOR["y0"], 0.0, DOOR["top"])])
    b.wall("corridor_end", "wood", (c["x1"], c["y0"], 0), (-1, 0, 0), (0, 0, 1), width, c["height"])
    b.wall("corridor_end", "plaster", (c["x0"], c["y1"], 0), (1, 0, 0), (0, 0, 1), width, c["height"])
    # Door reveals through the 10 cm wall, the frame on the hall side and the open door leaf.
    y0, y1, top = DOOR["y0"], DOOR["y1"], DOOR["top"]
    b.quad("door_threshold", "wood", (-0.05, (y0 + y1) / 2, 0.0), (1, 0, 0), (0, 1, 0), 0.05, (y1 - y0) / 2)
    b.quad("door_reveal", "plaster", (-0.05, y0, top / 2), (-1, 0, 0), (0, 0, 1), 0.05, top / 2)
    b.quad("door_reveal", "plaster", (-0.05, y1, top / 2), (1, 0, 0), (0, 0, 1), 0.05, top / 2)
    b.quad("door_reveal", "plaster", (-0.05, (y0 + y1) / 2, top), (0, 1, 0), (1, 0, 0), (y1 - y0) / 2, 0.05)
    b.box("door_frame", "frame_white", (0.0, y0 - 0.06, 0.0), (0.02, y0, top + 0.06), skip=("-z", "-x"))
    b.box("door_frame", "frame_white", (0.0, y1, 0.0), (0.02, y1 + 0.06, top + 0.06), skip=("-z", "-x"))
    b.box("door_frame", "frame_white", (0.0, y0, top), (0.02, y1, top + 0.06), skip=("-x",))
    b.box("door_leaf", "wood", (0.02, y1 - 0.04, 0.01), (0.02 + (y1 - y0) - 0.02, y1, top - 0.01), uv_scale=0.9)


def _pillar(b: MeshBuilder) -> None:
    """A 0.3 × 0.4 m pillar on the wall side of the probes at x = 0.6, y = 3.3: its +x face,
    which the scanners in the hall see, is PILLAR_GAP from them."""
    x_probe, y_probe = GRID["min"][0], 3.3
    b.box("pillar", "concrete", (x_probe - PILLAR_GAP - 0.3, y_probe - 0.2, 0.0),
          (x_probe - PILLAR_GAP, y_probe + 0.2, HALL[2]), skip=("-z", "+z"))


def build():
    rng = np.random.default_rng(SEED)
    b = MeshBuilder(WORLD_OFFSET)
    _materials(b, rng)
    _hall(b)
    _window_and_outside(b)
    _blinds(b)
    _radiator(b)
    _corridor(b)
    _pillar(b)
    for y in (4.6, 8.4):  # benches along the hall
        b.box("bench", "wood", (2.9, y - 0.6, 0.42), (3.4, y + 0.6, 0.46))
        b.box("bench", "frame_white", (3.0, y - 0.55, 0.0), (3.3, y - 0.5, 0.42), skip=("-z",))
        b.box("bench", "frame_white", (3.0, y + 0.5, 0.0), (3.3, y + 0.55, 0.42), skip=("-z",))

    slat_mid_z = WINDOW["z0"] + 0.05 + (slat_count() // 2) * BLINDS["pitch"]
    scene = {
        "name": "hard",
        "title": "Hard scene: blinds, narrow corridor, probe beside a pillar, glancing floor, UTM offset",
        "mesh": "hard_scene.obj",
        "world_offset": list(WORLD_OFFSET),
        "scanners": [world((1.75, 2.0, 1.5)), world((1.75, 6.6, 1.5)), world((-0.55, 7.6, 1.5))],
        "scan": {"step_deg": 0.25, "noise_mm": 2.0, "vertical_fov": 300},
        "grid": {"min": world(GRID["min"]), "max": world(GRID["max"]), "counts": list(GRID["counts"])},
        "views": [
            {"name": "blinds_at_probe", "position": world((2.9, 0.9, 1.6)), "look_at": world((3.43, 1.8, slat_mid_z)),
             "lens": 24, "resolution": [480, 360]},
            {"name": "blinds_between_probes", "position": world((1.9, 1.8, 1.4)),
             "look_at": world((3.43, 1.8, 1.5)), "lens": 24, "resolution": [480, 360]},
            {"name": "glancing_floor", "position": world((1.75, 0.3, 0.35)), "look_at": world((1.75, 9.0, 0.05)),
             "lens": 24, "resolution": [480, 360]},
            {"name": "beside_pillar", "position": world((0.7, 2.4, 1.3)), "look_at": world((0.4, 5.0, 1.1)),
             "lens": 24, "resolution": [480, 360]},
            {"name": "corridor", "position": world((-0.55, 4.3, 1.5)), "look_at": world((-0.55, 9.0, 1.2)),
             "lens": 24, "resolution": [480, 360]},
        ],
        "walk": {"points": [world((1.75, 4.8, 1.5)), world((0.6, 6.4, 1.5)), world((-0.55, 6.45, 1.5)),
                            world((-0.55, 8.0, 1.5))],
                 "look_at": world((-0.55, 9.0, 1.2)), "frames": 8, "lens": 24},
        # Points of interest for tests and the error analysis (world coordinates).
        "probes_near": {
            "pillar_probe": world((GRID["min"][0], 3.3, GRID["min"][2])),
            "pillar_gap_m": PILLAR_GAP,
            "blinds_x": BLINDS["x"] + WORLD_OFFSET[0],
        },
    }
    return b, scene
