// Filling a rendered view's narrow holes (unknown_fill.hpp): one colour around a hole fills it
// with exactly that colour, a hole wider than the fill reaches stays black, MISS is neither
// filled nor a source, the status plane never changes, and a render's HIT pixels are the same
// with the fill on or off.
#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include "lfprobe/camera.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/probe_trace.hpp"
#include "lfprobe/render.hpp"
#include "lfprobe/unknown_fill.hpp"
#include "trace_scenes.hpp"

namespace lfprobe {
namespace {

// A w×h image, every pixel a HIT of `colour` (coverage 1), with the unknown shares all 0.
struct Canvas {
    RenderedImage image;
    std::vector<float> unknown;

    Canvas(int w, int h, const glm::vec3& colour)
        : image(w, h), unknown(image.pixel_count(), 0.0f) {
        for (std::size_t i = 0; i < image.pixel_count(); ++i) {
            paint(i, colour);
        }
    }
    void paint(std::size_t i, const glm::vec3& colour) {
        image.rgba[4 * i] = colour.x;
        image.rgba[4 * i + 1] = colour.y;
        image.rgba[4 * i + 2] = colour.z;
        image.rgba[4 * i + 3] = 1.0f;
        image.status[i] = static_cast<std::uint8_t>(TraceStatus::Hit);
    }
    // Pixels [x0, x1) × [y0, y1) UNKNOWN: no colour, every sample unknown.
    void hole(int x0, int y0, int x1, int y1) {
        for (int y = y0; y < y1; ++y) {
            for (int x = x0; x < x1; ++x) {
                const std::size_t i = image.index(x, y);
                for (int c = 0; c < 4; ++c) {
                    image.rgba[4 * i + static_cast<std::size_t>(c)] = 0.0f;
                }
                image.status[i] = static_cast<std::uint8_t>(TraceStatus::Unknown);
                unknown[i] = 1.0f;
            }
        }
    }
    [[nodiscard]] glm::vec4 at(int x, int y) const {
        const std::size_t i = image.index(x, y);
        return {image.rgba[4 * i], image.rgba[4 * i + 1], image.rgba[4 * i + 2],
                image.rgba[4 * i + 3]};
    }
};

TEST(UnknownFill, AHoleInOneColourIsFilledWithThatColour) {
    const glm::vec3 colour(0.3f, 0.55f, 0.8f);
    Canvas canvas(37, 23, colour);
    canvas.hole(10, 5, 18, 12);
    const std::vector<std::uint8_t> status_before = canvas.image.status;
    const UnknownFillStats stats = fill_unknown_pixels(canvas.image, canvas.unknown, 8);
    EXPECT_EQ(stats.pixels_filled, 8u * 7u);
    EXPECT_EQ(stats.pixels_left, 0u);
    for (int y = 0; y < 23; ++y) {
        for (int x = 0; x < 37; ++x) {
            const glm::vec4 p = canvas.at(x, y);
            EXPECT_NEAR(p.x, colour.x, 1e-6f) << x << "," << y;
            EXPECT_NEAR(p.y, colour.y, 1e-6f) << x << "," << y;
            EXPECT_NEAR(p.z, colour.z, 1e-6f) << x << "," << y;
            EXPECT_EQ(p.w, 1.0f);
        }
    }
    EXPECT_EQ(canvas.image.status, status_before); // still UNKNOWN: the hole rate counts them
}

TEST(UnknownFill, AHoleWiderThanTheFillReachesStaysBlack) {
    const glm::vec3 colour(0.6f, 0.2f, 0.1f);
    // 12 pixels across: its middle is 6 steps from the pixels around it.
    for (const int width : {10, 11, 12, 13}) {
        Canvas canvas(40, 30, colour);
        canvas.hole(14, 9, 26, 21);
        const UnknownFillStats stats = fill_unknown_pixels(canvas.image, canvas.unknown, width);
        const bool fills = (width + 1) / 2 >= 6;
        EXPECT_EQ(stats.pixels_filled, fills ? 144u : 0u) << width;
        EXPECT_EQ(stats.pixels_left, fills ? 0u : 144u) << width;
        EXPECT_EQ(canvas.at(20, 15).w, fills ? 1.0f : 0.0f) << width;
        EXPECT_EQ(canvas.at(20, 15).x, fills ? canvas.at(20, 15).x : 0.0f) << width;
    }
}

TEST(UnknownFill, WidthZeroChangesNothing) {
    Canvas canvas(16, 16, {0.5f, 0.5f, 0.5f});
    canvas.hole(4, 4, 7, 7);
    const std::vector<float> before = canvas.image.rgba;
    const UnknownFillStats stats = fill_unknown_pixels(canvas.image, canvas.unknown, 0);
    EXPECT_EQ(canvas.image.rgba, before);
    EXPECT_EQ(stats.pixels_filled, 0u);
}

TEST(UnknownFill, APixelPartlyUnknownGetsItsMissingShare) {
    const glm::vec3 colour(0.25f, 0.5f, 0.75f);
    Canvas canvas(9, 9, colour);
    // Half the samples HIT (the colour premultiplied by 0.5), half UNKNOWN.
    const std::size_t i = canvas.image.index(4, 4);
    for (int c = 0; c < 3; ++c) {
        canvas.image.rgba[4 * i + static_cast<std::size_t>(c)] = 0.5f * colour[c];
    }
    canvas.image.rgba[4 * i + 3] = 0.5f;
    canvas.unknown[i] = 0.5f;
    const UnknownFillStats stats = fill_unknown_pixels(canvas.image, canvas.unknown, 4);
    EXPECT_EQ(stats.pixels_filled, 0u); // it had a HIT: not a hole pixel
    const glm::vec4 p = canvas.at(4, 4);
    EXPECT_NEAR(p.x, colour.x, 1e-6f);
    EXPECT_NEAR(p.y, colour.y, 1e-6f);
    EXPECT_NEAR(p.z, colour.z, 1e-6f);
    EXPECT_EQ(p.w, 1.0f);
}

TEST(UnknownFill, AHoleBetweenTwoColoursTakesEachFromItsOwnSide) {
    const glm::vec3 red(1.0f, 0.0f, 0.0f);
    const glm::vec3 blue(0.0f, 0.0f, 1.0f);
    Canvas canvas(32, 16, red);
    for (int y = 0; y < 16; ++y) {
        for (int x = 16; x < 32; ++x) {
            canvas.paint(canvas.image.index(x, y), blue);
        }
    }
    canvas.hole(12, 0, 20, 16); // across the border, 8 pixels wide, top to bottom
    (void)fill_unknown_pixels(canvas.image, canvas.unknown, 8);
    float previous_red = 2.0f;
    for (int x = 12; x < 20; ++x) {
        const glm::vec4 p = canvas.at(x, 8);
        EXPECT_NEAR(p.x + p.z, 1.0f, 1e-5f) << x; // a mix of the two, nothing else
        EXPECT_EQ(p.y, 0.0f);
        EXPECT_LE(p.x, previous_red) << x; // redder toward the red side
        previous_red = p.x;
    }
    EXPECT_GT(canvas.at(12, 8).x, 0.5f);
    EXPECT_LT(canvas.at(19, 8).x, 0.5f);
}

// A desk's front edge (near, red) over the floor under it (far, blue), and a hole no probe saw
// along the edge: the floor continues there, so the hole takes the floor's colour only, as a
// probe's own hole fill continues the surface behind a disocclusion. The near side keeps its
// colour, and a hole whose border lies on one depth still takes each colour from its side.
TEST(UnknownFill, AHoleBesideANearEdgeIsFilledFromTheSurfaceBehind) {
    const glm::vec3 red(1.0f, 0.0f, 0.0f);
    const glm::vec3 blue(0.0f, 0.0f, 1.0f);
    for (const float far : {3.0f, 1.02f}) {
        Canvas canvas(32, 16, red);
        for (int y = 0; y < 16; ++y) {
            for (int x = 0; x < 32; ++x) {
                const std::size_t i = canvas.image.index(x, y);
                if (x >= 16) {
                    canvas.paint(i, blue);
                }
                canvas.image.depth[i] = x >= 16 ? far : 1.0f;
            }
        }
        canvas.hole(12, 0, 20, 16);
        (void)fill_unknown_pixels(canvas.image, canvas.unknown, 8);
        for (int x = 12; x < 20; ++x) {
            const glm::vec4 p = canvas.at(x, 8);
            if (far > 1.5f) {
                EXPECT_NEAR(p.z, 1.0f, 1e-6f) << x; // the floor's colour alone
                EXPECT_EQ(p.x, 0.0f) << x;
            } else {
                EXPECT_NEAR(p.x + p.z, 1.0f, 1e-5f) << x; // one depth: a mix, as before
            }
        }
        if (far <= 1.5f) {
            EXPECT_GT(canvas.at(12, 8).x, 0.5f);
            EXPECT_LT(canvas.at(19, 8).x, 0.5f);
        }
        EXPECT_EQ(canvas.at(5, 8), glm::vec4(red, 1.0f)); // the near side is not touched
    }
}

TEST(UnknownFill, ADisocclusionIsTheSmoothBlendOfTheSurfaceBehind) {
    // Under a near object (red, 1 m, the rows above), a hole 12 pixels wide in a far surface
    // (3 m) whose colour is a ramp along x: filled as a probe's disocclusions are, the harmonic
    // blend of the far border continues the ramp exactly, where the layers alone gave the
    // hole's left column the colour of the column left of it.
    const glm::vec3 red(1.0f, 0.0f, 0.0f);
    const auto ramp = [](int x) {
        return glm::vec3(0.1f + 0.02f * static_cast<float>(x), 0.5f,
                         0.9f - 0.02f * static_cast<float>(x));
    };
    Canvas canvas(40, 16, red);
    for (int y = 0; y < 16; ++y) {
        for (int x = 0; x < 40; ++x) {
            const std::size_t i = canvas.image.index(x, y);
            canvas.image.depth[i] = y < 3 ? 1.0f : 3.0f;
            if (y >= 3) {
                canvas.paint(i, ramp(x));
            }
        }
    }
    canvas.hole(12, 3, 24, 10);
    (void)fill_unknown_pixels(canvas.image, canvas.unknown, 12);
    for (int y = 3; y < 10; ++y) {
        for (int x = 12; x < 24; ++x) {
            const glm::vec4 p = canvas.at(x, y);
            EXPECT_LT(glm::length(glm::vec3(p) - ramp(x)), 2e-3f) << x << ", " << y;
            EXPECT_EQ(p.w, 1.0f);
        }
    }
}

TEST(UnknownFill, MissIsNeitherFilledNorASource) {
    Canvas canvas(24, 24, {0.8f, 0.8f, 0.8f});
    // The left third MISS (nothing there: colour 0, no unknown share), a hole beside it.
    for (int y = 0; y < 24; ++y) {
        for (int x = 0; x < 8; ++x) {
            const std::size_t i = canvas.image.index(x, y);
            for (int c = 0; c < 4; ++c) {
                canvas.image.rgba[4 * i + static_cast<std::size_t>(c)] = 0.0f;
            }
            canvas.image.status[i] = static_cast<std::uint8_t>(TraceStatus::Miss);
        }
    }
    canvas.hole(8, 8, 12, 16);
    (void)fill_unknown_pixels(canvas.image, canvas.unknown, 8);
    EXPECT_EQ(canvas.at(3, 12), glm::vec4(0.0f));
    for (int x = 8; x < 12; ++x) {
        EXPECT_NEAR(canvas.at(x, 12).x, 0.8f, 1e-6f) << x; // not darkened by the MISS beside it
    }
}

TEST(UnknownFill, AHoleWithNoHitAroundItStaysBlack) {
    Canvas canvas(8, 8, {0.5f, 0.5f, 0.5f});
    canvas.hole(0, 0, 8, 8);
    const UnknownFillStats stats = fill_unknown_pixels(canvas.image, canvas.unknown, 100);
    EXPECT_EQ(stats.pixels_left, 64u);
    EXPECT_EQ(canvas.at(4, 4), glm::vec4(0.0f));
}

TEST(UnknownFill, BadArgumentsAreClearErrors) {
    Canvas canvas(4, 4, {0.5f, 0.5f, 0.5f});
    std::vector<float> short_shares(3, 0.0f);
    EXPECT_THROW((void)fill_unknown_pixels(canvas.image, short_shares, 4), InputError);
    EXPECT_THROW((void)fill_unknown_pixels(canvas.image, canvas.unknown, -1), InputError);
    EXPECT_EQ(default_hole_fill_pixels(640, 400), 32);
    EXPECT_EQ(default_hole_fill_pixels(10, 8), 2);
}

TEST(UnknownFill, ARenderFillsOnlyUnknownPixelsAndTheSameOnAnyThreadCount) {
    // One probe with a patch of unknown texels, seen from beside the probe with a wide lens:
    // the patch is a hole in the middle of the view, the room around it.
    const testing::BoxRoomScene scene;
    const glm::dvec3 centre(0.0, 0.0, 1.2);
    const int n = 64;
    ProbePlacement placement;
    placement.positions = {centre};
    std::vector<ProbeMap> probes;
    probes.push_back(testing::analytic_probe_with_holes(scene, centre, n));
    const ProbeField field(placement, std::move(probes));
    const glm::dvec3 patch(oct::texel_direction({n / 3 + n / 12, n / 5 + n / 16}, n));
    const glm::dvec3 eye = centre + glm::dvec3(0.01, 0.0, 0.0);
    const Camera camera = Camera::look_at(eye, eye + patch, 64, 48, 12.0);
    for (const int spp : {1, 4}) {
        RenderSettings off;
        off.samples_per_pixel = spp;
        off.hole_fill_pixels = 0;
        RenderSettings on = off;
        on.hole_fill_pixels = 48; // the patch is about 30 pixels across
        RenderStats stats;
        const RenderedImage black = render_probe_view(field, camera, off);
        RenderedImage one;
        RenderedImage two;
        tbb::task_arena(1).execute(
            [&] { one = render_probe_view(field, camera, on, nullptr, &stats); });
        tbb::task_arena(2).execute([&] { two = render_probe_view(field, camera, on); });
        EXPECT_EQ(one.rgba, two.rgba);
        EXPECT_EQ(one.status, black.status);
        EXPECT_EQ(one.depth, black.depth);
        std::size_t unknown = 0;
        std::size_t changed = 0;
        for (std::size_t i = 0; i < one.pixel_count(); ++i) {
            const bool differs = one.rgba[4 * i] != black.rgba[4 * i] ||
                                 one.rgba[4 * i + 3] != black.rgba[4 * i + 3];
            changed += differs ? 1 : 0;
            if (black.rgba[4 * i + 3] == 1.0f) {
                EXPECT_FALSE(differs) << i; // every sample answered HIT: untouched
            }
            unknown += one.status[i] == static_cast<std::uint8_t>(TraceStatus::Unknown) ? 1 : 0;
        }
        std::printf("spp %d: %zu pixels UNKNOWN at their centre, %zu changed by the fill, %llu "
                    "filled, %llu left\n",
                    spp, unknown, changed, static_cast<unsigned long long>(stats.holes_filled),
                    static_cast<unsigned long long>(stats.holes_left));
        EXPECT_GT(unknown, 0u);
        EXPECT_GT(changed, 0u);
        EXPECT_GT(stats.holes_filled, 0u);
        EXPECT_EQ(stats.holes_left, 0u);
        // The default reaches 5 % of the width, 3 pixels here: the patch stays black.
        RenderSettings default_settings;
        default_settings.samples_per_pixel = spp;
        RenderStats default_stats;
        (void)render_probe_view(field, camera, default_settings, nullptr, &default_stats);
        EXPECT_GT(default_stats.holes_left, 400u);
    }
}

} // namespace
} // namespace lfprobe
