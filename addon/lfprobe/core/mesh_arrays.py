"""Blender objects' triangles as the native mesh_from_arrays inputs, without Blender: the
add-on's mesh_export.py reads each object's arrays (foreach_get) and hands them here, where
they are moved to world coordinates and stacked into one mesh (world = world_offset +
Blender position, docs/DESIGN.md's frames)."""

from __future__ import annotations

from typing import Callable, List, Optional, Sequence

import numpy as np


def world_positions(local_co: np.ndarray, matrix, world_offset: Sequence[float]) -> np.ndarray:
    """Vertex positions (n, 3) float64 in the world frame from object-space ones and the
    object's 4×4 world matrix."""
    m = np.array(matrix, dtype=np.float64)
    local = np.asarray(local_co).reshape(-1, 3).astype(np.float64)
    return local @ m[:3, :3].T + m[:3, 3] + np.asarray(world_offset, dtype=np.float64)


def world_normals(normals: np.ndarray, matrix) -> np.ndarray:
    """Unit normals (n, 3) float32 in the world frame from object-space ones (the inverse
    transpose of the matrix's 3×3 part; zero normals stay zero)."""
    m = np.array(matrix, dtype=np.float64)
    normal_matrix = np.linalg.inv(m[:3, :3]).T
    world = normals.astype(np.float64) @ normal_matrix.T
    lengths = np.linalg.norm(world, axis=1, keepdims=True)
    return (world / np.where(lengths > 0, lengths, 1.0)).astype(np.float32)


def stack_optional(parts: List[Optional[np.ndarray]], sizes: List[int], width: int, fill: float):
    """Concatenates per-object corner arrays; objects without one get `fill`; None if none has."""
    if all(p is None for p in parts):
        return None
    return np.concatenate([
        p if p is not None else np.full((n, width), fill, dtype=np.float32) for p, n in zip(parts, sizes)
    ])


class MeshParts:
    """The mesh_from_arrays inputs, gathered object by object. Materials are the caller's
    objects with `uses_colors` (does the shading read the colour attribute) and `as_dict()`."""

    def __init__(self):
        self.vertices: List[np.ndarray] = []
        self.triangles: List[np.ndarray] = []
        self.uvs: List[Optional[np.ndarray]] = []
        self.colors: List[Optional[np.ndarray]] = []
        self.normals: List[np.ndarray] = []
        self.material: List[np.ndarray] = []
        self.object: List[np.ndarray] = []
        self.materials: list = []
        self.material_index = {}
        self.object_names: List[str] = []
        self.vertex_count = 0

    def material_slot(self, key, describe: Callable[[], object]) -> int:
        """The mesh's index of the material called key (None: no material), added on first use
        as describe() says."""
        if key not in self.material_index:
            self.material_index[key] = len(self.materials)
            self.materials.append(describe())
        return self.material_index[key]

    def add_object(self, name: str, local_co: np.ndarray, matrix, world_offset: Sequence[float],
                   triangles: np.ndarray, slots: np.ndarray, slot_materials: Sequence[int],
                   corner_uvs: Optional[np.ndarray], corner_colors: Optional[np.ndarray],
                   corner_normals: np.ndarray) -> None:
        """One object's triangles (vertex indices, flat), their material slots and the mesh
        indices of the slots' materials, and its per-corner arrays in object space."""
        world = world_positions(local_co, matrix, world_offset)
        slot_to_global = np.array(slot_materials, dtype=np.int64)
        slot = np.clip(slots, 0, len(slot_materials) - 1)
        if corner_colors is not None:
            # Triangles whose material ignores the colour attribute multiply by white.
            uses_colors = np.array([self.materials[g].uses_colors for g in slot_to_global])
            corner_colors = np.where(uses_colors[slot].repeat(3)[:, None], corner_colors, 1.0).astype(np.float32)
        self.uvs.append(corner_uvs)
        self.colors.append(corner_colors)
        self.normals.append(world_normals(corner_normals, matrix))
        self.vertices.append(world)
        self.triangles.append(triangles.reshape(-1, 3) + self.vertex_count)
        self.material.append(slot_to_global[slot])
        self.object.append(np.full(len(slots), len(self.object_names), dtype=np.int64))
        self.object_names.append(name)
        self.vertex_count += len(world)

    def mesh_arrays(self, name: str) -> dict:
        """The keyword arguments of _native.mesh_from_arrays for the objects added."""
        corners = [3 * len(t) for t in self.triangles]
        return dict(
            vertices=np.concatenate(self.vertices),
            triangles=np.concatenate(self.triangles),
            corner_uvs=stack_optional(self.uvs, corners, 2, 0.0),
            corner_colors=stack_optional(self.colors, corners, 3, 1.0),
            corner_normals=np.concatenate(self.normals),
            material=np.concatenate(self.material),
            object=np.concatenate(self.object),
            materials=[m.as_dict() for m in self.materials],
            object_names=self.object_names,
            name=name,
        )
