#include "lfprobe/probe_map.hpp"

namespace lfprobe {

ProbeMap::ProbeMap(int n, const glm::dvec3& centre)
    : resolution(n), position(centre), rgba(texel_count() * 4, Imath::half(0.0f)),
      distance(texel_count(), kUnknownDistance), normal(texel_count() * 3, Imath::half(0.0f)) {}

void ProbeMap::set_surface(std::size_t i, float dist, const glm::vec3& rgb, const glm::vec3& n,
                           float confidence) {
    distance[i] = dist;
    rgba[4 * i] = Imath::half(rgb.x);
    rgba[4 * i + 1] = Imath::half(rgb.y);
    rgba[4 * i + 2] = Imath::half(rgb.z);
    rgba[4 * i + 3] = Imath::half(confidence);
    normal[3 * i] = Imath::half(n.x);
    normal[3 * i + 1] = Imath::half(n.y);
    normal[3 * i + 2] = Imath::half(n.z);
}

void ProbeMap::set_unknown(std::size_t i) {
    distance[i] = kUnknownDistance;
    for (std::size_t c = 0; c < 4; ++c) {
        rgba[4 * i + c] = Imath::half(0.0f);
    }
    for (std::size_t c = 0; c < 3; ++c) {
        normal[3 * i + c] = Imath::half(0.0f);
    }
}

void ProbeMap::set_empty(std::size_t i) {
    set_unknown(i);
    distance[i] = kEmptyDistance;
}

bool ProbeMap::is_complete() const {
    const std::size_t n = texel_count();
    if (resolution < 1) {
        return false;
    }
    const bool has_distance =
        packed.distance.empty() ? distance.size() == n : packed.distance.size() == n;
    const bool has_radiance =
        packed.srgb.empty() ? rgba.size() >= 3 * n : packed.srgb.size() == 3 * n;
    const bool has_normal =
        packed.normal.empty() ? normal.size() == 3 * n : packed.normal.size() == n;
    return has_distance && has_radiance && has_normal;
}

std::size_t ProbeMap::memory_bytes() const {
    return rgba.size() * sizeof(Imath::half) + distance.size() * sizeof(float) +
           normal.size() * sizeof(Imath::half) + coverage.size() * sizeof(Imath::half) +
           packed.memory_bytes();
}

ProbeCoverage coverage_of(const ProbeMap& map) {
    std::size_t counts[4] = {0, 0, 0, 0};
    const std::size_t n = map.texel_count();
    for (std::size_t i = 0; i < n; ++i) {
        ++counts[static_cast<std::size_t>(map.state(i))];
    }
    const double total = n == 0 ? 1.0 : static_cast<double>(n);
    ProbeCoverage c;
    c.unknown = static_cast<double>(counts[static_cast<std::size_t>(TexelState::Unknown)]) / total;
    c.empty = static_cast<double>(counts[static_cast<std::size_t>(TexelState::Empty)]) / total;
    c.surface = static_cast<double>(counts[static_cast<std::size_t>(TexelState::Surface)]) / total;
    c.inferred =
        static_cast<double>(counts[static_cast<std::size_t>(TexelState::Inferred)]) / total;
    return c;
}

} // namespace lfprobe
