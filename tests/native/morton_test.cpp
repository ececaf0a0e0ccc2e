// Points sorted along the Morton curve (morton.hpp): every sort of the same positions must give
// the same order, ascending by (key, index), whatever the cloud's size and the thread count.
#include <algorithm>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include "lfprobe/morton.hpp"

using namespace lfprobe;

namespace {

// Points on a few planes and in a dense clump, with exact duplicates (equal keys, which the
// indices order): sizes below and above where the sort turns to buckets.
std::vector<glm::vec3> clumpy_points(std::size_t n, unsigned seed) {
    std::mt19937 random(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<glm::vec3> points;
    points.reserve(n);
    while (points.size() < n) {
        switch (points.size() % 4) {
        case 0:
            points.emplace_back(8.0f * u(random), 5.0f * u(random), 0.0f);
            break;
        case 1:
            points.emplace_back(0.0f, 5.0f * u(random), 3.0f * u(random));
            break;
        case 2:
            points.emplace_back(4.0f + 0.01f * u(random), 2.0f + 0.01f * u(random), 1.0f);
            break;
        default:
            points.push_back(points[points.size() / 2]);
            break; // a duplicate
        }
    }
    return points;
}

} // namespace

TEST(Morton, SortedPointsAscendByKeyThenIndexForAnySizeAndThreadCount) {
    for (const std::size_t n : {std::size_t{1000}, std::size_t{300000}, std::size_t{1100000}}) {
        const std::vector<glm::vec3> points = clumpy_points(n, static_cast<unsigned>(n));
        const morton::SortedPoints sorted = morton::sort_points(points);
        ASSERT_EQ(sorted.keys.size(), n);
        ASSERT_EQ(sorted.order.size(), n);
        // The expected order: every point's key (recomputed from the sort's own cube), the
        // pairs sorted by a plain comparison sort.
        std::vector<std::pair<std::uint64_t, std::uint32_t>> expected(n);
        const auto cells = static_cast<float>(1u << morton::kBitsPerAxis);
        for (std::size_t i = 0; i < n; ++i) {
            const glm::vec3 q = (points[i] - sorted.origin) / sorted.cube_size * cells;
            const auto cell = [&](int a) {
                return static_cast<std::uint64_t>(std::clamp(q[a], 0.0f, cells - 1.0f));
            };
            expected[i] = {morton::key(cell(0), cell(1), cell(2)), static_cast<std::uint32_t>(i)};
        }
        std::sort(expected.begin(), expected.end());
        for (std::size_t j = 0; j < n; ++j) {
            ASSERT_EQ(sorted.keys[j], expected[j].first) << "n " << n << " at " << j;
            ASSERT_EQ(sorted.order[j], expected[j].second) << "n " << n << " at " << j;
        }
        tbb::task_arena one(1);
        one.execute([&] {
            const morton::SortedPoints again = morton::sort_points(points);
            EXPECT_EQ(again.keys, sorted.keys);
            EXPECT_EQ(again.order, sorted.order);
        });
    }
}
