"""The alternatives probes are measured against, from the same simulated scan and cameras:
the raw cloud drawn as z-buffered splats (native), and an Open3D Poisson mesh reconstructed
from the scan and ray traced with Embree like the ground truth. The Poisson mesh takes the
normals the probe bake uses (k-nearest-neighbour PCA, oriented toward each point's scanner, read
from the run's prepared-cloud cache), or Open3D's own estimate per scan (normals="open3d")."""

from __future__ import annotations

import json
import os
import time
from typing import Dict, List, Optional, Tuple

import numpy as np

from ..atomic_write import atomic_open
from .measure import RunContext, downsample, measure, pixel_count, supersampled_camera, timing


def splat_rows(ctx: RunContext, density) -> Tuple[List[Dict[str, object]], Dict[str, tuple]]:
    """Splats the cloud from every view: timing (fastest of the preset's repeats) and error.
    Filtered as the ground truth is: drawn at n× the resolution for n×n samples per pixel and
    averaged over each n×n block (the frame time is of the large image)."""
    rows, images = [], {}
    for view in ctx.views:
        camera = ctx.camera(view)
        gt, _ = ctx.ground_truth(camera)
        big, n = supersampled_camera(camera, ctx.preset.gt_spp)
        path = ctx.work_path("peers", f"splat_{view.name}.exr")
        best = None
        for _ in range(ctx.preset.timing_repeats):
            stats = ctx.native.start_splat(density.cloud, json.dumps(big), path, threads=ctx.threads,
                                           cache_dir=ctx.cache_dir).run()
            if best is None or stats["seconds"] < best["seconds"]:
                best = stats
        image = downsample(ctx.native.read_image(path), n)
        figures, error_map = measure(gt, image)
        row = {"method": "splats (raw cloud)", "view": view.name, "points": density.points,
               "preparation_seconds": best.get("geometry_seconds"),
               # positions, colours (float32) and one spacing value per point
               "memory_bytes": density.points * (12 + 12 + 4),
               **timing(best, pixel_count(camera)), **figures}
        rows.append(row)
        images[view.name] = (gt, image, error_map, row)
    return rows, images


def _write_ply(path: str, vertices_world: np.ndarray, colours: np.ndarray, triangles: np.ndarray) -> None:
    """Binary PLY: double x y z (world coordinates keep their precision), float linear colour."""
    header = (
        "ply\nformat binary_little_endian 1.0\ncomment lfprobe report: Open3D Poisson mesh\n"
        f"element vertex {len(vertices_world)}\nproperty double x\nproperty double y\nproperty double z\n"
        "property float red\nproperty float green\nproperty float blue\n"
        f"element face {len(triangles)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    vertex = np.zeros(len(vertices_world), dtype=[("p", "<f8", 3), ("c", "<f4", 3)])
    vertex["p"], vertex["c"] = vertices_world, np.clip(colours, 0.0, 1.0)
    face = np.zeros(len(triangles), dtype=[("n", "u1"), ("i", "<i4", 3)])
    face["n"], face["i"] = 3, triangles
    with atomic_open(path, "wb") as out:
        out.write(header.encode("ascii"))
        out.write(vertex.tobytes())
        out.write(face.tobytes())


POISSON_NORMALS = {
    "lfprobe": "the probe bake's (k-nearest-neighbour PCA, oriented toward each point's scanner)",
    "open3d": "Open3D's estimate per scan (hybrid radius search, oriented toward its scanner)",
}


def poisson_mesh(ctx: RunContext, density, normals: str = "lfprobe") -> Tuple[Optional[str], Dict[str, object]]:
    """Reconstructs a Poisson mesh of the cloud with Open3D from the normals `normals` names
    (POISSON_NORMALS); returns (PLY path, figures), or (None, {"error": why}) when Open3D is
    missing or fails."""
    if normals not in POISSON_NORMALS:
        raise ValueError(f"Poisson normals: expected one of {', '.join(POISSON_NORMALS)}, got {normals!r}")
    try:
        import open3d as o3d
    except Exception as error:  # ImportError, or a broken binary dependency
        return None, {"error": f"Open3D could not be imported ({type(error).__name__}: {error}); "
                               "install Debian's python3-open3d"}
    cloud = density.cloud
    positions = np.asarray(cloud.positions, dtype=np.float64)
    colours = np.asarray(cloud.colors, dtype=np.float64)
    scan_index = np.asarray(cloud.scan_index)
    start = time.perf_counter()
    if normals == "lfprobe":
        # The bake's normals of this cloud: read from the cache its bakes left (seconds) where
        # Open3D would estimate them again (39 s for 21.6 M points on 2 cores).
        geometry = ctx.native.start_local_geometry(cloud, threads=ctx.threads, cache_dir=ctx.cache_dir).run()
        merged = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(positions))
        merged.colors = o3d.utility.Vector3dVector(colours)
        merged.normals = o3d.utility.Vector3dVector(np.asarray(geometry["normals"], dtype=np.float64))
    else:
        merged = o3d.geometry.PointCloud()
        spacing = float(np.radians(density.step_deg)) * 3.0  # scan spacing at 3 m
        for index, scan in enumerate(cloud.scans):
            mask = scan_index == index
            part = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(positions[mask]))
            part.colors = o3d.utility.Vector3dVector(colours[mask])
            part.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=max(4 * spacing, 0.05), max_nn=30))
            if scan["scanner"] is not None:
                part.orient_normals_towards_camera_location(np.asarray(scan["scanner"], dtype=np.float64))
            merged += part
    normals_seconds = time.perf_counter() - start
    with o3d.utility.VerbosityContextManager(o3d.utility.VerbosityLevel.Error):
        mesh, densities = o3d.geometry.TriangleMesh.create_from_point_cloud_poisson(
            merged, depth=ctx.preset.poisson_depth)
    # Poisson closes the surface far from the data too: drop the least supported vertices and
    # anything outside the cloud's box.
    densities = np.asarray(densities)
    mesh.remove_vertices_by_mask(densities < np.quantile(densities, 0.02))
    box = merged.get_axis_aligned_bounding_box()
    mesh = mesh.crop(o3d.geometry.AxisAlignedBoundingBox(box.min_bound - 0.02, box.max_bound + 0.02))
    seconds = time.perf_counter() - start
    vertices = np.asarray(mesh.vertices) + np.asarray(cloud.world_offset, dtype=np.float64)
    triangles = np.asarray(mesh.triangles, dtype=np.int32)
    vertex_colours = np.asarray(mesh.vertex_colors) if mesh.has_vertex_colors() else np.full((len(vertices), 3), 0.8)
    path = ctx.work_path("peers", "poisson.ply")
    _write_ply(path, vertices, vertex_colours, triangles)
    return path, {
        "reconstruction_seconds": seconds, "normals_seconds": normals_seconds, "normals": normals,
        "poisson_depth": ctx.preset.poisson_depth, "vertices": int(len(vertices)),
        "triangles": int(len(triangles)), "ply_bytes": os.path.getsize(path),
        # as the native mesh holds it: float32 positions + corner colours, uint32 indices
        "memory_bytes": int(len(vertices) * 12 + len(triangles) * (12 + 3 * 12)),
    }


def poisson_rows(ctx: RunContext, density, normals: str = "lfprobe") -> Tuple[List[Dict[str, object]], Dict[str, tuple], Dict[str, object]]:
    ctx.log("  Open3D Poisson reconstruction")
    path, info = poisson_mesh(ctx, density, normals)
    if path is None:
        return [], {}, info
    mesh = ctx.native.load_mesh(path)
    rows, images = [], {}
    for view in ctx.views:
        camera = ctx.camera(view)
        gt, _ = ctx.ground_truth(camera)
        best_image, best = None, None
        for _ in range(ctx.preset.timing_repeats):
            image, stats = ctx.ground_truth(camera, mesh=mesh, label="poisson")  # the same spp
            if best is None or stats["seconds"] < best["seconds"]:
                best_image, best = image, stats
        figures, error_map = measure(gt, best_image)
        row = {"method": f"Poisson mesh (Open3D, depth {info['poisson_depth']})", "view": view.name,
               "points": density.points, "preparation_seconds": info["reconstruction_seconds"],
               "memory_bytes": info["memory_bytes"], "triangles": info["triangles"],
               **timing(best, pixel_count(camera)), **figures}
        rows.append(row)
        images[view.name] = (gt, best_image, error_map, row)
    return rows, images, info
