#include "lfprobe/radiance_filter.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include <glm/geometric.hpp>

#include "lfprobe/enum_names.hpp"
#include "lfprobe/error.hpp"

namespace lfprobe {

namespace {

constexpr auto radiance_filter_names = std::to_array<EnumName<RadianceFilter>>({
    {RadianceFilter::Nearest, "nearest"},
    {RadianceFilter::Bilinear, "bilinear"},
    {RadianceFilter::Footprint, "footprint"},
    {RadianceFilter::Bicubic, "bicubic"},
});

} // namespace

RadianceFilter radiance_filter_from_name(const std::string& name) {
    return value_named_or_throw(
        radiance_filter_names, name,
        "radiance filter must be \"nearest\", \"bilinear\", \"footprint\" or \"bicubic\", got \"" +
            name + "\"");
}

const char* radiance_filter_name(RadianceFilter filter) {
    return name_of(radiance_filter_names, filter);
}

double footprint_in_texels(double eye_distance, double sample_angle, double probe_distance, int n) {
    const double texel_width = probe_distance * oct::kTexelAngleTimesN / static_cast<double>(n);
    return texel_width > 0.0 ? eye_distance * sample_angle / texel_width : 0.0;
}

namespace {

glm::vec3 same_surface_bilinear(const ProbeMap& map, const glm::dvec3& direction, oct::Texel texel,
                                double tolerance);
glm::vec3 same_surface_bicubic(const ProbeMap& map, const glm::dvec3& direction, oct::Texel texel,
                               double tolerance);

} // namespace

glm::vec3 filtered_radiance(const ProbeMap& map, const glm::dvec3& direction, oct::Texel texel,
                            double tolerance, RadianceFilter filter,
                            const RadianceFootprint& footprint) {
    if (filter == RadianceFilter::Nearest || map.resolution < 2) {
        return map.radiance_at(oct::texel_index(texel, map.resolution));
    }
    if (filter == RadianceFilter::Bicubic) {
        return same_surface_bicubic(map, direction, texel, tolerance);
    }
    const glm::vec3 fine = same_surface_bilinear(map, direction, texel, tolerance);
    if (filter != RadianceFilter::Footprint || footprint.mips == nullptr ||
        !(footprint.texels > 1.0)) {
        return fine;
    }
    // The level whose texels are as wide as the sample, between the two nearest levels.
    const double level =
        std::min(std::log2(footprint.texels), static_cast<double>(footprint.mips->level_count()));
    const int below = static_cast<int>(level);
    const auto blend = static_cast<float>(level - below);
    const glm::vec2 uv = oct::encode(glm::vec3(direction));
    bool found = false;
    const glm::vec3 lower = below == 0 ? fine : footprint.mips->bilinear(below, uv, found);
    if (below > 0 && !found) {
        return fine;
    }
    if (below == footprint.mips->level_count() || blend == 0.0f) {
        return lower;
    }
    const glm::vec3 upper = footprint.mips->bilinear(below + 1, uv, found);
    return found ? lower + blend * (upper - lower) : lower;
}

namespace {

// The texel met and the plane of its surface (stored point and normal), which the filters and
// the edge rule test the texels around it against.
struct SurfaceMet {
    std::size_t index;
    glm::vec3 radiance;
    double distance; // NaN unknown, +inf empty: then no plane
    glm::dvec3 normal;
    glm::dvec3 point;

    SurfaceMet(const ProbeMap& map, oct::Texel texel)
        : index(oct::texel_index(texel, map.resolution)), radiance(map.radiance_at(index)),
          distance(static_cast<double>(map.distance_at(index))), normal(map.normal_at(index)),
          point(distance * glm::dvec3(oct::texel_direction(texel, map.resolution))) {}

    // Whether texel `t`'s stored surface point lies on this plane within `tolerance`, its
    // normal on the same side: the same surface.
    [[nodiscard]] bool holds(const ProbeMap& map, oct::Texel t, double tolerance) const {
        const int n = map.resolution;
        const std::size_t k = oct::texel_index(t, n);
        const double r = static_cast<double>(map.distance_at(k));
        if (!std::isfinite(r)) {
            return false; // unknown or empty: no surface to read
        }
        const glm::dvec3 p = r * glm::dvec3(oct::texel_direction(t, n));
        return std::abs(glm::dot(normal, p - point)) <= tolerance &&
               glm::dot(glm::dvec3(map.normal_at(k)), normal) > 0.0;
    }
};

// Where a direction falls among an n×n map's texel centres (at half-integers of uv · n): the
// texel centre at or before it on each axis and how far past it, in texels.
struct CellPosition {
    int x0;
    int y0;
    float ax;
    float ay;
};

CellPosition cell_position(const glm::dvec3& direction, int n) {
    const glm::vec2 uv = oct::encode(glm::vec3(direction));
    const float fx = uv.x * static_cast<float>(n) - 0.5f;
    const float fy = uv.y * static_cast<float>(n) - 0.5f;
    const float x0 = std::floor(fx);
    const float y0 = std::floor(fy);
    return {static_cast<int>(x0), static_cast<int>(y0), fx - x0, fy - y0};
}

// Catmull-Rom weights of the four samples around a point `a` ∈ [0, 1) past the second.
std::array<float, 4> catmull_rom(float a) {
    const float a2 = a * a;
    const float a3 = a2 * a;
    return {0.5f * (-a3 + 2.0f * a2 - a), 0.5f * (3.0f * a3 - 5.0f * a2 + 2.0f),
            0.5f * (-3.0f * a3 + 4.0f * a2 + a), 0.5f * (a3 - a2)};
}

glm::vec3 same_surface_bicubic(const ProbeMap& map, const glm::dvec3& direction, oct::Texel texel,
                               double tolerance) {
    const int n = map.resolution;
    const SurfaceMet met(map, texel);
    if (!std::isfinite(met.distance) || n < 4) {
        return same_surface_bilinear(map, direction, texel, tolerance);
    }
    const CellPosition cell = cell_position(direction, n);
    const std::array<float, 4> wx = catmull_rom(cell.ax);
    const std::array<float, 4> wy = catmull_rom(cell.ay);
    // Summed as differences from the texel met, so that one colour stays exactly that colour;
    // the weights sum to one, so no texel may be left out: any other surface (or none) among
    // the sixteen, and the bilinear's renormalised four read the point instead.
    glm::vec3 sum{0.0f};
    for (int j = 0; j < 4; ++j) {
        for (int i = 0; i < 4; ++i) {
            const oct::Texel t = oct::wrap_texel(cell.x0 - 1 + i, cell.y0 - 1 + j, n);
            const std::size_t k = oct::texel_index(t, n);
            if (k == met.index) {
                continue;
            }
            if (!met.holds(map, t, tolerance)) {
                return same_surface_bilinear(map, direction, texel, tolerance);
            }
            sum += (wx[static_cast<std::size_t>(i)] * wy[static_cast<std::size_t>(j)]) *
                   (map.radiance_at(k) - met.radiance);
        }
    }
    return met.radiance + sum;
}

glm::vec3 same_surface_bilinear(const ProbeMap& map, const glm::dvec3& direction, oct::Texel texel,
                                double tolerance) {
    const int n = map.resolution;
    const SurfaceMet met(map, texel);
    if (!std::isfinite(met.distance)) {
        return met.radiance;
    }
    // The four texels around the direction and their weights.
    const CellPosition cell = cell_position(direction, n);
    const std::array<float, 2> wx{1.0f - cell.ax, cell.ax};
    const std::array<float, 2> wy{1.0f - cell.ay, cell.ay};
    // Summed as differences from the texel met, so that one colour stays exactly that colour.
    glm::vec3 sum{0.0f};
    float weight = 0.0f;
    for (int j = 0; j < 2; ++j) {
        for (int i = 0; i < 2; ++i) {
            const float w = wx[static_cast<std::size_t>(i)] * wy[static_cast<std::size_t>(j)];
            if (!(w > 0.0f)) {
                continue;
            }
            const oct::Texel t = oct::wrap_texel(cell.x0 + i, cell.y0 + j, n);
            const std::size_t k = oct::texel_index(t, n);
            if (k != met.index) {
                if (!met.holds(map, t, tolerance)) {
                    continue; // none, or another surface: across a silhouette or a fold
                }
                sum += w * (map.radiance_at(k) - met.radiance);
            }
            weight += w;
        }
    }
    if (!(weight > 0.0f)) {
        return met.radiance;
    }
    return met.radiance + sum / weight;
}

} // namespace

oct::Texel majority_surface_texel(const ProbeMap& map, const glm::dvec3& direction, oct::Texel met,
                                  double tolerance) {
    const int n = map.resolution;
    if (n < 2) {
        return met;
    }
    const CellPosition cell = cell_position(direction, n);
    std::array<oct::Texel, 4> texels{};
    std::array<float, 4> weights{};
    std::array<float, 4> coverages{};
    for (int j = 0; j < 2; ++j) {
        for (int i = 0; i < 2; ++i) {
            const auto q = static_cast<std::size_t>(2 * j + i);
            texels[q] = oct::wrap_texel(cell.x0 + i, cell.y0 + j, n);
            weights[q] = (i == 1 ? cell.ax : 1.0f - cell.ax) * (j == 1 ? cell.ay : 1.0f - cell.ay);
            coverages[q] = map.coverage_at(oct::texel_index(texels[q], n));
        }
    }
    // Same surface, or both empty; an unknown texel is of no group.
    const auto together = [&](const SurfaceMet& of, oct::Texel b) {
        const double rb = static_cast<double>(map.distance_at(oct::texel_index(b, n)));
        if (std::isinf(of.distance) || std::isinf(rb)) {
            return std::isinf(of.distance) && std::isinf(rb);
        }
        return !std::isnan(of.distance) && of.holds(map, b, tolerance);
    };
    // How much of the four texels' weight lies on the surface of `of`: a texel of its group
    // adds its weight times its coverage, a texel of a known other surface its weight times
    // the rest of it (what of that texel its own surface does not cover is taken to be this
    // one: at an edge there are two). Without coverage (1), the group's weight alone.
    const auto score = [&](const SurfaceMet& of) {
        float sum = 0.0f;
        for (std::size_t q = 0; q < 4; ++q) {
            if (together(of, texels[q])) {
                sum += weights[q] * coverages[q];
            } else if (!std::isnan(map.distance_at(oct::texel_index(texels[q], n)))) {
                sum += weights[q] * (1.0f - coverages[q]);
            }
        }
        return sum;
    };
    // The met texel's own share is a lower bound of its group's score: near its centre that
    // alone decides, without a neighbour's surface test.
    float own_share = 0.0f;
    for (std::size_t q = 0; q < 4; ++q) {
        if (texels[q].x == met.x && texels[q].y == met.y) {
            own_share += weights[q] * coverages[q];
        }
    }
    if (own_share >= 0.5f) {
        return met;
    }
    const SurfaceMet met_surface(map, met);
    const float own = score(met_surface);
    if (own >= 0.5f) {
        return met; // the common case: the met texel's surface holds the majority
    }
    // The best other group; among its texels the heaviest (fixed order: ties keep the first).
    oct::Texel best = met;
    float best_score = own;
    float best_weight = 0.0f;
    for (std::size_t q = 0; q < 4; ++q) {
        const std::size_t k = oct::texel_index(texels[q], n);
        if (std::isnan(map.distance_at(k)) || together(met_surface, texels[q])) {
            continue;
        }
        const float s = score(SurfaceMet(map, texels[q]));
        if (s > best_score || (s == best_score && best != met && weights[q] > best_weight)) {
            best = texels[q];
            best_score = s;
            best_weight = weights[q];
        }
    }
    return best;
}

} // namespace lfprobe
