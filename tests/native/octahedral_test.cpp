// Hard cases of the octahedral mapping (docs/DESIGN.md §3).
#include <algorithm>
#include <cmath>
#include <random>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "lfprobe/octahedral.hpp"

using namespace lfprobe;

namespace {

double angle_between(const glm::vec3& a, const glm::vec3& b) {
    const glm::dvec3 da = glm::normalize(glm::dvec3(a));
    const glm::dvec3 db = glm::normalize(glm::dvec3(b));
    // atan2 form: accurate for tiny angles where acos(dot) is not.
    return std::atan2(glm::length(glm::cross(da, db)), glm::dot(da, db));
}

void expect_uv(const glm::vec3& d, float u, float v) {
    const glm::vec2 uv = oct::encode(d);
    EXPECT_FLOAT_EQ(uv.x, u) << d.x << "," << d.y << "," << d.z;
    EXPECT_FLOAT_EQ(uv.y, v) << d.x << "," << d.y << "," << d.z;
}

} // namespace

TEST(Octahedral, SixAxisDirectionsMapToKnownPoints) {
    expect_uv({1, 0, 0}, 1.0f, 0.5f);
    expect_uv({-1, 0, 0}, 0.0f, 0.5f);
    expect_uv({0, 1, 0}, 0.5f, 1.0f);
    expect_uv({0, -1, 0}, 0.5f, 0.0f);
    expect_uv({0, 0, 1}, 0.5f, 0.5f);
    expect_uv({0, 0, -1}, 1.0f, 1.0f); // the lower pole lands on the corner
    for (const glm::vec3 d : {glm::vec3{1, 0, 0}, glm::vec3{-1, 0, 0}, glm::vec3{0, 1, 0},
                              glm::vec3{0, -1, 0}, glm::vec3{0, 0, 1}, glm::vec3{0, 0, -1}}) {
        const glm::vec3 back = oct::decode(oct::encode(d));
        EXPECT_LT(angle_between(back, d), 1e-6);
    }
}

TEST(Octahedral, SignedZeroComponentsFoldToPlusOne) {
    // s(-0.0) = +1: (−0, −0, −1) must land where (0, 0, −1) does, not on the opposite corner.
    expect_uv({-0.0f, -0.0f, -1.0f}, 1.0f, 1.0f);
    expect_uv({0.0f, -0.0f, -1.0f}, 1.0f, 1.0f);
    expect_uv({-0.0f, 0.0f, -1.0f}, 1.0f, 1.0f);
    expect_uv({-0.0f, -0.0f, 1.0f}, 0.5f, 0.5f);
    expect_uv({1.0f, -0.0f, -0.0f}, 1.0f, 0.5f); // z = -0 is not below the equator
    expect_uv({-0.0f, -1.0f, -0.0f}, 0.5f, 0.0f);
    EXPECT_EQ(oct::texel_of_direction({-0.0f, -0.0f, -1.0f}, 64), (oct::Texel{63, 63}));
}

TEST(Octahedral, FoldEdgesAreContinuous) {
    // The equator maps to the diamond |p.x| + |p.y| = 1 from both hemispheres.
    for (int i = 0; i < 360; ++i) {
        const float a = static_cast<float>(i) * 3.14159265f / 180.0f;
        const glm::vec3 above{std::cos(a), std::sin(a), 1e-6f};
        const glm::vec3 below{std::cos(a), std::sin(a), -1e-6f};
        const glm::vec2 ua = oct::encode(above);
        const glm::vec2 ub = oct::encode(below);
        EXPECT_LT(glm::length(ua - ub), 1e-5f) << "azimuth " << i;
        const glm::vec2 p = oct::encode({std::cos(a), std::sin(a), 0.0f}) * 2.0f - 1.0f;
        EXPECT_NEAR(std::abs(p.x) + std::abs(p.y), 1.0f, 1e-6f);
    }
    // Across the outer edge the map is mirrored: below the equator the plane y = 0 is the
    // left edge u = 0, reached at v and 1 - v from its two sides.
    const glm::vec2 above = oct::encode({-0.3f, 1e-7f, -0.7f});
    const glm::vec2 below = oct::encode({-0.3f, -1e-7f, -0.7f});
    EXPECT_NEAR(above.x, 0.0f, 1e-6f);
    EXPECT_NEAR(below.x, 0.0f, 1e-6f);
    EXPECT_NEAR(above.y, 1.0f - below.y, 1e-6f);
    EXPECT_NEAR(above.y, 0.85f, 1e-6f);
}

TEST(Octahedral, FourCornersAreTheLowerPole) {
    for (const glm::vec2 uv :
         {glm::vec2{0, 0}, glm::vec2{1, 0}, glm::vec2{0, 1}, glm::vec2{1, 1}}) {
        const glm::vec3 d = oct::decode(uv);
        EXPECT_LT(angle_between(d, {0, 0, -1}), 1e-6) << uv.x << "," << uv.y;
    }
    // The diamond's corners are the four horizontal axes.
    EXPECT_LT(angle_between(oct::decode({1.0f, 0.5f}), {1, 0, 0}), 1e-6);
    EXPECT_LT(angle_between(oct::decode({0.5f, 0.0f}), {0, -1, 0}), 1e-6);
}

TEST(Octahedral, NonNormalisedInputGivesTheSameTexel) {
    std::mt19937 rng(7);
    std::normal_distribution<float> g;
    for (int i = 0; i < 10000; ++i) {
        const glm::vec3 d{g(rng), g(rng), g(rng)};
        const glm::vec3 unit = glm::normalize(d);
        for (const float scale : {1e-20f, 1e-3f, 7.5f, 1e20f}) {
            EXPECT_LT(glm::length(oct::encode(d * scale) - oct::encode(unit)), 2e-7f);
        }
    }
}

TEST(Octahedral, NanInfAndZeroAreErrorsNotTexels) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    for (const glm::vec3 d :
         {glm::vec3{nan, 0, 1}, glm::vec3{0, nan, 0}, glm::vec3{0, 0, nan}, glm::vec3{inf, 0, 0},
          glm::vec3{0, -inf, 1}, glm::vec3{0, 0, 0}, glm::vec3{-0.0f, 0.0f, -0.0f}}) {
        EXPECT_FALSE(oct::is_valid_direction(d));
        EXPECT_THROW((void)oct::encode_checked(d), InputError);
    }
    EXPECT_NO_THROW((void)oct::encode_checked({0, 0, 1e-30f}));
}

TEST(Octahedral, TexelIndicesCoverHalfOpenIntervalsAndClamp) {
    const int n = 8;
    EXPECT_EQ(oct::texel_of_uv({0.0f, 0.0f}, n), (oct::Texel{0, 0}));
    EXPECT_EQ(oct::texel_of_uv({1.0f, 1.0f}, n), (oct::Texel{7, 7}));
    EXPECT_EQ(oct::texel_of_uv({0.125f, 0.25f}, n), (oct::Texel{1, 2})); // left edges belong
    EXPECT_EQ(oct::texel_of_uv({0.12499f, 0.24999f}, n), (oct::Texel{0, 1}));
    EXPECT_EQ(oct::texel_of_uv({-0.5f, 1.5f}, n), (oct::Texel{0, 7}));
    // The index is floor(u N) clamped, for every float near the map and its edges: just below
    // 0, at and next to each edge, just above 1.
    for (const int size : {1, 7, 8, 1024}) {
        const float fn = static_cast<float>(size);
        for (int edge = -2; edge <= size + 2; ++edge) {
            float u = static_cast<float>(edge) / fn;
            for (int k = 0; k < 4; ++k) {
                u = std::nextafter(u, -2.0f);
            }
            for (int k = 0; k < 9; ++k, u = std::nextafter(u, 2.0f)) {
                const int expected = std::clamp(static_cast<int>(std::floor(u * fn)), 0, size - 1);
                EXPECT_EQ(oct::texel_of_uv({u, u}, size), (oct::Texel{expected, expected}))
                    << "u=" << u << " n=" << size;
            }
        }
    }
}

TEST(Octahedral, EveryTexelCentreRoundTripsToItsTexel) {
    for (const int n : {1, 2, 3, 5, 7, 64, 127, 256}) {
        for (int y = 0; y < n; ++y) {
            for (int x = 0; x < n; ++x) {
                const glm::vec3 d = oct::texel_direction({x, y}, n);
                EXPECT_EQ(oct::texel_of_direction(d, n), (oct::Texel{x, y})) << "n=" << n;
            }
        }
    }
}

TEST(Octahedral, MillionRandomDirectionsRoundTripWithinTheTexelSize) {
    const int n = 2048;
    // The texel size: the largest angle between the centres of neighbouring texels.
    double texel_size = 0.0;
    for (int y = 0; y < n; ++y) {
        for (int x = 0; x + 1 < n; ++x) {
            texel_size = std::max(texel_size, angle_between(oct::texel_direction({x, y}, n),
                                                            oct::texel_direction({x + 1, y}, n)));
            texel_size = std::max(texel_size, angle_between(oct::texel_direction({y, x}, n),
                                                            oct::texel_direction({y, x + 1}, n)));
        }
    }
    std::mt19937 rng(2048);
    std::normal_distribution<float> g;
    double worst = 0.0;
    double worst_exact = 0.0;
    for (int i = 0; i < 1000000; ++i) {
        glm::vec3 d{g(rng), g(rng), g(rng)};
        if (glm::dot(d, d) == 0.0f) {
            continue;
        }
        d = glm::normalize(d);
        worst = std::max(worst,
                         angle_between(oct::texel_direction(oct::texel_of_direction(d, n), n), d));
        worst_exact = std::max(worst_exact, angle_between(oct::decode(oct::encode(d)), d));
    }
    RecordProperty("texel_size_rad", std::to_string(texel_size));
    RecordProperty("worst_texel_error_rad", std::to_string(worst));
    EXPECT_LE(worst, texel_size);
    // Without quantisation the map is exact up to float rounding.
    EXPECT_LT(worst_exact, 1e-6);
    std::printf("N=%d: texel size %.3g rad, worst round-trip error %.3g rad (%.0f%% of it), "
                "unquantised %.2g rad\n",
                n, texel_size, worst, 100.0 * worst / texel_size, worst_exact);
}

TEST(Octahedral, BorderWrapContinuesTheSphere) {
    const int n = 32;
    double step = 0.0;
    for (int x = 0; x + 1 < n; ++x) {
        step = std::max(step, angle_between(oct::texel_direction({x, 0}, n),
                                            oct::texel_direction({x + 1, 0}, n)));
    }
    for (int i = 0; i < n; ++i) {
        // One texel outside each edge is a neighbour of the edge texel on the sphere.
        const struct {
            int x, y, ex, ey;
        } cases[] = {{i, -1, i, 0}, {i, n, i, n - 1}, {-1, i, 0, i}, {n, i, n - 1, i}};
        for (const auto& c : cases) {
            const oct::Texel outside = oct::wrap_texel(c.x, c.y, n);
            ASSERT_GE(outside.x, 0);
            ASSERT_LT(outside.x, n);
            EXPECT_LE(angle_between(oct::texel_direction(outside, n),
                                    oct::texel_direction({c.ex, c.ey}, n)),
                      1.5 * step)
                << c.x << "," << c.y;
        }
    }
    EXPECT_EQ(oct::wrap_texel(3, 4, n), (oct::Texel{3, 4}));
}
