"""What each report preset sweeps. `tiny` runs in the tests (well under a minute); `demo` is the
demo's report at the paper's scan density (scans at 0.1°, views 640 pixels wide, probes up to
2048²: the report about 7 minutes on 2 cores for the lab room), measuring few settings; `full`
is the benchmark sweep (every setting, and the section "Model only what a scene needs")."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, List, Optional, Tuple

from .. import defaults

# The renderer's own defaults: the report's default setting is the one users get.
_MODE = defaults.trace("mode")
_THICKNESS = defaults.trace("thickness")
_FALLBACK = defaults.trace("fallback_thickness")
# Trace settings: (label, render keyword arguments). The first is the default setting.
DEFAULT_TRACE = (f"default ({_MODE}, {_THICKNESS * 100:g} cm, {_FALLBACK * 100:g} cm fallback, coarse levels)",
                 {"mode": _MODE, "thickness": _THICKNESS, "fallback_thickness": _FALLBACK,
                  "use_coarse_levels": True})
TRACE_VARIANTS = [
    DEFAULT_TRACE,
    ("no coarse levels", {**DEFAULT_TRACE[1], "use_coarse_levels": False}),
    # Coarse resolution: the coarsest min-distance level kept (ProbeField.load(coarse_resolution)).
    ("coarse levels down to 32²", {**DEFAULT_TRACE[1], "coarse_resolution": 32}),
    ("nearest-first (no grid walk)", {**DEFAULT_TRACE[1], "mode": "nearest"}),
    ("no fallback (the thickness alone)", {**DEFAULT_TRACE[1], "fallback_thickness": 0.0}),
    ("thickness 1 cm (the default before)", {**DEFAULT_TRACE[1], "thickness": 0.01}),
    ("thickness 2 cm (before that)", {**DEFAULT_TRACE[1], "thickness": 0.02}),
    # Holes of UNKNOWN pixels left black, as before the render filled them.
    ("no hole fill", {**DEFAULT_TRACE[1], "hole_fill": 0}),
    # The paper's colour: the first probe that answers, its one texel (no filter, no blending,
    # UNKNOWN black, a hole-filled texel's HIT taken as any other).
    ("first hit, nearest texel (the paper)", {**DEFAULT_TRACE[1], "filter": "nearest", "blend": 1, "hole_fill": 0,
                                              "prefer_measured": False}),
]

# The default trace on probes held in compact storage (ProbeField.load(storage="compact"):
# 8-bit sRGB radiance, 16-bit distance in 1 mm steps, 8+8-bit normals, no confidence). The
# sweep runs it beside the default on every fixed resolution of the densest scan.
COMPACT_TRACE = ("default, compact storage", {**DEFAULT_TRACE[1], "storage": "compact"})
# Trace keys that are load-time settings of ProbeField.load, not render arguments.
LOAD_KEYS = ("coarse_resolution", "storage")

# Bake settings compared in the resolution sweep: the project's splatted, hole-filled bake and
# the paper's one-point-one-texel bake (no footprint, no hole filling).
BAKE_VARIANTS = {
    "splat + fill": {"splat_scale": defaults.bake("splat_scale"),
                     "hole_fill_texels": defaults.bake("hole_fill_texels")},
    "points only": {"splat_scale": 0.0, "hole_fill_texels": 0},
}


@dataclass
class Preset:
    name: str
    max_view_width: Optional[int]     # views wider than this are scaled down (aspect kept)
    gt_spp: int                       # samples per pixel of the ground truth (a square)
    scan_step_factors: List[float]    # scan densities: multiples of the scene's step_deg
    min_scan_step_deg: float          # ... but never finer than this (keeps tiny tiny)
    fine_resolutions: List[int]       # probe map resolutions N (N×N)
    count_factors: List[float]        # probe counts: multiples of the scene grid's counts
    trace_variants: List[Tuple[str, Dict]]
    mesh_resolutions: List[int]       # mesh-baked single probe, eye at the probe
    distance_fractions: List[float]   # eye offsets as fractions of the grid cell's half diagonal
    timing_repeats: int               # renders per timing (the fastest counts)
    poisson_depth: int
    stability_resolution: int
    bake_variants: List[str] = field(default_factory=lambda: list(BAKE_VARIANTS))
    # Samples per pixel of a converged ground truth (a square): what the matched renders are
    # also measured against, free of the n×n ground truth's own sampling noise.
    reference_spp: int = 256
    # n×n Embree rays per texel for the sweep's mesh-baked grids (the section "from their own
    # centre" bakes with the bake's default, its fidelity being what it measures).
    mesh_supersample: int = 2
    # Adaptive placement (report section "Model only what a scene needs"): the base grid is the
    # scene grid's counts × this factor; probes are added at walk eyes up to this many, until
    # every frame is at most planning_target_unknown UNKNOWN or the scene grid's memory is spent.
    planning_base_factor: float = 0.5
    planning_target_unknown: float = 0.01
    planning_max_added: int = 12
    # The fine resolution of the reference setting (every trace variant, the images, the
    # peers' comparison); None: the middle of fine_resolutions.
    reference_resolution: Optional[int] = None
    # Fine resolutions of the sweep's mesh-baked grids; None: fine_resolutions.
    mesh_grid_resolutions: Optional[List[int]] = None
    # Scans coarser than the densest are baked at this fine resolution only; None: at every one.
    coarse_scan_resolution: Optional[int] = None
    # Frames of the walk the sweep renders; None: the scene's own count.
    walk_frames: Optional[int] = None
    # Whether the report runs its section "Model only what a scene needs" (two planned bakes of
    # the scene grid at up to 4096² and an adaptive placement: minutes at the paper's density).
    planning: bool = True

    def middle_fine_resolution(self) -> int:
        return self.fine_resolutions[len(self.fine_resolutions) // 2]

    def reference_fine_resolution(self) -> int:
        if self.reference_resolution is not None:
            return self.reference_resolution
        return self.middle_fine_resolution()


PRESETS = {
    "tiny": Preset("tiny", max_view_width=80, gt_spp=4, scan_step_factors=[8.0, 16.0],
                   min_scan_step_deg=1.0, fine_resolutions=[64, 128], count_factors=[1.0],
                   trace_variants=[*TRACE_VARIANTS[:2], TRACE_VARIANTS[-1]], mesh_resolutions=[64, 128, 256],
                   distance_fractions=[0.0, 0.1, 0.3, 0.6, 1.0], timing_repeats=1,
                   poisson_depth=6, stability_resolution=64, planning_max_added=3,
                   reference_spp=16, mesh_supersample=1),
    # The paper's density: four scans at 0.1° (21.6 M points in the lab room), views 640 pixels
    # wide, the reference grid at 2048². Each setting costs a bake of up to 100 s and 16 M rays of
    # rendering, so the demo measures few: the 1° scans beside the 0.1° ones at 1024² (at 2048² a
    # 1° bake costs 32 s, every texel's work for few points), two resolutions, the default trace
    # beside the paper's (first hit, nearest texel) and compact storage; `full` measures the rest
    # (nearest-first among them).
    "demo": Preset("demo", max_view_width=640, gt_spp=16, scan_step_factors=[0.4, 4.0],
                   min_scan_step_deg=0.1, fine_resolutions=[1024, 2048], count_factors=[1.0],
                   trace_variants=[TRACE_VARIANTS[0], TRACE_VARIANTS[-1]],
                   mesh_resolutions=[1024, 2048], distance_fractions=[0.0, 1.0],
                   timing_repeats=1, poisson_depth=9, stability_resolution=256,
                   bake_variants=["splat + fill"], reference_spp=64,
                   reference_resolution=2048, mesh_grid_resolutions=[1024],
                   coarse_scan_resolution=1024, walk_frames=6, planning=False),
    "full": Preset("full", max_view_width=None, gt_spp=16, scan_step_factors=[1.0, 2.0, 4.0],
                   min_scan_step_deg=0.05, fine_resolutions=[256, 512, 1024, 2048, 3072, 4096],
                   count_factors=[0.5, 1.0, 2.0], trace_variants=TRACE_VARIANTS,
                   mesh_resolutions=[256, 512, 1024, 2048, 4096],
                   distance_fractions=[0.0, 0.02, 0.05, 0.1, 0.2, 0.35, 0.5, 0.75, 1.0],
                   timing_repeats=5, poisson_depth=9, stability_resolution=512,
                   planning_max_added=24, mesh_supersample=4),
}


def get_preset(name: str) -> Preset:
    if name not in PRESETS:
        raise ValueError(f"unknown preset {name!r}: expected one of {', '.join(PRESETS)}")
    return PRESETS[name]
