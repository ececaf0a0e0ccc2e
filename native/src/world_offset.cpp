#include "lfprobe/world_offset.hpp"

#include <cmath>

#include <glm/common.hpp>

namespace lfprobe {

glm::dvec3 world_offset_for_bounds(const glm::dvec3& min, const glm::dvec3& max) {
    if (min.x > max.x || min.y > max.y || min.z > max.z) {
        return glm::dvec3(0.0);
    }
    const glm::dvec3 largest = glm::max(glm::abs(min), glm::abs(max));
    if (largest.x <= kNearOriginLimit && largest.y <= kNearOriginLimit &&
        largest.z <= kNearOriginLimit) {
        return glm::dvec3(0.0);
    }
    const glm::dvec3 centre = 0.5 * (min + max);
    return glm::dvec3(std::round(centre.x), std::round(centre.y), std::round(centre.z));
}

} // namespace lfprobe
