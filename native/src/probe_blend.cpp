#include "lfprobe/probe_blend.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <tuple>

#include <glm/geometric.hpp>

#include "lfprobe/error.hpp"
#include "lfprobe/grid_walk.hpp"
#include "lfprobe/octahedral.hpp"

namespace lfprobe {

namespace {

constexpr std::size_t kMaxBlend = 8;
// Below this cosine a probe sees the surface too obliquely to add to its colour.
constexpr double kMinCosine = 0.05;

// Candidate probes ordered by squared distance to the point, ties by position: nothing
// depends on the probes' order in the set.
struct BlendCandidate {
    double distance2;
    glm::dvec3 position;
    std::size_t index;
};

bool by_position(const glm::dvec3& a, const glm::dvec3& b) {
    return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
}

bool nearer(const BlendCandidate& a, const BlendCandidate& b) {
    if (a.distance2 != b.distance2) {
        return a.distance2 < b.distance2;
    }
    return by_position(a.position, b.position);
}

// The probes around `point`: a grid's cell corners (clamped at the faces), or every probe of
// a set that is not a grid; the `wanted` nearest of them, the answering probe always among
// them. Returns how many were written to `out`.
std::size_t candidates_around(const ProbeField& field, const glm::dvec3& point,
                              std::size_t answered, std::size_t wanted,
                              std::array<std::size_t, kMaxBlend>& out) {
    std::array<BlendCandidate, kMaxBlend> best{};
    std::size_t kept = 0;
    auto offer = [&](std::size_t index) {
        const glm::dvec3 position = field.probe_position(index);
        const glm::dvec3 to = position - point;
        const BlendCandidate c{glm::dot(to, to), position, index};
        if (kept < wanted) {
            best[kept++] = c;
        } else if (nearer(c, best[kept - 1])) {
            best[kept - 1] = c;
        } else {
            return;
        }
        for (std::size_t j = kept - 1; j > 0 && nearer(best[j], best[j - 1]); --j) {
            std::swap(best[j], best[j - 1]);
        }
    };
    if (field.is_grid()) {
        std::array<std::size_t, 8> corners{};
        const std::size_t count =
            grid_cell_corners(field.grid(), grid_cell_containing(field.grid(), point), corners);
        for (std::size_t k = 0; k < count; ++k) {
            offer(corners[k]);
        }
    } else {
        for (std::size_t i = 0; i < field.probe_count(); ++i) {
            offer(i);
        }
    }
    std::size_t count = 0;
    bool has_answered = false;
    for (std::size_t k = 0; k < kept; ++k) {
        out[count++] = best[k].index;
        has_answered = has_answered || best[k].index == answered;
    }
    if (!has_answered) {
        if (count == wanted) {
            --count;
        }
        out[count++] = answered;
    }
    return count;
}

// How well the probe at `position` stands in for the eye at the surface point: the texel
// density with which it samples the point, (n / r)² cos θ, over the square of the angle between
// its line of sight to the point and the eye's (`view`, unit, eye to point), plus a texel's
// angle. A probe on the eye's line of sight outweighs the others by the square of their angle
// over a texel's, so as the eye reaches a probe the colour becomes that probe's lookup, the
// image an eye at the probe gets (probes that saw the surface from elsewhere also placed its
// texture with their own small depth errors). 0 when the probe sees the point too obliquely.
// Split in two so that the arccosine is taken only for a probe that passed every test: facing()
// is the cosine test, weight() the rest.
struct SamplingWeight {
    glm::dvec3 to_probe;
    double r2 = 0.0;
    double r = 0.0;
    double cosine = 0.0;

    SamplingWeight(const glm::dvec3& position, const glm::dvec3& point, const glm::dvec3& normal)
        : to_probe(position - point), r2(glm::dot(to_probe, to_probe)) {
        if (r2 > 0.0) {
            r = std::sqrt(r2);
            cosine = glm::dot(normal, to_probe) / r;
        }
    }
    [[nodiscard]] bool facing(double min_cosine) const { return r2 > 0.0 && cosine >= min_cosine; }
    [[nodiscard]] double weight(int resolution, const glm::dvec3& view) const {
        const double n = static_cast<double>(resolution);
        const double texel_angle = oct::kTexelAngleTimesN / n;
        const double off_view = std::acos(std::clamp(-glm::dot(view, to_probe) / r, -1.0, 1.0));
        const double angle = off_view + texel_angle;
        return n * n * cosine / (r2 * angle * angle);
    }
};

double sampling_weight(const glm::dvec3& position, int resolution, const glm::dvec3& point,
                       const glm::dvec3& normal, const glm::dvec3& view, double min_cosine) {
    const SamplingWeight w(position, point, normal);
    return w.facing(min_cosine) ? w.weight(resolution, view) : 0.0;
}

} // namespace

glm::vec3 blend_probes(const ProbeField& field, const glm::dvec3& point, const glm::dvec3& normal,
                       const glm::dvec3& view, const std::size_t* probes, std::size_t count,
                       std::size_t answered, const glm::vec3& answered_radiance,
                       const FieldTraceSettings& settings, double eye_distance) {
    if (count > kMaxBlend) {
        throw InputError("probe blend: at most 8 probes, got " + std::to_string(count));
    }
    struct Contribution {
        glm::dvec3 position;
        glm::vec3 radiance;
        double weight;
    };
    std::array<Contribution, kMaxBlend> seen{};
    std::size_t seen_count = 0;
    for (std::size_t k = 0; k < count; ++k) {
        const std::size_t index = probes[k];
        const ProbeMap& map = field.probe(index);
        if (index == answered) {
            // It met the point; however obliquely, it counts.
            const double w =
                sampling_weight(map.position, map.resolution, point, normal, view, 0.0);
            seen[seen_count++] = {map.position, answered_radiance, std::max(w, 1e-30)};
            continue;
        }
        const SamplingWeight sampling(map.position, point, normal);
        const glm::dvec3 direction = -sampling.to_probe;
        const double r = sampling.r; // 0 where r2 is not positive: skipped below as before
        if (!(r > settings.probe.eye_at_probe_distance) || !std::isfinite(r)) {
            continue;
        }
        if (!sampling.facing(kMinCosine)) {
            continue;
        }
        const oct::Texel texel = oct::texel_of_direction(glm::vec3(direction), map.resolution);
        const std::size_t i = oct::texel_index(texel, map.resolution);
        const double stored = static_cast<double>(map.distance_at(i));
        const double tolerance = surface_thickness(settings.probe, r, map.resolution);
        if (!std::isfinite(stored) || std::abs(stored - r) > tolerance) {
            continue; // it saw something else there, or nothing
        }
        const glm::dvec3 stored_normal(map.normal_at(i));
        if (glm::dot(stored_normal, direction) >= 0.0 || glm::dot(stored_normal, normal) <= 0.0) {
            continue; // the back of a surface, or another surface
        }
        const double w = sampling.weight(map.resolution, view);
        if (!(w > 0.0)) {
            continue;
        }
        seen[seen_count++] = {
            map.position,
            filtered_radiance(map, direction, texel, tolerance, settings.filter,
                              footprint_of(field, probes[k], r, eye_distance, settings)),
            w};
    }
    // An insertion sort: std::sort on a small std::array trips GCC 12's -Warray-bounds.
    for (std::size_t k = 1; k < seen_count; ++k) {
        for (std::size_t j = k; j > 0 && by_position(seen[j].position, seen[j - 1].position); --j) {
            std::swap(seen[j], seen[j - 1]);
        }
    }
    if (seen_count == 0) {
        return answered_radiance;
    }
    // Differences from the first in position order: one colour stays exactly that colour.
    const glm::dvec3 base(seen[0].radiance);
    glm::dvec3 sum{0.0};
    double weight = 0.0;
    for (std::size_t k = 0; k < seen_count; ++k) {
        sum += seen[k].weight * (glm::dvec3(seen[k].radiance) - base);
        weight += seen[k].weight;
    }
    return glm::vec3(base + sum / weight);
}

RadianceFootprint footprint_of(const ProbeField& field, std::size_t probe, double probe_distance,
                               double eye_distance, const FieldTraceSettings& settings) {
    if (settings.filter != RadianceFilter::Footprint) {
        return {};
    }
    return {&field.radiance_mips(probe),
            footprint_in_texels(eye_distance, settings.sample_angle, probe_distance,
                                field.probe_resolution(probe))};
}

void shade_hit(const ProbeField& field, const Ray& ray, FieldTraceResult& hit,
               const FieldTraceSettings& settings) {
    if (hit.status != TraceStatus::Hit || hit.probe < 0) {
        return;
    }
    if (settings.filter == RadianceFilter::Nearest && settings.blend <= 1) {
        return;
    }
    const auto answered = static_cast<std::size_t>(hit.probe);
    const ProbeMap& map = field.probe(answered);
    const glm::dvec3 point = ray.at(hit.t);
    const glm::dvec3 direction = point - map.position;
    const double r = glm::length(direction);
    const double eye_distance = glm::length(point - ray.origin);
    const glm::vec3 own = filtered_radiance(
        map, direction, hit.texel, surface_thickness(settings.probe, r, map.resolution),
        settings.filter, footprint_of(field, answered, r, eye_distance, settings));
    if (settings.blend <= 1 || field.probe_count() < 2) {
        hit.radiance = own;
        return;
    }
    std::array<std::size_t, kMaxBlend> probes{};
    const std::size_t wanted =
        std::min<std::size_t>(kMaxBlend, static_cast<std::size_t>(settings.blend));
    const std::size_t count = candidates_around(field, point, answered, wanted, probes);
    hit.radiance = blend_probes(field, point, glm::dvec3(hit.normal), ray.direction, probes.data(),
                                count, answered, own, settings, eye_distance);
}

} // namespace lfprobe
