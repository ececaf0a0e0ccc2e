// The image's fidelity (docs/DESIGN.md §5): samples per pixel, the bilinear radiance
// filter and the blending of probes. Hard cases by name: a surface of one colour, a
// silhouette in front of a wall, the order of the probes, the thread count, and the paper's
// one-sample first-hit image that spp 1, nearest, blend 1, no hole fill and the first HIT
// (guess or not) must reproduce bit for bit.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>
#include <vector>

#include <Imath/half.h>
#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include "lfprobe/camera.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/probe_blend.hpp"
#include "lfprobe/radiance_filter.hpp"
#include "lfprobe/render.hpp"
#include "trace_scenes.hpp"

namespace lfprobe {
namespace {

using testing::analytic_probe;
using testing::BoxRoomScene;

// A colour as a map stores it (half floats) and reads it back.
glm::vec3 stored(const glm::vec3& c) {
    return {static_cast<float>(Imath::half(c.x)), static_cast<float>(Imath::half(c.y)),
            static_cast<float>(Imath::half(c.z))};
}

ProbePlacement grid_placement(const glm::dvec3& lo, const glm::dvec3& hi,
                              const std::array<int, 3>& counts) {
    ProbePlacement placement;
    placement.is_grid = true;
    placement.grid = ProbeGrid::spanning(lo, hi, counts);
    placement.positions = placement.grid.positions();
    return placement;
}

ProbePlacement positions_placement(const std::vector<glm::dvec3>& positions) {
    ProbePlacement placement;
    placement.positions = positions;
    return placement;
}

// The box room's probes with every texel's colour replaced by `colour`.
std::vector<ProbeMap> one_colour_probes(const ProbePlacement& placement, int n,
                                        const glm::vec3& colour) {
    const BoxRoomScene scene;
    std::vector<ProbeMap> probes;
    for (const glm::dvec3& p : placement.positions) {
        ProbeMap map = analytic_probe(scene, p, n);
        for (std::size_t i = 0; i < map.texel_count(); ++i) {
            for (int c = 0; c < 3; ++c) {
                map.rgba[4 * i + static_cast<std::size_t>(c)] = Imath::half(colour[c]);
            }
        }
        probes.push_back(std::move(map));
    }
    return probes;
}

RenderSettings fidelity(int spp, RadianceFilter filter, int blend,
                        FieldMode mode = FieldMode::Auto) {
    RenderSettings settings;
    settings.samples_per_pixel = spp;
    settings.trace.filter = filter;
    settings.trace.blend = blend;
    settings.trace.mode = mode;
    return settings;
}

TEST(Fidelity, OneColourSurfaceReadsExactlyThatColourWithAnyFiltering) {
    const glm::vec3 colour = stored({0.3f, 0.55f, 0.8f});
    const ProbePlacement placement = grid_placement({-1.0, -0.8, 0.6}, {1.0, 0.8, 1.8}, {2, 2, 2});
    const ProbeField field(placement, one_colour_probes(placement, 64, colour));
    const Camera between = Camera::look_at({-0.3, -0.2, 1.1}, {1.5, 0.7, 0.9}, 24, 16, 20.0);
    const Camera at_probe = Camera::look_at(placement.positions[5], {1.5, 0.7, 0.2}, 24, 16, 20.0);
    for (const Camera& camera : {between, at_probe}) {
        for (const int spp : {1, 4, 9}) {
            for (const RadianceFilter filter :
                 {RadianceFilter::Nearest, RadianceFilter::Bilinear, RadianceFilter::Footprint,
                  RadianceFilter::Bicubic}) {
                for (const int blend : {1, 4, 8}) {
                    const RenderedImage image =
                        render_probe_view(field, camera, fidelity(spp, filter, blend));
                    std::size_t covered = 0;
                    for (std::size_t i = 0; i < image.pixel_count(); ++i) {
                        if (image.rgba[4 * i + 3] != 1.0f) {
                            continue;
                        }
                        ++covered;
                        ASSERT_EQ(image.rgba[4 * i], colour.x) << spp << " " << blend;
                        ASSERT_EQ(image.rgba[4 * i + 1], colour.y);
                        ASSERT_EQ(image.rgba[4 * i + 2], colour.z);
                    }
                    EXPECT_GT(covered, image.pixel_count() * 9 / 10);
                }
            }
        }
    }
}

// A plate x = 1, |y|, |z| < 0.3 in front of a wall x = 3; nothing behind the probes (x < 0).
constexpr float kPlateX = 1.0f;
constexpr float kPlateHalf = 0.3f;
constexpr float kWallX = 3.0f;
const glm::vec3 kPlateColour{0.8f, 0.1f, 0.1f};
const glm::vec3 kWallColour{0.1f, 0.2f, 0.9f};

ProbeMap plate_probe(const glm::dvec3& centre, int n) {
    return testing::custom_probe(n, centre, [&](const glm::vec3& d, std::size_t i, ProbeMap& map) {
        const glm::vec3 c(centre);
        if (d.x <= 0.0f) {
            map.set_empty(i);
            return;
        }
        const float t_plate = (kPlateX - c.x) / d.x;
        const glm::vec3 on_plate = c + t_plate * d;
        if (std::abs(on_plate.y) < kPlateHalf && std::abs(on_plate.z) < kPlateHalf) {
            map.set_surface(i, t_plate, kPlateColour, {-1.0f, 0.0f, 0.0f}, 1.0f);
        } else {
            map.set_surface(i, (kWallX - c.x) / d.x, kWallColour, {-1.0f, 0.0f, 0.0f}, 1.0f);
        }
    });
}

TEST(Fidelity, BilinearBicubicAndBlendingNeverMixAForegroundAndABackgroundSurface) {
    const std::vector<glm::dvec3> centres{{0.0, 0.0, 0.0}, {0.0, 0.25, 0.05}, {0.1, -0.2, 0.1}};
    std::vector<ProbeMap> probes;
    for (const glm::dvec3& c : centres) {
        probes.push_back(plate_probe(c, 96));
    }
    const ProbeField field(positions_placement(centres), std::move(probes));
    const glm::vec3 plate = stored(kPlateColour);
    const glm::vec3 wall = stored(kWallColour);
    // From a probe's centre (one lookup a ray) and from between the probes (traced, blended),
    // looking at the plate's edge.
    const Camera cameras[] = {
        Camera::look_at(centres[0], {1.0, 0.3, 0.3}, 48, 48, 40.0),
        Camera::look_at({0.02, 0.08, 0.04}, {1.0, 0.3, -0.3}, 48, 48, 40.0),
    };
    for (const Camera& camera : cameras) {
        for (const auto& [filter, blend] :
             {std::pair{RadianceFilter::Bilinear, 1}, std::pair{RadianceFilter::Bilinear, 3},
              std::pair{RadianceFilter::Bicubic, 1}, std::pair{RadianceFilter::Bicubic, 3}}) {
            const RenderedImage image =
                render_probe_view(field, camera, fidelity(1, filter, blend, FieldMode::Nearest));
            std::size_t on_plate = 0;
            std::size_t on_wall = 0;
            for (std::size_t i = 0; i < image.pixel_count(); ++i) {
                if (image.status[i] != static_cast<std::uint8_t>(TraceStatus::Hit)) {
                    continue;
                }
                const glm::vec3 got(image.rgba[4 * i], image.rgba[4 * i + 1],
                                    image.rgba[4 * i + 2]);
                // Depth along the ray tells the surface; its colour must be that surface's alone.
                const bool front = image.depth[i] < 2.0f;
                EXPECT_EQ(got, front ? plate : wall)
                    << "pixel " << i << " depth " << image.depth[i];
                ++(front ? on_plate : on_wall);
            }
            EXPECT_GT(on_plate, 100u);
            EXPECT_GT(on_wall, 100u);
        }
    }
}

// The map coordinate of the centre of stratum s (of `per_texel`) across texel `texel` of n.
float stratum_coordinate(int texel, int s, int per_texel, int n) {
    return (static_cast<float>(texel) +
            (static_cast<float>(s) + 0.5f) / static_cast<float>(per_texel)) /
           static_cast<float>(n);
}

// The share of each texel's 4×4 stratum directions that see the texel's own surface (plate or
// wall), as a mesh bake's coverage.
void set_plate_coverage(ProbeMap& map) {
    const int n = map.resolution;
    const glm::dvec3 c = map.position;
    const auto plate = [&](const glm::dvec3& d) {
        const glm::dvec3 p = c + ((kPlateX - c.x) / d.x) * d;
        return std::abs(p.y) < kPlateHalf && std::abs(p.z) < kPlateHalf;
    };
    map.coverage.assign(map.texel_count(), Imath::half(1.0f));
    for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
            const std::size_t i = oct::texel_index({x, y}, n);
            if (!std::isfinite(map.distance[i])) {
                continue;
            }
            const bool own = plate(glm::dvec3(oct::texel_direction({x, y}, n)));
            int same = 0;
            for (int sy = 0; sy < 4; ++sy) {
                for (int sx = 0; sx < 4; ++sx) {
                    const glm::vec2 uv{stratum_coordinate(x, sx, 4, n),
                                       stratum_coordinate(y, sy, 4, n)};
                    const glm::dvec3 d(oct::decode(uv));
                    same += d.x > 0.0 && plate(d) == own ? 1 : 0;
                }
            }
            map.coverage[i] = Imath::half(static_cast<float>(same) / 16.0f);
        }
    }
}

TEST(Fidelity, ASilhouetteSeenFromTheProbeIsCutAtTheRaysDirectionNotAtTheTexels) {
    // From the probe's centre, 4×4 samples a pixel over the plate's corner: a coarse probe's
    // pixels against those of a probe 8 times as fine (its edges within an eighth of the coarse
    // texel). The texel a ray falls in cuts the plate's slanted edges in steps a texel high;
    // the surface with most of the bilinear weight around the ray follows the edge closer.
    const glm::dvec3 centre{0.0, 0.0, 0.0};
    const Camera camera = Camera::look_at(centre, {1.0, 0.27, 0.25}, 40, 40, 60.0);
    const auto view = [&](int n, RadianceFilter filter, bool with_coverage = false) {
        std::vector<ProbeMap> probes;
        probes.push_back(plate_probe(centre, n));
        if (with_coverage) {
            set_plate_coverage(probes.back());
        }
        const ProbeField field(positions_placement({centre}), std::move(probes));
        return render_probe_view(field, camera, fidelity(16, filter, 1, FieldMode::Nearest));
    };
    const RenderedImage fine = view(512, RadianceFilter::Nearest);
    const auto error = [&](const RenderedImage& image) {
        double sum = 0.0;
        for (std::size_t i = 0; i < image.pixel_count(); ++i) {
            sum += std::abs(image.rgba[4 * i] - fine.rgba[4 * i]);
        }
        return sum / static_cast<double>(image.pixel_count());
    };
    const double nearest = error(view(64, RadianceFilter::Nearest));
    const double bilinear = error(view(64, RadianceFilter::Bilinear));
    const double bicubic = error(view(64, RadianceFilter::Bicubic));
    // With each texel's coverage (as a mesh bake measures it), the edge is placed inside the
    // texel.
    const double covered = error(view(64, RadianceFilter::Bilinear, true));
    std::printf("plate edge, mean |red - fine red|: nearest %.5f, bilinear %.5f, bicubic %.5f, "
                "bilinear with coverage %.5f\n",
                nearest, bilinear, bicubic, covered);
    EXPECT_GT(nearest, 0.005);          // the edge crosses enough pixels to measure
    EXPECT_LT(bilinear, 0.9 * nearest); // measured 0.85×
    EXPECT_LT(bicubic, 0.9 * nearest);
    EXPECT_LT(covered, 0.5 * nearest);
    // Nearest stays the paper's texel, coverage or not.
    EXPECT_EQ(view(64, RadianceFilter::Nearest).rgba, view(64, RadianceFilter::Nearest, true).rgba);
}

TEST(Fidelity, BlendingIsOrderIndependentAndBitIdenticalForOneAndTwoThreads) {
    const BoxRoomScene scene;
    const ProbePlacement grid = grid_placement({-1.2, -0.9, 0.6}, {1.2, 0.9, 1.9}, {3, 2, 2});
    const ProbeField field = testing::analytic_field(scene, grid, 64);
    const Camera camera = Camera::look_at({-0.5, -0.3, 1.1}, {1.6, 0.9, 0.7}, 40, 30, 24.0);
    const RenderSettings settings = fidelity(4, RadianceFilter::Bilinear, 8);
    const RenderedImage one =
        tbb::task_arena(1).execute([&] { return render_probe_view(field, camera, settings); });
    const RenderedImage two =
        tbb::task_arena(2).execute([&] { return render_probe_view(field, camera, settings); });
    EXPECT_EQ(one.rgba, two.rgba);
    EXPECT_EQ(one.depth, two.depth);
    EXPECT_EQ(one.steps, two.steps);
    // Blending changed the colour somewhere: the test measures something.
    const RenderedImage first_hit =
        render_probe_view(field, camera, fidelity(4, RadianceFilter::Bilinear, 1));
    EXPECT_NE(one.rgba, first_hit.rgba);

    // The same probes listed in another order (a set that is not a grid, nearest first): the
    // same probes answer and blend, so every colour is the same, bit for bit.
    std::vector<glm::dvec3> forward = grid.positions;
    std::vector<glm::dvec3> backward(forward.rbegin(), forward.rend());
    std::rotate(backward.begin(), backward.begin() + 5, backward.end());
    const RenderSettings nearest = fidelity(4, RadianceFilter::Bilinear, 4, FieldMode::Nearest);
    const RenderedImage a = render_probe_view(
        testing::analytic_field(scene, positions_placement(forward), 64), camera, nearest);
    const RenderedImage b = render_probe_view(
        testing::analytic_field(scene, positions_placement(backward), 64), camera, nearest);
    EXPECT_EQ(a.rgba, b.rgba);
    EXPECT_EQ(a.depth, b.depth);
    EXPECT_EQ(a.status, b.status);
}

// A wall x = 3 painted in stripes 8 cm wide along y: finer than the pixels of a small view, so
// one sample per pixel aliases unless the lookup averages what the pixel covers.
ProbeMap striped_wall_probe(int n) {
    return testing::custom_probe(
        n, glm::dvec3(0.0), [](const glm::vec3& d, std::size_t i, ProbeMap& map) {
            if (d.x <= 0.0f) {
                map.set_empty(i);
                return;
            }
            const float t = 3.0f / d.x;
            const bool light = static_cast<int>(std::floor(t * d.y / 0.08f)) % 2 == 0;
            map.set_surface(i, t, light ? glm::vec3(0.9f) : glm::vec3(0.1f), {-1.0f, 0.0f, 0.0f},
                            1.0f);
        });
}

TEST(Fidelity, FootprintFilterAntiAliasesOneSamplePerPixel) {
    std::vector<ProbeMap> probes;
    probes.push_back(striped_wall_probe(512));
    const ProbeField field(positions_placement({glm::dvec3(0.0)}), std::move(probes));
    // The eye at the probe: every pixel one lookup, ~4 texels wide at the wall.
    const Camera camera = Camera::look_at({0.0, 0.0, 0.0}, {1.0, 0.15, 0.05}, 48, 32, 24.0);
    const RenderedImage reference =
        render_probe_view(field, camera, fidelity(64, RadianceFilter::Bilinear, 1));
    auto error = [&](const RenderedImage& image) {
        double sum = 0.0;
        for (std::size_t i = 0; i < image.pixel_count(); ++i) {
            sum += std::abs(image.rgba[4 * i] - reference.rgba[4 * i]);
        }
        return sum / static_cast<double>(image.pixel_count());
    };
    const double bilinear =
        error(render_probe_view(field, camera, fidelity(1, RadianceFilter::Bilinear, 1)));
    const double footprint =
        error(render_probe_view(field, camera, fidelity(1, RadianceFilter::Footprint, 1)));
    EXPECT_GT(bilinear, 0.1);             // the stripes alias at one sample per pixel
    EXPECT_LT(footprint, 0.5 * bilinear); // the footprint's average is near the 8×8 mean
    // A footprint narrower than a texel (64 samples per pixel) reads as bilinear, bit for bit.
    const RenderedImage fine =
        render_probe_view(field, camera, fidelity(64, RadianceFilter::Footprint, 1));
    EXPECT_EQ(fine.rgba, reference.rgba);
}

TEST(Fidelity, OneSampleNearestFirstHitIsThePapersImageBitForBit) {
    // The image before filtering and blending existed: one ray through each pixel centre, the
    // colour of the texel the first answering probe met.
    const BoxRoomScene scene;
    const ProbePlacement grid = grid_placement({-1.2, -0.9, 0.6}, {1.2, 0.9, 1.9}, {3, 2, 2});
    const ProbeField field = testing::analytic_field(scene, grid, 64);
    const Camera cameras[] = {Camera::look_at({-0.5, -0.3, 1.1}, {1.6, 0.9, 0.7}, 32, 24, 24.0),
                              Camera::look_at(grid.positions[4], {1.6, 0.9, 0.7}, 32, 24, 24.0)};
    for (const Camera& camera : cameras) {
        for (const FieldMode mode : {FieldMode::Grid, FieldMode::Nearest}) {
            // The paper's image: no hole fill either (an UNKNOWN pixel stays black).
            RenderSettings paper = fidelity(1, RadianceFilter::Nearest, 1, mode);
            paper.hole_fill_pixels = 0;
            paper.trace.prefer_measured = false;
            const RenderedImage image = render_probe_view(field, camera, paper);
            FieldTraceSettings visibility;
            visibility.mode = mode;
            visibility.prefer_measured = false;
            for (int y = 0; y < camera.height; ++y) {
                for (int x = 0; x < camera.width; ++x) {
                    const std::size_t i = image.index(x, y);
                    const Ray ray = camera.local_pixel_ray(x, y, field.world_offset());
                    const FieldTraceResult r = mode == FieldMode::Grid
                                                   ? field.trace_grid(ray, visibility)
                                                   : field.trace_nearest(ray, visibility);
                    ASSERT_EQ(image.status[i], static_cast<std::uint8_t>(r.status));
                    if (r.status != TraceStatus::Hit) {
                        for (int c = 0; c < 4; ++c) {
                            EXPECT_EQ(image.rgba[4 * i + static_cast<std::size_t>(c)], 0.0f);
                        }
                        continue;
                    }
                    EXPECT_EQ(image.rgba[4 * i], r.radiance.x);
                    EXPECT_EQ(image.rgba[4 * i + 1], r.radiance.y);
                    EXPECT_EQ(image.rgba[4 * i + 2], r.radiance.z);
                    EXPECT_EQ(image.rgba[4 * i + 3], 1.0f);
                    EXPECT_EQ(image.depth[i], static_cast<float>(r.t));
                }
            }
        }
    }
}

TEST(Fidelity, SamplesPerPixelAverageTheGroundTruthsStrata) {
    const BoxRoomScene scene;
    const ProbePlacement grid = grid_placement({-1.2, -0.9, 0.6}, {1.2, 0.9, 1.9}, {3, 2, 2});
    const ProbeField field = testing::analytic_field(scene, grid, 64);
    const Camera camera = Camera::look_at({-0.5, -0.3, 1.1}, {1.6, 0.9, 0.7}, 20, 14, 24.0);
    for (const int n : {2, 3}) {
        RenderStats stats;
        const RenderedImage image = render_probe_view(
            field, camera, fidelity(n * n, RadianceFilter::Bilinear, 4), nullptr, &stats);
        const RenderedImage centre =
            render_probe_view(field, camera, fidelity(1, RadianceFilter::Bilinear, 4));
        // Each stratum on its own: a one-sample image at that offset.
        std::vector<RenderedImage> strata;
        for (int sy = 0; sy < n; ++sy) {
            for (int sx = 0; sx < n; ++sx) {
                RenderSettings s = fidelity(1, RadianceFilter::Bilinear, 4);
                s.sample_x = stratum_centre(sx, n);
                s.sample_y = stratum_centre(sy, n);
                strata.push_back(render_probe_view(field, camera, s));
            }
        }
        for (std::size_t i = 0; i < image.pixel_count(); ++i) {
            glm::vec3 sum{0.0f};
            float hits = 0.0f;
            for (const RenderedImage& s : strata) {
                sum += glm::vec3(s.rgba[4 * i], s.rgba[4 * i + 1], s.rgba[4 * i + 2]);
                hits += s.rgba[4 * i + 3];
            }
            const float samples = static_cast<float>(n * n);
            EXPECT_EQ(image.rgba[4 * i + 3], hits / samples);
            EXPECT_NEAR(image.rgba[4 * i], sum.x / samples, 1e-5f);
            EXPECT_NEAR(image.rgba[4 * i + 1], sum.y / samples, 1e-5f);
            // Depth and status are the pixel centre's.
            EXPECT_EQ(image.status[i], centre.status[i]);
            EXPECT_EQ(image.depth[i], centre.depth[i]);
        }
        const std::uint64_t per_pixel = n % 2 == 1 ? n * n : n * n + 1;
        EXPECT_EQ(stats.rays, image.pixel_count() * per_pixel);
    }
    EXPECT_THROW((void)render_probe_view(field, camera, fidelity(3, RadianceFilter::Nearest, 1)),
                 InputError);
    EXPECT_THROW((void)render_probe_view(field, camera, fidelity(1, RadianceFilter::Nearest, 9)),
                 InputError);
    EXPECT_THROW((void)radiance_filter_from_name("lanczos"), InputError);
}

} // namespace
} // namespace lfprobe
