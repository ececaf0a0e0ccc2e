// A ray as the renderer passes it around: origin, unit direction and the parameter interval it
// covers. Double precision, so that a camera in world coordinates (possibly georeferenced) keeps
// its sub-millimetre position once the world offset is subtracted, and so that edge crossings
// computed from plane equations stay exact enough near probe centres.
#pragma once

#include <limits>
#include <utility>

#include <glm/vec3.hpp>

namespace lfprobe {

struct Ray {
    glm::dvec3 origin{0.0};
    glm::dvec3 direction{0.0, 0.0, -1.0}; // unit length
    double t_min = 0.0;
    double t_max = std::numeric_limits<double>::infinity();

    [[nodiscard]] glm::dvec3 at(double t) const { return origin + t * direction; }
};

// Narrows [t_enter, t_exit] to where `ray` is between the planes coordinate `axis` = low and
// = high (a slab); a ray parallel to the slab and outside it gets t_enter = +inf (no interval).
inline void clip_to_slab(const Ray& ray, int axis, double low, double high, double& t_enter,
                         double& t_exit) {
    const double o = ray.origin[axis];
    const double d = ray.direction[axis];
    if (d == 0.0) {
        if (o < low || o > high) {
            t_enter = std::numeric_limits<double>::infinity();
        }
        return;
    }
    double t0 = (low - o) / d;
    double t1 = (high - o) / d;
    if (t0 > t1) {
        std::swap(t0, t1);
    }
    t_enter = t0 > t_enter ? t0 : t_enter;
    t_exit = t1 < t_exit ? t1 : t_exit;
}

} // namespace lfprobe
