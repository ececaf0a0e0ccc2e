// The simulated scanner: ray count of the pattern, points on the mesh within the noise, and a
// file the scan reader takes back with its scanner position.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <string>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "lfprobe/color.hpp"
#include "lfprobe/mesh_reader.hpp"
#include "lfprobe/scan_reader.hpp"
#include "lfprobe/scanner_sim.hpp"

namespace lfprobe {
namespace {

// A closed box room [-2,2] × [-3,3] × [0,2.5] as a mesh, shifted by a world offset.
Mesh closed_room() {
    Mesh m;
    m.vertices = {{-2, -3, 0},   {2, -3, 0},   {2, 3, 0},   {-2, 3, 0},
                  {-2, -3, 2.5}, {2, -3, 2.5}, {2, 3, 2.5}, {-2, 3, 2.5}};
    const std::uint32_t quads[6][4] = {{0, 1, 2, 3}, {4, 7, 6, 5}, {0, 4, 5, 1},
                                       {3, 2, 6, 7}, {0, 3, 7, 4}, {1, 5, 6, 2}};
    for (const auto& q : quads) {
        m.triangles.push_back({q[0], q[1], q[2]});
        m.triangles.push_back({q[0], q[2], q[3]});
    }
    m.materials.push_back(Material{"red", glm::vec3(1.0f, 0.0f, 0.0f), nullptr});
    m.object_names.push_back("room");
    m.material.assign(m.triangles.size(), 0);
    m.object.assign(m.triangles.size(), 0);
    return m;
}

double distance_to_room(const glm::dvec3& p) {
    // Distance from a point near the boundary to the nearest of the six planes.
    return std::min({std::abs(p.x + 2), std::abs(p.x - 2), std::abs(p.y + 3), std::abs(p.y - 3),
                     std::abs(p.z), std::abs(p.z - 2.5)});
}

// A full sweep from `position` at `step_deg`, ranges noisy by `noise_mm` at 10 m.
ScannerSettings station(const glm::dvec3& position, double step_deg, double noise_mm) {
    ScannerSettings s;
    s.position = position;
    s.step_deg = step_deg;
    s.noise_mm = noise_mm;
    return s;
}

// The points of scan `s` in a closed room, which returns every one of the pattern's `rays`.
std::vector<SimulatedPoint> scan_of_closed_room(const EmbreeScene& scene, const ScannerSettings& s,
                                                std::uint64_t rays) {
    ScanStats stats;
    std::vector<SimulatedPoint> points = simulate_scan(scene, s, nullptr, &stats);
    EXPECT_EQ(stats.rays, rays);
    EXPECT_EQ(points.size(), stats.rays);
    return points;
}

TEST(Scanner, PatternCountNoiseAndRoundTrip) {
    const Mesh mesh = closed_room();
    const EmbreeScene scene(mesh);
    const ScannerSettings s = station({0.5, 0.5, 1.5}, 2.0, 2.0);
    // 180 azimuths × 75 rows (−60° .. 88°) + the zenith; a closed room returns every ray.
    const std::vector<SimulatedPoint> points = scan_of_closed_room(scene, s, 180u * 75u + 1u);
    double max_off = 0.0;
    for (const SimulatedPoint& p : points) {
        const double range = glm::length(p.position - s.position);
        const double sigma = 2e-3 * range / 10.0;
        EXPECT_LT(distance_to_room(p.position), 6.0 * sigma + 1e-9);
        max_off = std::max(max_off, distance_to_room(p.position));
    }
    EXPECT_GT(max_off, 0.0); // the noise is there
    // Nothing below −60° elevation.
    for (const SimulatedPoint& p : points) {
        const glm::dvec3 d = p.position - s.position;
        EXPECT_GE(std::asin(d.z / glm::length(d)), -60.0 * std::numbers::pi / 180.0 - 1e-6);
    }
    // Deterministic for a seed.
    EXPECT_EQ(simulate_scan(scene, s)[1234].position, points[1234].position);

    const auto path =
        (std::filesystem::temp_directory_path() / "lfprobe_scanner_test.xyz").string();
    const ScanStats written = write_simulated_scan(scene, s, path);
    EXPECT_EQ(written.points, points.size());
    const ScanFile file = read_scan_file(path, {});
    ASSERT_EQ(file.positions.size(), points.size());
    ASSERT_TRUE(file.has_scanner);
    EXPECT_NEAR(file.scanner.x, 0.5, 1e-9);
    EXPECT_NEAR(file.scanner.z, 1.5, 1e-9);
    ASSERT_FALSE(file.colors.empty());
    EXPECT_NEAR(file.colors[0].x, 1.0f, 1e-6f);
    EXPECT_NEAR(file.colors[0].y, 0.0f, 1e-6f);
    const glm::dvec3 p0 = file.origin + glm::dvec3(file.positions[0]);
    EXPECT_NEAR(glm::length(p0 - points[0].position), 0.0, 1e-5);
}

TEST(Scanner, EveryRayOfAFineSweepInTheClosedLabRoomHits) {
    // The demo's first station at 0.1°, 5.4 M rays, a row's rays traced in coherent packets:
    // the packet traversal let 15 of them escape through the edges the room's triangles share,
    // where single rays do not. The room is closed, so every ray must return a point.
    const Mesh mesh = read_obj(std::string(LFPROBE_SOURCE_DIR) + "/blend/lab_room/lab_room.obj");
    const EmbreeScene scene(mesh);
    (void)scan_of_closed_room(scene, station({1.2, 0.9, 1.5}, 0.1, 1.0), 3600u * 1500u + 1u);
}

// The .xyz lines are formatted on all cores with to_chars: each must be what printf's
// "%.6f %.6f %.6f %d %d %d" makes of the point, over a room far from the origin (large
// coordinates, both signs, the colour bytes of a red wall), in ray order.
TEST(Scanner, WrittenLinesAreWhatPrintfWritesInRayOrder) {
    Mesh mesh = closed_room();
    for (glm::vec3& v : mesh.vertices) {
        v += glm::vec3(-0.25f, 0.125f, 0.0f);
    }
    mesh.world_offset = {-452117.0, 5411630.0, 212.0};
    mesh.materials[0].base_color = {0.6f, 0.02f, 0.3f};
    const EmbreeScene scene(mesh);
    const ScannerSettings s = station(mesh.world_offset + glm::dvec3(0.5, 0.5, 1.5), 3.0, 2.0);
    const std::vector<SimulatedPoint> points = simulate_scan(scene, s);
    ASSERT_EQ(points.size(), 120u * 50u + 1u); // the closed room returns every ray
    const auto path =
        (std::filesystem::temp_directory_path() / "lfprobe_scanner_lines_test.xyz").string();
    (void)write_simulated_scan(scene, s, path);
    std::ifstream in(path);
    std::string line;
    std::size_t k = 0;
    while (std::getline(in, line)) {
        if (line.empty() || line[0] == '#') {
            continue;
        }
        ASSERT_LT(k, points.size());
        const SimulatedPoint& q = points[k++];
        const auto byte = [](float linear) {
            return static_cast<int>(
                std::lround(linear_to_srgb(std::clamp(linear, 0.0f, 1.0f)) * 255.0f));
        };
        char expected[256];
        std::snprintf(expected, sizeof expected, "%.6f %.6f %.6f %d %d %d", q.position.x,
                      q.position.y, q.position.z, byte(q.color.x), byte(q.color.y),
                      byte(q.color.z));
        ASSERT_EQ(line, expected) << "point " << k - 1;
    }
    EXPECT_EQ(k, points.size());
    std::filesystem::remove(path);
}

// A partial sweep: the scanner turns through 90° of azimuth from 30°, keeping the zenith; a
// window may wrap past 0°.
TEST(Scanner, PartialSweepKeepsItsAzimuthWindow) {
    const Mesh mesh = closed_room();
    const EmbreeScene scene(mesh);
    ScannerSettings s = station({0.5, 0.5, 1.5}, 2.0, 0.0);
    s.horizontal_fov_deg = 90.0;
    s.horizontal_start_deg = 30.0;
    // 45 azimuths × 75 rows + the zenith.
    const std::vector<SimulatedPoint> points = scan_of_closed_room(scene, s, 45u * 75u + 1u);
    const double deg = std::numbers::pi / 180.0;
    std::size_t zenith = 0;
    for (const SimulatedPoint& p : points) {
        const glm::dvec3 d = p.position - s.position;
        if (std::hypot(d.x, d.y) < 1e-9 * glm::length(d)) {
            ++zenith;
            continue;
        }
        const double azimuth = std::atan2(d.y, d.x);
        EXPECT_GE(azimuth, 30.0 * deg - 1e-9);
        EXPECT_LE(azimuth, 118.0 * deg + 1e-9); // the last of 45 steps of 2° from 30°
    }
    EXPECT_EQ(zenith, 1u);
    // A window from 300° wraps past 0°: its azimuths lie in [300°, 360°) and [0°, 30°).
    s.horizontal_start_deg = 300.0;
    for (const SimulatedPoint& p : simulate_scan(scene, s)) {
        const glm::dvec3 d = p.position - s.position;
        if (std::hypot(d.x, d.y) < 1e-9 * glm::length(d)) {
            continue;
        }
        const double azimuth = std::atan2(d.y, d.x); // (-180°, 180°]
        EXPECT_TRUE(azimuth >= -60.0 * deg - 1e-9 && azimuth < 30.0 * deg) << azimuth / deg;
    }
}

TEST(Scanner, RejectsBadSettings) {
    const Mesh mesh = closed_room();
    const EmbreeScene scene(mesh);
    ScannerSettings s;
    s.step_deg = 0.0;
    EXPECT_THROW((void)simulate_scan(scene, s), InputError);
    s.step_deg = 1.0;
    s.vertical_fov_deg = 400.0;
    EXPECT_THROW((void)simulate_scan(scene, s), InputError);
    s.vertical_fov_deg = 300.0;
    for (const double fov : {0.0, -90.0, 361.0, std::nan("")}) {
        s.horizontal_fov_deg = fov;
        EXPECT_THROW((void)simulate_scan(scene, s), InputError) << fov;
    }
    s.horizontal_fov_deg = 90.0;
    s.horizontal_start_deg = std::numeric_limits<double>::infinity();
    EXPECT_THROW((void)simulate_scan(scene, s), InputError);
}

} // namespace
} // namespace lfprobe
