"""What a bake and a render will cost, said before they run (the grid and render panels show it,
a line of a panel per line of these texts):
a bake's memory from its probe count, resolution and storage; an F12 render's rays, and its
time at the rays per second of the last render of this session."""

from __future__ import annotations

from typing import Optional, Sequence

# Above these the panels warn: a set that would not fit a laptop's spare memory, and a render
# that a user would otherwise sit through without knowing.
MEMORY_WARNING_BYTES = 1 << 30
RENDER_WARNING_SECONDS = 30.0

# Rays per second of this session's last finished F12 render (render_engine records it).
_last_rays_per_second: Optional[float] = None


def record_render_rate(rays_per_second: float) -> None:
    global _last_rays_per_second
    if rays_per_second > 0:
        _last_rays_per_second = float(rays_per_second)


def last_render_rate() -> Optional[float]:
    return _last_rays_per_second


def bake_memory_bytes(counts: Sequence[int], resolution: int, bytes_per_texel: int) -> int:
    """In-memory bytes of a grid's probe set: probes × resolution² × bytes a texel (what the
    manifest's memory figures will say)."""
    probes = 1
    for c in counts:
        probes *= int(c)
    return probes * int(resolution) ** 2 * int(bytes_per_texel)


def bake_memory_text(counts: Sequence[int], resolution: int, bytes_per_texel: int, storage: str) -> tuple:
    """(text, warn) for the grid panel before Bake."""
    total = bake_memory_bytes(counts, resolution, bytes_per_texel)
    probes = bake_memory_bytes(counts, 1, 1)
    text = (f"Bake: {probes} probes at {resolution}²\nabout {total / 2**20:,.0f} MiB in memory\n"
            f"({storage}, {bytes_per_texel} bytes a texel)")
    return text, total > MEMORY_WARNING_BYTES


# A probe that would not know more than half of its directions.
MOSTLY_UNKNOWN = 0.5
# Above this mean unknown fraction the grid panel warns before Bake.
UNKNOWN_WARNING = 0.5


def coverage_estimate(planned: Sequence[dict]) -> dict:
    """The grid panel's coverage estimate from plan_probes' probes (their classification's
    unknown fraction, from a coarse bake at each probe): mean, worst, and how many probes would
    know less than half of their directions."""
    unknown = [float(p.get("classification", {}).get("unknown", 1.0)) for p in planned]
    if not unknown:
        return {"probes": 0, "mean_unknown": 1.0, "worst_unknown": 1.0, "mostly_unknown": 0}
    return {"probes": len(unknown), "mean_unknown": sum(unknown) / len(unknown),
            "worst_unknown": max(unknown),
            "mostly_unknown": sum(1 for u in unknown if u > MOSTLY_UNKNOWN)}


def coverage_estimate_text(estimate: dict) -> tuple:
    """(text, warn) for the grid panel."""
    text = (f"Estimate: {100 * estimate['mean_unknown']:.0f}% of directions unknown\n"
            f"{estimate['mostly_unknown']} of {estimate['probes']} probes mostly unknown")
    return text, estimate["mean_unknown"] > UNKNOWN_WARNING


def render_rays(width: int, height: int, percentage: int, samples: int) -> int:
    """Rays an F12 render traces: pixels at the resolution percentage, samples² each."""
    w = max(1, int(width) * int(percentage) // 100)
    h = max(1, int(height) * int(percentage) // 100)
    return w * h * int(samples) ** 2


def render_time_text(width: int, height: int, percentage: int, samples: int,
                     rays_per_second: Optional[float] = None) -> tuple:
    """(text, warn) for the render panel: the rays F12 traces, and, once a render of this session
    measured a rate, the time at that rate."""
    rays = render_rays(width, height, percentage, samples)
    text = f"F12: {rays / 1e6:.1f} M rays ({samples}×{samples} a pixel)"
    rate = last_render_rate() if rays_per_second is None else rays_per_second
    if not rate:
        return text + "\ntime shown after a first render", False
    seconds = rays / rate
    return (f"{text}\nabout {_duration(seconds)} at {rate / 1e6:.2f} M rays/s\n(the last render's rate)",
            seconds > RENDER_WARNING_SECONDS)


def _duration(seconds: float) -> str:
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"
