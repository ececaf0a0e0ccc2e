// The eye at a probe (docs/DESIGN.md §4 "Trace one probe"): a ray that starts at the probe centre
// needs no walk. Its answer is one texel lookup in the ray's direction, judged as the walk
// judges a texel (probe_trace.hpp) with the ray's distance from the probe equal to t, so it is
// O(1) per ray whatever the map's resolution.
#pragma once

#include <array>
#include <cstddef>

#include <glm/vec3.hpp>

#include "lfprobe/octahedral.hpp"
#include "lfprobe/probe_map.hpp"
#include "lfprobe/probe_trace.hpp"
#include "lfprobe/ray.hpp"

namespace lfprobe {

// The answer when the eye is at the probe: one texel lookup in the ray's direction, judged over
// [t_min, t_max] like any texel (HIT at the stored distance, MISS for empty or beyond t_max,
// UNKNOWN for unknown, for a back face, or when the surface lies before t_min).
[[nodiscard]] ProbeTraceResult lookup_probe(const ProbeMap& map, const glm::dvec3& direction,
                                            double t_min, double t_max,
                                            const TraceSettings& settings = {});

// lookup_probe for many rays of one map: the map's check and the thickness's texel factor done
// once, what a renderer holds while every ray of a view starts at the probe. The answers are
// lookup_probe's, bit for bit. The map must outlive it.
class ProbeLookup {
public:
    // Rays lookup_batch aims before it judges any: their texels are fetched from memory
    // together instead of one ray's wait after another's.
    static constexpr std::size_t kBatch = 16;

    // InputError when the map is empty or inconsistent.
    ProbeLookup(const ProbeMap& map, const TraceSettings& settings);

    // lookup_probe(map, direction, t_min, t_max, settings); InputError for a direction that is
    // not finite and non-zero.
    [[nodiscard]] ProbeTraceResult lookup(const glm::dvec3& direction, double t_min,
                                          double t_max) const;

    // lookup() for rays[0, count) into results[0, count). Only the rays' directions and
    // intervals are read: every ray starts at the probe centre.
    void lookup_batch(const Ray* rays, std::size_t count, ProbeTraceResult* results) const;

    // lookup() judged on `texel` instead of the texel the direction falls in: where a filter
    // has decided, at finer than a texel, that the ray sees a neighbouring texel's surface.
    [[nodiscard]] ProbeTraceResult lookup_texel(const glm::dvec3& direction, oct::Texel texel,
                                                double t_min, double t_max) const;

private:
    // A ray's unit direction and the texel it looks into.
    struct Aim {
        glm::dvec3 d;
        oct::Texel texel;
        std::size_t index;
    };
    // Written in place, as judge's results are: a batch's aims are not copied through
    // temporaries.
    void aim(const glm::dvec3& direction, Aim& aim) const;
    void prefetch(std::size_t index) const;
    void judge(const Aim& aim, double t_min, double t_max, ProbeTraceResult& result) const;

    const ProbeMap& map_;
    int n_;
    double eye_at_probe_distance_;
    double thickness_;
    double thickness_per_metre_; // surface_thickness's texel term per metre of distance
    // The channels a judgement reads, in the form the map holds them: first byte and bytes
    // per texel.
    struct Channel {
        const char* data;
        std::size_t stride;
    };
    std::array<Channel, 3> channels_;
};

} // namespace lfprobe
