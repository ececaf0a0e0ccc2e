// A ray as the renderer passes it around: origin, unit direction and the parameter interval it
// covers. Double precision, so that a camera in world coordinates (possibly georeferenced) keeps
// its sub-millimetre position once the world offset is subtracted, and so that edge crossings
// computed from plane equations stay exact enough near probe centres.
#pragma once

#include <limits>

#include <glm/vec3.hpp>

namespace lfprobe {

struct Ray {
    glm::dvec3 origin{0.0};
    glm::dvec3 direction{0.0, 0.0, -1.0}; // unit length
    double t_min = 0.0;
    double t_max = std::numeric_limits<double>::infinity();

    [[nodiscard]] glm::dvec3 at(double t) const { return origin + t * direction; }
};

} // namespace lfprobe
