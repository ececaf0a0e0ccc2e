"""Progressive refinement of the viewport's probe-traced view, off Blender's main thread.

A request (probe field, camera, trace settings) is rendered at 1/8 of the viewport's size,
then 1/4, 1/2 and full size; each finished level replaces the shown image. Every level is
traced in bands of rows (the same camera with another height and shift), so that a new
request — the user orbits, a setting changes — waits at most one band, not one frame. The
native trace releases the GIL, so Blender stays interactive while it runs.

This module does not import bpy: `on_update` is how Blender is told to redraw, and the
timings it keeps are what the README's refinement figures come from.
"""

from __future__ import annotations

import json
import threading
import time
from dataclasses import dataclass, field as dataclass_field
from typing import Callable, List, Optional, Tuple

import numpy as np

from ..camera_export import band_of

LEVELS = (8, 4, 2, 1)  # downscale factor of each refinement level, coarsest first
BAND_RAYS = 40_000  # rays per band: a few tens of milliseconds between chances to restart


@dataclass
class ViewImage:
    """One finished refinement level: linear RGBA (h, w, 4) float32, top row first."""

    generation: int
    level: int  # downscale factor (1 = full size)
    rgba: np.ndarray
    final: bool


@dataclass
class _Request:
    generation: int
    field: object
    camera: dict
    width: int
    height: int
    trace: dict
    key: tuple


@dataclass
class LevelTiming:
    level: int
    width: int
    height: int
    seconds: float  # this level's trace alone
    since_request: float  # from the request to this level on screen (queued wait included)


@dataclass
class RefineStats:
    generation: int = 0
    levels: List[LevelTiming] = dataclass_field(default_factory=list)


class ProgressiveView:
    """Refines the latest requested view in one worker thread."""

    def __init__(self, on_update: Callable[[], None], levels: Tuple[int, ...] = LEVELS,
                 band_rays: int = BAND_RAYS):
        self._on_update = on_update
        self._levels = levels
        self._band_rays = band_rays
        self._lock = threading.Condition()
        self._pending: Optional[_Request] = None
        self._generation = 0
        self._key: Optional[tuple] = None
        self._latest: Optional[ViewImage] = None
        self._error: Optional[str] = None
        self._stats = RefineStats()
        self._request_time = 0.0
        self._stopped = False
        self._thread = threading.Thread(target=self._run, name="lfprobe viewport", daemon=True)
        self._thread.start()

    def request(self, field, camera: dict, width: int, height: int, trace: dict, key: tuple) -> bool:
        """Asks for a view; `key` says what makes it new (a repeat of the current key is
        ignored). Returns True when a new refinement starts."""
        with self._lock:
            if key == self._key:
                return False
            self._generation += 1
            self._key = key
            self._pending = _Request(self._generation, field, dict(camera), int(width), int(height),
                                     dict(trace), key)
            self._request_time = time.perf_counter()
            self._error = None
            self._lock.notify()
            return True

    def latest(self) -> Optional[ViewImage]:
        with self._lock:
            return self._latest

    def error(self) -> Optional[str]:
        with self._lock:
            return self._error

    def stats(self) -> RefineStats:
        with self._lock:
            return RefineStats(self._stats.generation, list(self._stats.levels))

    def busy(self) -> bool:
        with self._lock:
            return self._pending is not None or (
                self._latest is None or self._latest.generation != self._generation or not self._latest.final)

    def wait_final(self, timeout: float) -> bool:
        """Waits until the latest request is fully refined (for tests and measurements)."""
        end = time.perf_counter() + timeout
        while time.perf_counter() < end:
            with self._lock:
                latest = self._latest
                if self._error is not None:
                    return False
                if latest is not None and latest.generation == self._generation and latest.final:
                    return True
            time.sleep(0.005)
        return False

    def stop(self) -> None:
        """Ends the worker after the band it is tracing; never calls on_update again."""
        with self._lock:
            self._stopped = True
            self._pending = None
            self._lock.notify()

    def _stale(self, generation: int) -> bool:
        with self._lock:
            return self._stopped or generation != self._generation

    def _run(self) -> None:
        while True:
            with self._lock:
                while self._pending is None and not self._stopped:
                    self._lock.wait()
                if self._stopped:
                    return
                request, self._pending = self._pending, None
                started = self._request_time
                self._stats = RefineStats(request.generation)
            try:
                self._refine(request, started)
            except Exception as error:  # a native trace error: shown in the viewport, not raised
                with self._lock:
                    if request.generation == self._generation:
                        self._error = str(error)
                self._notify(request.generation)

    def _refine(self, request: _Request, started: float) -> None:
        for index, scale in enumerate(self._levels):
            width = max(1, request.width // scale)
            height = max(1, request.height // scale)
            begin = time.perf_counter()
            image = self._trace_level(request, width, height)
            if image is None:
                return  # a newer request replaced this one
            now = time.perf_counter()
            final = index == len(self._levels) - 1
            with self._lock:
                if request.generation != self._generation or self._stopped:
                    return
                self._latest = ViewImage(request.generation, scale, image, final)
                self._stats.levels.append(LevelTiming(scale, width, height, now - begin, now - started))
            self._notify(request.generation)

    def _trace_level(self, request: _Request, width: int, height: int) -> Optional[np.ndarray]:
        camera = dict(request.camera)
        camera["resolution"] = [width, height]
        rows = max(1, self._band_rays // width)
        rgba = np.empty((height, width, 4), dtype=np.float32)
        for row in range(0, height, rows):
            if self._stale(request.generation):
                return None
            count = min(rows, height - row)
            band = camera if count == height else band_of(camera, width, height, row, count)
            image, _stats = request.field.render(json.dumps(band), **request.trace)
            rgba[row : row + count] = image["rgba"]
        return rgba

    def _notify(self, generation: int) -> None:
        with self._lock:
            if self._stopped or generation != self._generation:
                return
            self._on_update()
