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
    // The cloud's intensity range, mapped to grey [0, 1]: one pass over the cloud, which a
    // caller baking many probes keeps (PointHierarchy does) instead of making again per probe.
    struct IntensityRange {
        float min = 0.0f;
        float scale = 0.0f;
    };
    [[nodiscard]] static IntensityRange intensity_range(const PointCloud& cloud) {
        IntensityRange range;
        if (!cloud.has_colors() && !cloud.intensities.empty()) {
            const auto [lo, hi] =
                std::minmax_element(cloud.intensities.begin(), cloud.intensities.end());
            range.min = *lo;
            range.scale = *hi > *lo ? 1.0f / (*hi - *lo) : 0.0f;
        }
        return range;
    }

    explicit PointColours(const PointCloud& cloud) : PointColours(cloud, intensity_range(cloud)) {}
    PointColours(const PointCloud& cloud, IntensityRange range)
        : cloud_(cloud), intensity_min_(range.min), intensity_scale_(range.scale) {}
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
