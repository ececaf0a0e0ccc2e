"""Procedural base-colour textures (numpy): wood grain, tiles, fabric, keyboards, screens,
posters with text-like marks, book spines, bricks. Every function takes a numpy Generator, so
a scene seeded once gives the same bytes every run, and returns (h, w, 3) uint8 sRGB.
Tiling textures wrap seamlessly (their noise is periodic), since the meshes repeat them."""

from __future__ import annotations

from typing import Sequence, Tuple

import numpy as np

Color = Tuple[float, float, float]  # sRGB in [0, 1]


def to_u8(img: np.ndarray) -> np.ndarray:
    return (np.clip(img, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)


def periodic_noise(rng: np.random.Generator, height: int, width: int, cells_y: int, cells_x: int) -> np.ndarray:
    """Smooth value noise in [0, 1] that wraps at the image edges: a random lattice of
    cells_y × cells_x values, smoothstep-interpolated."""
    lattice = rng.random((cells_y, cells_x))
    y = np.arange(height) * cells_y / height
    x = np.arange(width) * cells_x / width
    y0, x0 = np.floor(y).astype(int), np.floor(x).astype(int)
    fy, fx = y - y0, x - x0
    fy, fx = fy * fy * (3 - 2 * fy), fx * fx * (3 - 2 * fx)
    y1, x1 = (y0 + 1) % cells_y, (x0 + 1) % cells_x
    top = lattice[y0][:, x0] * (1 - fx) + lattice[y0][:, x1] * fx
    bottom = lattice[y1][:, x0] * (1 - fx) + lattice[y1][:, x1] * fx
    return top * (1 - fy)[:, None] + bottom * fy[:, None]


def fbm(rng: np.random.Generator, height: int, width: int, cells: int = 4, octaves: int = 5) -> np.ndarray:
    """Sum of periodic noise octaves (each twice as fine, half as strong), in [0, 1]."""
    total, weight, norm = np.zeros((height, width)), 1.0, 0.0
    for o in range(octaves):
        c = cells * 2 ** o
        total += weight * periodic_noise(rng, height, width, min(c, height), min(c, width))
        norm += weight
        weight *= 0.5
    return total / norm


def tint(value: np.ndarray, dark: Color, light: Color) -> np.ndarray:
    """Maps a [0, 1] field to colours between `dark` and `light`."""
    d, l = np.asarray(dark, float), np.asarray(light, float)
    return d + (l - d) * value[..., None]


def fill_rect(img: np.ndarray, x0: float, y0: float, x1: float, y1: float, color) -> None:
    h, w = img.shape[:2]
    xa, xb = int(max(0, round(x0))), int(min(w, round(x1)))
    ya, yb = int(max(0, round(y0))), int(min(h, round(y1)))
    if xb > xa and yb > ya:
        img[ya:yb, xa:xb] = color


# -- text-like marks ----------------------------------------------------------------------------

_GLYPH_SEED = 20260601


def glyph_alphabet(count: int = 40) -> np.ndarray:
    """`count` letter-like 7 × 5 bitmaps, each made of two to four strokes (bars on a 3 × 3
    skeleton), from a fixed seed: the same alphabet in every texture."""
    rng = np.random.default_rng(_GLYPH_SEED)
    glyphs = np.zeros((count, 7, 5), bool)
    strokes = [("v", 0), ("v", 2), ("v", 4), ("h", 0), ("h", 3), ("h", 6), ("d", 0), ("d", 1)]
    for g in glyphs:
        for kind, at in (strokes[i] for i in rng.choice(len(strokes), rng.integers(2, 5), replace=False)):
            if kind == "v":
                a, b = sorted(rng.choice([0, 3, 6], 2, replace=False))
                g[a:b + 1, at] = True
            elif kind == "h":
                a, b = sorted(rng.choice([0, 2, 4], 2, replace=False))
                g[at, a:b + 1] = True
            else:
                for r in range(7):
                    g[r, round(r * 4 / 6) if at == 0 else 4 - round(r * 4 / 6)] = True
    return glyphs


_GLYPHS = glyph_alphabet()


def text_line(img: np.ndarray, rng: np.random.Generator, x: float, y: float, chars: int,
              scale: int, color, words: bool = True) -> float:
    """Draws `chars` glyphs of 5 × 7 × scale pixels from (x, y) (top left), with spaces between
    words; returns the x after the last glyph."""
    h, w = img.shape[:2]
    cx = int(x)
    for i in range(chars):
        if words and i > 0 and rng.random() < 0.18:
            cx += 4 * scale
            continue
        g = np.kron(_GLYPHS[rng.integers(len(_GLYPHS))], np.ones((scale, scale), bool))
        ys, xs = np.nonzero(g)
        ys, xs = ys + int(y), xs + cx
        keep = (ys >= 0) & (ys < h) & (xs >= 0) & (xs < w)
        img[ys[keep], xs[keep]] = color
        cx += 6 * scale
    return cx


def polyline(img: np.ndarray, points: Sequence[Tuple[float, float]], width: float, color) -> None:
    """A stroke through `points` (pixel coordinates), `width` pixels wide."""
    h, w = img.shape[:2]
    for (xa, ya), (xb, yb) in zip(points[:-1], points[1:]):
        n = int(max(abs(xb - xa), abs(yb - ya)) * 2) + 1
        for t in np.linspace(0.0, 1.0, n):
            cx, cy = xa + (xb - xa) * t, ya + (yb - ya) * t
            r = width / 2
            fill_rect(img, cx - r, cy - r, cx + r, cy + r, color)


# -- materials ----------------------------------------------------------------------------------

def wood(rng: np.random.Generator, size: int = 512, dark: Color = (0.45, 0.28, 0.15),
         light: Color = (0.78, 0.58, 0.36), planks: int = 4) -> np.ndarray:
    """Planks running along u: growth rings distorted by noise, knots, dark seams."""
    h = w = size
    warp = fbm(rng, h, w, cells=2, octaves=4)
    y = np.arange(h)[:, None] / h * planks
    rings = np.sin((y * 9.0 + warp * 6.0 + periodic_noise(rng, h, w, 4, 1) * 2.0) * np.pi * 2) * 0.5 + 0.5
    fibre = periodic_noise(rng, h, w, h // 2, 8)
    value = 0.55 * rings ** 2 + 0.25 * fibre + 0.2 * fbm(rng, h, w, 8, 3)
    plank = np.floor(y).astype(int) % planks
    value = value * (0.85 + 0.3 * rng.random(planks))[plank]
    img = tint(np.clip(value, 0, 1), dark, light)
    for k in range(planks):  # seams between planks
        row = int(k * h / planks)
        img[row:row + 2] *= 0.45
    return to_u8(img)


def floor_tiles(rng: np.random.Generator, size: int = 512, tiles: int = 2,
                base: Color = (0.62, 0.63, 0.60), grout: Color = (0.35, 0.35, 0.34)) -> np.ndarray:
    """tiles × tiles vinyl tiles with coloured chips and speckle, 2-px grout lines."""
    img = tint(fbm(rng, size, size, 8, 4), np.asarray(base) * 0.85, np.asarray(base) * 1.1)
    chips = periodic_noise(rng, size, size, size // 4, size // 4)
    img[chips > 0.86] = (0.30, 0.32, 0.35)
    img[chips < 0.10] = (0.85, 0.84, 0.80)
    step = size // tiles
    for t in range(tiles):
        for s in range(tiles):
            img[t * step:(t + 1) * step, s * step:(s + 1) * step] *= 0.92 + 0.16 * rng.random()
    for k in range(tiles):
        img[k * step:k * step + 2, :] = grout
        img[:, k * step:k * step + 2] = grout
    return to_u8(img)


def ceiling_tiles(rng: np.random.Generator, size: int = 256) -> np.ndarray:
    """2 × 2 acoustic tiles: off-white with perforation dots and a metal grid."""
    img = tint(fbm(rng, size, size, 8, 3), (0.80, 0.80, 0.78), (0.93, 0.93, 0.91))
    holes = periodic_noise(rng, size, size, size // 2, size // 2) > 0.8
    img[holes] *= 0.6
    half = size // 2
    for k in (0, half):
        img[k:k + 3, :] = (0.70, 0.70, 0.72)
        img[:, k:k + 3] = (0.70, 0.70, 0.72)
    return to_u8(img)


def plaster(rng: np.random.Generator, size: int = 256, color: Color = (0.86, 0.85, 0.80)) -> np.ndarray:
    c = np.asarray(color)
    return to_u8(tint(fbm(rng, size, size, 6, 5), c * 0.9, np.minimum(c * 1.06, 1.0)))


def fabric(rng: np.random.Generator, size: int = 256, color: Color = (0.18, 0.25, 0.45)) -> np.ndarray:
    """A woven pattern: alternating over/under threads with noise."""
    y, x = np.mgrid[0:size, 0:size]
    weave = ((x // 4 + y // 4) % 2) * 0.5 + 0.5 * np.sin(x * np.pi / 2) ** 2
    value = 0.6 * weave + 0.4 * fbm(rng, size, size, 16, 3)
    c = np.asarray(color)
    return to_u8(tint(value, c * 0.6, np.minimum(c * 1.4, 1.0)))


def brushed_metal(rng: np.random.Generator, size: int = 128, color: Color = (0.62, 0.63, 0.65)) -> np.ndarray:
    streaks = periodic_noise(rng, size, size, size, 2)
    c = np.asarray(color)
    return to_u8(tint(0.7 * streaks + 0.3 * fbm(rng, size, size, 8, 3), c * 0.85, np.minimum(c * 1.12, 1.0)))


def keyboard(rng: np.random.Generator, width: int = 512, height: int = 160) -> np.ndarray:
    """A keyboard seen from above: rows of keys (a space bar, wide modifiers) with a glyph on
    each key, on a dark case."""
    img = np.empty((height, width, 3))
    img[:] = (0.10, 0.10, 0.11)
    rows = [([1.0] * 13 + [2.0]), ([1.5] + [1.0] * 12 + [1.5]), ([1.8] + [1.0] * 11 + [2.2]),
            ([2.3] + [1.0] * 10 + [2.7]), ([1.3] * 3 + [6.3] + [1.3] * 4)]
    key = (width - 16) / 15.0
    for r, widths in enumerate(rows):
        y0 = 8 + r * (height - 16) / len(rows)
        x = 8.0
        for wk in widths:
            x1 = x + wk * key
            fill_rect(img, x + 2, y0 + 2, x1 - 2, y0 + key - 4, (0.22, 0.22, 0.24))
            fill_rect(img, x + 4, y0 + 3, x1 - 4, y0 + key - 7, (0.27, 0.27, 0.29))
            if wk < 2.5:
                text_line(img, rng, x + 6, y0 + 6, 1, 2, (0.85, 0.85, 0.85), words=False)
            x = x1
    return to_u8(img)


def screen(rng: np.random.Generator, width: int = 512, height: int = 320, kind: str = "code") -> np.ndarray:
    """A monitor showing windows: an editor full of coloured code lines ('code'), or a plot
    with axes and curves ('plot'), with a task bar and a black bezel."""
    img = np.empty((height, width, 3))
    img[:] = (0.02, 0.02, 0.02)
    fill_rect(img, 10, 10, width - 10, height - 10, (0.16, 0.30, 0.45))  # desktop
    fill_rect(img, 10, height - 28, width - 10, height - 10, (0.12, 0.12, 0.14))  # task bar
    for i in range(6):
        fill_rect(img, 16 + i * 26, height - 25, 36 + i * 26, height - 13, (0.5, 0.5 + 0.07 * i, 0.6))
    fill_rect(img, 30, 22, width - 40, height - 40, (0.95, 0.95, 0.95) if kind == "plot" else (0.11, 0.12, 0.15))
    fill_rect(img, 30, 22, width - 40, 36, (0.25, 0.27, 0.33))  # title bar
    text_line(img, rng, 36, 25, 14, 1, (0.9, 0.9, 0.9))
    if kind == "code":
        palette = [(0.8, 0.6, 0.9), (0.6, 0.85, 0.6), (0.9, 0.8, 0.5), (0.85, 0.85, 0.85), (0.5, 0.7, 0.95)]
        y = 44
        indent = 0
        while y < height - 52:
            indent = int(np.clip(indent + rng.integers(-1, 2), 0, 4))
            x = 40 + indent * 14
            for _ in range(rng.integers(1, 4)):
                x = text_line(img, rng, x, y, int(rng.integers(2, 9)), 1, palette[rng.integers(len(palette))], False) + 6
            y += 11
    else:
        x0, y0, x1, y1 = 70, 50, width - 60, height - 60
        fill_rect(img, x0, y1, x1, y1 + 2, (0.1, 0.1, 0.1))
        fill_rect(img, x0, y0, x0 + 2, y1, (0.1, 0.1, 0.1))
        for k in range(6):
            tx = x0 + k * (x1 - x0) / 5
            fill_rect(img, tx, y1, tx + 1, y1 + 6, (0.1, 0.1, 0.1))
            text_line(img, rng, tx - 6, y1 + 9, 2, 1, (0.2, 0.2, 0.2), False)
        xs = np.linspace(0, 1, 120)
        for c, color in enumerate([(0.85, 0.2, 0.15), (0.15, 0.4, 0.85), (0.2, 0.65, 0.25)]):
            phase, amp = rng.random() * 6, 0.2 + 0.15 * rng.random()
            ys = 0.5 + amp * np.sin(xs * (4 + 2 * c) + phase) * np.exp(-xs * (c + 0.5))
            polyline(img, list(zip(x0 + xs * (x1 - x0), y1 - ys * (y1 - y0))), 2, color)
    return to_u8(img)


def poster(rng: np.random.Generator, width: int = 360, height: int = 512) -> np.ndarray:
    """A scientific poster: title bar, author line, three columns of text-like marks, a bar
    chart and a picture-like colour field."""
    img = np.empty((height, width, 3))
    img[:] = (0.97, 0.96, 0.93)
    fill_rect(img, 0, 0, width, 70, (0.10, 0.22, 0.45))
    text_line(img, rng, 14, 12, 22, 2, (1.0, 1.0, 1.0))
    text_line(img, rng, 14, 42, 30, 1, (0.85, 0.88, 0.95))
    col_w = (width - 40) / 3
    for c in range(3):
        x0 = 12 + c * (col_w + 8)
        y = 84
        while y < height - 16:
            if rng.random() < 0.08:  # a figure
                fh = rng.integers(40, 80)
                if rng.random() < 0.5:
                    bars = rng.random(6)
                    for b, v in enumerate(bars):
                        fill_rect(img, x0 + 4 + b * (col_w - 8) / 6, y + fh * (1 - v), x0 + (b + 0.8) * (col_w - 8) / 6,
                                  y + fh, (0.85, 0.35 + 0.08 * b, 0.2))
                else:
                    field = tint(fbm(rng, int(fh), int(col_w), 2, 4), (0.1, 0.3, 0.5), (0.95, 0.8, 0.3))
                    ys, xs = int(y), int(x0)
                    img[ys:ys + field.shape[0], xs:xs + field.shape[1]] = field[:img.shape[0] - ys, :img.shape[1] - xs]
                y += fh + 8
                continue
            if rng.random() < 0.1:  # a heading
                text_line(img, rng, x0, y, int(col_w // 12), 2, (0.10, 0.22, 0.45))
                y += 18
                continue
            text_line(img, rng, x0, y, int((col_w // 6) * (0.6 + 0.4 * rng.random())), 1, (0.15, 0.15, 0.15))
            y += 10
    return to_u8(img)


def paper_page(rng: np.random.Generator, width: int = 192, height: int = 256) -> np.ndarray:
    img = np.empty((height, width, 3))
    img[:] = (0.95, 0.95, 0.93)
    text_line(img, rng, 14, 14, 14, 2, (0.1, 0.1, 0.1))
    y = 40
    while y < height - 14:
        text_line(img, rng, 14, y, int(20 + 8 * rng.random()), 1, (0.2, 0.2, 0.2))
        y += 9
    return to_u8(img)


def book_spines(rng: np.random.Generator, size: int = 512, columns: int = 16) -> np.ndarray:
    """An atlas of `columns` book spines side by side (each size/columns pixels wide, full
    height): cloth colour, bands, a vertical title and a publisher mark."""
    img = np.empty((size, size, 3))
    col_w = size // columns
    for k in range(columns):
        base = np.array([rng.uniform(0.1, 0.85), rng.uniform(0.1, 0.7), rng.uniform(0.1, 0.7)])
        x0 = k * col_w
        img[:, x0:x0 + col_w] = tint(fbm(rng, size, col_w, 4, 3), base * 0.8, np.minimum(base * 1.15, 1))
        ink = (0.95, 0.9, 0.6) if base.mean() < 0.45 else (0.08, 0.08, 0.08)
        for band in rng.choice([30, 60, size - 60, size - 36], 2, replace=False):
            fill_rect(img, x0, band, x0 + col_w, band + 5, ink)
        # The title runs along the spine: glyphs drawn on a rotated strip.
        strip = np.zeros((col_w, size - 160, 3))
        strip[:] = img[80:size - 80, x0:x0 + col_w].transpose(1, 0, 2)
        text_line(strip, rng, 4, (col_w - 14) // 2, int(rng.integers(8, 20)), 2, ink)
        img[80:size - 80, x0:x0 + col_w] = strip.transpose(1, 0, 2)
        fill_rect(img, x0 + col_w // 4, size - 30, x0 + 3 * col_w // 4, size - 18, ink)
        img[:, x0:x0 + 1] *= 0.5
    return to_u8(img)


def whiteboard(rng: np.random.Generator, width: int = 512, height: int = 256) -> np.ndarray:
    """A whiteboard with marker writing, boxes and arrows of a diagram."""
    img = tint(fbm(rng, height, width, 4, 3), (0.90, 0.91, 0.92), (0.98, 0.98, 0.99))
    fill_rect(img, 0, 0, width, 6, (0.7, 0.7, 0.72))
    fill_rect(img, 0, height - 6, width, height, (0.7, 0.7, 0.72))
    inks = [(0.1, 0.2, 0.6), (0.1, 0.1, 0.1), (0.7, 0.1, 0.1)]
    for _ in range(5):
        x, y = rng.uniform(20, width - 160), rng.uniform(20, height - 60)
        ink = inks[rng.integers(3)]
        w, h = rng.uniform(60, 140), rng.uniform(30, 50)
        polyline(img, [(x, y), (x + w, y), (x + w, y + h), (x, y + h), (x, y)], 2, ink)
        text_line(img, rng, x + 6, y + h / 2 - 6, int(w // 14), 2, ink)
    for _ in range(4):
        pts = [(rng.uniform(10, width - 10), rng.uniform(10, height - 10)) for _ in range(3)]
        polyline(img, pts, 2, inks[rng.integers(3)])
    return to_u8(img)


def outside_view(rng: np.random.Generator, width: int = 512, height: int = 256) -> np.ndarray:
    """What a window shows: sky gradient with clouds, a building across the street, trees."""
    v = np.linspace(0, 1, height)[:, None, None]
    img = (1 - v) * np.array([0.45, 0.62, 0.88]) + v * np.array([0.80, 0.86, 0.95])
    img = img * np.ones((1, width, 1))
    clouds = fbm(rng, height, width, 4, 5)
    img = np.where((clouds > 0.58)[..., None], img * 0.3 + 0.7, img)
    fill_rect(img, 0, height * 0.45, width, height, (0.62, 0.55, 0.48))  # building
    for r in range(6):
        for c in range(12):
            fill_rect(img, 12 + c * 42, height * 0.5 + r * 22, 40 + c * 42, height * 0.5 + r * 22 + 14,
                      (0.25, 0.3, 0.38) if rng.random() < 0.7 else (0.9, 0.85, 0.6))
    trees = fbm(rng, height, width, 8, 4)
    y = np.arange(height)[:, None]
    mask = (trees > 0.5) & (y > height * (0.35 + 0.25 * periodic_noise(rng, 1, width, 1, 6)))
    img[mask] = tint(trees[mask], (0.1, 0.25, 0.08), (0.3, 0.5, 0.2))
    return to_u8(img)


def bricks(rng: np.random.Generator, size: int = 512, rows: int = 16, per_row: int = 4) -> np.ndarray:
    """Running-bond brickwork: per-brick colour, mortar joints, surface noise."""
    img = np.empty((size, size, 3))
    img[:] = (0.72, 0.70, 0.66)
    bh, bw = size / rows, size / per_row
    noise = fbm(rng, size, size, 16, 3)
    for r in range(rows):
        shift = bw / 2 if r % 2 else 0.0
        for c in range(-1, per_row + 1):
            color = np.array([0.55, 0.25, 0.16]) * (0.8 + 0.4 * rng.random())
            x0, y0 = c * bw + shift + 3, r * bh + 3
            fill_rect(img, x0, y0, x0 + bw - 3, y0 + bh - 3, color)
    img *= (0.85 + 0.3 * noise)[..., None]
    return to_u8(img)


def slat_metal(rng: np.random.Generator, size: int = 64) -> np.ndarray:
    return brushed_metal(rng, size, (0.80, 0.80, 0.76))
