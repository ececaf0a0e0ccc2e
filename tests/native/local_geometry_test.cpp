// The neighbour search behind normals and spacing (docs/DESIGN.md §4): the Morton-cell block
// search must find exactly the k nearest points, wherever the density changes.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include "lfprobe/local_geometry.hpp"

using namespace lfprobe;

namespace {

// A floor of sparse points, a dense patch on it (100× the density), a lone cluster of three
// points far off (fewer than the neighbours asked for: the search must grow to the whole
// cloud), and duplicates.
PointCloud uneven_cloud() {
    PointCloud cloud;
    std::mt19937 random(11);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const auto add = [&](glm::vec3 p) {
        cloud.positions.push_back(p);
        cloud.scan_index.push_back(0);
    };
    for (int i = 0; i < 2000; ++i) {
        add({4.0f * u(random), 4.0f * u(random), 0.01f * u(random)});
    }
    for (int i = 0; i < 2000; ++i) {
        add({1.0f + 0.4f * u(random), 1.0f + 0.4f * u(random), 0.001f * u(random)});
    }
    for (int i = 0; i < 3; ++i) {
        add({30.0f + 0.1f * static_cast<float>(i), 30.0f, 5.0f});
    }
    for (int i = 0; i < 20; ++i) {
        add(cloud.positions[static_cast<std::size_t>(i) * 97]);
    }
    cloud.scans.push_back(ScanSource{"uneven", cloud.positions.size(), glm::dvec3(2, 2, 3), true});
    return cloud;
}

// Mean distance to the `count` nearest distinct points, by comparing with every point.
float brute_force_spacing(const PointCloud& cloud, std::size_t i, int count) {
    std::vector<float> d2;
    for (std::size_t q = 0; q < cloud.size(); ++q) {
        const glm::vec3 d = cloud.positions[q] - cloud.positions[i];
        const float e = glm::dot(d, d);
        if (e > 0.0f) {
            d2.push_back(e);
        }
    }
    std::sort(d2.begin(), d2.end());
    double sum = 0.0;
    const auto n = std::min<std::size_t>(d2.size(), static_cast<std::size_t>(count));
    for (std::size_t q = 0; q < n; ++q) {
        sum += std::sqrt(static_cast<double>(d2[q]));
    }
    return n > 0 ? static_cast<float>(sum / static_cast<double>(n)) : 0.0f;
}

} // namespace

TEST(LocalGeometry, TheBlockSearchFindsExactlyTheNearestPointsWhereDensityJumps) {
    const PointCloud cloud = uneven_cloud();
    const LocalGeometryOptions options;
    const LocalGeometry geometry = estimate_local_geometry(cloud, options);
    // Every fifth point, and every point of the lone cluster and the duplicates.
    for (std::size_t i = 0; i < cloud.size(); i += i + 23 >= cloud.size() ? 1 : 5) {
        const float expected = brute_force_spacing(cloud, i, options.spacing_neighbours);
        // The sums run over the same distances; only their order can differ.
        ASSERT_NEAR(geometry.spacing[i], expected, 1e-6f * std::max(1.0f, expected)) << i;
    }
    // The floor's normals are vertical, the lone cluster's (a line) whatever PCA gives.
    std::size_t vertical = 0;
    for (std::size_t i = 0; i < 4000; ++i) {
        vertical += std::abs(geometry.normals[i].z) > 0.95f ? 1 : 0;
    }
    EXPECT_GT(vertical, 3900u);
}

TEST(LocalGeometry, NormalsAndSpacingAreTheSameForAnyThreadCount) {
    const PointCloud cloud = uneven_cloud();
    const LocalGeometry many = estimate_local_geometry(cloud, {});
    LocalGeometry one;
    tbb::task_arena single(1);
    single.execute([&] { one = estimate_local_geometry(cloud, {}); });
    ASSERT_EQ(many.spacing, one.spacing);
    ASSERT_EQ(many.normals, one.normals);
    ASSERT_EQ(many.spatial_order, one.spatial_order);
}

// The candidates compared eight at a time (AVX2, where the CPU has it) or one at a time: the
// same neighbours, so the same normals, spacing and edges bit for bit, on the uneven cloud (a
// density jump, a lone cluster, duplicates) and on clouds so small that every run of
// candidates ends inside a group of eight, or at the cloud's last point.
TEST(LocalGeometry, ComparingCandidatesEightAtATimeChangesNothing) {
    std::vector<PointCloud> clouds{uneven_cloud()};
    std::mt19937 random(3);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (const int size : {4, 7, 8, 9, 15, 17, 40}) {
        PointCloud small;
        for (int i = 0; i < size; ++i) {
            small.positions.push_back({u(random), u(random), 0.05f * u(random)});
            small.scan_index.push_back(0);
        }
        small.scans.push_back(
            ScanSource{"small", small.positions.size(), glm::dvec3(0, 0, 2), true});
        clouds.push_back(small);
    }
    for (const PointCloud& cloud : clouds) {
        LocalGeometryOptions one_at_a_time;
        one_at_a_time.vector_instructions = false;
        const LocalGeometry vectors = estimate_local_geometry(cloud, {});
        const LocalGeometry scalar = estimate_local_geometry(cloud, one_at_a_time);
        ASSERT_EQ(vectors.spacing, scalar.spacing) << cloud.size() << " points";
        ASSERT_EQ(vectors.normals, scalar.normals) << cloud.size() << " points";
        ASSERT_EQ(vectors.oriented, scalar.oriented) << cloud.size() << " points";
        ASSERT_EQ(vectors.spatial_order, scalar.spatial_order) << cloud.size() << " points";
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            ASSERT_EQ(std::memcmp(&vectors.edges[i], &scalar.edges[i], sizeof(SurfaceEdge)), 0)
                << cloud.size() << " points, point " << i;
        }
    }
}

namespace {

// R · diag(values) · Rᵀ for the rotation R whose columns are `axes` (orthonormal).
void covariance_of(const glm::dvec3 (&axes)[3], const double (&values)[3], double out[3][3]) {
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            out[i][j] = 0.0;
            for (int k = 0; k < 3; ++k) {
                out[i][j] += values[k] * axes[k][i] * axes[k][j];
            }
        }
    }
}

} // namespace

// The closed-form solver on what scans give it: surfaces so flat that the smallest eigenvalue
// is 1e-14 of the largest, at any orientation and at any scale of the coordinates; and the
// cases it hands to Jacobi, where the smallest eigenvector is not unique (a line's
// neighbourhood, a ball's, no spread at all): any unit vector the spread allows.
TEST(LocalGeometry, SmallestEigenvectorOfFlatLineLikeAndDegenerateSpreads) {
    std::mt19937 random(5);
    std::normal_distribution<double> g(0.0, 1.0);
    for (int trial = 0; trial < 200; ++trial) {
        const glm::dvec3 a = glm::normalize(glm::dvec3(g(random), g(random), g(random)));
        const glm::dvec3 b =
            glm::normalize(glm::cross(a, glm::dvec3(g(random), g(random), g(random))));
        const glm::dvec3 axes[3] = {a, b, glm::cross(a, b)};
        const double scale = std::pow(10.0, trial % 13 - 9);       // 1e-9 to 1e3
        const double flatness = std::pow(10.0, -(trial % 15) - 1); // 1e-1 to 1e-15
        double flat[3][3];
        covariance_of(axes, {scale, 0.4 * scale, flatness * 0.4 * scale}, flat);
        const glm::vec3 n = smallest_eigenvector(flat);
        EXPECT_NEAR(std::abs(glm::dot(glm::dvec3(n), axes[2])), 1.0, 1e-6)
            << "trial " << trial << " scale " << scale << " flatness " << flatness;

        double line[3][3];
        covariance_of(axes, {scale, 1e-9 * scale, (1e-9 + 1e-15) * scale}, line);
        const glm::vec3 l = smallest_eigenvector(line);
        EXPECT_NEAR(glm::length(l), 1.0f, 1e-5f);
        EXPECT_LT(std::abs(glm::dot(glm::dvec3(l), axes[0])), 1e-6) << "trial " << trial;
    }
    const double zero[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    const double ball[3][3] = {{2, 0, 0}, {0, 2, 0}, {0, 0, 2}};
    for (const auto* m : {&zero, &ball}) {
        const glm::vec3 v = smallest_eigenvector(*m);
        EXPECT_NEAR(glm::length(v), 1.0f, 1e-6f);
    }
}
