// Rendering views against a probe field (docs/DESIGN.md §4): accuracy against an analytic scene for
// probes baked from a dense cloud, determinism over thread counts, EXR output, progress and
// cancellation.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iterator>
#include <random>
#include <vector>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <tbb/task_arena.h>

#include "lfprobe/cloud_bake.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/image_exr.hpp"
#include "lfprobe/probe_bake.hpp"
#include "lfprobe/probe_exr.hpp"
#include "lfprobe/probe_lookup.hpp"
#include "lfprobe/probe_set.hpp"
#include "lfprobe/radiance_filter.hpp"
#include "lfprobe/render.hpp"
#include "trace_scenes.hpp"

using namespace lfprobe;
using lfprobe::testing::BoxRoomScene;
namespace scenes = lfprobe::testing;

namespace {

// Probes baked from a dense cloud of the box room: 2×2×2 probes at 256², built once.
const ProbeField& baked_box_room() {
    static const ProbeField field = [] {
        const BoxRoomScene scene;
        PointCloud cloud = scene.cloud(0.01f, glm::dvec3(0.0, 0.0, 1.2));
        // The synthetic cloud holds points no single scanner could see (the far side of the
        // sphere): let each probe orient normals toward itself instead.
        cloud.scans[0].has_scanner = false;
        const LocalGeometry geometry = estimate_local_geometry(cloud, {});
        const ProbeGrid grid = ProbeGrid::spanning({-1.0, -0.6, 0.7}, {0.6, 0.6, 1.7}, {2, 2, 2});
        const ProbePlacement placement = ProbePlacement::from_grid(grid);
        BakeSettings bake;
        bake.resolution = 256;
        std::vector<ProbeMap> probes;
        for (const glm::dvec3& p : placement.positions) {
            probes.push_back(bake_probe_from_cloud(cloud, geometry, p, bake));
        }
        return ProbeField(placement, std::move(probes));
    }();
    return field;
}

struct ViewErrors {
    double hole_rate = 0.0;    // pixels the scene hits but the probes did not
    double median_error = 0.0; // |Z − exact distance| over hits
    double p95_error = 0.0;
    double far_off_rate = 0.0; // hits more than 10 cm off, over all pixels
    double colour_ok = 0.0;    // hits whose colour is within 0.1 of the scene's
};

ViewErrors compare_with_scene(const RenderedImage& image, const Camera& camera,
                              const BoxRoomScene& scene) {
    std::vector<double> errors;
    std::size_t holes = 0;
    std::size_t far_off = 0;
    std::size_t colour_ok = 0;
    for (int y = 0; y < image.height; ++y) {
        for (int x = 0; x < image.width; ++x) {
            const Ray ray = camera.pixel_ray(x, y);
            const glm::vec3 o(ray.origin);
            const glm::vec3 d(ray.direction);
            const double exact = static_cast<double>(scene.distance(o, d));
            const std::size_t i = image.index(x, y);
            if (image.status[i] != static_cast<std::uint8_t>(TraceStatus::Hit)) {
                ++holes;
                continue;
            }
            const double error = std::abs(static_cast<double>(image.depth[i]) - exact);
            errors.push_back(error);
            far_off += error > 0.1 ? 1 : 0;
            const glm::vec3 expected = BoxRoomScene::colour_at(o + static_cast<float>(exact) * d);
            const glm::vec3 got(image.rgba[4 * i], image.rgba[4 * i + 1], image.rgba[4 * i + 2]);
            colour_ok += glm::length(got - expected) < 0.1f ? 1 : 0;
        }
    }
    std::sort(errors.begin(), errors.end());
    const double pixels = static_cast<double>(image.pixel_count());
    ViewErrors e;
    e.hole_rate = static_cast<double>(holes) / pixels;
    e.far_off_rate = static_cast<double>(far_off) / pixels;
    if (!errors.empty()) {
        e.median_error = errors[errors.size() / 2];
        e.p95_error = errors[errors.size() * 95 / 100];
        e.colour_ok = static_cast<double>(colour_ok) / static_cast<double>(errors.size());
    }
    return e;
}

bool same_bits(const RenderedImage& a, const RenderedImage& b) {
    auto same = [](const auto& x, const auto& y) {
        return x.size() == y.size() &&
               std::memcmp(x.data(), y.data(), x.size() * sizeof(x[0])) == 0;
    };
    return a.width == b.width && a.height == b.height && same(a.rgba, b.rgba) &&
           same(a.depth, b.depth) && same(a.normal, b.normal) && same(a.status, b.status) &&
           same(a.probe, b.probe) && same(a.steps, b.steps);
}

} // namespace

TEST(Render, BakedBoxRoomAtBetweenAndOutsideTheProbes) {
    const BoxRoomScene scene;
    const ProbeField& field = baked_box_room();
    const glm::dvec3 sphere(scene.sphere_centre);
    struct View {
        const char* name;
        Camera camera;
        double max_hole_rate;
        double max_median_error;
        double max_far_off_rate;
    };
    // Bounds from measured figures with margin. Behind the sphere the probes cannot see what
    // the camera sees (its near side and the floor in its shadow): holes there are right.
    const std::vector<View> views{
        {"at a probe", Camera::look_at(field.probe(0).position, sphere, 160, 120, 20.0), 0.005,
         0.01, 0.02},
        {"between probes",
         Camera::look_at({-0.2, 0.0, 1.2}, sphere + glm::dvec3(0.3, 0.6, 0.0), 160, 120, 20.0),
         0.01, 0.005, 0.015},
        {"outside the grid", Camera::look_at({1.7, -1.2, 2.0}, {-1.0, 0.5, 0.8}, 160, 120, 20.0),
         0.08, 0.01, 0.05},
        {"outside, behind the sphere",
         Camera::look_at({1.8, 1.3, 0.5}, {-1.5, -1.0, 1.5}, 160, 120, 20.0), 0.4, 0.01, 0.06},
    };
    for (const View& v : views) {
        RenderStats stats;
        const RenderedImage image = render_probe_view(field, v.camera, {}, nullptr, &stats);
        const ViewErrors e = compare_with_scene(image, v.camera, scene);
        std::printf("%-28s hole rate %.4f, depth error median %.4f m, 95%% %.4f m, hits off by "
                    "> 10 cm %.4f, colour ok %.4f; %.1f steps and %.2f probes per ray, "
                    "%.0f rays/s\n",
                    v.name, e.hole_rate, e.median_error, e.p95_error, e.far_off_rate, e.colour_ok,
                    stats.mean_steps(), stats.mean_probes(), stats.rays_per_second());
        EXPECT_LE(e.hole_rate, v.max_hole_rate) << v.name;
        EXPECT_LE(e.median_error, v.max_median_error) << v.name;
        EXPECT_LE(e.far_off_rate, v.max_far_off_rate) << v.name;
        EXPECT_GT(e.colour_ok, 0.9) << v.name;
        EXPECT_EQ(stats.rays, image.pixel_count());
    }
}

TEST(Render, BitIdenticalForOneAndTwoThreads) {
    const BoxRoomScene scene;
    const ProbeGrid grid = ProbeGrid::spanning({-1.0, -0.6, 0.7}, {1.0, 0.6, 1.7}, {3, 2, 2});
    const ProbeField field = scenes::analytic_field(scene, ProbePlacement::from_grid(grid), 64);
    const Camera camera = Camera::look_at({1.6, -1.1, 1.9}, {-0.5, 0.3, 0.9}, 96, 64, 18.0);
    RenderSettings settings;
    settings.tile_size = 8;
    RenderedImage one;
    RenderedImage two;
    tbb::task_arena(1).execute([&] { one = render_probe_view(field, camera, settings); });
    tbb::task_arena(2).execute([&] { two = render_probe_view(field, camera, settings); });
    EXPECT_TRUE(same_bits(one, two));
    // And nearest-first tracing, another tile size.
    settings.trace.mode = FieldMode::Nearest;
    settings.tile_size = 13;
    tbb::task_arena(1).execute([&] { one = render_probe_view(field, camera, settings); });
    tbb::task_arena(2).execute([&] { two = render_probe_view(field, camera, settings); });
    EXPECT_TRUE(same_bits(one, two));
}

TEST(Render, ExrRoundTripIsExactAndAtomic) {
    const BoxRoomScene scene = scenes::empty_box_room();
    const ProbeGrid grid = ProbeGrid::spanning({-0.5, -0.5, 1.0}, {0.5, 0.5, 1.0}, {2, 2, 1});
    const ProbeField field = scenes::analytic_field(scene, ProbePlacement::from_grid(grid), 48);
    Camera camera = Camera::look_at({2.5, 0.0, 1.2}, {0.0, 0.0, 1.2}, 40, 30, 25.0);
    RenderStats stats;
    const RenderedImage image = render_probe_view(field, camera, {}, nullptr, &stats);
    // The camera stands outside the room: every ray starts behind the wall x = 2.
    EXPECT_EQ(stats.unknown, stats.rays);

    camera = Camera::look_at({1.5, 0.0, 1.2}, {0.0, 0.0, 1.2}, 40, 30, 25.0);
    RenderedImage inside = render_probe_view(field, camera, {}, nullptr, &stats);
    EXPECT_EQ(stats.hits, stats.rays);
    const std::filesystem::path folder =
        std::filesystem::temp_directory_path() /
        ("lfprobe_render_test_" + std::to_string(std::random_device{}()));
    std::filesystem::create_directories(folder);
    const std::string path = (folder / "view.exr").string();
    write_rendered_exr(path, inside, R"({"note": "test"})");
    write_rendered_exr(path, image); // replaces it whole
    write_rendered_exr(path, inside, R"({"note": "test"})");
    std::string metadata;
    const RenderedImage back = read_rendered_exr(path, &metadata);
    EXPECT_TRUE(same_bits(back, inside));
    EXPECT_EQ(metadata, R"({"note": "test"})");
    std::size_t files = 0;
    for (const auto& entry : std::filesystem::directory_iterator(folder)) {
        (void)entry;
        ++files;
    }
    EXPECT_EQ(files, 1u); // no temporary left behind
    EXPECT_THROW((void)read_rendered_exr((folder / "missing.exr").string()), IoError);
    std::filesystem::remove_all(folder);
}

TEST(Render, ProgressCountsPixelsAndCancellationStops) {
    const BoxRoomScene scene;
    const ProbeField field = scenes::analytic_field(
        scene, ProbePlacement::from_positions({glm::dvec3(0.0, 0.0, 1.2)}), 32);
    const Camera camera = Camera::look_at({0.5, 0.1, 1.0}, {-1.0, 0.0, 1.2}, 50, 40, 30.0);
    Progress progress;
    RenderSettings settings;
    settings.tile_size = 7;
    (void)render_probe_view(field, camera, settings, &progress);
    EXPECT_EQ(progress.fraction(), 1.0);
    Progress cancelled;
    cancelled.request_cancel();
    EXPECT_THROW((void)render_probe_view(field, camera, settings, &cancelled), Cancelled);
    settings.tile_size = 0;
    EXPECT_THROW((void)render_probe_view(field, camera, settings), InputError);
}

TEST(Render, CoarseLevelsChangeNothingButTheStepCount) {
    const ProbeField& field = baked_box_room();
    const Camera camera = Camera::look_at({1.7, -1.2, 2.0}, {-1.0, 0.5, 0.8}, 120, 90, 20.0);
    RenderSettings with;
    RenderSettings without;
    without.trace.probe.use_coarse_levels = false;
    RenderStats a;
    RenderStats b;
    const RenderedImage image_with = render_probe_view(field, camera, with, nullptr, &a);
    const RenderedImage image_without = render_probe_view(field, camera, without, nullptr, &b);
    EXPECT_EQ(image_with.rgba, image_without.rgba);
    EXPECT_EQ(image_with.depth, image_without.depth);
    EXPECT_EQ(image_with.status, image_without.status);
    EXPECT_EQ(image_with.probe, image_without.probe);
    std::printf("256² probes, view from outside the grid: %.1f texels per ray with coarse "
                "levels, %.1f without; %.0f vs %.0f rays/s\n",
                a.mean_steps(), b.mean_steps(), a.rays_per_second(), b.rays_per_second());
    EXPECT_LT(a.mean_steps(), b.mean_steps());
}

TEST(Render, FromAProbeSetFolderAndACameraFileToAnExr) {
    const BoxRoomScene room;
    const std::filesystem::path folder =
        std::filesystem::temp_directory_path() /
        ("lfprobe_render_folder_test_" + std::to_string(std::random_device{}()));
    const PointCloud cloud = room.cloud(0.05f, glm::dvec3(0.0, 0.0, 1.2));
    BakeSettings bake;
    bake.resolution = 32;
    (void)bake_probe_set_from_cloud(cloud,
                                    ProbePlacement::from_grid(ProbeGrid::spanning(
                                        {-0.5, 0.0, 1.2}, {0.5, 0.0, 1.2}, {2, 1, 1})),
                                    bake, {}, (folder / "probes").string(),
                                    nlohmann::json::array());
    const Camera camera = Camera::look_at({0.0, -1.0, 1.3}, {0.0, 1.0, 1.0}, 24, 16, 20.0);
    const std::string camera_path = (folder / "camera.json").string();
    write_file_atomically(camera_path, camera.to_json().dump());
    const std::string out = (folder / "view.exr").string();
    const RenderStats stats = render_probe_set_to_exr((folder / "probes").string(),
                                                      read_camera_json(camera_path), {}, {}, out);
    EXPECT_EQ(stats.rays, 24u * 16u);
    EXPECT_GT(stats.hits, stats.rays / 2);
    std::string metadata;
    const RenderedImage image = read_rendered_exr(out, &metadata);
    EXPECT_EQ(image.width, 24);
    const nlohmann::json m = nlohmann::json::parse(metadata);
    EXPECT_EQ(m.at("stats").at("hits").get<std::uint64_t>(), stats.hits);
    EXPECT_EQ(m.at("settings").at("mode"), "auto");
    EXPECT_EQ(m.at("renderer"), "lfprobe probe trace");
    EXPECT_EQ(m.at("probes"), (folder / "probes").string());
    EXPECT_EQ(m.at("resolved_mode"), "grid");
    EXPECT_TRUE(m.contains("storage") && m.contains("memory_bytes") && m.contains("camera"));

    // A field loaded once and rendered to a file (the add-on's batch render) writes the same
    // metadata as the folder-to-file render (the command line), timings aside.
    const ProbeField field = ProbeField::load((folder / "probes").string());
    const std::string again = (folder / "again.exr").string();
    (void)render_probe_view_to_exr(field, camera, {}, again);
    std::string metadata_again;
    (void)read_rendered_exr(again, &metadata_again);
    nlohmann::json a = nlohmann::json::parse(metadata_again);
    nlohmann::json b = m;
    for (nlohmann::json* j : {&a, &b}) {
        (*j)["stats"].erase("seconds");
        (*j)["stats"].erase("rays_per_second");
    }
    EXPECT_EQ(a, b);
    std::filesystem::remove_all(folder);
}

TEST(Render, AnEyeApproachingAProbeConvergesToItsLookupEdgeRuleIncluded) {
    // The edge rule reads a silhouette at the eye probe's centre at finer than a texel; a ray
    // traced from an eye a micrometre away must see the same edges, or the image jumps as the
    // eye reaches the probe (the report's "eye approaching a probe").
    const ProbeField& field = baked_box_room();
    const glm::dvec3 eye = field.probe(3).position + field.world_offset();
    const glm::dvec3 ahead = glm::dvec3(-1.0, 0.4, -0.2);
    const glm::dvec3 nudge = 1e-6 * glm::normalize(glm::dvec3(1.0, 0.7, 0.3));
    RenderSettings settings;
    settings.trace.blend = 1;
    settings.trace.filter = RadianceFilter::Bilinear;
    const RenderedImage at =
        render_probe_view(field, Camera::look_at(eye, eye + ahead, 64, 48, 18.0), settings);
    const RenderedImage near = render_probe_view(
        field, Camera::look_at(eye + nudge, eye + nudge + ahead, 64, 48, 18.0), settings);
    float worst = 0.0f;
    for (std::size_t i = 0; i < at.pixel_count(); ++i) {
        ASSERT_EQ(at.status[i], near.status[i]) << i;
        for (int c = 0; c < 3; ++c) {
            worst = std::max(worst, std::abs(at.rgba[4 * i + c] - near.rgba[4 * i + c]));
        }
    }
    EXPECT_LT(worst, 1e-3f);
}

TEST(Render, AnEyeApproachingAProbeSeesSurfacesAroundAnOpenTexelAsItsLookupDoes) {
    // A probe that saw open space through single texels of a surface (the gaps of blinds
    // before a window: the hard scene's "eye approaching a probe" case): from its centre, a
    // ray whose texel is open but whose bilinear weight lies mostly on the surface around it
    // sees the surface. A ray traced from a micrometre away got a MISS there, through the open
    // texel, and the image jumped as the eye reached the probe.
    const int n = 32;
    ProbeMap map(n, glm::dvec3(0.0));
    for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
            const std::size_t i = oct::texel_index({x, y}, n);
            const glm::vec3 direction = oct::texel_direction({x, y}, n);
            // A wall at x = 2 with holes of one texel (every third row and column).
            if (direction.x > 0.3f && !(x % 3 == 1 && y % 3 == 1)) {
                map.set_surface(i, 2.0f / direction.x, glm::vec3(0.8f, 0.2f, 0.1f),
                                glm::vec3(-1.0f, 0.0f, 0.0f), 1.0f);
            } else {
                map.set_empty(i);
            }
        }
    }
    std::vector<ProbeMap> probes;
    probes.push_back(std::move(map));
    const ProbeField field(ProbePlacement::from_positions({glm::dvec3(0.0)}), std::move(probes));
    const glm::dvec3 ahead(1.0, 0.3, 0.2);
    const glm::dvec3 nudge = 1e-6 * glm::normalize(glm::dvec3(1.0, 0.7, 0.3));
    RenderSettings settings;
    settings.trace.filter = RadianceFilter::Bilinear;
    const RenderedImage at =
        render_probe_view(field, Camera::look_at(glm::dvec3(0.0), ahead, 160, 120, 18.0), settings);
    const RenderedImage near =
        render_probe_view(field, Camera::look_at(nudge, nudge + ahead, 160, 120, 18.0), settings);
    std::size_t surface_seen_from_open_texels = 0;
    for (int y = 0; y < at.height; ++y) {
        for (int x = 0; x < at.width; ++x) {
            const std::size_t i = at.index(x, y);
            ASSERT_EQ(at.status[i], near.status[i]) << x << ", " << y;
            const Ray ray = Camera::look_at(glm::dvec3(0.0), ahead, 160, 120, 18.0)
                                .local_pixel_ray(x, y, glm::dvec3(0.0));
            const oct::Texel met =
                oct::texel_of_direction(glm::vec3(glm::normalize(ray.direction)), n);
            surface_seen_from_open_texels +=
                at.status[i] == static_cast<std::uint8_t>(TraceStatus::Hit) && met.x % 3 == 1 &&
                met.y % 3 == 1;
            if (at.status[i] == static_cast<std::uint8_t>(TraceStatus::Hit)) {
                EXPECT_NEAR(at.depth[i], near.depth[i], 1e-5f);
            }
        }
    }
    // The case arises: the edge rule sees the surface from open texels in a share of the view.
    EXPECT_GT(surface_seen_from_open_texels, 10u);
}

TEST(Render, EyeAtAProbeIsOneLookupPerRay) {
    // docs/DESIGN.md §4: with the eye at a probe every ray is a single texel lookup in that probe,
    // in grid mode as in nearest mode, and the answer is the lookup's: of the texel the ray
    // falls in, or (filters other than nearest) of the texel whose surface holds most of the
    // bilinear weight around the ray.
    const ProbeField& field = baked_box_room();
    const glm::dvec3 eye = field.probe(3).position;
    const Camera camera = Camera::look_at(eye, eye + glm::dvec3(-1.0, 0.4, -0.2), 64, 48, 18.0);
    for (const FieldMode mode : {FieldMode::Grid, FieldMode::Nearest}) {
        RenderSettings settings;
        settings.trace.mode = mode;
        RenderStats stats;
        const RenderedImage image = render_probe_view(field, camera, settings, nullptr, &stats);
        std::size_t answered = 0;
        std::size_t refined = 0;
        for (int y = 0; y < image.height; ++y) {
            for (int x = 0; x < image.width; ++x) {
                const std::size_t i = image.index(x, y);
                if (image.status[i] == static_cast<std::uint8_t>(TraceStatus::Unknown)) {
                    continue; // the eye probe had no data: the field was asked
                }
                ++answered;
                EXPECT_EQ(image.probe[i], 3);
                EXPECT_EQ(image.steps[i], 1u);
                const Ray ray = camera.local_pixel_ray(x, y, field.world_offset());
                const ProbeMap& map = field.probe(3);
                ProbeTraceResult lookup = lookup_probe(map, ray.direction, ray.t_min, ray.t_max);
                if (lookup.status == TraceStatus::Hit) {
                    const oct::Texel seen = majority_surface_texel(
                        map, ray.direction, lookup.texel,
                        surface_thickness(settings.trace.probe, lookup.t, map.resolution));
                    if (seen.x != lookup.texel.x || seen.y != lookup.texel.y) {
                        lookup = ProbeLookup(map, {}).lookup_texel(ray.direction, seen, ray.t_min,
                                                                   ray.t_max);
                        ++refined;
                    }
                }
                EXPECT_EQ(image.status[i], static_cast<std::uint8_t>(lookup.status));
                if (lookup.status == TraceStatus::Hit) {
                    EXPECT_EQ(image.depth[i], static_cast<float>(lookup.t));
                    // The colour: the lookup's texel read through the radiance filter.
                    const glm::vec3 colour =
                        filtered_radiance(field.probe(3), ray.direction, lookup.texel,
                                          surface_thickness(settings.trace.probe, lookup.t,
                                                            field.probe(3).resolution),
                                          settings.trace.filter);
                    EXPECT_EQ(image.rgba[4 * i], colour.x);
                }
            }
        }
        EXPECT_GT(answered, image.pixel_count() * 99 / 100);
        EXPECT_LT(stats.mean_probes(), 1.01);
        // The room's edges (its walls' corners) are a few rays; the rest keep their texel.
        EXPECT_GT(refined, 0u);
        EXPECT_LT(refined, image.pixel_count() / 20);
    }
}

namespace lfprobe {
namespace {

TEST(Render, TraceThroughputTracesTheSameRaysAsTheImage) {
    // The throughput figure (compared with Embree's) must come from the very traces the image
    // shows: same hit count, for an eye between probes and an eye at a probe.
    const ProbeField& field = baked_box_room();
    const glm::dvec3 at_probe = field.probe(3).position;
    for (const Camera& camera :
         {Camera::look_at({0.3, -0.2, 1.1}, {-1.0, 0.4, 0.9}, 48, 32, 18.0),
          Camera::look_at(at_probe, at_probe + glm::dvec3(-1.0, 0.4, -0.2), 48, 32, 18.0)}) {
        RenderStats stats;
        (void)render_probe_view(field, camera, {}, nullptr, &stats);
        const ThroughputResult t = probe_trace_throughput(field, camera, {}, 2);
        EXPECT_EQ(t.rays, stats.rays);
        EXPECT_EQ(t.hits, stats.hits);
        EXPECT_EQ(t.repeats, 2);
        EXPECT_GT(t.rays_per_second, 0.0);
    }
    EXPECT_THROW(
        (void)probe_trace_throughput(field, Camera::look_at({0, 0, 1}, {1, 0, 1}, 4, 4), {}, 0),
        InputError);
}

} // namespace
} // namespace lfprobe

namespace lfprobe {
namespace {

TEST(Render, RaysStartedAtTheirAnswersBeginWhereTheImageEnds) {
    // The floor under the throughput figure: each ray restarted at its own answer (the image's
    // depth for a HIT), so that nothing is left to skip; traced again, it walks less.
    const ProbeField& field = baked_box_room();
    const Camera camera = Camera::look_at({0.3, -0.2, 1.1}, {-1.0, 0.4, 0.9}, 48, 32, 18.0);
    RenderStats stats;
    const RenderedImage image = render_probe_view(field, camera, {}, nullptr, &stats);
    const std::vector<Ray> rays = rays_started_at_answers(field, camera);
    ASSERT_EQ(rays.size(), image.pixel_count());
    const CameraRays camera_rays(camera);
    std::uint64_t steps_from_camera = 0;
    std::uint64_t steps_from_answer = 0;
    std::uint64_t hits_again = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
        const int x = static_cast<int>(i % static_cast<std::size_t>(camera.width));
        const int y = static_cast<int>(i / static_cast<std::size_t>(camera.width));
        const Ray from_camera = camera_rays.local_pixel_ray(x, y, field.world_offset());
        EXPECT_EQ(rays[i].origin, from_camera.origin);
        EXPECT_EQ(rays[i].direction, from_camera.direction);
        const auto status = static_cast<TraceStatus>(image.status[i]);
        if (status == TraceStatus::Hit) {
            EXPECT_EQ(static_cast<float>(rays[i].t_min), image.depth[i]);
        } else if (status == TraceStatus::Miss) {
            EXPECT_EQ(rays[i].t_min, from_camera.t_min);
        } else {
            EXPECT_GE(rays[i].t_min, from_camera.t_min);
        }
        steps_from_camera += field.trace(from_camera).steps;
        const FieldTraceResult again = field.trace(rays[i]);
        steps_from_answer += again.steps;
        hits_again += again.status == TraceStatus::Hit ? 1 : 0;
    }
    EXPECT_LT(steps_from_answer, steps_from_camera);
    // A ray started at its HIT meets the same surface there.
    EXPECT_GE(hits_again, stats.hits * 99 / 100);
    const ThroughputResult t =
        probe_trace_throughput(field, camera, {}, 2, ThroughputStart::Answer);
    EXPECT_EQ(t.rays, stats.rays);
    EXPECT_EQ(t.hits, hits_again);
}

} // namespace
} // namespace lfprobe

namespace lfprobe {
namespace {

TEST(Render, ACameraWhoseRaysAreNotFiniteIsAClearErrorInEveryMode) {
    // A lens of 1e-300 mm passes the camera file's check (positive) but makes rays of inf/NaN:
    // the grid walk once cast a NaN cell index to int and crashed.
    const ProbeField& field = baked_box_room();
    Camera camera = Camera::look_at({0.0, -0.5, 1.3}, {0.0, 1.0, 1.0}, 16, 12, 20.0);
    camera.lens = 1e-300;
    for (const FieldMode mode : {FieldMode::Grid, FieldMode::Nearest}) {
        RenderSettings settings;
        settings.trace.mode = mode;
        EXPECT_THROW((void)render_probe_view(field, camera, settings), InputError);
        EXPECT_THROW((void)probe_trace_throughput(field, camera, settings, 1), InputError);
    }
    // A ray that is not finite, handed to the field directly, is refused the same way.
    Ray ray;
    ray.origin = {0.0, 0.0, 1.2};
    ray.direction = {std::nan(""), 0.0, 0.0};
    FieldTraceSettings grid;
    grid.mode = FieldMode::Grid;
    EXPECT_THROW((void)field.trace(ray, grid), InputError);
}

TEST(Render, AnImageWhoseIntegerChannelsAreNotWholeNumbersIsRefused) {
    // The status, probe and steps channels are floats in the file; NaN or 1e30 there must not
    // reach an integer conversion, under the names written now and under the older ones.
    const std::string path =
        (std::filesystem::temp_directory_path() /
         ("lfprobe_bad_status_" + std::to_string(std::random_device{}()) + ".exr"))
            .string();
    const char* current[] = {"R",   "G",   "B",        "A",       "Z",      "N.X",
                             "N.Y", "N.Z", "status.X", "probe.X", "steps.X"};
    const char* older[] = {"R",   "G",   "B",      "A",     "Z",    "N.X",
                           "N.Y", "N.Z", "status", "probe", "steps"};
    for (const auto* channels : {current, older}) {
        for (const float bad : {1.0f, std::nanf(""), 1e30f, 2.5f}) {
            // Every channel a float plane of zeros, one status value bad (1: a HIT, the control).
            const int w = 4;
            const int h = 3;
            std::vector<std::vector<float>> planes(std::size(current),
                                                   std::vector<float>(w * h, 0.0f));
            planes[8][5] = bad;
            Imf::Header header(w, h);
            Imf::FrameBuffer frame;
            for (std::size_t c = 0; c < std::size(current); ++c) {
                header.channels().insert(channels[c], Imf::Channel(Imf::FLOAT));
                frame.insert(channels[c],
                             Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(planes[c].data()),
                                        sizeof(float), sizeof(float) * w));
            }
            {
                Imf::OutputFile file(path.c_str(), header);
                file.setFrameBuffer(frame);
                file.writePixels(h);
            }
            if (bad == 1.0f) {
                EXPECT_EQ(read_rendered_exr(path).status[5], 1) << channels[8];
            } else {
                EXPECT_THROW((void)read_rendered_exr(path), InputError) << bad << channels[8];
            }
        }
    }
    std::filesystem::remove(path);
}

} // namespace
} // namespace lfprobe
