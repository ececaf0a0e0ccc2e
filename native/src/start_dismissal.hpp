// Where a probe's trace stops at its first texel, UNKNOWN (TraceSettings::dismiss_unknown_start):
// the judgement the trace makes from the map's texels (probe_trace.cpp), and the one the probe
// field makes from a summary of them without reading the probe (SeenDirections). One code for
// both, so that the summary's can only ever agree with the trace's. Internal to the core.
#pragma once

#include <cmath>
#include <optional>

#include <glm/geometric.hpp>

#include "lfprobe/octahedral.hpp"
#include "lfprobe/probe_trace.hpp"
#include "texel_verdict.hpp"

namespace lfprobe::start_dismissal {

// Where a ray (in the probe's frame) starts, as the dismissal sees it.
struct Start {
    oct::Texel home; // the texel around the direction to the start
    double length;   // the start's distance from the probe centre
    double t_lo;     // where along the ray it starts
};

// The start of `ray` (probe frame, any direction length) where a dismissal may apply; none where
// the trace does not judge it so: the eye at the probe (a lookup), a start near the probe
// centre (left to the walk), an empty or non-finite interval, a direction that is not one (the
// trace reports it).
[[nodiscard]] inline std::optional<Start> dismissible_start(const Ray& ray, int n,
                                                            const TraceSettings& settings) {
    if (!settings.dismiss_unknown_start ||
        !(glm::length(ray.origin) > settings.eye_at_probe_distance)) {
        return std::nullopt;
    }
    const glm::dvec3 d = glm::normalize(ray.direction);
    const double t_lo = ray.t_min;
    if (!(ray.t_max > t_lo) || !std::isfinite(t_lo)) {
        return std::nullopt;
    }
    const glm::dvec3 start = ray.origin + t_lo * d;
    const double length = glm::length(start);
    if (!(length > 2.0 * settings.eye_at_probe_distance) || !std::isfinite(length)) {
        return std::nullopt;
    }
    return Start{oct::texel_of_direction(glm::vec3(start / length), n), length, t_lo};
}

// Whether `start` lies behind a surface at `distance` by more than the fallback's reach (the walk
// passes behind it, or meets its back face, with no fallback kept). Larger distances only ever
// answer false: a bound of a distance judges as the distance does, or keeps the walk going.
[[nodiscard]] inline bool behind_beyond_reach(const Start& start, int n,
                                              const TraceSettings& settings, double distance) {
    const double reach = std::max(settings.thickness, settings.fallback_thickness);
    const double reach_per_metre = texel_verdict::thickness_per_metre(settings, n);
    return start.length > distance + reach + reach_per_metre * distance;
}

// Whether the walk from `start` stops at its first texel: the texels around the home texel
// (read too, so that the texel the walk's own arithmetic picks at an edge or across an
// octant's fold is covered) are each unknown, or hold a surface the start lies behind by more
// than the fallback's reach. `distance_of(texel)` is the texel's distance, NaN where unknown;
// an upper bound of it gives a judgement that dismisses only where the exact one does.
template <typename DistanceOf>
[[nodiscard]] bool stops_at_first_texel(const Start& start, int n, const TraceSettings& settings,
                                        DistanceOf&& distance_of) {
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            const double r = distance_of(oct::wrap_texel(start.home.x + dx, start.home.y + dy, n));
            if (!std::isnan(r) && !behind_beyond_reach(start, n, settings, r)) {
                return false;
            }
        }
    }
    return true;
}

} // namespace lfprobe::start_dismissal
