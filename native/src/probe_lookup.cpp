#include "lfprobe/probe_lookup.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include <glm/geometric.hpp>

#include "texel_verdict.hpp"

namespace lfprobe {

using namespace texel_verdict;

namespace {

// Where a channel's texel i starts, and how far apart texels are.
template <class T>
std::pair<const char*, std::size_t> channel_of(const std::vector<T>& values,
                                               std::size_t per_texel) {
    return {reinterpret_cast<const char*>(values.data()), per_texel * sizeof(T)};
}

} // namespace

ProbeLookup::ProbeLookup(const ProbeMap& map, const TraceSettings& settings)
    : map_(map), n_(map.resolution), eye_at_probe_distance_(settings.eye_at_probe_distance),
      thickness_(settings.thickness),
      thickness_per_metre_(thickness_per_metre(settings, map.resolution)), channels_{} {
    check_map(map);
    const PackedChannels& packed = map.packed;
    const auto [distance, distance_stride] =
        packed.distance.empty() ? channel_of(map.distance, 1) : channel_of(packed.distance, 1);
    const auto [normal, normal_stride] =
        packed.normal.empty() ? channel_of(map.normal, 3) : channel_of(packed.normal, 1);
    const auto [radiance, radiance_stride] =
        packed.srgb.empty() ? channel_of(map.rgba, 4) : channel_of(packed.srgb, 3);
    channels_ = {Channel{distance, distance_stride}, Channel{normal, normal_stride},
                 Channel{radiance, radiance_stride}};
}

// Inline, like prefetch and judge: the batch's loops are the whole of an eye-at-probe view.
inline void ProbeLookup::aim(const glm::dvec3& direction, Aim& aim) const {
    // A finite positive squared length is the common case of check_direction's test, in one
    // comparison; anything else goes to the full test and its error.
    const double length2 = glm::dot(direction, direction);
    if (!(length2 > 0.0 && length2 < kInf)) {
        check_direction(direction);
    }
    aim.d = glm::normalize(direction);
    aim.texel = oct::texel_of_direction(glm::vec3(aim.d), n_);
    aim.index = oct::texel_index(aim.texel, n_);
}

inline void ProbeLookup::prefetch(std::size_t index) const {
    for (const Channel& c : channels_) {
        __builtin_prefetch(c.data + index * c.stride);
    }
}

// The walk's judgement of one texel (Tracer::visit_texel) with the origin at the probe centre,
// where the ray's distance from the probe at parameter t is |t|, written out because it is the
// whole cost of an eye-at-probe view. Written into `result` in place: a batch's results are
// not copied through temporaries.
inline void ProbeLookup::judge(const Aim& aim, double t_min, double t_max,
                               ProbeTraceResult& result) const {
    result = ProbeTraceResult{};
    if (!(t_max > t_min)) {
        set_miss(result, t_max);
        return;
    }
    result.fine_steps = 1;
    const double far = std::isfinite(t_max) ? std::max(std::abs(t_min), std::abs(t_max)) : kInf;
    if (far <= eye_at_probe_distance_) {
        set_miss(result, t_max); // within the ball around the centre nothing can be
        return;
    }
    const double r = static_cast<double>(map_.distance_at(aim.index));
    if (std::isnan(r)) {
        set_unknown(result, aim.texel, t_min);
        return;
    }
    if (std::isinf(r) || far < r) {
        set_miss(result, t_max); // empty, or the surface lies beyond t_max
        return;
    }
    const double near = std::abs(std::clamp(0.0, t_min, t_max));
    if (near > r + (thickness_ + thickness_per_metre_ * r)) {
        // The surface lies before t_min: what is behind it is not known.
        set_unknown(result, aim.texel, t_min);
        return;
    }
    // Where the ray is at distance r; within the thickness only, the end nearest to it.
    double t = r;
    if (!(r >= t_min && r <= t_max)) {
        double best_error = kInf;
        for (const double candidate : {t_min, std::clamp(0.0, t_min, t_max), t_max}) {
            const double error = std::abs(std::abs(candidate) - r);
            if (std::isfinite(candidate) && error < best_error) {
                best_error = error;
                t = candidate;
            }
        }
    }
    meet_texel(map_, aim.index, aim.texel, aim.d, t, t_min, result);
}

ProbeTraceResult ProbeLookup::lookup(const glm::dvec3& direction, double t_min,
                                     double t_max) const {
    ProbeTraceResult result;
    Aim a;
    aim(direction, a);
    judge(a, t_min, t_max, result);
    return result;
}

ProbeTraceResult ProbeLookup::lookup_texel(const glm::dvec3& direction, oct::Texel texel,
                                           double t_min, double t_max) const {
    ProbeTraceResult result;
    Aim a;
    aim(direction, a);
    a.texel = texel;
    a.index = oct::texel_index(texel, n_);
    judge(a, t_min, t_max, result);
    return result;
}

void ProbeLookup::lookup_batch(const Ray* rays, std::size_t count,
                               ProbeTraceResult* results) const {
    std::array<Aim, kBatch> aims;
    for (std::size_t first = 0; first < count; first += kBatch) {
        const std::size_t size = std::min(kBatch, count - first);
        for (std::size_t k = 0; k < size; ++k) {
            aim(rays[first + k].direction, aims[k]);
            prefetch(aims[k].index);
        }
        for (std::size_t k = 0; k < size; ++k) {
            const Ray& ray = rays[first + k];
            judge(aims[k], ray.t_min, ray.t_max, results[first + k]);
        }
    }
}

ProbeTraceResult lookup_probe(const ProbeMap& map, const glm::dvec3& direction, double t_min,
                              double t_max, const TraceSettings& settings) {
    return ProbeLookup(map, settings).lookup(direction, t_min, t_max);
}

} // namespace lfprobe
