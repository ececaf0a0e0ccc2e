// The neighbour search behind normals and spacing (docs/DESIGN.md §4): the Morton-cell block
// search must find exactly the k nearest points, wherever the density changes.
#include <algorithm>
#include <cmath>
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
