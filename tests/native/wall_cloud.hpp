// A test cloud of a dense scanned wall, and bit-for-bit comparison of arrays (shared by the
// point hierarchy's and the prepared-cloud cache's tests).
#pragma once

#include <algorithm>
#include <cstring>
#include <random>
#include <vector>

#include <glm/vec3.hpp>

#include "lfprobe/point_cloud.hpp"

namespace lfprobe::testing {

// A square wall in the plane x = 0, `half_extent` about the origin, sampled on a jittered
// grid of `pitch` (as a scanner's lines are never exactly regular), seen by a scanner at
// (-2, 0, 0).
inline PointCloud dense_wall(float pitch, float half_extent, glm::vec3 colour) {
    PointCloud cloud;
    std::mt19937 random(7);
    std::uniform_real_distribution<float> jitter(-0.3f * pitch, 0.3f * pitch);
    const int steps = static_cast<int>(2.0f * half_extent / pitch);
    for (int i = 0; i <= steps; ++i) {
        for (int j = 0; j <= steps; ++j) {
            const float y =
                std::clamp(-half_extent + static_cast<float>(i) * pitch + jitter(random),
                           -half_extent, half_extent);
            const float z =
                std::clamp(-half_extent + static_cast<float>(j) * pitch + jitter(random),
                           -half_extent, half_extent);
            cloud.positions.emplace_back(0.0f, y, z);
            cloud.colors.push_back(colour);
            cloud.scan_index.push_back(0);
        }
    }
    cloud.scans.push_back(
        ScanSource{"wall", cloud.positions.size(), glm::dvec3(-2.0, 0.0, 0.0), true});
    return cloud;
}

// Two such walls at right angles, of two colours, so that the hierarchy's cells hold two
// facings: dense_wall's and one in the plane y = 0.5.
inline PointCloud wall_corner(float pitch) {
    PointCloud cloud = dense_wall(pitch, 0.5f, glm::vec3(0.2f));
    const PointCloud side = dense_wall(pitch, 0.5f, glm::vec3(0.7f, 0.1f, 0.1f));
    for (const glm::vec3& p : side.positions) {
        cloud.positions.emplace_back(p.y, 0.5f, p.z);
        cloud.colors.emplace_back(0.7f, 0.1f, 0.1f);
        cloud.scan_index.push_back(0);
    }
    cloud.scans[0].point_count = cloud.positions.size();
    return cloud;
}

// Bit-for-bit equality (unknown distances are NaN, which == never matches).
template <class T>
inline bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

} // namespace lfprobe::testing
