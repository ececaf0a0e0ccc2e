"""The costs the panels state before a bake and a render (core/estimates.py)."""

from lfprobe.core import estimates


def test_bake_memory_is_what_the_manifest_will_say():
    # 6 × 6 × 5 probes at 512², full storage: 180 × 512² × 18 bytes, the 870 MiB of the pump room.
    text, warn = estimates.bake_memory_text((6, 6, 5), 512, 18, "full")
    assert estimates.bake_memory_bytes((6, 6, 5), 512, 18) == 180 * 512 * 512 * 18
    assert "180 probes at 512²" in text and "810 MiB" in text
    assert not warn
    _, warn = estimates.bake_memory_text((6, 6, 5), 1024, 18, "full")
    assert warn  # 3.2 GiB


def test_render_time_needs_a_measured_rate_and_warns_when_long():
    assert estimates.render_rays(1920, 1080, 50, 2) == 960 * 540 * 4
    text, warn = estimates.render_time_text(1920, 1080, 100, 2, rays_per_second=None)
    if estimates.last_render_rate() is None:
        assert "after a first render" in text and not warn
    text, warn = estimates.render_time_text(1920, 1080, 100, 2, rays_per_second=0.2e6)
    assert "8.3 M rays" in text and "about 41 s" in text and warn
    text, warn = estimates.render_time_text(640, 360, 100, 1, rays_per_second=2e6)
    assert "about 0 s" in text and not warn
    estimates.record_render_rate(1e6)
    assert estimates.last_render_rate() == 1e6


def test_coverage_estimate_from_the_plan():
    planned = [{"classification": {"unknown": u}} for u in (0.1, 0.3, 0.9, 0.7)]
    estimate = estimates.coverage_estimate(planned)
    assert estimate == {"probes": 4, "mean_unknown": 0.5, "worst_unknown": 0.9, "mostly_unknown": 2}
    text, warn = estimates.coverage_estimate_text(estimate)
    assert "50% of directions unknown" in text and "2 of 4 probes mostly unknown" in text and not warn
    _, warn = estimates.coverage_estimate_text(estimates.coverage_estimate(planned[2:]))
    assert warn
