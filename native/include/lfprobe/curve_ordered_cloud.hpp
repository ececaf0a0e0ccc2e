// A cloud's bake attributes copied into its point hierarchy's curve (Morton) order, once per
// cloud: what a probe's bake reads of every point (position, colour as the bake resolves it,
// normal, spacing, orientation, edge). A probe's cut lists its full-density points in curve
// order, so a bake then reads these arrays front to back; read through the cloud's own arrays
// (file order) every point of the cut was a cache miss per attribute and pass, two fifths of a
// 2048² bake from 10 M points. The spatial cloud (spatial_cloud.hpp) is the same layout on disk.
// 45 bytes a point.
#pragma once

#include <glm/vec3.hpp>

#include "lfprobe/local_geometry.hpp"
#include "lfprobe/point_cloud.hpp"
#include "lfprobe/point_hierarchy.hpp"
#include "lfprobe/probe_bake.hpp"
#include "lfprobe/probe_map.hpp"
#include "lfprobe/progress.hpp"

namespace lfprobe {

struct CurveOrderedCloud {
    // Point k is the hierarchy's order[k]: positions and resolved colours (PointColours).
    PointCloud points;
    // Normals, spacing, orientation and edges of the same points; no spatial order (the points
    // are in it).
    LocalGeometry geometry;

    [[nodiscard]] bool empty() const { return points.positions.empty(); }
};

// The copy, on all cores; cancellable. Empty for a hierarchy with no levels (a bake of every
// point, which reads the cloud in its own spatial order).
[[nodiscard]] CurveOrderedCloud curve_ordered_cloud(const PointCloud& cloud,
                                                    const LocalGeometry& geometry,
                                                    const PointHierarchy& hierarchy,
                                                    Progress* progress = nullptr);

// bake_probe_from_hierarchy from the copy: the same cut, the same probe bit for bit. `curve`
// must come from `hierarchy` (InputError otherwise).
[[nodiscard]] ProbeMap bake_probe_from_curve_ordered(const CurveOrderedCloud& curve,
                                                     const PointHierarchy& hierarchy,
                                                     const glm::dvec3& centre,
                                                     const BakeSettings& settings,
                                                     Progress* progress = nullptr);

} // namespace lfprobe
