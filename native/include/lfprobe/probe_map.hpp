// One probe's octahedral maps at one resolution: radiance, confidence, radial distance and
// surface normal per texel, stored with the same types as the probe's EXR file, so that a
// probe read back from disk is bit for bit the probe that was written. A loaded probe may be
// packed to the compact form of probe_storage.hpp; the *_at accessors read either form.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Imath/half.h>
#include <glm/vec3.hpp>

#include "lfprobe/octahedral.hpp"
#include "lfprobe/probe_storage.hpp"
#include "lfprobe/texel_state.hpp"

namespace lfprobe {

// The largest map side any bake writes or any reader accepts (16384² texels: 4.5 GiB at full
// storage), so that a resolution read from a file cannot size an allocation beyond it.
inline constexpr int kMaxProbeResolution = 16384;

struct ProbeMap {
    int resolution = 0;
    glm::dvec3 position{0.0}; // probe centre in the local (offset) frame
    // R, G, B linear radiance and A confidence (1 measured, (0,1) inferred, 0 unknown/empty).
    std::vector<Imath::half> rgba;
    std::vector<float> distance;     // radial distance in metres; NaN unknown, +inf empty
    std::vector<Imath::half> normal; // world-space unit normal, 3 per texel; 0 where no surface
    // Optional (empty: 1 for every texel): the fraction of a surface texel's solid angle that
    // its stored surface covers, where a bake knows it (mesh bakes with n×n rays a texel). A
    // texel on a silhouette holds one surface; its coverage says how much of the texel is that
    // surface, so that a lookup can place the edge inside the texel (majority_surface_texel).
    std::vector<Imath::half> coverage;
    // The compact channels (pack_probe); each replaces the full vector above it empties.
    PackedChannels packed;

    ProbeMap() = default;
    ProbeMap(int n, const glm::dvec3& centre);

    [[nodiscard]] std::size_t texel_count() const {
        return static_cast<std::size_t>(resolution) * static_cast<std::size_t>(resolution);
    }
    // True when every channel a trace reads is there for every texel, in either form.
    [[nodiscard]] bool is_complete() const;
    [[nodiscard]] TexelState state(std::size_t i) const {
        return texel_state(distance_at(i),
                           rgba.empty() ? 1.0f : static_cast<float>(rgba[4 * i + 3]));
    }
    [[nodiscard]] float distance_at(std::size_t i) const {
        return packed.distance.empty() ? distance[i]
                                       : decode_distance(packed.distance[i], packed.distance_step);
    }
    [[nodiscard]] glm::vec3 radiance_at(std::size_t i) const {
        if (!packed.srgb.empty()) {
            return {srgb8_to_linear(packed.srgb[3 * i]), srgb8_to_linear(packed.srgb[3 * i + 1]),
                    srgb8_to_linear(packed.srgb[3 * i + 2])};
        }
        return {static_cast<float>(rgba[4 * i]), static_cast<float>(rgba[4 * i + 1]),
                static_cast<float>(rgba[4 * i + 2])};
    }
    [[nodiscard]] float coverage_at(std::size_t i) const {
        return coverage.empty() ? 1.0f : static_cast<float>(coverage[i]);
    }
    [[nodiscard]] glm::vec3 normal_at(std::size_t i) const {
        if (!packed.normal.empty()) {
            return decode_normal_oct16(packed.normal[i]);
        }
        return {static_cast<float>(normal[3 * i]), static_cast<float>(normal[3 * i + 1]),
                static_cast<float>(normal[3 * i + 2])};
    }
    [[nodiscard]] bool is_packed() const {
        return !packed.distance.empty() || !packed.srgb.empty() || !packed.normal.empty();
    }
    void set_surface(std::size_t i, float dist, const glm::vec3& rgb, const glm::vec3& n,
                     float confidence);
    void set_unknown(std::size_t i);
    void set_empty(std::size_t i);

    // Bytes the maps take in memory (fine level only, either form).
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
