// What the probe trace (probe_trace.cpp) and the eye-at-probe lookup (probe_lookup.cpp) both
// say of a texel: the verdicts written into a ProbeTraceResult, the thickness's texel term and
// the checks of their inputs. Internal to the core.
#pragma once

#include <cmath>
#include <limits>
#include <string>

#include <glm/geometric.hpp>

#include "lfprobe/error.hpp"
#include "lfprobe/octahedral.hpp"
#include "lfprobe/probe_map.hpp"
#include "lfprobe/probe_trace.hpp"

namespace lfprobe::texel_verdict {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

// The texel term of surface_thickness per metre of distance, for a map of resolution n: one
// expression for the walk, the lookup and surface_thickness, so that their sums agree bit for
// bit.
[[nodiscard]] inline double thickness_per_metre(const TraceSettings& settings, int n) {
    return settings.thickness_texels * oct::kTexelAngleTimesN / static_cast<double>(n);
}

inline void set_miss(ProbeTraceResult& result, double t_max) {
    result.status = TraceStatus::Miss;
    result.t = kInf;
    result.free_until = t_max;
    result.texel = {-1, -1};
}

inline void set_unknown(ProbeTraceResult& result, oct::Texel texel, double t_enter) {
    result.status = TraceStatus::Unknown;
    result.t = kInf;
    result.free_until = t_enter;
    result.texel = texel;
}

// The ray meets the surface of texel `index` at t: a HIT when the surface faces the ray, else
// UNKNOWN from t_enter (the back of a surface: what is in front of it is not known).
// Inline: it is the second half of every eye-at-probe lookup that hits.
inline void meet_texel(const ProbeMap& map, std::size_t index, oct::Texel texel,
                       const glm::dvec3& d, double t, double t_enter, ProbeTraceResult& result) {
    const glm::vec3 normal = map.normal_at(index);
    if (glm::dot(glm::dvec3(normal), d) > 0.0) {
        set_unknown(result, texel, t_enter);
        return;
    }
    result.status = TraceStatus::Hit;
    result.t = t;
    result.free_until = t;
    result.texel = texel;
    result.radiance = map.radiance_at(index);
    result.normal = normal;
}

inline void check_map(const ProbeMap& map) {
    if (!map.is_complete()) {
        throw InputError("probe trace: the probe map is empty or inconsistent (resolution " +
                         std::to_string(map.resolution) + ")");
    }
}

inline void check_direction(const glm::dvec3& direction) {
    if (!std::isfinite(direction.x) || !std::isfinite(direction.y) || !std::isfinite(direction.z) ||
        glm::dot(direction, direction) == 0.0) {
        throw InputError("probe trace: the ray direction must be finite and non-zero");
    }
}

inline void check_inputs(const ProbeMap& map, const glm::dvec3& direction) {
    check_map(map);
    check_direction(direction);
}

} // namespace lfprobe::texel_verdict
