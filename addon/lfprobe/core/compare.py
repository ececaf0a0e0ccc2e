"""A view measured against ground truth of the same camera: read both images, compute every
figure of lfprobe.core.metrics, write the FLIP error map and previews as PNG and the figures as
JSON. `lfprobe compare` measures two image files with `compare_files` (lfprobe's own EXRs, other
EXRs, PNG and JPEG: core/image_files.py); the add-on's Compare renders ground truth and probes
into a report folder and measures them with `CompareReport`. Colour metrics are computed for any
pair; depth and the HIT/MISS/UNKNOWN figures only where both images carry lfprobe's status and
depth planes, and the figures say which were computed (`computed`) and why the others were not
(`not_computed`)."""

from __future__ import annotations

import json
import os
import struct
import time
import zlib
from typing import Dict, Optional, Tuple

import numpy as np

from . import metrics, native
from .atomic_write import atomic_open
from .camera_json import write_camera
from .colour import magma8, srgb8
from .errors import InputError
from .flip import DEFAULT_PPD
from .image_files import read_any_image
from .json_values import strict_json



def check_samples_per_pixel(spp: int) -> None:
    """Ground truth and probes are rendered with the same n×n samples per pixel."""
    if spp < 1 or int(round(spp ** 0.5)) ** 2 != spp:
        raise InputError(f"samples per pixel must be 1 or a square (4, 9, 16, ...), not {spp}")


def read_image(path: str) -> Dict[str, object]:
    """A native EXR as read_image's dict; FileNotFoundError or ValueError saying which file."""
    if not os.path.isfile(path):
        raise FileNotFoundError(f"no such image: {path}")
    try:
        return native.load().read_image(path)
    except native.NativeModuleError:
        raise
    except Exception as error:  # the native reader's own error types
        raise ValueError(f"cannot read {path}: {error}") from error


def render_seconds(image: Dict[str, object]) -> Optional[float]:
    """The renderer's own time for the image, when its metadata records one."""
    try:
        stats = json.loads(image.get("metadata") or "{}").get("stats", {})
        seconds = stats.get("seconds")
        return float(seconds) if seconds is not None else None
    except (ValueError, AttributeError, TypeError):
        return None


def write_png(path: str, rgb8: np.ndarray) -> None:
    """Writes an (h, w, 3) uint8 image as an 8-bit RGB PNG (zlib, no filtering)."""
    h, w = rgb8.shape[:2]
    raw = b"".join(b"\x00" + rgb8[y].tobytes() for y in range(h))

    def chunk(tag: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)
    with atomic_open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, 6))
                + chunk(b"IEND", b""))


def measure(reference: dict, test: dict, ppd: float = DEFAULT_PPD) -> Tuple[Dict[str, object], np.ndarray]:
    """(the figures of metrics.compare_images_with_map plus compare_seconds, computed and
    not_computed, FLIP error map). Two lfprobe renders (status planes in both) are measured
    exactly as they always were; any other pair by metrics.compare_colour_with_map."""
    start = time.perf_counter()
    if "status" in reference and "status" in test:
        result, error_map = metrics.compare_images_with_map(reference, test, ppd=ppd)
    else:
        result, error_map = metrics.compare_colour_with_map(reference, test, ppd=ppd)
    result.update(metrics.guessed_figures(reference, test))
    result["compare_seconds"] = time.perf_counter() - start
    result["computed"], result["not_computed"] = metrics.availability(reference, test, result["ssim"])
    return result, error_map


def compare_files(reference_path: str, test_path: str, ppd: float = DEFAULT_PPD,
                  error_map_path: Optional[str] = None) -> Dict[str, object]:
    """The figures of a test image against a reference image (`lfprobe compare`), with both
    renders' own times and what each file was (`reference_source`, `test_source`); writes the
    FLIP error as a magma PNG when `error_map_path` is given. FileNotFoundError for a missing
    file, InputError naming the file for one that cannot be read or images of different sizes."""
    if ppd <= 0:
        raise ValueError(f"--ppd must be positive, got {ppd}")
    reference = read_any_image(reference_path)
    test = read_any_image(test_path)
    (h0, w0), (h1, w1) = reference["rgba"].shape[:2], test["rgba"].shape[:2]
    if (h0, w0) != (h1, w1):
        raise InputError(f"images differ in size: reference {reference_path} is {w0}×{h0}, "
                         f"test {test_path} is {w1}×{h1}; compare needs the same camera and size")
    result, error_map = measure(reference, test, ppd)
    result["reference"], result["test"] = os.path.abspath(reference_path), os.path.abspath(test_path)
    result["ref_render_seconds"] = render_seconds(reference)
    result["test_render_seconds"] = render_seconds(test)
    result["reference_source"], result["test_source"] = reference["source"], test["source"]
    if error_map_path:
        write_png(error_map_path, magma8(error_map))
        result["error_map"] = os.path.abspath(error_map_path)
    return result


class CompareReport:
    """A compare report folder: camera.json, ground_truth.exr and probes.exr (the EXRs of
    `./lfprobe gt` and `./lfprobe render`), their sRGB previews ground_truth.png and probes.png,
    error_flip.png (the FLIP error, magma) and compare.json (the figures of `lfprobe compare
    --json` plus what the caller describes: camera, grid, references, render times)."""

    def __init__(self, out_dir: str, camera: dict, spp: int = 1, ppd: float = DEFAULT_PPD):
        check_samples_per_pixel(spp)
        self.camera = camera
        self.spp = spp
        self.ppd = ppd
        self.out_dir = os.path.abspath(out_dir)
        self.paths = {
            "camera": os.path.join(self.out_dir, "camera.json"),
            "ground_truth": os.path.join(self.out_dir, "ground_truth.exr"),
            "probes": os.path.join(self.out_dir, "probes.exr"),
            "error": os.path.join(self.out_dir, "error_flip.png"),
            "ground_truth_preview": os.path.join(self.out_dir, "ground_truth.png"),
            "probes_preview": os.path.join(self.out_dir, "probes.png"),
            "report": os.path.join(self.out_dir, "compare.json"),
        }

    def write_camera(self) -> None:
        """Creates the folder and writes camera.json (before any rendering)."""
        os.makedirs(self.out_dir, exist_ok=True)
        write_camera(self.paths["camera"], self.camera)

    def start_ground_truth(self, mesh, threads: int = 0):
        """The native job that renders the mesh's ground truth into ground_truth.exr."""
        return native.load().start_ground_truth(mesh, json.dumps(self.camera), self.paths["ground_truth"],
                                                spp=self.spp, threads=threads)

    def render_probes(self, field, trace: dict) -> dict:
        """Traces the probes into probes.exr with the ground truth's samples per pixel (matched
        filtering); returns the render's stats."""
        _image, stats = field.render(json.dumps(self.camera), output=self.paths["probes"], spp=self.spp, **trace)
        return stats

    def measure(self, gt_stats: dict, probe_stats: dict, description: dict) -> dict:
        """Measures probes.exr against ground_truth.exr, writes the PNGs and compare.json (the
        figures, the render times and `description`); returns what compare.json holds."""
        reference = read_image(self.paths["ground_truth"])
        test = read_image(self.paths["probes"])
        result, error_map = measure(reference, test, self.ppd)
        write_png(self.paths["error"], magma8(error_map))
        for key, image in (("ground_truth_preview", reference), ("probes_preview", test)):
            write_png(self.paths[key], srgb8(image["rgba"][..., :3]))  # alpha dropped: misses are black
        result.update({
            "reference": self.paths["ground_truth"],
            "test": self.paths["probes"],
            "error_map": self.paths["error"],
            "ref_render_seconds": gt_stats.get("seconds"),
            "test_render_seconds": probe_stats.get("seconds"),
            "probe_rays_per_second": probe_stats.get("rays_per_second"),
            "ground_truth_rays_per_second": gt_stats.get("rays_per_second"),
            "camera": self.camera,
            **description,
            "spp": self.spp,
        })
        with atomic_open(self.paths["report"]) as stream:
            json.dump(strict_json(result), stream, indent=2, allow_nan=False)
        return result
