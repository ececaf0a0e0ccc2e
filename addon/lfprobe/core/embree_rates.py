"""Embree's primary-ray throughput on a camera's rays, as the probe trace is measured against
it (`bench render`, the report): single rays, and its packet API at its fastest width."""

from __future__ import annotations

PACKET_WIDTHS = (4, 8, 16)


def embree_rates(_native, mesh, camera_text: str, threads: int, repeats: int) -> dict:
    """Rays per second of rtcIntersect1 ("single") and of the fastest of rtcIntersect4/8/16
    flagged coherent ("packet", its width "packet_width"): the fairer match for a tracer that takes camera rays
    in runs. Trace only, rays made beforehand, fastest of `repeats`."""
    single = _native.embree_throughput(mesh, camera_text, threads=threads, repeats=repeats)
    packets = {width: _native.embree_throughput(mesh, camera_text, threads=threads, repeats=repeats,
                                                packet=width)["rays_per_second"]
               for width in PACKET_WIDTHS}
    best = max(packets, key=packets.get)
    return {"single": single["rays_per_second"], "packet": packets[best], "packet_width": best}
