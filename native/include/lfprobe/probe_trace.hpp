// Tracing one ray against one probe (docs/DESIGN.md §4 "Trace one probe").
//
// The ray is split at the probe's three axis planes into at most four pieces that each stay in
// one octant. Inside an octant the octahedral map is a linear-fractional function of the
// position, u(t) = (a + b t) / (c + e t), so the ray projects to a straight segment walked
// monotonically, and every texel edge (u or v constant) is a plane through the probe centre:
// the ray meets it at t = −(n·o)/(n·d). The walk goes texel by texel with those exact crossings;
// over each texel's t-interval the ray's distance from the probe is known exactly (largest at
// an end, smallest at an end or at the closest approach t* = −o·d), and is compared with the
// radial distance the probe stored for that texel. Coarse min-distance levels skip whole
// blocks of texels the ray passes in front of; the skip never changes the answer. Which edge
// comes next is read off the ray's straight image in the map (a multiply-add per edge), and
// only the edge crossed is solved for its time (a division).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>

#include <glm/vec3.hpp>

#include "lfprobe/min_distance_pyramid.hpp"
#include "lfprobe/octahedral.hpp"
#include "lfprobe/probe_map.hpp"
#include "lfprobe/ray.hpp"

namespace lfprobe {

// The answer for one ray; the numeric values are those of the images' "status.X" channel.
enum class TraceStatus : std::uint8_t {
    Miss = 0,    // nothing before t_max: passed in front of every surface or through empty texels
    Hit = 1,     // met a surface the probe saw, facing the ray
    Unknown = 2, // passed behind a surface, met a back face, or entered texels without data
};

[[nodiscard]] const char* trace_status_name(TraceStatus status);

struct TraceSettings {
    // A ray within this distance (metres) in front of or behind a stored surface still meets
    // it: the stored distance is a per-texel sample of a continuous surface. Added to the texel
    // term below, which grows with the distance; this floor keeps a few millimetres near the
    // probe, where the texel term vanishes, for a scanner's range noise. A ray that passes a
    // surface within the thickness and then turns up behind the next texel meets it where it
    // passed, in front of the surface: the thinner, the nearer the surface that point lies, and
    // the less the colour read from it is shifted. 2.5 mm against 1 cm (the default before;
    // 2 cm before that), lab room, the demo's four views, 4×4 samples a pixel, the scene's grid:
    // 0.1° scans, 2048² probes +0.00 / +1.13 / +0.02 / +0.13 dB (between probes 31.63 ->
    // 32.76), wrong-surface pixels down at three views; 0.25°, 1024² +0.22 dB on average, 1°,
    // 512² +0.13; the hard scene +0.03; thinner still gains less (0.1°: +0.14 dB more at 0).
    // The real pump-room scan: no HIT pixel lost on three views.
    double thickness = 0.0025;
    // A ray that stops UNKNOWN behind a stored surface, having come within this distance (plus
    // the same texel term) of it or of one it passed just in front of, keeps that surface as a
    // fallback answer: the probe field answers HIT on it when no later probe answers the ray and
    // none proves the ray free past it. Where one station saw a near object's edge, no probe
    // sees behind it, and without the fallback the edge's rays would end UNKNOWN. At most
    // `thickness` turns the fallback off.
    double fallback_thickness = 0.02;
    // Plus this many texel footprints at the surface's distance (footprint = distance × the
    // texel's angular size, sqrt(4π)/N): grazing surfaces change distance across a texel.
    double thickness_texels = 1.0;
    // Skip texels with the coarse min-distance levels (false: walk every fine texel; the
    // answer is the same, only slower; for tests and measurements).
    bool use_coarse_levels = true;
    // Order the walk's texel edges along the ray's straight image in the map, with the exact
    // crossing times settling ties (false: compare the crossing times of every edge; the answer
    // is the same, only slower; for tests and measurements).
    bool order_by_image = true;
    // Answer UNKNOWN at once where the probe never saw the ray's start (the texels around the
    // direction to it are unknown, or hold surfaces the start lies behind by more than the
    // fallback's reach), without setting up the walk (false: walk; the answer is the same, only
    // slower; for tests and measurements).
    bool dismiss_unknown_start = true;
    // A ray origin closer than this (metres) to the probe centre is at the probe: its answer is
    // one texel lookup.
    double eye_at_probe_distance = 1e-9;
};

struct ProbeTraceResult {
    TraceStatus status = TraceStatus::Unknown;
    // HIT: ray parameter where the ray meets the surface; otherwise +inf.
    double t = std::numeric_limits<double>::infinity();
    // The ray is proven free of surfaces on [t_min, free_until]: t on HIT, t_max on MISS, the
    // entry into the texel that stopped the trace on UNKNOWN. A next probe starts there.
    double free_until = 0.0;
    // HIT: the texel met; UNKNOWN: the texel that stopped the trace; MISS: {-1, -1}.
    oct::Texel texel{-1, -1};
    glm::vec3 radiance{0.0f}; // HIT: the texel's linear RGB
    glm::vec3 normal{0.0f};   // HIT: the texel's stored normal
    // UNKNOWN: whether the ray met a surface facing it within the fallback thickness (passed
    // behind the stopping texel's, or just in front of one before it); then t_fallback,
    // fallback_texel, radiance and normal are that meeting's.
    bool has_fallback = false;
    double t_fallback = std::numeric_limits<double>::infinity();
    oct::Texel fallback_texel{-1, -1};
    std::uint32_t fine_steps = 0;   // fine texels visited
    std::uint32_t coarse_steps = 0; // coarse cells tested

    [[nodiscard]] std::uint32_t steps() const { return fine_steps + coarse_steps; }
};

// Traces `ray`, given in the probe's frame (origin relative to the probe centre, unit
// direction), over [ray.t_min, ray.t_max] against `map`. `levels` are the map's coarse levels
// (may be null: every fine texel is walked).
[[nodiscard]] ProbeTraceResult trace_probe(const ProbeMap& map, const MinDistancePyramid* levels,
                                           const Ray& ray, const TraceSettings& settings = {});

// The tolerance a stored surface at `distance` gets in a map of resolution n.
[[nodiscard]] double surface_thickness(const TraceSettings& settings, double distance, int n);

} // namespace lfprobe
