// Property tests of the coarse min-distance levels (DESIGN.md §4).
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "lfprobe/min_distance_pyramid.hpp"
#include "lfprobe/texel_state.hpp"

using namespace lfprobe;

namespace {

std::vector<float> random_map(int n, std::mt19937& rng, double unknown_rate, double empty_rate) {
    std::uniform_real_distribution<float> dist(0.05f, 30.0f);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<float> map(static_cast<std::size_t>(n) * static_cast<std::size_t>(n));
    for (float& d : map) {
        const double r = u(rng);
        d = r < unknown_rate ? kUnknownDistance
                             : (r < unknown_rate + empty_rate ? kEmptyDistance : dist(rng));
    }
    return map;
}

} // namespace

TEST(MinDistancePyramid, EveryCoarseTexelBoundsTheFineTexelsItCovers) {
    std::mt19937 rng(42);
    for (const int n : {1, 2, 3, 7, 37, 64, 100, 129}) {
        for (const auto& [unknown, empty] :
             {std::pair{0.0, 0.0}, {0.01, 0.3}, {0.2, 0.5}, {0.0, 1.0}}) {
            const std::vector<float> fine = random_map(n, rng, unknown, empty);
            const MinDistancePyramid pyramid(fine, n);
            int span = 1; // fine texels per coarse texel side
            for (const MinDistanceLevel& level : pyramid.levels()) {
                span *= 2;
                ASSERT_EQ(level.resolution, (n + span - 1) / span);
                for (int y = 0; y < n; ++y) {
                    for (int x = 0; x < n; ++x) {
                        const float f = fine[static_cast<std::size_t>(y * n + x)];
                        const float c = level.min_distance[static_cast<std::size_t>(
                            (y / span) * level.resolution + x / span)];
                        ASSERT_FALSE(std::isnan(c));
                        if (std::isnan(f)) {
                            EXPECT_EQ(c, 0.0f); // unknown below: never skippable
                        } else {
                            EXPECT_LE(c, f);
                        }
                    }
                }
            }
            if (n > 1) {
                EXPECT_EQ(pyramid.levels().back().resolution, 1);
            }
        }
    }
}

TEST(MinDistancePyramid, EmptyTexelsDoNotPoisonTheMinimum) {
    const float inf = kEmptyDistance;
    const std::vector<float> fine = {inf,  2.0f, inf, inf, //
                                     inf,  inf,  inf, inf, //
                                     3.0f, inf,  inf, inf, //
                                     inf,  inf,  inf, inf};
    const MinDistancePyramid pyramid(fine, 4);
    ASSERT_EQ(pyramid.levels().size(), 2u);
    const auto& l0 = pyramid.levels()[0].min_distance;
    EXPECT_EQ(l0[0], 2.0f);
    EXPECT_EQ(l0[1], inf); // all empty: nothing to hit, stays +inf
    EXPECT_EQ(l0[2], 3.0f);
    EXPECT_EQ(l0[3], inf);
    EXPECT_EQ(pyramid.levels()[1].min_distance[0], 2.0f);
}

TEST(MinDistancePyramid, IsTheExactMinimumNotASample) {
    // The public ports point-sample the coarse level and miss hits: the bound must be the min.
    std::vector<float> fine(16 * 16, 10.0f);
    fine[5 * 16 + 9] = 0.5f;
    const MinDistancePyramid pyramid(fine, 16, 2);
    for (const auto& level : pyramid.levels()) {
        float smallest = std::numeric_limits<float>::infinity();
        for (const float v : level.min_distance) {
            smallest = std::min(smallest, v);
        }
        EXPECT_EQ(smallest, 0.5f);
    }
    EXPECT_EQ(pyramid.levels().back().resolution, 2);
}
