// Property tests of the coarse min-distance levels (docs/DESIGN.md §4).
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "lfprobe/error.hpp"
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

// Compact storage holds the levels in 16-bit steps: each quantised bound is at most the exact
// one and at most a step below it, empty stays +inf, unknown (0) stays 0, and distances past
// the last code are bounded by it.
TEST(MinDistancePyramid, QuantisedLevelsStayBoundsWithinAStep) {
    std::mt19937 rng(7);
    for (const double step : {0.001, 0.0003, 0.01}) {
        const int n = 77;
        std::vector<float> fine = random_map(n, rng, 0.02, 0.2);
        fine[5] = 100.0f; // beyond 65534 steps of 1 mm and of 0.3 mm
        const MinDistancePyramid exact(fine, n);
        MinDistancePyramid quantised(fine, n);
        quantised.quantise(step);
        EXPECT_LT(quantised.memory_bytes(), exact.memory_bytes());
        EXPECT_EQ(2 * quantised.memory_bytes(), exact.memory_bytes());
        for (std::size_t l = 0; l < exact.levels().size(); ++l) {
            const MinDistanceLevel& e = exact.levels()[l];
            const MinDistanceLevel& q = quantised.levels()[l];
            ASSERT_TRUE(q.min_distance.empty());
            for (std::size_t i = 0; i < e.min_distance.size(); ++i) {
                const float a = e.min_distance[i];
                const float b = q.value(i);
                if (std::isinf(a)) {
                    EXPECT_TRUE(std::isinf(b));
                    continue;
                }
                EXPECT_LE(b, a);
                if (a < 65534.0 * step) {
                    EXPECT_GE(static_cast<double>(b), static_cast<double>(a) - step - 1e-6);
                }
                if (a == 0.0f) {
                    EXPECT_EQ(b, 0.0f);
                }
            }
        }
    }
    MinDistancePyramid twice(std::vector<float>(16, 1.0f), 4);
    twice.quantise(0.001);
    EXPECT_THROW(twice.quantise(0.001), InputError);
    EXPECT_THROW(MinDistancePyramid(std::vector<float>(16, 1.0f), 4).quantise(0.0), InputError);
}
