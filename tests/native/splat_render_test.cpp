// The z-buffered point splat baseline (docs/DESIGN.md §6): nearest point wins whatever the order,
// depths match the analytic scene, the output is the same for any thread count.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <tbb/task_arena.h>

#include "lfprobe/error.hpp"
#include "lfprobe/image_exr.hpp"
#include "lfprobe/probe_exr.hpp"
#include "lfprobe/splat_render.hpp"
#include "trace_scenes.hpp"

using namespace lfprobe;
using lfprobe::testing::BoxRoomScene;

namespace {

PointCloud two_points(const glm::vec3& a, const glm::vec3& b) {
    PointCloud cloud;
    cloud.positions = {a, b};
    cloud.colors = {glm::vec3(1, 0, 0), glm::vec3(0, 1, 0)};
    cloud.scan_index = {0, 0};
    return cloud;
}

} // namespace

TEST(Splat, NearestPointWinsWhateverTheOrder) {
    const Camera camera = Camera::look_at({0.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, 33, 33, 20.0);
    SplatSettings settings;
    settings.fixed_radius = 0.05;
    // Both on the central pixel's ray; the nearer is green.
    for (const bool swapped : {false, true}) {
        const glm::vec3 near(0.0f, 1.0f, 0.0f);
        const glm::vec3 far(0.0f, 3.0f, 0.0f);
        PointCloud cloud = swapped ? two_points(near, far) : two_points(far, near);
        const glm::vec3 near_colour = swapped ? cloud.colors[0] : cloud.colors[1];
        const RenderedImage image = render_splats(cloud, nullptr, camera, settings);
        const std::size_t centre = image.index(16, 16);
        EXPECT_EQ(image.status[centre], static_cast<std::uint8_t>(TraceStatus::Hit));
        EXPECT_NEAR(image.depth[centre], 1.0f, 1e-6f);
        EXPECT_EQ(glm::vec3(image.rgba[4 * centre], image.rgba[4 * centre + 1],
                            image.rgba[4 * centre + 2]),
                  near_colour);
        EXPECT_EQ(image.steps[centre], 2u); // both points cover it
        EXPECT_EQ(image.probe[centre], -1);
        EXPECT_EQ(image.status[image.index(0, 0)], static_cast<std::uint8_t>(TraceStatus::Miss));
        EXPECT_TRUE(std::isinf(image.depth[image.index(0, 0)]));
    }
    // Equal depths: the lower index wins, whatever the threads did.
    PointCloud tie = two_points({0.0f, 2.0f, 0.0f}, {0.0f, 2.0f, 0.0f});
    const RenderedImage image = render_splats(tie, nullptr, camera, settings);
    EXPECT_EQ(image.rgba[4 * image.index(16, 16)], 1.0f);
    // Behind the camera or outside the clip range: nothing.
    const RenderedImage behind = render_splats(
        two_points({0.0f, -1.0f, 0.0f}, {0.0f, 0.001f, 0.0f}), nullptr, camera, settings);
    EXPECT_EQ(std::count(behind.status.begin(), behind.status.end(),
                         static_cast<std::uint8_t>(TraceStatus::Hit)),
              0);
}

TEST(Splat, BoxRoomDepthsMatchTheScene) {
    const BoxRoomScene scene;
    const PointCloud cloud = scene.cloud(0.02f, glm::dvec3(0.0, 0.0, 1.2));
    const LocalGeometry geometry = estimate_local_geometry(cloud, {});
    for (const Camera& camera :
         {Camera::look_at({-1.2, -0.8, 1.4}, glm::dvec3(scene.sphere_centre), 160, 120, 20.0), [] {
              Camera pano = Camera::look_at({0.0, 0.0, 1.2}, {1.0, 0.0, 1.2}, 256, 128, 20.0);
              pano.type = CameraType::PanoramaEquirect;
              return pano;
          }()}) {
        SplatStats stats;
        const RenderedImage image = render_splats(cloud, &geometry, camera, {}, nullptr, &stats);
        std::vector<double> errors;
        std::size_t holes = 0;
        for (int y = 0; y < image.height; ++y) {
            for (int x = 0; x < image.width; ++x) {
                const Ray ray = camera.pixel_ray(x, y);
                const double exact = static_cast<double>(
                    scene.distance(glm::vec3(ray.origin), glm::vec3(ray.direction)));
                const std::size_t i = image.index(x, y);
                if (image.status[i] != static_cast<std::uint8_t>(TraceStatus::Hit)) {
                    ++holes;
                    continue;
                }
                errors.push_back(std::abs(static_cast<double>(image.depth[i]) - exact));
            }
        }
        std::sort(errors.begin(), errors.end());
        const double hole_rate =
            static_cast<double>(holes) / static_cast<double>(image.pixel_count());
        const double median = errors[errors.size() / 2];
        const double p95 = errors[errors.size() * 95 / 100];
        std::printf("splats (%s): %llu points, %llu drawn, %.1f fragments per point; hole rate "
                    "%.4f, depth error median %.4f m, 95%% %.4f m; %.0f points/s\n",
                    camera.type == CameraType::Perspective ? "perspective" : "panorama",
                    static_cast<unsigned long long>(stats.points),
                    static_cast<unsigned long long>(stats.drawn),
                    static_cast<double>(stats.fragments) / static_cast<double>(stats.drawn),
                    hole_rate, median, p95, stats.points_per_second());
        EXPECT_LT(hole_rate, 0.01);
        // A flat square stands at its point's distance: off the point, it is off the surface.
        EXPECT_LT(median, 0.03);
        EXPECT_LT(p95, 0.1);
    }
}

TEST(Splat, BitIdenticalForOneAndTwoThreads) {
    const BoxRoomScene scene;
    const PointCloud cloud = scene.cloud(0.04f, glm::dvec3(0.0, 0.0, 1.2));
    const LocalGeometry geometry = estimate_local_geometry(cloud, {});
    const Camera camera = Camera::look_at({1.5, -1.0, 2.0}, {-1.0, 0.5, 0.5}, 120, 80, 20.0);
    RenderedImage one;
    RenderedImage two;
    tbb::task_arena(1).execute([&] { one = render_splats(cloud, &geometry, camera); });
    tbb::task_arena(2).execute([&] { two = render_splats(cloud, &geometry, camera); });
    auto same = [](const auto& a, const auto& b) {
        return a.size() == b.size() &&
               std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0;
    };
    EXPECT_TRUE(same(one.rgba, two.rgba));
    EXPECT_TRUE(same(one.depth, two.depth));
    EXPECT_TRUE(same(one.normal, two.normal));
    EXPECT_TRUE(same(one.status, two.status));
    EXPECT_TRUE(same(one.steps, two.steps));
    // Progress and cancellation.
    Progress progress;
    (void)render_splats(cloud, &geometry, camera, {}, &progress);
    EXPECT_EQ(progress.fraction(), 1.0);
    Progress cancelled;
    cancelled.request_cancel();
    EXPECT_THROW((void)render_splats(cloud, &geometry, camera, {}, &cancelled), Cancelled);
}

TEST(Splat, CameraFileToExr) {
    const BoxRoomScene scene;
    const PointCloud cloud = scene.cloud(0.05f, glm::dvec3(0.0, 0.0, 1.2));
    const std::filesystem::path folder =
        std::filesystem::temp_directory_path() /
        ("lfprobe_splat_test_" + std::to_string(std::random_device{}()));
    std::filesystem::create_directories(folder);
    const std::string camera_path = (folder / "camera.json").string();
    write_file_atomically(
        camera_path,
        Camera::look_at({0.0, 0.0, 1.2}, {1.0, 0.2, 1.0}, 32, 24, 20.0).to_json().dump());
    SplatSettings fixed;
    fixed.fixed_radius = 0.05;
    const SplatStats stats = splat_cloud_to_exr(cloud, read_camera_json(camera_path), fixed,
                                                (folder / "splats.exr").string());
    EXPECT_EQ(stats.covered, 32u * 24u);
    std::string metadata;
    const RenderedImage image = read_rendered_exr((folder / "splats.exr").string(), &metadata);
    EXPECT_EQ(image.height, 24);
    const nlohmann::json m = nlohmann::json::parse(metadata);
    EXPECT_EQ(m.at("renderer"), "lfprobe point splats");
    EXPECT_EQ(m.at("settings").at("fixed_radius"), 0.05);
    EXPECT_EQ(m.at("stats").at("covered"), 32u * 24u);
    std::filesystem::remove_all(folder);
}

// Splatting one cloud from several cameras estimates its local spacing once: the first splat
// caches it, the next ones read it and draw the same image bit for bit.
TEST(Splat, SpacingIsEstimatedOnceAndReadFromTheCacheAfter) {
    const BoxRoomScene scene;
    const PointCloud cloud = scene.cloud(0.05f, glm::dvec3(0.0, 0.0, 1.2));
    const std::filesystem::path folder =
        std::filesystem::temp_directory_path() /
        ("lfprobe_splat_cache_test_" + std::to_string(std::random_device{}()));
    const std::filesystem::path cache = folder / "cache";
    std::filesystem::create_directories(folder);
    const Camera camera = Camera::look_at({0.0, 0.0, 1.2}, {1.0, 0.2, 1.0}, 32, 24, 20.0);
    const std::string uncached = (folder / "uncached.exr").string();
    (void)splat_cloud_to_exr(cloud, camera, {}, uncached);
    EXPECT_FALSE(std::filesystem::exists(cache));

    (void)splat_cloud_to_exr(cloud, camera, {}, (folder / "first.exr").string(), nullptr, nullptr,
                             cache.string());
    std::vector<std::filesystem::path> entries;
    for (const auto& entry : std::filesystem::directory_iterator(cache)) {
        entries.push_back(entry.path());
    }
    ASSERT_EQ(entries.size(), 1u);
    const auto written = std::filesystem::last_write_time(entries[0]);
    (void)splat_cloud_to_exr(cloud, camera, {}, (folder / "second.exr").string(), nullptr, nullptr,
                             cache.string());
    EXPECT_EQ(std::filesystem::last_write_time(entries[0]), written); // read, not rewritten

    const RenderedImage reference = read_rendered_exr(uncached);
    for (const char* name : {"first.exr", "second.exr"}) {
        const RenderedImage image = read_rendered_exr((folder / name).string());
        EXPECT_EQ(image.rgba, reference.rgba) << name;
        EXPECT_EQ(image.depth, reference.depth) << name;
    }
    std::filesystem::remove_all(folder);
}
