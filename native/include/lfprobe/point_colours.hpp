// The colour a point bakes with: its linear RGB where the scan has colour, else its intensity
// mapped to grey over the cloud's intensity range, else a neutral grey. One definition, so a
// probe baked from every point and one baked from the point hierarchy see the same colours.
#pragma once

#include <algorithm>
#include <cstddef>

#include <glm/vec3.hpp>

#include "lfprobe/point_cloud.hpp"

namespace lfprobe {

class PointColours {
public:
    explicit PointColours(const PointCloud& cloud) : cloud_(cloud) {
        if (!cloud.has_colors() && !cloud.intensities.empty()) {
            const auto [lo, hi] =
                std::minmax_element(cloud.intensities.begin(), cloud.intensities.end());
            intensity_min_ = *lo;
            intensity_scale_ = *hi > *lo ? 1.0f / (*hi - *lo) : 0.0f;
        }
    }
    [[nodiscard]] glm::vec3 operator()(std::size_t i) const {
        if (cloud_.has_colors()) {
            return cloud_.colors[i];
        }
        if (!cloud_.intensities.empty()) {
            return glm::vec3((cloud_.intensities[i] - intensity_min_) * intensity_scale_);
        }
        return glm::vec3(0.5f);
    }

private:
    const PointCloud& cloud_;
    float intensity_min_ = 0.0f;
    float intensity_scale_ = 0.0f;
};

} // namespace lfprobe
