#include "lfprobe/radiance_filter.hpp"

#include <array>
#include <cmath>

#include <glm/geometric.hpp>

#include "lfprobe/error.hpp"

namespace lfprobe {

RadianceFilter radiance_filter_from_name(const std::string& name) {
    if (name == "nearest") {
        return RadianceFilter::Nearest;
    }
    if (name == "bilinear") {
        return RadianceFilter::Bilinear;
    }
    throw InputError("radiance filter must be \"nearest\" or \"bilinear\", got \"" + name + "\"");
}

const char* radiance_filter_name(RadianceFilter filter) {
    return filter == RadianceFilter::Bilinear ? "bilinear" : "nearest";
}

glm::vec3 filtered_radiance(const ProbeMap& map, const glm::dvec3& direction, oct::Texel texel,
                            double tolerance, RadianceFilter filter) {
    const int n = map.resolution;
    const std::size_t met = oct::texel_index(texel, n);
    const glm::vec3 base = map.radiance_at(met);
    if (filter == RadianceFilter::Nearest || n < 2) {
        return base;
    }
    const double r_met = static_cast<double>(map.distance_at(met));
    if (!std::isfinite(r_met)) {
        return base;
    }
    // The plane of the surface met: its stored point and normal.
    const glm::dvec3 normal_met(map.normal_at(met));
    const glm::dvec3 point_met = r_met * glm::dvec3(oct::texel_direction(texel, n));
    const glm::vec2 uv = oct::encode(glm::vec3(direction));
    // Texel centres sit at half-integers of uv * n: the four around uv and their weights.
    const float fx = uv.x * static_cast<float>(n) - 0.5f;
    const float fy = uv.y * static_cast<float>(n) - 0.5f;
    const float x0 = std::floor(fx);
    const float y0 = std::floor(fy);
    const float ax = fx - x0;
    const float ay = fy - y0;
    const std::array<float, 2> wx{1.0f - ax, ax};
    const std::array<float, 2> wy{1.0f - ay, ay};
    // Summed as differences from the texel met, so that one colour stays exactly that colour.
    glm::vec3 sum{0.0f};
    float weight = 0.0f;
    for (int j = 0; j < 2; ++j) {
        for (int i = 0; i < 2; ++i) {
            const float w = wx[static_cast<std::size_t>(i)] * wy[static_cast<std::size_t>(j)];
            if (!(w > 0.0f)) {
                continue;
            }
            const oct::Texel t =
                oct::wrap_texel(static_cast<int>(x0) + i, static_cast<int>(y0) + j, n);
            const std::size_t k = oct::texel_index(t, n);
            if (k != met) {
                const double r = static_cast<double>(map.distance_at(k));
                if (!std::isfinite(r)) {
                    continue; // unknown or empty: no surface to read
                }
                const glm::dvec3 point = r * glm::dvec3(oct::texel_direction(t, n));
                if (std::abs(glm::dot(normal_met, point - point_met)) > tolerance ||
                    glm::dot(glm::dvec3(map.normal_at(k)), normal_met) <= 0.0) {
                    continue; // another surface: across a silhouette or a fold
                }
                sum += w * (map.radiance_at(k) - base);
            }
            weight += w;
        }
    }
    if (!(weight > 0.0f)) {
        return base;
    }
    return base + sum / weight;
}

} // namespace lfprobe
