"""One run's shared state and the measurement every section repeats: render a camera (probes,
splats, a mesh) and compare it with the Embree ground truth of the same camera."""

from __future__ import annotations

import json
import math
import os
import shutil
import sys
import time
from collections import OrderedDict
from typing import Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np

from .. import metrics, native
from .presets import Preset
from .scene import Scene, View

METRIC_KEYS = ("psnr", "psnr_answered", "ssim", "flip", "depth_absrel", "depth_rmse", "hole_rate", "wrong_surface_rate", "false_hit_rate",
               "false_miss_rate", "unknown_rate")


_START = time.perf_counter()


def stderr_log(message: str) -> None:
    """Progress lines on stderr, each with the seconds since the run started."""
    print(f"[{time.perf_counter() - _START:7.1f} s] {message}", file=sys.stderr, flush=True)


def _file_stamp(path: str) -> tuple:
    info = os.stat(path)
    return (info.st_size, info.st_mtime_ns)


class RunContext:
    """The scene, preset, native module, reference mesh and work folder of one report run,
    with a cache of ground-truth images keyed by camera."""

    def __init__(self, scene: Scene, preset: Preset, out_dir: str, threads: int = 0,
                 log: Callable[[str], None] = stderr_log):
        self.scene = scene
        self.preset = preset
        self.out_dir = os.path.abspath(out_dir)
        self.work_dir = os.path.join(self.out_dir, "work")
        # The prepared-cloud cache of this run's clouds: each cloud's normals, spacing and point
        # hierarchy are computed by its first bake (or splat) and read by the others.
        self.cache_dir = os.path.join(self.work_dir, "prepared")
        self.images_dir = os.path.join(self.out_dir, "images")
        self.threads = int(threads)
        self.log = log
        self.native = native.load()
        start = time.perf_counter()
        try:
            self.mesh = self.native.load_mesh(scene.mesh)
        except (ValueError, OSError) as error:  # the native reader's InputError / NativeIOError name the line
            raise ValueError(f"{scene.path}: mesh {scene.mesh}: {error}") from error
        self.mesh_load_seconds = time.perf_counter() - start
        self.mesh_stamp = _file_stamp(scene.mesh)
        os.makedirs(self.work_dir, exist_ok=True)
        os.makedirs(self.images_dir, exist_ok=True)
        self._ground_truth: Dict[str, Tuple[dict, dict]] = {}
        self.views = list(scene.views)

    def mesh_changed(self) -> bool:
        """True when the scene's mesh file was rewritten after this run loaded it."""
        return _file_stamp(self.scene.mesh) != self.mesh_stamp

    # --- cameras -----------------------------------------------------------------------------
    def camera(self, view: View, position: Optional[Sequence[float]] = None) -> dict:
        return view.camera(self.preset.max_view_width, position)

    def work_path(self, *parts: str) -> str:
        path = os.path.join(self.work_dir, *parts)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        return path

    # --- ground truth ------------------------------------------------------------------------
    def ground_truth(self, camera: dict, spp: Optional[int] = None, mesh=None,
                     label: str = "gt", filter_textures: bool = True) -> Tuple[dict, dict]:
        """(image, stats) of the Embree ground truth of `camera` (cached for the scene mesh);
        filter_textures=False point-samples the textures (no texture LOD)."""
        spp = self.preset.gt_spp if spp is None else spp
        text = json.dumps(camera, sort_keys=True)
        key = f"{spp}:{filter_textures}:{text}"
        if mesh is None and key in self._ground_truth:
            return self._ground_truth[key]
        path = self.work_path("gt", f"{label}_{len(self._ground_truth):04d}.exr")
        job = self.native.start_ground_truth(self.mesh if mesh is None else mesh, text, path,
                                             spp=spp, threads=self.threads, filter_textures=filter_textures)
        stats = job.run()
        image = self.native.read_image(path)
        os.remove(path)
        if mesh is None:
            self._ground_truth[key] = (image, stats)
        return image, stats

    # --- probe renders -----------------------------------------------------------------------
    def render_probes(self, field, camera: dict, trace: Dict, spp: Optional[int] = None,
                      repeats: Optional[int] = None) -> Tuple[dict, dict]:
        """(image, stats) of tracing the probes at the ground truth's samples per pixel (matched
        filtering; `spp` overrides it); stats["seconds"] is the fastest of the preset's repeats
        (this machine is shared: the fastest is the least disturbed), or of `repeats`."""
        text = json.dumps(camera)
        spp = self.preset.gt_spp if spp is None else spp
        best_image, best = None, None
        for _ in range(self.preset.timing_repeats if repeats is None else repeats):
            image, stats = field.render(text, threads=self.threads, spp=spp, **trace)
            if best is None or stats["seconds"] < best["seconds"]:
                best_image, best = image, stats
        return best_image, best

    def cleanup(self, keep: bool) -> None:
        forget_prepared_references()
        if not keep:
            shutil.rmtree(self.work_dir, ignore_errors=True)


def supersampled_camera(camera: dict, spp: int) -> Tuple[dict, int]:
    """The camera at n times the resolution for n×n samples per pixel, and n: pixel (i, j) of
    the larger image is sampled at the centre of stratum (i mod n, j mod n) of pixel
    (i // n, j // n), the ground truth's stratified pattern, so that downsample() of its image
    is filtered exactly as the ground truth is."""
    n = int(round(math.sqrt(spp)))
    if n < 1 or n * n != spp:
        raise ValueError(f"samples per pixel must be a square, got {spp}")
    big = dict(camera)
    big["resolution"] = [int(camera["resolution"][0]) * n, int(camera["resolution"][1]) * n]
    return big, n


def downsample(image: dict, n: int) -> dict:
    """An image rendered by supersampled_camera, filtered to the camera's own pixels: colour and
    coverage are the mean of each n×n block; depth, normal, status and probe are the block's
    sample nearest its centre."""
    if n == 1:
        return image
    h, w = int(image["height"]) // n, int(image["width"]) // n
    out = dict(image)
    rgba = np.asarray(image["rgba"], np.float64).reshape(h, n, w, n, 4)
    out["rgba"] = rgba.mean(axis=(1, 3)).astype(np.float32)
    c = n // 2
    for key in ("depth", "normal", "status", "probe", "steps"):
        if key in image:
            out[key] = np.ascontiguousarray(np.asarray(image[key])[c::n, c::n][:h, :w])
    out["width"], out["height"] = w, h
    return out


# The ground truths last measured against, each with its half of the colour metrics
# (metrics.PreparedColour): the sweep compares each view's ground truth with every setting's
# render, and the views come round in turn. Each entry holds its image, so an id is not reused
# while it is kept.
_PREPARED: "OrderedDict[int, metrics.PreparedColour]" = OrderedDict()
_PREPARED_KEPT = 4


def _prepared_colour(reference: dict, ppd: float) -> metrics.PreparedColour:
    prepared = _PREPARED.get(id(reference))
    if prepared is not None and prepared.serves(reference, ppd):
        _PREPARED.move_to_end(id(reference))
        return prepared
    prepared = metrics.PreparedColour(reference, ppd)
    _PREPARED[id(reference)] = prepared
    while len(_PREPARED) > _PREPARED_KEPT:
        _PREPARED.popitem(last=False)
    return prepared


def forget_prepared_references() -> None:
    """Drops the kept ground truths' colour halves (the run is over)."""
    _PREPARED.clear()


def measure(reference: dict, test: dict, ppd: float = 67.0) -> Tuple[Dict[str, object], np.ndarray]:
    """The metrics of lfprobe.core.metrics (PSNR, SSIM, FLIP, depth, confusion) and the FLIP map."""
    result, error_map = metrics.compare_images_with_map(reference, test, ppd=ppd,
                                                        prepared=_prepared_colour(reference, ppd))
    row = {key: result[key] for key in METRIC_KEYS}
    row["confusion"] = result["counts"]
    return row, error_map


def psnr_only(reference: dict, test: dict) -> float:
    """PSNR alone (as in measure), for controls that need nothing else: FLIP and SSIM cost more."""
    return metrics.psnr(metrics.visible_colour(reference), metrics.visible_colour(test))


def silhouette_pixels(image: dict, relative_step: float = 0.03) -> np.ndarray:
    """Pixels beside a depth step (their centre depth and a 4-neighbour's differ by more than
    `relative_step` of the nearer): where a silhouette crosses the pixel or its neighbour."""
    depth = np.asarray(image["depth"], np.float64).reshape(int(image["height"]), int(image["width"]))
    hit = np.isfinite(depth) & (depth > 0)
    depth = np.where(hit, depth, np.inf)
    mask = np.zeros(depth.shape, bool)
    for a, b, pick in ((depth[:, 1:], depth[:, :-1], (slice(None), slice(1, None))),
                       (depth[1:], depth[:-1], (slice(1, None), slice(None)))):
        with np.errstate(invalid="ignore"):
            step = ~(np.abs(a - b) <= relative_step * np.minimum(a, b))
        mask[pick] |= step
        mask[tuple(slice(None, -1) if p.start == 1 else p for p in pick)] |= step
    return mask


# The shares of the squared error, in core.metrics (compare uses them too), named here as the
# report's modules and tests import them.
error_share = metrics.error_share
guessed_figures = metrics.guessed_figures


def timing(stats: dict, pixels: int) -> Dict[str, float]:
    """Frame time, rays per second (every ray traced, samples included, where the stats count
    them) and pixels per second."""
    seconds = float(stats["seconds"])
    rays = int(stats.get("rays") or pixels)
    return {"ms_per_frame": 1000.0 * seconds,
            "rays_per_second": rays / seconds if seconds > 0 else math.inf,
            "pixels_per_second": pixels / seconds if seconds > 0 else math.inf}


def nearest_probe_distance(position: Sequence[float], probes: List[Sequence[float]]) -> float:
    return min(math.dist(position, p) for p in probes)


def pixel_count(camera: dict) -> int:
    return int(camera["resolution"][0]) * int(camera["resolution"][1])
