// The one rule for choosing a world offset (docs/DESIGN.md §3), shared by scans and meshes so that
// a mesh and the scans simulated from it land in the same local frame: no offset for data within
// ±1024 units of the origin (float32 keeps sub-0.1 mm there), else the bounding-box centre
// rounded to whole units.
#pragma once

#include <glm/vec3.hpp>

namespace lfprobe {

inline constexpr double kNearOriginLimit = 1024.0;

// `min` > `max` on any axis means no data: offset 0.
[[nodiscard]] glm::dvec3 world_offset_for_bounds(const glm::dvec3& min, const glm::dvec3& max);

} // namespace lfprobe
