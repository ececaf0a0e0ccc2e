"""Moving scan clouds between frames: the world frame of a probe set (world = offset + local
position, the offset keeping float32 coordinates small) and scans placed by a 4×4 transform
(a scan object moved in Blender). Pure numpy; the add-on hands in plain matrices."""

from __future__ import annotations

from typing import List, Optional, Sequence

import numpy as np

from . import native

Matrix4 = Sequence[Sequence[float]]


def to_world(local: Sequence[float], offset: Sequence[float]) -> List[float]:
    """A local position (Blender's frame) in the world frame: offset + local."""
    return [float(p + o) for p, o in zip(local, offset)]


def to_local(world: Sequence[float], offset: Sequence[float]) -> List[float]:
    """A world position in the local frame (Blender's): world − offset."""
    return [float(p - o) for p, o in zip(world, offset)]


def is_identity(matrix: Matrix4, tolerance: float = 1e-9) -> bool:
    return all(abs(matrix[r][c] - (1.0 if r == c else 0.0)) < tolerance for r in range(4) for c in range(4))


def transform_point(matrix: Matrix4, point: Optional[Sequence[float]]) -> Optional[list]:
    """An affine 4×4 transform applied to one point (None stays None)."""
    if point is None:
        return None
    m = np.asarray(matrix, dtype=np.float64)
    return list(m[:3, :3] @ np.asarray(point) + m[:3, 3])


def transform_scans(cloud, file_matrices: Sequence[Matrix4]):
    """The loaded cloud (load_scans' PointCloud) with each scan file's points and scanner moved
    by that file's 4×4 transform; the cloud itself when every transform is the identity."""
    if all(is_identity(m) for m in file_matrices):
        return cloud
    positions = cloud.positions.astype(np.float64)
    scan_index = cloud.scan_index
    scanners = []
    for file_index, scan in enumerate(cloud.scans):
        matrix = np.asarray(file_matrices[file_index], dtype=np.float64)
        members = scan_index == file_index
        positions[members] = positions[members] @ matrix[:3, :3].T + matrix[:3, 3]
        scanners.append(transform_point(matrix, scan["scanner"]))
    return native.load().PointCloud.from_arrays(
        positions.astype(np.float32),
        colors=cloud.colors,
        # File normals turn with their points; intensities and file paths are kept.
        normals=None if cloud.normals is None else _turned_normals(cloud, file_matrices),
        scan_index=scan_index,
        scanners=scanners,
        world_offset=list(cloud.world_offset),
        intensities=cloud.intensities,
        scan_paths=[scan["path"] for scan in cloud.scans],
    )


def _turned_normals(cloud, file_matrices) -> np.ndarray:
    """The cloud's file normals turned by each file's matrix (its inverse transpose, so a
    scaled object keeps them perpendicular to its surfaces), unit length again."""
    normals = np.array(cloud.normals, dtype=np.float64)
    for file_index in range(len(cloud.scans)):
        members = cloud.scan_index == file_index
        linear = np.asarray(file_matrices[file_index], dtype=np.float64)[:3, :3]
        normals[members] = normals[members] @ np.linalg.inv(linear)
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    return (normals / np.where(length > 0.0, length, 1.0)).astype(np.float32)
