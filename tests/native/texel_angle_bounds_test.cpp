// The bounds that turn a splat's angle into a texel search radius (texel_angle_bounds.hpp): below
// the angle between any two neighbouring texel centres, and near it at every resolution a bake
// takes (at 4096² the arccosine of a float dot product once made corner blocks' bounds 0).
#include <algorithm>
#include <cmath>
#include <numbers>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "lfprobe/octahedral.hpp"
#include "texel_angle_bounds.hpp"

using namespace lfprobe;

namespace {

// The angle between the centres of texels a and b, in double.
double angle_between(oct::Texel a, oct::Texel b, int n) {
    const glm::dvec3 u = glm::normalize(glm::dvec3(oct::texel_direction(a, n)));
    const glm::dvec3 v = glm::normalize(glm::dvec3(oct::texel_direction(b, n)));
    return 2.0 * std::asin(std::min(1.0, 0.5 * glm::length(u - v)));
}

// Every row `step`-th: each texel's bound against the angles to its right and lower neighbours.
void expect_bounds_below_neighbour_angles(int n, int step) {
    const TexelAngleBounds& bounds = TexelAngleBounds::of(n);
    for (int y = 0; y < n - 1; y += step) {
        for (int x = 0; x < n - 1; ++x) {
            const double bound = bounds.around({x, y});
            ASSERT_LE(bound, angle_between({x, y}, {x + 1, y}, n)) << n << "² at " << x << "," << y;
            ASSERT_LE(bound, angle_between({x, y}, {x, y + 1}, n)) << n << "² at " << x << "," << y;
        }
    }
}

} // namespace

TEST(TexelAngleBounds, AreBelowTheAngleBetweenNeighbouringTexels) {
    expect_bounds_below_neighbour_angles(256, 1);
    expect_bounds_below_neighbour_angles(4096, 61);
}

// The hard case: at 4096² and 8192² the octahedral corners' neighbours lie a quarter of a
// milliradian apart. No block's bound may collapse toward 0 there (it fell to the 1e-6 rad
// fallback in 14 % of the 4096² map's blocks and in all of 8192²'s, and a splat in them searched
// 129 × 129 texels instead of about 5 × 5).
TEST(TexelAngleBounds, StayNearTheTexelAngleAtHighResolutions) {
    for (const int n : {2048, 4096, 8192}) {
        const TexelAngleBounds& bounds = TexelAngleBounds::of(n);
        const double mean_texel_angle = std::sqrt(4.0 * std::numbers::pi) / n;
        EXPECT_GT(bounds.global(), 0.4 * mean_texel_angle) << n << "²";
        for (int y = 0; y < n; y += TexelAngleBounds::kBlock) {
            for (int x = 0; x < n; x += TexelAngleBounds::kBlock) {
                ASSERT_GT(bounds.around({x, y}), 0.4 * mean_texel_angle)
                    << n << "² at " << x << "," << y;
            }
        }
        // A splat two mean texel angles wide at the map's corner searches a few texels around.
        EXPECT_LE(bounds.search_radius({0, 0}, static_cast<float>(2.0 * mean_texel_angle), 64), 6)
            << n << "²";
    }
}
