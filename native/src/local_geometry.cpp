#include "lfprobe/local_geometry.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <nanoflann.hpp>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "lfprobe/error.hpp"
#include "lfprobe/morton.hpp"

namespace lfprobe {

namespace {

struct PositionsAdaptor {
    const std::vector<glm::vec3>& points;
    [[nodiscard]] std::size_t kdtree_get_point_count() const { return points.size(); }
    [[nodiscard]] float kdtree_get_pt(std::size_t index, std::size_t dim) const {
        return points[index][static_cast<glm::length_t>(dim)];
    }
    template <class Box>
    bool kdtree_get_bbox(Box& /*box*/) const {
        return false;
    }
};

using KdTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, PositionsAdaptor>,
                                        PositionsAdaptor, 3, std::uint32_t>;

constexpr std::size_t kChunk = 16384;

} // namespace

std::vector<std::uint32_t> morton_order(const std::vector<glm::vec3>& positions) {
    const std::size_t n = positions.size();
    glm::vec3 lo(std::numeric_limits<float>::max());
    glm::vec3 hi(std::numeric_limits<float>::lowest());
    for (const glm::vec3& p : positions) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    const glm::vec3 extent = glm::max(hi - lo, glm::vec3(1e-30f));
    const float cells = static_cast<float>((1u << 21) - 1);
    std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(n);
    tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
        const glm::vec3 q = (positions[i] - lo) / extent * cells;
        const auto cell = [&](int a) {
            return static_cast<std::uint64_t>(std::clamp(q[a], 0.0f, cells));
        };
        keyed[i] = {morton::key(cell(0), cell(1), cell(2)), static_cast<std::uint32_t>(i)};
    });
    tbb::parallel_sort(keyed.begin(), keyed.end());
    std::vector<std::uint32_t> order(n);
    for (std::size_t i = 0; i < n; ++i) {
        order[i] = keyed[i].second;
    }
    return order;
}

glm::vec3 smallest_eigenvector(const double covariance[3][3]) {
    double a[3][3];
    double v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            a[i][j] = covariance[i][j];
        }
    }
    // Cyclic Jacobi: each rotation zeroes one off-diagonal element; a handful of sweeps
    // converge to machine precision for 3×3.
    for (int sweep = 0; sweep < 32; ++sweep) {
        const double off = std::abs(a[0][1]) + std::abs(a[0][2]) + std::abs(a[1][2]);
        const double scale = std::abs(a[0][0]) + std::abs(a[1][1]) + std::abs(a[2][2]);
        if (off <= 1e-300 || off <= 1e-15 * scale) {
            break;
        }
        for (int p = 0; p < 2; ++p) {
            for (int q = p + 1; q < 3; ++q) {
                if (a[p][q] == 0.0) {
                    continue;
                }
                const double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                const double t =
                    (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1.0));
                const double c = 1.0 / std::sqrt(t * t + 1.0);
                const double s = t * c;
                for (int k = 0; k < 3; ++k) {
                    const double akp = a[k][p];
                    const double akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 3; ++k) {
                    const double apk = a[p][k];
                    const double aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for (int k = 0; k < 3; ++k) {
                    const double vkp = v[k][p];
                    const double vkq = v[k][q];
                    v[k][p] = c * vkp - s * vkq;
                    v[k][q] = s * vkp + c * vkq;
                }
            }
        }
    }
    int smallest = 0;
    for (int i = 1; i < 3; ++i) {
        if (a[i][i] < a[smallest][smallest]) {
            smallest = i;
        }
    }
    const glm::dvec3 e{v[0][smallest], v[1][smallest], v[2][smallest]};
    return glm::vec3(glm::normalize(e));
}

LocalGeometry estimate_local_geometry(const PointCloud& cloud, const LocalGeometryOptions& options,
                                      Progress* progress) {
    if (options.normal_neighbours < 3 || options.spacing_neighbours < 1) {
        throw InputError("local geometry: need at least 3 neighbours for normals and 1 for "
                         "spacing");
    }
    const std::size_t n = cloud.size();
    LocalGeometry result;
    result.normals.assign(n, glm::vec3(0.0f));
    result.spacing.assign(n, 0.0f);
    result.oriented.assign(n, 0);
    if (n == 0) {
        return result;
    }
    if (progress != nullptr) {
        progress->begin_stage("indexing points", 1);
    }
    // The tree is built over a Morton-sorted copy, and queried in that order, so that a query
    // and its neighbours sit close together in memory.
    result.spatial_order = morton_order(cloud.positions);
    std::vector<glm::vec3> sorted(n);
    tbb::parallel_for(std::size_t{0}, n,
                      [&](std::size_t j) { sorted[j] = cloud.positions[result.spatial_order[j]]; });
    const PositionsAdaptor adaptor{sorted};
    const KdTree tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
    if (progress != nullptr) {
        progress->begin_stage("estimating normals and spacing", n);
    }
    const bool use_file_normals = options.keep_file_normals && cloud.has_normals();
    const std::size_t k =
        std::min<std::size_t>(n, static_cast<std::size_t>(std::max(
                                     options.normal_neighbours, options.spacing_neighbours + 1)) +
                                     1);
    tbb::parallel_for(std::size_t{0}, (n + kChunk - 1) / kChunk, [&](std::size_t chunk) {
        if (progress != nullptr) {
            progress->throw_if_cancelled();
        }
        std::vector<std::uint32_t> idx(k);
        std::vector<float> d2(k);
        const std::size_t end = std::min(n, (chunk + 1) * kChunk);
        for (std::size_t j = chunk * kChunk; j < end; ++j) {
            const std::size_t i = result.spatial_order[j];
            const glm::vec3 p = sorted[j];
            const std::size_t found = tree.knnSearch(&p.x, k, idx.data(), d2.data());
            // Spacing: mean distance to the nearest distinct neighbours (duplicates skipped).
            double spacing_sum = 0.0;
            int spacing_count = 0;
            for (std::size_t q = 0; q < found && spacing_count < options.spacing_neighbours; ++q) {
                if (d2[q] > 0.0f) {
                    spacing_sum += std::sqrt(static_cast<double>(d2[q]));
                    ++spacing_count;
                }
            }
            result.spacing[i] =
                spacing_count > 0 ? static_cast<float>(spacing_sum / spacing_count) : 0.0f;

            glm::vec3 normal(0.0f);
            if (use_file_normals) {
                normal = cloud.normals[i];
                result.oriented[i] = 1;
            } else {
                const std::size_t m =
                    std::min(found, static_cast<std::size_t>(options.normal_neighbours) + 1);
                glm::dvec3 mean(0.0);
                for (std::size_t q = 0; q < m; ++q) {
                    mean += glm::dvec3(sorted[idx[q]]);
                }
                mean /= static_cast<double>(m);
                double cov[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
                for (std::size_t q = 0; q < m; ++q) {
                    const glm::dvec3 e = glm::dvec3(sorted[idx[q]]) - mean;
                    for (int r = 0; r < 3; ++r) {
                        for (int c = 0; c < 3; ++c) {
                            cov[r][c] += e[r] * e[c];
                        }
                    }
                }
                if (m >= 3) {
                    normal = smallest_eigenvector(cov);
                }
            }
            const ScanSource& scan = cloud.scans[cloud.scan_index[i]];
            if (scan.has_scanner && glm::dot(normal, normal) > 0.0f) {
                const glm::vec3 to_scanner = glm::vec3(scan.scanner - glm::dvec3(p));
                if (glm::dot(normal, to_scanner) < 0.0f) {
                    normal = -normal;
                }
                result.oriented[i] = 1;
            }
            result.normals[i] = normal;
        }
        if (progress != nullptr) {
            progress->advance(end - chunk * kChunk);
        }
    });
    return result;
}

} // namespace lfprobe
