"""Blender cameras → the camera JSON of docs/DESIGN.md §3 that the native renderer reads.

Two sources: a camera object with the scene's render settings (F12, the batch CLI, compare),
and the 3D viewport's view (the engine's viewport render). Positions become *world*
coordinates: Blender's scene holds scans in their local frame (world = offset + local, the
offset kept in double on the scan objects), and the native renderer subtracts the probe
set's own offset from the camera, so the frame offset is added here, in double.
"""

from __future__ import annotations

import math
from typing import Optional, Sequence

from ..core.errors import InputError

SUPPORTED_PANORAMA = "EQUIRECTANGULAR"


class CameraExportError(InputError):
    """A camera the native renderer cannot reproduce (the message says which and why)."""


def render_size(render) -> tuple:
    """Pixels Blender renders: resolution × percentage, truncated as Blender does."""
    percentage = int(render.resolution_percentage)
    width = int(render.resolution_x) * percentage // 100
    height = int(render.resolution_y) * percentage // 100
    return max(width, 1), max(height, 1)


def _matrix_rows(matrix, world_offset: Sequence[float]) -> list:
    rows = [[float(matrix[r][c]) for c in range(4)] for r in range(4)]
    for axis in range(3):
        rows[axis][3] += float(world_offset[axis])
    return rows


def _panorama_settings(cam) -> tuple:
    """(panorama_type, owner of latitude/longitude): Blender 4.0 moved them from Cycles'
    camera settings (cam.cycles, 3.x) onto the camera itself."""
    if hasattr(cam, "panorama_type"):
        return cam.panorama_type, cam
    cycles = getattr(cam, "cycles", None)
    if cycles is None or not hasattr(cycles, "panorama_type"):
        raise CameraExportError(
            f"camera '{cam.name}' is a panorama, but this Blender keeps the panorama settings in "
            "the Cycles add-on, which is disabled: enable Cycles to read them"
        )
    return cycles.panorama_type, cycles


def camera_dict(scene, camera_obj=None, world_offset: Sequence[float] = (0.0, 0.0, 0.0),
                depsgraph=None, resolution: Optional[Sequence[int]] = None) -> dict:
    """The camera JSON (as a dict) for `camera_obj` (default: the scene camera) rendered with
    the scene's render settings. `depsgraph` gives the evaluated transform (animation,
    constraints); `resolution` overrides the render size."""
    camera_obj = camera_obj if camera_obj is not None else scene.camera
    if camera_obj is None:
        raise CameraExportError(f"scene '{scene.name}' has no active camera: add a camera and make it active")
    if camera_obj.type != "CAMERA":
        raise CameraExportError(f"object '{camera_obj.name}' is a {camera_obj.type.lower()}, not a camera")
    evaluated = camera_obj.evaluated_get(depsgraph) if depsgraph is not None else camera_obj
    cam = evaluated.data
    render = scene.render
    width, height = (int(resolution[0]), int(resolution[1])) if resolution else render_size(render)
    out = {
        "name": camera_obj.name,
        "matrix_world": _matrix_rows(evaluated.matrix_world, world_offset),
        "resolution": [width, height],
        "lens": float(cam.lens),
        "sensor_width": float(cam.sensor_width),
        "sensor_height": float(cam.sensor_height),
        "sensor_fit": cam.sensor_fit,
        "shift_x": float(cam.shift_x),
        "shift_y": float(cam.shift_y),
        "clip_start": float(cam.clip_start),
        "clip_end": float(cam.clip_end),
        "pixel_aspect_x": float(render.pixel_aspect_x),
        "pixel_aspect_y": float(render.pixel_aspect_y),
    }
    if cam.type == "PERSP":
        out["type"] = "PERSP"
    elif cam.type == "PANO":
        panorama_type, owner = _panorama_settings(cam)
        if panorama_type != SUPPORTED_PANORAMA:
            raise CameraExportError(
                f"camera '{camera_obj.name}': panorama type {panorama_type} is not traced; "
                f"use {SUPPORTED_PANORAMA} or a perspective camera"
            )
        out["type"] = "PANO_EQUIRECT"
        for key in ("latitude_min", "latitude_max", "longitude_min", "longitude_max"):
            out[key] = float(getattr(owner, key))
    else:
        raise CameraExportError(
            f"camera '{camera_obj.name}' is {cam.type.lower()}graphic; the probes are traced "
            "from perspective and equirectangular panorama cameras only"
        )
    return out


def viewport_camera_dict(region_data, width: int, height: int,
                         world_offset: Sequence[float] = (0.0, 0.0, 0.0)) -> dict:
    """The camera of a 3D viewport (RegionView3D) drawn at width × height pixels.

    The view's projection is an OpenGL frustum: P[0][0] = 1/tan(half width), P[0][2] and
    P[1][2] its off-centre shift, P[2][2] and P[2][3] the clip planes. It is written as a
    horizontally fitted 36 mm sensor, so that a band of rows is the same camera with another
    resolution and shift (viewport refinement renders bands)."""
    if not region_data.is_perspective:
        raise CameraExportError("orthographic views are not traced: switch the view to perspective (Numpad 5)")
    p = region_data.window_matrix
    sensor_width = 36.0
    aspect = width / height
    near = p[2][3] / (p[2][2] - 1.0)
    far = p[2][3] / (p[2][2] + 1.0)
    return {
        "name": "viewport",
        "type": "PERSP",
        "matrix_world": _matrix_rows(region_data.view_matrix.inverted(), world_offset),
        "resolution": [int(width), int(height)],
        "lens": 0.5 * sensor_width * float(p[0][0]),
        "sensor_width": sensor_width,
        "sensor_height": sensor_width / aspect,
        "sensor_fit": "HORIZONTAL",
        "shift_x": 0.5 * float(p[0][2]),
        "shift_y": 0.5 * float(p[1][2]) / aspect,
        "clip_start": float(near) if math.isfinite(near) and near > 0 else 0.01,
        "clip_end": float(far) if math.isfinite(far) and far > near else 1000.0,
    }


def band_of(camera: dict, width: int, height: int, row_start: int, row_count: int) -> dict:
    """Rows [row_start, row_start + row_count) of a horizontally fitted perspective camera
    rendered at width × height, as a camera of its own (width × row_count, shifted). With a
    horizontal fit one pixel spans sensor_width / lens / width in tangent units whatever the
    height, and the shift is in units of the image width, so only shift_y changes."""
    if camera.get("type") != "PERSP" or camera.get("sensor_fit") != "HORIZONTAL":
        raise CameraExportError("bands need a horizontally fitted perspective camera")
    band = dict(camera)
    band["resolution"] = [int(width), int(row_count)]
    centre_offset = 0.5 * height - (row_start + 0.5 * row_count)  # pixels above the centre
    band["shift_y"] = float(camera["shift_y"]) + centre_offset / width
    band["sensor_height"] = float(camera["sensor_width"]) * row_count / width
    return band
