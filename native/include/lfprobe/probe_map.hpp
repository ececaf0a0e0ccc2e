// One probe's octahedral maps at one resolution: radiance, confidence, radial distance and
// surface normal per texel, stored with the same types as the probe's EXR file, so that a
// probe read back from disk is bit for bit the probe that was written.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Imath/half.h>
#include <glm/vec3.hpp>

#include "lfprobe/octahedral.hpp"
#include "lfprobe/texel_state.hpp"

namespace lfprobe {

struct ProbeMap {
    int resolution = 0;
    glm::dvec3 position{0.0}; // probe centre in the local (offset) frame
    // R, G, B linear radiance and A confidence (1 measured, (0,1) inferred, 0 unknown/empty).
    std::vector<Imath::half> rgba;
    std::vector<float> distance;     // radial distance in metres; NaN unknown, +inf empty
    std::vector<Imath::half> normal; // world-space unit normal, 3 per texel; 0 where no surface

    ProbeMap() = default;
    ProbeMap(int n, const glm::dvec3& centre);

    [[nodiscard]] std::size_t texel_count() const {
        return static_cast<std::size_t>(resolution) * static_cast<std::size_t>(resolution);
    }
    [[nodiscard]] TexelState state(std::size_t i) const {
        return texel_state(distance[i], static_cast<float>(rgba[4 * i + 3]));
    }
    [[nodiscard]] glm::vec3 radiance_at(std::size_t i) const {
        return {static_cast<float>(rgba[4 * i]), static_cast<float>(rgba[4 * i + 1]),
                static_cast<float>(rgba[4 * i + 2])};
    }
    [[nodiscard]] glm::vec3 normal_at(std::size_t i) const {
        return {static_cast<float>(normal[3 * i]), static_cast<float>(normal[3 * i + 1]),
                static_cast<float>(normal[3 * i + 2])};
    }
    void set_surface(std::size_t i, float dist, const glm::vec3& rgb, const glm::vec3& n,
                     float confidence);
    void set_unknown(std::size_t i);
    void set_empty(std::size_t i);

    // Bytes the maps take in memory (fine level only).
    [[nodiscard]] std::size_t memory_bytes() const;
};

// How much of a map is in each state, as fractions of all texels.
struct ProbeCoverage {
    double surface = 0.0;
    double inferred = 0.0;
    double empty = 0.0;
    double unknown = 0.0;
};
[[nodiscard]] ProbeCoverage coverage_of(const ProbeMap& map);

} // namespace lfprobe
