"""Triangle soup with per-corner UVs, per-triangle material and object, in a local frame.

World = world_offset + local position (docs/DESIGN.md §3): the builder works in metres near the
origin and the offset is added only when a file is written, in double precision, so that a
georeferenced scene keeps sub-millimetre detail. Every primitive is made of quads wound
counter-clockwise as seen from the side its normal points to.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

UP = np.array([0.0, 0.0, 1.0])


@dataclass
class Material:
    name: str
    base_color: Tuple[float, float, float] = (0.8, 0.8, 0.8)  # linear RGB
    texture: Optional[str] = None  # key into MeshBuilder.textures


def _unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    n = np.linalg.norm(v)
    if n == 0.0:
        raise ValueError("zero-length direction")
    return v / n


class MeshBuilder:
    def __init__(self, world_offset: Sequence[float] = (0.0, 0.0, 0.0)):
        self.world_offset = np.asarray(world_offset, dtype=np.float64)
        self.materials: List[Material] = []
        self.textures: Dict[str, np.ndarray] = {}  # name → (h, w, 3) uint8, sRGB
        self.object_names: List[str] = []
        self._material_index: Dict[str, int] = {}
        self._object_index: Dict[str, int] = {}
        self._corners: List[np.ndarray] = []  # (k, 3, 3) corner positions per batch
        self._uvs: List[np.ndarray] = []  # (k, 3, 2)
        self._material: List[np.ndarray] = []
        self._object: List[np.ndarray] = []

    # -- registries --------------------------------------------------------------------------
    def texture(self, name: str, pixels: np.ndarray) -> str:
        if pixels.dtype != np.uint8 or pixels.ndim != 3 or pixels.shape[2] != 3:
            raise ValueError(f"texture {name}: expected (h, w, 3) uint8")
        if max(pixels.shape[:2]) > 512:
            raise ValueError(f"texture {name}: {pixels.shape[1]}×{pixels.shape[0]} is over 512²")
        self.textures[name] = pixels
        return name

    def material(self, name: str, base_color=(1.0, 1.0, 1.0), texture: Optional[str] = None) -> str:
        if texture is not None and texture not in self.textures:
            raise ValueError(f"material {name}: unknown texture {texture}")
        if name in self._material_index:
            raise ValueError(f"material {name} defined twice")
        self._material_index[name] = len(self.materials)
        self.materials.append(Material(name, tuple(float(c) for c in base_color), texture))
        return name

    def _object_id(self, name: str) -> int:
        if name not in self._object_index:
            self._object_index[name] = len(self.object_names)
            self.object_names.append(name)
        return self._object_index[name]

    def _add(self, obj: str, material: str, corners: np.ndarray, uvs: np.ndarray) -> None:
        if material not in self._material_index:
            raise ValueError(f"unknown material {material}")
        k = corners.shape[0]
        self._corners.append(corners.astype(np.float64))
        self._uvs.append(uvs.astype(np.float64))
        self._material.append(np.full(k, self._material_index[material], np.int64))
        self._object.append(np.full(k, self._object_id(obj), np.int64))

    # -- primitives --------------------------------------------------------------------------
    def quad(self, obj: str, material: str, centre, u_dir, v_dir, half_u: float, half_v: float,
             uv_rect: Optional[Sequence[float]] = None, uv_scale: float = 1.0) -> None:
        """A rectangle; its normal is u_dir × v_dir. UVs: the rectangle (u0, v0, u1, v1) of the
        texture stretched over the quad (u to the right, v up as seen from the front), or world
        planar coordinates in units of uv_scale metres (continuous across neighbouring quads)."""
        c, u, v = np.asarray(centre, float), _unit(u_dir), _unit(v_dir)
        p = np.array([c - half_u * u - half_v * v, c + half_u * u - half_v * v,
                      c + half_u * u + half_v * v, c - half_u * u + half_v * v])
        if uv_rect is not None:
            u0, v0, u1, v1 = uv_rect
            t = np.array([[u0, v0], [u1, v0], [u1, v1], [u0, v1]], float)
        else:
            t = np.stack([p @ u, p @ v], axis=1) / uv_scale
        corners = np.array([[p[0], p[1], p[2]], [p[0], p[2], p[3]]])
        uvs = np.array([[t[0], t[1], t[2]], [t[0], t[2], t[3]]])
        self._add(obj, material, corners, uvs)

    def box(self, obj: str, material: str, lo, hi, uv_scale: float = 1.0,
            faces: Optional[Dict[str, Tuple[str, Optional[Sequence[float]]]]] = None,
            skip: Sequence[str] = ()) -> None:
        """An axis-aligned box (outward normals); see oriented_box."""
        lo, hi = np.asarray(lo, float), np.asarray(hi, float)
        self.oriented_box(obj, material, (lo + hi) / 2, np.eye(3), (hi - lo) / 2, uv_scale, faces, skip)

    def oriented_box(self, obj: str, material: str, centre, axes, half, uv_scale: float = 1.0,
                     faces: Optional[Dict[str, Tuple[str, Optional[Sequence[float]]]]] = None,
                     skip: Sequence[str] = ()) -> None:
        """A box with rows of `axes` as its local x, y, z and half extents `half`. Faces are named
        '+x', '-x', '+y', '-y', '+z', '-z' (local); `faces` gives some of them their own
        (material, uv rect or None), `skip` leaves faces out (e.g. one resting on the floor).
        On a vertical face v runs up, so textures stand upright."""
        axes = np.asarray(axes, float)
        half = np.asarray(half, float)
        if np.any(half <= 0):
            raise ValueError(f"{obj}: box extents must be positive, got {2 * half}")
        faces = faces or {}
        for k in range(3):
            for sign, label in ((1.0, "+"), (-1.0, "-")):
                name = f"{label}{'xyz'[k]}"
                if name in skip:
                    continue
                n = sign * axes[k]
                others = [j for j in range(3) if j != k]
                if abs(n @ UP) < 0.9:  # a side: v is the other axis closest to world up
                    j_v = max(others, key=lambda j: abs(axes[j] @ UP))
                    v = axes[j_v] * (1.0 if axes[j_v] @ UP >= 0 else -1.0)
                else:
                    j_v = others[1]
                    v = axes[j_v]
                j_u = others[0] if others[1] == j_v else others[1]
                u = np.cross(v, n)
                mat, rect = faces.get(name, (material, None))
                self.quad(obj, mat, centre + n * half[k], u, v, half[j_u], half[j_v], rect, uv_scale)

    def wall(self, obj: str, material: str, origin, u_dir, v_dir, width: float, height: float,
             openings: Sequence[Tuple[float, float, float, float]] = (), uv_scale: float = 1.0) -> None:
        """A rectangle from origin spanning width along u_dir and height along v_dir (normal
        u × v), with rectangular holes (u0, u1, v0, v1) in wall coordinates, cut into quads."""
        o, u, v = np.asarray(origin, float), _unit(u_dir), _unit(v_dir)
        cuts = sorted({0.0, width, *[c for op in openings for c in op[:2]]})
        for a, b in zip(cuts[:-1], cuts[1:]):
            if b - a <= 1e-9:
                continue
            mid = (a + b) / 2
            blocked = sorted((op[2], op[3]) for op in openings if op[0] <= mid <= op[1])
            start = 0.0
            for v0, v1 in blocked + [(height, height)]:
                if v0 - start > 1e-9:
                    centre = o + u * mid + v * (start + v0) / 2
                    self.quad(obj, material, centre, u, v, (b - a) / 2, (v0 - start) / 2, None, uv_scale)
                start = max(start, v1)

    def cylinder(self, obj: str, material: str, base, radius: float, height: float, sides: int = 16,
                 axis=(0.0, 0.0, 1.0), caps: bool = True, uv_scale: float = 1.0) -> None:
        """A closed cylinder standing on `base` along `axis`."""
        a = _unit(axis)
        ring = self._ring_frame(a)
        self.tube(obj, material, [np.asarray(base, float), np.asarray(base, float) + a * height],
                  radius, sides, uv_scale, frame=ring)
        if caps:
            angles = np.linspace(0.0, 2 * np.pi, sides + 1)
            circle = np.cos(angles)[:, None] * ring[0] + np.sin(angles)[:, None] * ring[1]
            for centre, sign in ((np.asarray(base, float), -1.0), (np.asarray(base, float) + a * height, 1.0)):
                rim = centre + radius * circle
                tris, uvs = [], []
                for i in range(sides):
                    p0, p1 = (rim[i], rim[i + 1]) if sign > 0 else (rim[i + 1], rim[i])
                    tris.append([centre, p0, p1])
                    uvs.append([[0.5, 0.5], 0.5 + 0.5 * (p0 - centre)[:2] / radius,
                                0.5 + 0.5 * (p1 - centre)[:2] / radius])
                self._add(obj, material, np.array(tris), np.array(uvs))

    @staticmethod
    def _ring_frame(direction: np.ndarray) -> np.ndarray:
        helper = np.array([1.0, 0.0, 0.0]) if abs(direction[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        e1 = _unit(np.cross(direction, helper))
        return np.array([e1, np.cross(direction, e1)])

    def tube(self, obj: str, material: str, points, radius: float, sides: int = 6,
             uv_scale: float = 1.0, frame: Optional[np.ndarray] = None) -> None:
        """An open tube of `sides` facets along a polyline (cables): frames carried along by
        parallel transport so the tube does not twist."""
        pts = np.asarray(points, float)
        if len(pts) < 2:
            raise ValueError(f"{obj}: a tube needs at least two points")
        tangents = np.diff(pts, axis=0)
        tangents /= np.linalg.norm(tangents, axis=1, keepdims=True)
        # Vertex tangents: the mean of the neighbouring segments.
        vt = np.vstack([tangents[:1], tangents[:-1] + tangents[1:], tangents[-1:]])
        vt /= np.linalg.norm(vt, axis=1, keepdims=True)
        e1, e2 = frame if frame is not None else self._ring_frame(vt[0])
        angles = np.linspace(0.0, 2 * np.pi, sides + 1)
        rings = []
        for point, t in zip(pts, vt):
            e1 = _unit(e1 - (e1 @ t) * t)  # the previous frame, turned onto this ring's plane
            e2 = np.cross(t, e1)
            rings.append(point + radius * (np.cos(angles)[:, None] * e1 + np.sin(angles)[:, None] * e2))
        rings = np.array(rings)  # (n, sides+1, 3)
        length = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
        around = np.linspace(0.0, 2 * np.pi * radius, sides + 1)
        tris, uvs = [], []
        for i in range(len(pts) - 1):
            for s in range(sides):
                a, b, c, d = rings[i, s], rings[i, s + 1], rings[i + 1, s + 1], rings[i + 1, s]
                ta, tb = [around[s], length[i]], [around[s + 1], length[i]]
                tc, td = [around[s + 1], length[i + 1]], [around[s], length[i + 1]]
                tris += [[a, b, c], [a, c, d]]
                uvs += [[ta, tb, tc], [ta, tc, td]]
        self._add(obj, material, np.array(tris), np.array(uvs) / uv_scale)

    # -- results -----------------------------------------------------------------------------
    @property
    def triangle_count(self) -> int:
        return int(sum(len(m) for m in self._material))

    def arrays(self):
        """(corners (T, 3, 3) local positions, uvs (T, 3, 2), material (T,), object (T,))."""
        if not self._corners:
            raise ValueError("the scene has no triangles")
        return (np.concatenate(self._corners), np.concatenate(self._uvs),
                np.concatenate(self._material), np.concatenate(self._object))

    def indexed(self, object_index: Optional[int] = None):
        """Shared vertices: (vertices (V, 3) local, triangles (T, 3), uvs (T, 3, 2), material,
        object) of every triangle, or of one object's. Corners at the same position (to 0.01 mm)
        share one vertex."""
        corners, uvs, material, obj = self.arrays()
        if object_index is not None:
            pick = obj == object_index
            corners, uvs, material, obj = corners[pick], uvs[pick], material[pick], obj[pick]
        flat = corners.reshape(-1, 3)
        keys = np.round(flat * 1e5).astype(np.int64)
        unique, inverse = np.unique(keys, axis=0, return_inverse=True)
        vertices = np.zeros((len(unique), 3))
        vertices[inverse.ravel()] = flat
        return vertices, inverse.reshape(-1, 3), uvs, material, obj
