#include "lfprobe/curve_ordered_cloud.hpp"

#include <cstddef>
#include <cstdint>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lfprobe/error.hpp"
#include "lfprobe/point_colours.hpp"

namespace lfprobe {

CurveOrderedCloud curve_ordered_cloud(const PointCloud& cloud, const LocalGeometry& geometry,
                                      const PointHierarchy& hierarchy, Progress* progress) {
    CurveOrderedCloud curve;
    if (hierarchy.levels.empty()) {
        return curve;
    }
    const std::size_t n = hierarchy.order.size();
    if (n != cloud.size() || geometry.normals.size() != n || geometry.spacing.size() != n ||
        geometry.oriented.size() != n) {
        throw InputError("bake: the point hierarchy or the local geometry does not belong to "
                         "this cloud");
    }
    const bool has_edges = geometry.edges.size() == n;
    curve.points.positions.resize(n);
    curve.points.colors.resize(n);
    curve.geometry.normals.resize(n);
    curve.geometry.spacing.resize(n);
    curve.geometry.oriented.resize(n);
    curve.geometry.edges.resize(has_edges ? n : 0);
    if (progress != nullptr) {
        progress->begin_stage("copying points into curve order", n);
    }
    const PointColours colour_of(cloud, hierarchy.intensity);
    constexpr std::size_t kChunk = 65536;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kChunk),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          if (progress != nullptr) {
                              progress->throw_if_cancelled();
                          }
                          for (std::size_t k = range.begin(); k < range.end(); ++k) {
                              const std::uint32_t i = hierarchy.order[k];
                              curve.points.positions[k] = cloud.positions[i];
                              curve.points.colors[k] = colour_of(i);
                              curve.geometry.normals[k] = geometry.normals[i];
                              curve.geometry.spacing[k] = geometry.spacing[i];
                              curve.geometry.oriented[k] = geometry.oriented[i];
                              if (has_edges) {
                                  curve.geometry.edges[k] = geometry.edges[i];
                              }
                          }
                          if (progress != nullptr) {
                              progress->advance(range.size());
                          }
                      });
    return curve;
}

ProbeMap bake_probe_from_curve_ordered(const CurveOrderedCloud& curve,
                                       const PointHierarchy& hierarchy, const glm::dvec3& centre,
                                       const BakeSettings& settings, Progress* progress) {
    if (curve.points.size() != hierarchy.order.size() || hierarchy.levels.empty()) {
        throw InputError("bake: the curve-ordered points do not belong to this hierarchy");
    }
    // The cut over the hierarchy with its points taken in curve order: the cut's indices are
    // then positions in the copy.
    PointHierarchyView view = PointHierarchyView::of(hierarchy);
    view.order = {};
    const HierarchyCut cut =
        cut_for_bake(view, centre, settings, "a curve-ordered cloud", progress);
    return bake_probe_from_gathered_cut(curve.points, curve.geometry, cut, centre, settings,
                                        progress);
}

} // namespace lfprobe
