"""The defaults of the native core's settings, as the native module states them
(``_native.DEFAULTS``): the command line, the report and the add-on take them from here instead
of writing their own copies. ``trace(name)``: mode, thickness, fallback_thickness, use_coarse_levels, max_probes, max_probes_per_ray,
filter, blend, spp, tile_size, hole_fill, prefer_measured; ``bake(name)``: resolution, splat_scale, hole_fill_texels,
max_splat_radius_texels, normal_neighbours, lod_texels, splat_edge_margin, splat_core_scale,
lod_colour_tolerance, supersample;
``storage(name)``: distance_step."""

from __future__ import annotations

from . import native


def trace(name: str):
    """A trace or render setting's default."""
    return native.load().DEFAULTS["trace"][name]


def bake(name: str):
    """A bake setting's default."""
    return native.load().DEFAULTS["bake"][name]


def storage(name: str):
    """A storage setting's default: distance_step (compact storage's distance quantum, metres)."""
    return native.load().DEFAULTS["storage"][name]
