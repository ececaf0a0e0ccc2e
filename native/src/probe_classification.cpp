#include "lfprobe/probe_classification.hpp"

#include <cmath>

#include <glm/geometric.hpp>

#include "lfprobe/enum_names.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/octahedral.hpp"

namespace lfprobe {

const char* probe_class_name(ProbeClass c) {
    static constexpr auto names = std::to_array<EnumName<ProbeClass>>({
        {ProbeClass::Useful, "useful"},
        {ProbeClass::Inside, "inside"},
        {ProbeClass::TooClose, "too_close"},
        {ProbeClass::Blind, "blind"},
        {ProbeClass::Idle, "idle"},
    });
    return name_of(names, c);
}

ProbeClassification classify_probe(const ProbeMap& map, const ClassificationSettings& settings) {
    if (map.resolution < 1 || map.distance.size() != map.texel_count()) {
        throw InputError("classify probe: the probe map is empty or inconsistent");
    }
    const int n = map.resolution;
    std::size_t surface = 0;
    std::size_t back = 0;
    std::size_t near = 0;
    std::size_t unknown = 0;
    std::size_t empty = 0;
    glm::dvec3 near_sum(0.0);
    glm::dvec3 far_sum(0.0);
    std::size_t far = 0;
    glm::dvec3 known_sum(0.0);
    glm::dvec3 unknown_sum(0.0);
    ProbeClassification c;
    for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
            const std::size_t i = oct::texel_index({x, y}, n);
            const float r = map.distance[i];
            const glm::dvec3 d(oct::texel_direction({x, y}, n));
            if (std::isnan(r)) {
                ++unknown;
                unknown_sum += d;
                continue;
            }
            known_sum += d;
            if (std::isinf(r)) {
                ++empty;
                continue;
            }
            ++surface;
            // The probe sees the back of a surface whose normal points away from it.
            if (glm::dot(glm::dvec3(map.normal_at(i)), d) > 0.0) {
                ++back;
            }
            if (r < settings.clearance) {
                ++near;
                near_sum += d;
            } else {
                ++far;
                far_sum += d;
            }
            if (r < c.nearest_surface) {
                c.nearest_surface = r;
                c.toward_nearest = d;
            }
        }
    }
    const auto all = static_cast<double>(map.texel_count());
    c.surface_fraction = static_cast<double>(surface) / all;
    c.back_face_fraction =
        surface > 0 ? static_cast<double>(back) / static_cast<double>(surface) : 0.0;
    c.near_fraction = static_cast<double>(near) / all;
    c.unknown_fraction = static_cast<double>(unknown) / all;
    c.empty_fraction = static_cast<double>(empty) / all;
    // Toward the open side: away from the near texels and toward the far ones. A probe on a
    // wall's plane sees the wall edge-on all around (the near directions cancel); the room's
    // side still pulls it off the wall.
    if (near > 0) {
        glm::dvec3 away = -near_sum / static_cast<double>(near);
        if (far > 0) {
            away += far_sum / static_cast<double>(far);
        }
        if (glm::length(away) > 1e-6) {
            c.away_from_near = glm::normalize(away);
        }
    }
    if (unknown > 0 && surface + empty > 0) {
        const glm::dvec3 toward = known_sum / static_cast<double>(surface + empty) -
                                  unknown_sum / static_cast<double>(unknown);
        if (glm::length(toward) > 1e-6) {
            c.toward_known = glm::normalize(toward);
        }
    }
    if (surface > 0 && c.back_face_fraction > settings.inside_back_face_fraction) {
        c.kind = ProbeClass::Inside;
    } else if (c.near_fraction > settings.too_close_fraction) {
        c.kind = ProbeClass::TooClose;
    } else if (c.surface_fraction < settings.blind_surface_fraction) {
        c.kind = ProbeClass::Blind;
    } else if (c.nearest_surface > settings.cell_reach) {
        c.kind = ProbeClass::Idle;
    }
    return c;
}

} // namespace lfprobe
