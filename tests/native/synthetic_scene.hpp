// Point clouds with a known answer for bake tests: a box room with a sphere inside, sampled
// on a regular pattern, with analytic ray distances.
#pragma once

#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "lfprobe/point_cloud.hpp"

namespace lfprobe::testing {

struct BoxRoomScene {
    glm::vec3 room_min{-2.0f, -1.5f, 0.0f};
    glm::vec3 room_max{2.0f, 1.5f, 2.5f};
    glm::vec3 sphere_centre{1.0f, 0.4f, 1.0f};
    float sphere_radius = 0.45f;

    // Distance from `origin` along unit `dir` to the first surface (sphere or wall).
    [[nodiscard]] float distance(const glm::vec3& origin, const glm::vec3& dir) const {
        float t_wall = std::numeric_limits<float>::infinity();
        for (int a = 0; a < 3; ++a) {
            if (dir[a] > 0.0f) {
                t_wall = std::min(t_wall, (room_max[a] - origin[a]) / dir[a]);
            } else if (dir[a] < 0.0f) {
                t_wall = std::min(t_wall, (room_min[a] - origin[a]) / dir[a]);
            }
        }
        const glm::vec3 oc = origin - sphere_centre;
        const float b = glm::dot(oc, dir);
        const float c = glm::dot(oc, oc) - sphere_radius * sphere_radius;
        const float disc = b * b - c;
        if (disc >= 0.0f) {
            const float t = -b - std::sqrt(disc);
            if (t > 0.0f && t < t_wall) {
                return t;
            }
        }
        return t_wall;
    }

    // A colour pattern that changes with position so radiance lookups can be checked.
    [[nodiscard]] static glm::vec3 colour_at(const glm::vec3& p) {
        const float stripes = 0.5f + 0.5f * std::sin(6.0f * p.x) * std::cos(5.0f * p.y);
        return {0.2f + 0.6f * stripes, 0.3f + 0.2f * std::fmod(std::abs(p.z), 1.0f), 0.5f};
    }

    // Points on the six walls on a square pattern of `spacing`, and on the sphere with about
    // the same density (Fibonacci lattice). One scan, scanner at `scanner`.
    [[nodiscard]] PointCloud cloud(float spacing, const glm::dvec3& scanner) const {
        PointCloud cloud;
        auto add = [&](const glm::vec3& p) {
            cloud.positions.push_back(p);
            cloud.colors.push_back(colour_at(p));
            cloud.scan_index.push_back(0);
        };
        for (int axis = 0; axis < 3; ++axis) {
            const int u = (axis + 1) % 3;
            const int v = (axis + 2) % 3;
            const int nu = static_cast<int>((room_max[u] - room_min[u]) / spacing) + 1;
            const int nv = static_cast<int>((room_max[v] - room_min[v]) / spacing) + 1;
            for (const float w : {room_min[axis], room_max[axis]}) {
                for (int i = 0; i < nu; ++i) {
                    for (int j = 0; j < nv; ++j) {
                        glm::vec3 p;
                        p[axis] = w;
                        p[u] = std::min(room_max[u],
                                        room_min[u] + (static_cast<float>(i) + 0.5f) * spacing);
                        p[v] = std::min(room_max[v],
                                        room_min[v] + (static_cast<float>(j) + 0.5f) * spacing);
                        add(p);
                    }
                }
            }
        }
        const float area = 4.0f * 3.14159265f * sphere_radius * sphere_radius;
        const int count = static_cast<int>(area / (spacing * spacing));
        const float golden = 3.14159265f * (3.0f - std::sqrt(5.0f));
        for (int i = 0; i < count; ++i) {
            const float z =
                1.0f - 2.0f * (static_cast<float>(i) + 0.5f) / static_cast<float>(count);
            const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
            const float phi = golden * static_cast<float>(i);
            add(sphere_centre + sphere_radius * glm::vec3(r * std::cos(phi), r * std::sin(phi), z));
        }
        ScanSource source;
        source.path = "synthetic box room";
        source.point_count = cloud.positions.size();
        source.scanner = scanner;
        source.has_scanner = true;
        cloud.scans.push_back(source);
        return cloud;
    }
};

} // namespace lfprobe::testing
