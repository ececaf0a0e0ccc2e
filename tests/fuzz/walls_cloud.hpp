// The small cloud the cache harnesses prepare their genuine entries from: two walls at right
// angles, seen from a scanner, dense enough for a point hierarchy with levels.
#pragma once

#include <memory>

#include <glm/vec3.hpp>

#include "lfprobe/point_cloud.hpp"

namespace lfprobe::fuzz {

inline std::shared_ptr<const PointCloud> walls_cloud() {
    auto cloud = std::make_shared<PointCloud>();
    for (int i = 0; i < 20; ++i) {
        for (int j = 0; j < 20; ++j) {
            const float u = 0.05f * static_cast<float>(i);
            const float v = 0.05f * static_cast<float>(j);
            cloud->positions.emplace_back(1.0f, u, v);
            cloud->positions.emplace_back(u, 1.0f, v);
            cloud->colors.emplace_back(0.8f, 0.2f, 0.1f);
            cloud->colors.emplace_back(0.1f, 0.3f, 0.9f);
        }
    }
    cloud->scan_index.assign(cloud->positions.size(), 0);
    cloud->scans.push_back({"walls", cloud->positions.size(), glm::dvec3(0.0), true});
    return cloud;
}

} // namespace lfprobe::fuzz
