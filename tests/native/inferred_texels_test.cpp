// A HIT on a hole-filled (inferred) texel is a probe's guess (FieldTraceSettings::
// prefer_measured): another probe that measured the point wins, the guess answers where none
// did, an eye at the guessing probe keeps its own lookup, and prefer_measured false is the
// first-hit rule.
#include <cmath>
#include <cstddef>
#include <vector>

#include <Imath/half.h>
#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "lfprobe/camera.hpp"
#include "lfprobe/octahedral.hpp"
#include "lfprobe/render.hpp"
#include "trace_scenes.hpp"

namespace lfprobe {
namespace {

using testing::analytic_probe;
using testing::BoxRoomScene;

const glm::vec3 kGuess(1.0f, 0.0f, 1.0f); // the inferred texels' colour, nowhere in the room

// Probe `map`'s texels within `cone` radians of `direction` turned into guesses: the same
// surface, another colour, confidence 0.5 (inferred).
void guess_around(ProbeMap& map, const glm::vec3& direction, float cone) {
    const int n = map.resolution;
    for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
            const std::size_t i = oct::texel_index({x, y}, n);
            if (glm::dot(oct::texel_direction({x, y}, n), direction) < std::cos(cone)) {
                continue;
            }
            map.set_surface(i, map.distance_at(i), kGuess, map.normal_at(i), 0.5f);
        }
    }
}

// Pixels whose colour is the guess's.
std::size_t guessed_pixels(const RenderedImage& image) {
    std::size_t count = 0;
    for (std::size_t i = 0; i < image.pixel_count(); ++i) {
        count += image.rgba[4 * i] == 1.0f && image.rgba[4 * i + 1] == 0.0f &&
                         image.rgba[4 * i + 2] == 1.0f && image.status[i] == 1
                     ? 1
                     : 0;
    }
    return count;
}

RenderSettings first_hit(bool prefer_measured) {
    RenderSettings s;
    s.trace.mode = FieldMode::Nearest;
    s.trace.filter = RadianceFilter::Nearest;
    s.trace.blend = 1;
    s.trace.prefer_measured = prefer_measured;
    return s;
}

struct TwoProbes {
    BoxRoomScene scene;
    glm::dvec3 a{-0.6, 0.0, 1.2};
    glm::dvec3 b{0.2, -0.4, 1.2};
    glm::dvec3 wall_point{-2.0, 0.3, 1.0}; // on the wall x = -2, which both probes see
    ProbePlacement placement;

    TwoProbes() { placement.positions = {a, b}; }
    [[nodiscard]] ProbeField field(bool b_knows) const {
        std::vector<ProbeMap> probes;
        probes.push_back(analytic_probe(scene, a, 64));
        guess_around(probes.back(), glm::normalize(glm::vec3(wall_point - a)), 0.35f);
        probes.push_back(analytic_probe(scene, b, 64));
        if (!b_knows) {
            // b never saw that wall: its texels toward it are unknown.
            guess_around(probes.back(), glm::normalize(glm::vec3(wall_point - b)), 0.6f);
            ProbeMap& m = probes.back();
            for (std::size_t i = 0; i < m.texel_count(); ++i) {
                if (static_cast<float>(m.rgba[4 * i + 3]) < 1.0f) {
                    m.set_unknown(i);
                }
            }
        }
        return ProbeField(placement, std::move(probes));
    }
};

TEST(InferredTexels, AnotherProbesMeasurementBeatsAGuessAndTheGuessAnswersWhereNoneDoes) {
    const TwoProbes setup;
    // Beside probe a, nearer to it than to b, looking at the guessed patch of the wall.
    const glm::dvec3 eye = setup.a + glm::dvec3(0.05, 0.02, 0.0);
    const Camera camera = Camera::look_at(eye, setup.wall_point, 48, 32, 30.0);
    const ProbeField measured_by_b = setup.field(true);
    const RenderedImage first = render_probe_view(measured_by_b, camera, first_hit(false));
    const RenderedImage preferred = render_probe_view(measured_by_b, camera, first_hit(true));
    EXPECT_GT(guessed_pixels(first), first.pixel_count() / 4); // a, asked first, guessed
    EXPECT_EQ(guessed_pixels(preferred), 0u);                  // b measured it
    EXPECT_EQ(first.status, preferred.status);
    for (std::size_t i = 0; i < first.pixel_count(); ++i) {
        // The same wall (within 5 %, the wrong-surface rule), each probe placing it within its
        // texel (a 64² map: 9 cm at 1.6 m).
        EXPECT_NEAR(first.depth[i], preferred.depth[i], 0.05f * first.depth[i]) << i;
    }

    // b never saw the wall: the guess answers (a HIT, not UNKNOWN), with or without waiting.
    const ProbeField unseen_by_b = setup.field(false);
    const RenderedImage guessed = render_probe_view(unseen_by_b, camera, first_hit(true));
    EXPECT_EQ(guessed_pixels(guessed),
              guessed_pixels(render_probe_view(unseen_by_b, camera, first_hit(false))));
    EXPECT_GT(guessed_pixels(guessed), guessed.pixel_count() / 4);
    for (std::size_t i = 0; i < guessed.pixel_count(); ++i) {
        EXPECT_EQ(guessed.status[i], 1) << i;
    }
}

TEST(InferredTexels, AnEyeAtTheGuessingProbeKeepsItsOwnLookup) {
    const TwoProbes setup;
    const Camera camera = Camera::look_at(setup.a, setup.wall_point, 48, 32, 30.0);
    const ProbeField field = setup.field(true);
    const RenderedImage preferred = render_probe_view(field, camera, first_hit(true));
    const RenderedImage first = render_probe_view(field, camera, first_hit(false));
    EXPECT_EQ(preferred.rgba, first.rgba);
    EXPECT_GT(guessed_pixels(preferred), preferred.pixel_count() / 4);
}

// The render's guessed channel marks exactly the pixels a guess answers: with the nearest texel
// and no blending, those whose colour is the guess's; where another probe measured the point
// (prefer_measured), none.
TEST(InferredTexels, TheGuessedChannelMarksThePixelsAGuessAnswers) {
    const TwoProbes setup;
    const Camera camera = Camera::look_at(setup.a, setup.wall_point, 48, 32, 30.0);
    for (const bool b_knows : {false, true}) {
        const ProbeField field = setup.field(b_knows);
        RenderStats stats;
        const RenderedImage at_a =
            render_probe_view(field, camera, first_hit(true), nullptr, &stats);
        ASSERT_EQ(at_a.guessed.size(), at_a.pixel_count());
        std::size_t marked = 0;
        for (std::size_t i = 0; i < at_a.pixel_count(); ++i) {
            const bool guess_colour = at_a.status[i] == 1 && at_a.rgba[4 * i] == 1.0f &&
                                      at_a.rgba[4 * i + 1] == 0.0f && at_a.rgba[4 * i + 2] == 1.0f;
            EXPECT_EQ(at_a.guessed[i], guess_colour ? 1 : 0) << i;
            marked += at_a.guessed[i];
        }
        EXPECT_GT(marked, at_a.pixel_count() / 4);
        EXPECT_EQ(stats.guessed, marked); // the count the CLI and F12 report
    }
    // An eye beside probe a, off its centre: where b measured the wall, b answers and nothing
    // is a guess; where b never saw it, a's guesses answer and are marked.
    const Camera beside =
        Camera::look_at(setup.a + glm::dvec3(0.1, 0.05, 0.0), setup.wall_point, 48, 32, 30.0);
    const RenderedImage measured = render_probe_view(setup.field(true), beside, first_hit(true));
    const RenderedImage guessed = render_probe_view(setup.field(false), beside, first_hit(true));
    std::size_t measured_marks = 0;
    std::size_t guessed_marks = 0;
    for (std::size_t i = 0; i < measured.pixel_count(); ++i) {
        measured_marks += measured.guessed[i];
        guessed_marks += guessed.guessed[i];
    }
    EXPECT_EQ(measured_marks, 0u);
    EXPECT_GT(guessed_marks, guessed.pixel_count() / 4);
}

} // namespace
} // namespace lfprobe
