// Per-point surface geometry estimated from the k nearest neighbours: the normal
// (PCA, the direction of least spread) oriented toward the scanner that saw the point, and the
// local point spacing that sizes the point's splat when it is baked into a probe.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "lfprobe/point_cloud.hpp"
#include "lfprobe/progress.hpp"

namespace lfprobe {

struct LocalGeometryOptions {
    int normal_neighbours = 12;    // k for the PCA normal
    int spacing_neighbours = 6;    // the spacing is the mean distance to this many neighbours
    bool keep_file_normals = true; // use normals the file carries instead of estimating
    // Compare a query's candidates eight at a time where the CPU has AVX2 (false: one at a
    // time; the same results bit for bit, only slower; for tests and measurements).
    bool vector_instructions = true;
};

// Where a point lies at its surface's edge: the mean of its normal neighbours then lies off
// it, toward the surface's inside, within the tangent plane. `inward` is that direction (int8
// components, ×127), `offset` how far off the mean lies in 1/64 spacings (0 to 255). A
// point inside its surface has an offset near 0. 4 bytes a point.
struct SurfaceEdge {
    std::int8_t inward[3] = {0, 0, 0};
    std::uint8_t offset = 0;
};

struct LocalGeometry {
    std::vector<glm::vec3> normals; // unit; oriented toward the scanner where it is known
    std::vector<float> spacing;     // mean distance to the nearest neighbours, metres
    // Per point: true when the normal's sign is known (the scan has a scanner position or the
    // file gave normals); false means the sign is arbitrary and a baker orients it toward
    // its probe.
    std::vector<std::uint8_t> oriented;
    // Per point (empty: not estimated, and no point is taken for an edge): see SurfaceEdge.
    std::vector<SurfaceEdge> edges;
    // The points' indices in Morton (Z-curve) order of their positions: visiting points in this
    // order keeps neighbour searches and splat writes in cache, whatever order the file had.
    std::vector<std::uint32_t> spatial_order;
};

// Indices of `positions` sorted along a Morton curve over their bounding cube.
[[nodiscard]] std::vector<std::uint32_t> morton_order(const std::vector<glm::vec3>& positions);

[[nodiscard]] LocalGeometry estimate_local_geometry(const PointCloud& cloud,
                                                    const LocalGeometryOptions& options,
                                                    Progress* progress = nullptr);

// The unit eigenvector of the smallest eigenvalue of a symmetric positive semi-definite 3×3
// matrix (a covariance): the characteristic cubic's smallest root by Newton's method, the
// vector from the cross products of A - λI's rows; Jacobi rotations where the two smallest
// eigenvalues lie too close for that (the vector is then any the spread allows).
[[nodiscard]] glm::vec3 smallest_eigenvector(const double covariance[3][3]);

} // namespace lfprobe
