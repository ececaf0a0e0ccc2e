// Probes with a known answer for trace and render tests: every texel holds the analytic distance,
// normal and colour of a BoxRoomScene in the direction of the texel's centre, so a trace's
// error is the map's quantisation alone; and helpers to compare traced rays with the scene.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>

#include "lfprobe/ray.hpp"
#include <random>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "lfprobe/octahedral.hpp"
#include "lfprobe/probe_field.hpp"
#include "lfprobe/probe_map.hpp"
#include "synthetic_scene.hpp"

namespace lfprobe::testing {

// A room without the sphere: convex, so every point inside sees every surface.
[[nodiscard]] inline BoxRoomScene empty_box_room() {
    BoxRoomScene scene;
    scene.sphere_radius = 0.0f;
    return scene;
}

// The unit normal of the surface met from `origin` along `dir` at distance t, facing `origin`.
[[nodiscard]] inline glm::vec3 box_room_normal(const BoxRoomScene& scene, const glm::vec3& origin,
                                               const glm::vec3& dir, float t) {
    const glm::vec3 p = origin + t * dir;
    glm::vec3 n(0.0f);
    if (scene.sphere_radius > 0.0f &&
        std::abs(glm::length(p - scene.sphere_centre) - scene.sphere_radius) < 1e-3f) {
        n = glm::normalize(p - scene.sphere_centre);
    } else {
        float best = std::numeric_limits<float>::infinity();
        for (int a = 0; a < 3; ++a) {
            const float to_min = std::abs(p[a] - scene.room_min[a]);
            const float to_max = std::abs(p[a] - scene.room_max[a]);
            if (to_min < best) {
                best = to_min;
                n = glm::vec3(0.0f);
                n[a] = 1.0f;
            }
            if (to_max < best) {
                best = to_max;
                n = glm::vec3(0.0f);
                n[a] = -1.0f;
            }
        }
    }
    return glm::dot(n, dir) > 0.0f ? -n : n;
}

// A probe at `centre` whose texels hold the scene's exact answer at each texel centre.
[[nodiscard]] inline ProbeMap analytic_probe(const BoxRoomScene& scene, const glm::dvec3& centre,
                                             int n) {
    ProbeMap map(n, centre);
    const glm::vec3 c(centre);
    for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
            const glm::vec3 dir = oct::texel_direction({x, y}, n);
            const float t = scene.distance(c, dir);
            map.set_surface(oct::texel_index({x, y}, n), t, BoxRoomScene::colour_at(c + t * dir),
                            box_room_normal(scene, c, dir, t), 1.0f);
        }
    }
    return map;
}

// The analytic probe with a patch of unknown and a patch of empty texels.
[[nodiscard]] inline ProbeMap analytic_probe_with_holes(const BoxRoomScene& scene,
                                                        const glm::dvec3& centre, int n) {
    ProbeMap map = analytic_probe(scene, centre, n);
    for (int y = n / 5; y < n / 5 + n / 8; ++y) {
        for (int x = n / 3; x < n / 3 + n / 6; ++x) {
            map.set_unknown(oct::texel_index({x, y}, n));
            map.set_empty(oct::texel_index({y, x}, n));
        }
    }
    return map;
}

// A probe whose texels are set by `texel(direction, index, map)`.
[[nodiscard]] inline ProbeMap
custom_probe(int n, const glm::dvec3& centre,
             const std::function<void(const glm::vec3&, std::size_t, ProbeMap&)>& texel) {
    ProbeMap map(n, centre);
    for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
            texel(oct::texel_direction({x, y}, n), oct::texel_index({x, y}, n), map);
        }
    }
    return map;
}

// A field of analytic probes at the placement's positions.
[[nodiscard]] inline ProbeField analytic_field(const BoxRoomScene& scene,
                                               const ProbePlacement& placement, int n) {
    std::vector<ProbeMap> probes;
    for (const glm::dvec3& p : placement.positions) {
        probes.push_back(analytic_probe(scene, p, n));
    }
    return ProbeField(placement, std::move(probes));
}

[[nodiscard]] inline glm::dvec3 random_unit(std::mt19937& rng) {
    std::normal_distribution<double> g(0.0, 1.0);
    for (;;) {
        const glm::dvec3 v(g(rng), g(rng), g(rng));
        const double l = glm::length(v);
        if (l > 1e-6) {
            return v / l;
        }
    }
}

[[nodiscard]] inline glm::dvec3 random_point_in_room(const BoxRoomScene& scene, std::mt19937& rng,
                                                     double margin) {
    for (;;) {
        glm::dvec3 p;
        for (int a = 0; a < 3; ++a) {
            std::uniform_real_distribution<double> u(scene.room_min[a] + margin,
                                                     scene.room_max[a] - margin);
            p[a] = u(rng);
        }
        const double to_sphere =
            glm::length(p - glm::dvec3(scene.sphere_centre)) - scene.sphere_radius;
        if (to_sphere > margin) {
            return p;
        }
    }
}

// A ray in a probe's frame: origin relative to the probe centre, direction normalised.
inline Ray probe_ray(const glm::dvec3& origin_rel, const glm::dvec3& dir, double t_min = 0.0,
                     double t_max = std::numeric_limits<double>::infinity()) {
    Ray ray;
    ray.origin = origin_rel;
    ray.direction = glm::normalize(dir);
    ray.t_min = t_min;
    ray.t_max = t_max;
    return ray;
}

} // namespace lfprobe::testing
