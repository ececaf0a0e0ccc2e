"""The lab room, modelled on the paper's scanned lab: 3 × 6 × 2.8 m (x 0..3, y 0..6, z 0..2.8),
a door in the y = 0 wall, a window in the x = 3 wall, three tables with monitors, keyboards,
papers and a laptop, three office chairs, a bookcase full of books against the y = 6 wall, a
poster and a whiteboard, cables as thin tubes, small objects. Four scanner stations at about
1.5 m spread along the room (the paper used four), a 3 × 5 × 2 probe grid inside it."""

from __future__ import annotations

import math

import numpy as np

from . import textures as tex
from .mesh_builder import MeshBuilder

SEED = 6  # the issue number: every random choice of the scene comes from this seed

ROOM = (3.0, 6.0, 2.8)
TABLE_TOP = 0.75


def _rot_z(angle: float) -> np.ndarray:
    """Rows: the local axes of a frame turned by `angle` about world Z."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])


def _catenary(a, b, sag: float, n: int = 24) -> np.ndarray:
    """Points of a cable hanging from a to b, dipping `sag` metres at its middle."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    t = np.linspace(0.0, 1.0, n)[:, None]
    p = a + (b - a) * t
    p[:, 2] -= sag * 4 * t[:, 0] * (1 - t[:, 0])
    return p


def _floor_cable(rng, points, radius: float, z: float, wiggle: float = 0.03, n: int = 60) -> np.ndarray:
    """A cable lying on the floor through `points` (x, y), meandering a little."""
    pts = np.asarray(points, float)
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    s = np.concatenate([[0], np.cumsum(seg)])
    u = np.linspace(0, s[-1], n)
    x, y = np.interp(u, s, pts[:, 0]), np.interp(u, s, pts[:, 1])
    phase = rng.random() * 6
    x += wiggle * np.sin(u * 5.0 + phase) * np.sin(np.pi * u / s[-1])
    y += wiggle * np.cos(u * 4.0 + phase) * np.sin(np.pi * u / s[-1])
    return np.column_stack([x, y, np.full(n, z + radius)])


def _materials(b: MeshBuilder, rng: np.random.Generator) -> None:
    b.texture("floor_tiles", tex.floor_tiles(rng))
    b.texture("ceiling_tiles", tex.ceiling_tiles(rng))
    b.texture("plaster", tex.plaster(rng))
    b.texture("plaster_accent", tex.plaster(rng, color=(0.55, 0.68, 0.72)))
    b.texture("wood_oak", tex.wood(rng))
    b.texture("wood_walnut", tex.wood(rng, 256, dark=(0.22, 0.12, 0.06), light=(0.48, 0.30, 0.16), planks=2))
    b.texture("fabric_blue", tex.fabric(rng))
    b.texture("fabric_red", tex.fabric(rng, color=(0.50, 0.12, 0.10)))
    b.texture("metal", tex.brushed_metal(rng))
    b.texture("keyboard", tex.keyboard(rng))
    b.texture("screen_code", tex.screen(rng, kind="code"))
    b.texture("screen_plot", tex.screen(rng, kind="plot"))
    b.texture("poster", tex.poster(rng))
    b.texture("paper", tex.paper_page(rng))
    b.texture("book_spines", tex.book_spines(rng))
    b.texture("whiteboard", tex.whiteboard(rng))
    b.texture("outside", tex.outside_view(rng))
    for name, t in [("floor", "floor_tiles"), ("ceiling", "ceiling_tiles"), ("wall", "plaster"),
                    ("wall_accent", "plaster_accent"), ("oak", "wood_oak"), ("walnut", "wood_walnut"),
                    ("seat_blue", "fabric_blue"), ("seat_red", "fabric_red"), ("metal", "metal"),
                    ("keyboard", "keyboard"), ("screen_code", "screen_code"), ("screen_plot", "screen_plot"),
                    ("poster", "poster"), ("paper", "paper"), ("books", "book_spines"),
                    ("whiteboard", "whiteboard"), ("outside", "outside")]:
        b.material(name, texture=t)
    for name, colour in (
        ("plastic_black", (0.02, 0.02, 0.025)),
        ("plastic_grey", (0.25, 0.25, 0.27)),
        ("plastic_white", (0.75, 0.75, 0.72)),
        ("frame_white", (0.80, 0.80, 0.78)),
        ("ceramic", (0.70, 0.12, 0.08)),
        ("ceramic_white", (0.82, 0.82, 0.80)),
        ("page_edges", (0.78, 0.74, 0.62)),
        ("cable_black", (0.015, 0.015, 0.015)),
        ("cable_white", (0.70, 0.70, 0.68)),
        ("cable_blue", (0.03, 0.10, 0.45)),
        ("leaf", (0.05, 0.25, 0.04)),
        ("terracotta", (0.45, 0.16, 0.07)),
        ("light_panel", (0.95, 0.95, 0.93)),
    ):
        b.material(name, colour)


def _shell(b: MeshBuilder) -> None:
    w, d, h = ROOM
    b.quad("floor", "floor", (w / 2, d / 2, 0), (1, 0, 0), (0, 1, 0), w / 2, d / 2, uv_scale=1.2)
    b.quad("ceiling", "ceiling", (w / 2, d / 2, h), (1, 0, 0), (0, -1, 0), w / 2, d / 2, uv_scale=1.2)
    b.wall("wall_west", "wall", (0, 0, 0), (0, 1, 0), (0, 0, 1), d, h, uv_scale=1.5)
    b.wall("wall_far", "wall_accent", (0, d, 0), (1, 0, 0), (0, 0, 1), w, h, uv_scale=1.5)
    # East wall with the window (y 2..4, z 0.9..2.2); wall coordinate u runs from y = 6 down.
    b.wall("wall_east", "wall", (w, d, 0), (0, -1, 0), (0, 0, 1), d, h, openings=[(2.0, 4.0, 0.9, 2.2)],
           uv_scale=1.5)
    # Door wall (y = 0) with the door opening at x 0.3..1.2; u runs from x = 3 down.
    b.wall("wall_door", "wall", (w, 0, 0), (-1, 0, 0), (0, 0, 1), w, h, openings=[(1.8, 2.7, 0.0, 2.1)],
           uv_scale=1.5)
    # Skirting boards along the two walls without furniture in front of their foot.
    b.box("skirting", "walnut", (0.0, 0.0, 0.0), (0.012, d, 0.08), uv_scale=0.8, skip=("-z",))
    b.box("skirting", "walnut", (0.012, d - 0.012, 0.0), (w, d, 0.08), uv_scale=0.8, skip=("-z",))


def _window(b: MeshBuilder) -> None:
    x, y0, y1, z0, z1, depth = 3.0, 2.0, 4.0, 0.9, 2.2, 0.2
    b.quad("window", "wall", (x + depth / 2, (y0 + y1) / 2, z1), (0, 1, 0), (1, 0, 0), (y1 - y0) / 2, depth / 2)
    b.quad("window", "wall", (x + depth / 2, y0, (z0 + z1) / 2), (1, 0, 0), (0, 0, 1), depth / 2, (z1 - z0) / 2)
    b.quad("window", "wall", (x + depth / 2, y1, (z0 + z1) / 2), (-1, 0, 0), (0, 0, 1), depth / 2, (z1 - z0) / 2)
    b.box("window", "frame_white", (x - 0.12, y0 - 0.03, z0 - 0.03), (x + depth, y1 + 0.03, z0), uv_scale=1)
    # The view outside, behind the glass plane, and the frame with a mullion and a transom.
    b.quad("window_view", "outside", (x + depth, (y0 + y1) / 2, (z0 + z1) / 2), (0, 1, 0), (0, 0, 1),
           (y1 - y0) / 2, (z1 - z0) / 2, uv_rect=(0, 0, 1, 1))
    fx0, fx1 = x + 0.12, x + 0.17
    for ya, yb in ((y0, y0 + 0.05), (y1 - 0.05, y1), (2.975, 3.025)):
        b.box("window_frame", "frame_white", (fx0, ya, z0), (fx1, yb, z1))
    for za, zb in ((z0, z0 + 0.05), (z1 - 0.05, z1), (1.78, 1.83)):
        b.box("window_frame", "frame_white", (fx0, y0, za), (fx1, y1, zb))


def _door(b: MeshBuilder) -> None:
    x0, x1, top = 0.3, 1.2, 2.1
    b.box("door", "walnut", (x0, -0.09, 0.0), (x1, -0.05, top), uv_scale=0.9, skip=("-z", "-y"))
    b.quad("door_reveal", "wall", (x0, -0.025, top / 2), (0, 1, 0), (0, 0, 1), 0.025, top / 2)
    b.quad("door_reveal", "wall", (x1, -0.025, top / 2), (0, -1, 0), (0, 0, 1), 0.025, top / 2)
    b.quad("door_reveal", "wall", ((x0 + x1) / 2, -0.025, top), (-1, 0, 0), (0, 1, 0), (x1 - x0) / 2, 0.025)
    b.quad("door_threshold", "walnut", ((x0 + x1) / 2, -0.025, 0.0), (1, 0, 0), (0, 1, 0), (x1 - x0) / 2, 0.025)
    b.box("door_frame", "frame_white", (x0 - 0.06, 0.0, 0.0), (x0, 0.02, top + 0.06), skip=("-z", "-y"))
    b.box("door_frame", "frame_white", (x1, 0.0, 0.0), (x1 + 0.06, 0.02, top + 0.06), skip=("-z", "-y"))
    b.box("door_frame", "frame_white", (x0, 0.0, top), (x1, 0.02, top + 0.06), skip=("-y",))
    b.cylinder("door_handle", "metal", (1.08, -0.05, 1.05), 0.01, 0.06, 8, axis=(0, 1, 0))
    b.box("door_handle", "metal", (0.96, 0.0, 1.04), (1.09, 0.02, 1.06))


def _table(b: MeshBuilder, name: str, lo, hi) -> None:
    (x0, y0), (x1, y1) = lo, hi
    b.box(name, "oak", (x0, y0, TABLE_TOP - 0.03), (x1, y1, TABLE_TOP), uv_scale=1.0)
    for lx, ly in ((x0 + 0.03, y0 + 0.03), (x1 - 0.07, y0 + 0.03), (x0 + 0.03, y1 - 0.07), (x1 - 0.07, y1 - 0.07)):
        b.box(name + "_legs", "metal", (lx, ly, 0.0), (lx + 0.04, ly + 0.04, TABLE_TOP - 0.03), uv_scale=0.3,
              skip=("-z",))
    b.box(name + "_rail", "metal", (x0 + 0.03, y0 + 0.07, 0.62), (x0 + 0.05, y1 - 0.07, 0.72), uv_scale=0.3)


def _monitor(b: MeshBuilder, name: str, y: float, screen: str, cable_rng) -> None:
    z = TABLE_TOP
    b.box(name + "_stand", "plastic_grey", (0.10, y - 0.10, z), (0.30, y + 0.10, z + 0.015), skip=("-z",))
    b.box(name + "_stand", "plastic_grey", (0.15, y - 0.03, z + 0.015), (0.19, y + 0.03, z + 0.26))
    b.box(name, "plastic_black", (0.19, y - 0.28, z + 0.14), (0.23, y + 0.28, z + 0.48),
          faces={"+x": (screen, (0, 0, 1, 1))})
    b.tube(name + "_cable", "cable_black",
           np.vstack([_catenary((0.19, y + 0.05, z + 0.2), (0.07, y + 0.1, z + 0.02), 0.05, 12),
                      _catenary((0.055, y + 0.1, z - 0.04), (0.06, y + 0.12, 0.006), 0.0, 6),
                      _floor_cable(cable_rng, [(0.07, y + 0.12), (0.10, 2.95)], 0.004, 0.0)[1:]]),
           0.004, 6)


def _desk_items(b: MeshBuilder, rng, name: str, y: float, x_user: float = 0.55) -> None:
    z = TABLE_TOP
    # Keyboard: texture upright for the person sitting at +x and looking toward -x.
    b.oriented_box(name + "_keyboard", "plastic_black", (x_user, y, z + 0.012), [(0, 1, 0), (-1, 0, 0), (0, 0, 1)],
                   (0.22, 0.07, 0.012), faces={"+z": ("keyboard", (0, 0, 1, 1))}, skip=("-z",))
    b.box(name + "_mouse", "plastic_grey", (x_user - 0.05, y - 0.36, z), (x_user + 0.05, y - 0.30, z + 0.03),
          skip=("-z",))
    b.tube(name + "_mouse_cable", "cable_black",
           _catenary((x_user - 0.05, y - 0.33, z + 0.006), (0.2, y - 0.2, z + 0.006), 0.0, 10), 0.0025, 5)
    for k in range(int(rng.integers(1, 4))):  # papers, a little turned
        angle = rng.uniform(-0.4, 0.4)
        cx, cy = x_user + rng.uniform(-0.05, 0.2), y + rng.uniform(0.25, 0.45)
        b.oriented_box(name + "_papers", "ceramic_white", (cx, cy, z + 0.001 + 0.0012 * k), _rot_z(angle),
                       (0.105, 0.148, 0.0005), faces={"+z": ("paper", (0, 0, 1, 1))})
    mx, my = x_user + 0.15, y - 0.45
    b.cylinder(name + "_mug", "ceramic" if rng.random() < 0.5 else "ceramic_white", (mx, my, z), 0.04, 0.10, 16)
    b.tube(name + "_mug", "ceramic", [(mx + 0.04, my, z + 0.08), (mx + 0.065, my, z + 0.07),
                                      (mx + 0.065, my, z + 0.03), (mx + 0.04, my, z + 0.02)], 0.006, 6)
    for k in range(3):  # pens
        angle = rng.uniform(0, math.pi)
        d = np.array([math.cos(angle), math.sin(angle), 0.0])
        base = np.array([x_user + 0.05 + 0.03 * k, y - 0.2, z + 0.004])
        b.cylinder(name + "_pens", ("cable_blue", "plastic_black", "ceramic")[k], base - 0.07 * d, 0.004, 0.14, 6,
                   axis=d)


def _chair(b: MeshBuilder, name: str, x: float, y: float, facing: float, seat: str) -> None:
    """An office chair: five legs with casters, gas column, seat, tilted backrest. `facing` is
    the direction (radians about Z) the sitter looks."""
    for k in range(5):
        a = facing + k * 2 * math.pi / 5
        axes = _rot_z(a)
        b.oriented_box(name + "_base", "plastic_black", (x + 0.15 * math.cos(a), y + 0.15 * math.sin(a), 0.07),
                       axes, (0.15, 0.018, 0.018))
        b.cylinder(name + "_casters", "plastic_black", (x + 0.29 * math.cos(a), y + 0.29 * math.sin(a), 0.0),
                   0.025, 0.05, 8)
    b.cylinder(name + "_column", "metal", (x, y, 0.09), 0.025, 0.33, 12)
    axes = _rot_z(facing)
    b.oriented_box(name + "_seat", seat, (x, y, 0.455), axes, (0.23, 0.23, 0.035), uv_scale=0.2)
    back = -axes[0]  # behind the sitter
    tilt = math.radians(12)
    lean = math.cos(tilt) * np.array([0.0, 0.0, 1.0]) + math.sin(tilt) * back  # the backrest leans back
    centre = np.array([x, y, 0.77]) + back * 0.30
    b.oriented_box(name + "_back", seat, centre, [axes[1], np.cross(lean, axes[1]), lean], (0.22, 0.03, 0.2),
                   uv_scale=0.2)
    b.oriented_box(name + "_back_bar", "metal", np.array([x, y, 0.55]) + back * 0.27, axes, (0.04, 0.02, 0.07))


def _bookcase(b: MeshBuilder, rng) -> None:
    x0, x1, y0, y1, top = 0.5, 2.1, 5.65, 6.0, 2.0
    b.box("bookcase", "walnut", (x0, y0, 0), (x0 + 0.02, y1 - 0.01, top), uv_scale=0.9, skip=("-z",))
    b.box("bookcase", "walnut", (x1 - 0.02, y0, 0), (x1, y1 - 0.01, top), uv_scale=0.9, skip=("-z",))
    b.box("bookcase", "walnut", (x0 + 0.02, y1 - 0.02, 0), (x1 - 0.02, y1 - 0.01, top), uv_scale=0.9)
    levels = [0.0, 0.4, 0.8, 1.2, 1.6, top - 0.02]
    for z in levels:
        b.box("bookcase", "walnut", (x0 + 0.02, y0, z), (x1 - 0.02, y1 - 0.02, z + 0.02), uv_scale=0.9)
    columns = 16
    for shelf, z in enumerate(levels[:-1]):
        z += 0.02
        gap = levels[shelf + 1] - z
        x = x0 + 0.03
        while x < x1 - 0.08:
            if rng.random() < 0.06:  # a gap, or a stack of books lying flat
                if rng.random() < 0.5:
                    x += rng.uniform(0.04, 0.12)
                    continue
                zz = z
                for _ in range(int(rng.integers(2, 5))):
                    t = rng.uniform(0.02, 0.045)
                    k = int(rng.integers(columns))
                    cols = (k / columns, 0.45, (k + 1) / columns, 0.55)
                    b.box("books", "books", (x, y0 + 0.05, zz), (x + 0.22, y1 - 0.05, zz + t),
                          faces={f: ("books", cols) for f in ("+x", "-x", "+y", "-y", "+z", "-z")})
                    zz += t
                x += 0.25
                continue
            width = rng.uniform(0.018, 0.05)
            height = min(rng.uniform(0.17, 0.34), gap - 0.02)
            depth = rng.uniform(0.15, 0.27)
            k = int(rng.integers(columns))
            margin = 0.1 / columns
            spine = (k / columns + margin, 0.0, (k + 1) / columns - margin, 1.0)
            cover = (k / columns + margin, 0.45, (k + 1) / columns - margin, 0.55)
            b.box("books", "books", (x, y1 - 0.02 - depth, z), (x + width, y1 - 0.02, z + height),
                  faces={"-y": ("books", spine), "+x": ("books", cover), "-x": ("books", cover),
                         "+z": ("page_edges", None)}, skip=("-z", "+y"))
            x += width + rng.uniform(0.0, 0.004)
    for k in range(3):  # boxes and a plant on top
        b.box("bookcase_boxes", "plastic_white", (x0 + 0.1 + 0.35 * k, y0 + 0.05, top),
              (x0 + 0.38 + 0.35 * k, y1 - 0.05, top + 0.18 + 0.05 * k), skip=("-z",))


def _plant(b: MeshBuilder, rng, x: float, y: float, z: float) -> None:
    b.cylinder("plant_pot", "terracotta", (x, y, z), 0.08, 0.14, 16)
    for k in range(14):  # thin leaves fanned out from the pot
        a = rng.uniform(0, 2 * math.pi)
        lean = rng.uniform(0.2, 0.8)
        length = rng.uniform(0.18, 0.32)
        d = np.array([math.cos(a) * math.sin(lean), math.sin(a) * math.sin(lean), math.cos(lean)])
        side = np.cross(d, [0, 0, 1.0])
        side /= np.linalg.norm(side)
        normal = np.cross(side, d)
        centre = np.array([x, y, z + 0.12]) + d * length / 2
        b.oriented_box("plant_leaves", "leaf", centre, [side, normal, d], (0.015, 0.0015, length / 2))


def _lamp(b: MeshBuilder, x: float, y: float) -> None:
    z = TABLE_TOP
    b.cylinder("desk_lamp", "plastic_black", (x, y, z), 0.07, 0.02, 16)
    b.tube("desk_lamp", "metal", [(x, y, z + 0.02), (x, y + 0.02, z + 0.25), (x - 0.05, y + 0.05, z + 0.42),
                                  (x - 0.18, y + 0.08, z + 0.44)], 0.008, 6)
    b.cylinder("desk_lamp", "plastic_black", (x - 0.18, y + 0.08, z + 0.46), 0.06, 0.12, 16, axis=(-0.4, 0, -0.9))


def _cables(b: MeshBuilder, rng) -> None:
    # A power strip on the floor under the west tables, and the laptop's charger across the room.
    b.box("power_strip", "plastic_white", (0.08, 2.85, 0.0), (0.14, 3.25, 0.04), skip=("-z",))
    for k in range(5):
        b.box("power_strip", "plastic_black", (0.095, 2.9 + 0.07 * k, 0.04), (0.125, 2.93 + 0.07 * k, 0.042))
    b.tube("cable_wall", "cable_white", _floor_cable(rng, [(0.11, 3.25), (0.02, 3.6), (0.02, 4.6)], 0.005, 0.0),
           0.005, 6)
    b.tube("cable_laptop", "cable_black",
           np.vstack([_catenary((2.55, 3.15, TABLE_TOP + 0.01), (2.93, 3.4, TABLE_TOP - 0.02), 0.02, 10),
                      _catenary((2.935, 3.42, TABLE_TOP - 0.06), (2.94, 3.5, 0.004), 0.0, 6),
                      _floor_cable(rng, [(2.94, 3.5), (2.6, 4.9), (1.5, 5.45), (0.6, 5.45), (0.14, 3.25)],
                                   0.0035, 0.0, wiggle=0.06, n=120)[1:]]), 0.0035, 6)
    b.tube("cable_network", "cable_blue", _floor_cable(rng, [(0.02, 1.0), (0.3, 1.1), (0.2, 2.4)], 0.003, 0.0),
           0.003, 6)


def build():
    rng = np.random.default_rng(SEED)
    b = MeshBuilder()
    _materials(b, rng)
    _shell(b)
    _window(b)
    _door(b)
    _table(b, "table_west_1", (0.05, 0.8), (0.85, 2.8))
    _table(b, "table_west_2", (0.05, 3.0), (0.85, 5.0))
    _table(b, "table_window", (2.25, 1.6), (2.95, 4.4))
    _monitor(b, "monitor_1", 1.35, "screen_code", rng)
    _monitor(b, "monitor_2", 2.3, "screen_plot", rng)
    _monitor(b, "monitor_3", 4.0, "screen_code", rng)
    _desk_items(b, rng, "desk_1", 1.8)
    _desk_items(b, rng, "desk_2", 4.0)
    # Laptop on the window table, its screen tilted back, facing the room (−x).
    z = TABLE_TOP
    b.box("laptop", "plastic_grey", (2.45, 2.8, z), (2.75, 3.15, z + 0.018), faces={"+z": ("keyboard", (0, 0, 1, 1))},
          skip=("-z",))
    tilt = math.radians(15)
    up = np.array([math.sin(tilt), 0.0, math.cos(tilt)])
    face = np.array([-math.cos(tilt), 0.0, math.sin(tilt)])
    b.oriented_box("laptop_screen", "plastic_grey", np.array([2.76, 2.975, z + 0.018]) + up * 0.11 - face * 0.006,
                   [np.cross(up, face), up, face], (0.175, 0.11, 0.006),
                   faces={"+z": ("screen_code", (0, 0, 1, 1))})
    for k in range(4):  # a stack of books on the window table
        b.box("desk_books", "books", (2.5, 3.8, z + 0.035 * k), (2.78, 4.0, z + 0.035 * (k + 1)),
              faces={f: ("books", (k / 4, 0.45, (k + 1) / 4, 0.55)) for f in ("+x", "-x", "+y", "-y", "+z", "-z")})
    _plant(b, rng, 2.8, 1.8, TABLE_TOP)
    _lamp(b, 2.85, 4.25)
    _chair(b, "chair_1", 1.1, 1.8, math.pi, "seat_blue")
    _chair(b, "chair_2", 1.1, 4.0, math.pi, "seat_blue")
    _chair(b, "chair_3", 1.9, 2.95, 0.0, "seat_red")
    _bookcase(b, rng)
    b.box("pc_tower", "plastic_black", (0.1, 2.3, 0.0), (0.32, 2.75, 0.45), skip=("-z",),
          faces={"+x": ("metal", (0, 0, 1, 1))})
    b.cylinder("bin", "plastic_grey", (2.6, 5.5, 0.0), 0.14, 0.32, 20, caps=False)
    b.quad("bin", "plastic_grey", (2.6, 5.5, 0.02), (1, 0, 0), (0, 1, 0), 0.1, 0.1)
    b.box("poster", "frame_white", (0.0, 1.45, 1.35), (0.008, 2.15, 2.35), faces={"+x": ("poster", (0, 0, 1, 1))},
          skip=("-x",))
    b.box("whiteboard", "frame_white", (1.5, 0.0, 1.1), (2.8, 0.02, 1.75), faces={"+y": ("whiteboard", (0, 0, 1, 1))},
          skip=("-y",))
    b.box("whiteboard", "plastic_grey", (1.6, 0.0, 1.06), (2.7, 0.06, 1.08), skip=("-y",))
    for y in (1.5, 4.5):
        b.box("ceiling_light", "light_panel", (1.2, y - 0.6, ROOM[2] - 0.04), (1.8, y + 0.6, ROOM[2]), skip=("+z",))
    _cables(b, rng)

    scene = {
        "name": "lab",
        "title": "Lab room (3 × 6 × 2.8 m, modelled on the paper's scanned lab)",
        "mesh": "lab_room.obj",
        "scanners": [[1.2, 0.9, 1.50], [1.8, 2.3, 1.55], [1.4, 3.6, 1.45], [1.7, 5.1, 1.50]],
        "scan": {"step_deg": 0.25, "noise_mm": 1.0, "vertical_fov": 300},
        "grid": {"min": [0.7, 0.9, 1.1], "max": [2.3, 5.1, 1.9], "counts": [3, 5, 2]},
        "views": [
            {"name": "at_probe", "position": [1.5, 3.0, 1.1], "look_at": [0.6, 5.6, 0.9], "lens": 24,
             "resolution": [640, 400]},
            {"name": "between_probes", "position": [1.1, 2.45, 1.5], "look_at": [3.0, 3.0, 1.4], "lens": 24,
             "resolution": [640, 400]},
            {"name": "near_wall", "position": [2.85, 0.35, 1.6], "look_at": [0.8, 3.5, 0.9], "lens": 24,
             "resolution": [640, 400]},
            {"name": "toward_door", "position": [1.9, 4.6, 1.5], "look_at": [0.7, 0.0, 1.2], "lens": 24,
             "resolution": [640, 400]},
        ],
        "walk": {"points": [[1.5, 0.6, 1.6], [1.35, 2.0, 1.55], [1.6, 3.4, 1.5], [1.45, 4.8, 1.5]],
                 "look_at": [1.2, 6.0, 1.1], "frames": 12, "lens": 24},
    }
    return b, scene
