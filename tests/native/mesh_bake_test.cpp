// Probes baked from a mesh: exact radial distances in a box room, empties where the mesh has
// no geometry, and a probe set that reads back with a "mesh" bake record.
#include <cmath>
#include <filesystem>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <Imath/half.h>
#include <nlohmann/json.hpp>

#include "lfprobe/mesh_bake.hpp"
#include "lfprobe/octahedral.hpp"

namespace lfprobe {
namespace {

// An open box room [-2,2] × [-3,3] × [0,2.5] without a ceiling: upward texels stay empty.
Mesh open_room() {
    Mesh m;
    m.vertices = {{-2, -3, 0},   {2, -3, 0},   {2, 3, 0},   {-2, 3, 0},
                  {-2, -3, 2.5}, {2, -3, 2.5}, {2, 3, 2.5}, {-2, 3, 2.5}};
    const std::uint32_t quads[5][4] = {
        {0, 1, 2, 3}, {0, 4, 5, 1}, {3, 2, 6, 7}, {0, 3, 7, 4}, {1, 5, 6, 2}};
    for (const auto& q : quads) {
        m.triangles.push_back({q[0], q[1], q[2]});
        m.triangles.push_back({q[0], q[2], q[3]});
    }
    m.materials.push_back(Material{"grey", glm::vec3(0.25f, 0.5f, 0.75f), nullptr});
    m.object_names.push_back("room");
    m.material.assign(m.triangles.size(), 0);
    m.object.assign(m.triangles.size(), 0);
    return m;
}

TEST(MeshBake, ProbeDistancesAreAnalyticAndSkyIsEmpty) {
    const Mesh mesh = open_room();
    const EmbreeScene scene(mesh);
    const glm::dvec3 c{0.5, -0.25, 1.0};
    const ProbeMap map = bake_probe_from_mesh(scene, c, MeshBakeSettings{64, 1});
    int empty = 0;
    for (int y = 0; y < 64; ++y) {
        for (int x = 0; x < 64; ++x) {
            const oct::Texel t{x, y};
            const std::size_t i = oct::texel_index(t, 64);
            const glm::dvec3 d(oct::texel_direction(t, 64));
            double best = INFINITY;
            const double planes[3][2] = {{-2, 2}, {-3, 3}, {0, INFINITY}};
            for (int a = 0; a < 3; ++a) {
                for (const double p : planes[a]) {
                    if (std::isfinite(p) && d[a] != 0.0) {
                        const double s = (p - c[a]) / d[a];
                        if (s > 0.0) {
                            best = std::min(best, s);
                        }
                    }
                }
            }
            // Above the walls' top edge there is nothing; a ray grazing the edge itself may go
            // either way in float.
            if (std::isfinite(best) && std::abs(c.z + best * d.z - 2.5) < 1e-4) {
                continue;
            }
            if (std::isfinite(best) && c.z + best * d.z > 2.5) {
                best = INFINITY;
            }
            if (!std::isfinite(best)) {
                EXPECT_EQ(map.state(i), TexelState::Empty) << x << "," << y;
                ++empty;
                continue;
            }
            ASSERT_EQ(map.state(i), TexelState::Surface) << x << "," << y;
            EXPECT_NEAR(map.distance[i], best, 2e-6 * best) << x << "," << y;
            EXPECT_LT(glm::dot(glm::dvec3(map.normal_at(i)), d), 0.0); // faces the probe
            EXPECT_NEAR(map.radiance_at(i).y, 0.5f, 1e-3f);
        }
    }
    EXPECT_GT(empty, 100);
}

TEST(MeshBake, ProbeSetOnDisk) {
    const Mesh mesh = open_room();
    const EmbreeScene scene(mesh);
    const auto folder =
        (std::filesystem::temp_directory_path() / "lfprobe_mesh_bake_test").string();
    std::filesystem::remove_all(folder);
    const ProbePlacement placement =
        ProbePlacement::from_grid(ProbeGrid::spanning({-1, -1, 1}, {1, 1, 1}, {2, 2, 1}));
    Progress progress;
    const BakeSummary s = bake_probe_set_from_mesh(scene, placement, MeshBakeSettings{32, 2},
                                                   folder, nlohmann::json::array(), &progress);
    EXPECT_EQ(s.probe_count, 4u);
    EXPECT_EQ(s.mean_coverage.unknown, 0.0);
    const ProbeSetManifest m = read_manifest(folder);
    EXPECT_EQ(m.bake.at("source"), "mesh");
    EXPECT_TRUE(m.placement.is_grid);
    const ProbeMap p = read_probe(folder, m, 3);
    EXPECT_EQ(p.resolution, 32);
    Progress cancelled;
    cancelled.request_cancel();
    EXPECT_THROW((void)bake_probe_set_from_mesh(scene, placement, MeshBakeSettings{32, 1}, folder,
                                                nlohmann::json::array(), &cancelled),
                 Cancelled);
}

// A red plate (x = 1, |y|, |z| < 0.3) in front of a blue wall (x = 3).
Mesh plate_before_wall() {
    Mesh m;
    m.vertices = {{1, -0.3f, -0.3f}, {1, 0.3f, -0.3f}, {1, 0.3f, 0.3f}, {1, -0.3f, 0.3f},
                  {3, -5, -5},       {3, 5, -5},       {3, 5, 5},       {3, -5, 5}};
    m.triangles = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
    m.materials.push_back(Material{"red", glm::vec3(0.8f, 0.1f, 0.1f), nullptr});
    m.materials.push_back(Material{"blue", glm::vec3(0.1f, 0.2f, 0.9f), nullptr});
    m.object_names = {"plate", "wall"};
    m.material = {0, 0, 1, 1};
    m.object = {0, 0, 1, 1};
    return m;
}

TEST(MeshBake, SupersampledTexelsAcrossASilhouetteKeepTheirCentresSurfaceColour) {
    // A texel is the centre ray's surface: its colour averages only the rays that meet that
    // surface, so the plate's edge texels stay red and the wall's stay blue.
    const Mesh mesh = plate_before_wall();
    const EmbreeScene scene(mesh);
    const int n = 48;
    const ProbeMap map = bake_probe_from_mesh(scene, {0, 0.05, 0.02}, MeshBakeSettings{n, 4});
    const glm::vec3 red(Imath::half(0.8f), Imath::half(0.1f), Imath::half(0.1f));
    const glm::vec3 blue(Imath::half(0.1f), Imath::half(0.2f), Imath::half(0.9f));
    int plate = 0;
    int wall_beside_plate = 0;
    for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
            const std::size_t i = oct::texel_index({x, y}, n);
            const float r = map.distance[i];
            if (!std::isfinite(r)) {
                continue;
            }
            const glm::vec3 d = oct::texel_direction({x, y}, n);
            const bool on_plate = std::abs(r * d.x - 1.0f) < 1e-3f;
            EXPECT_EQ(map.radiance_at(i), on_plate ? red : blue) << x << ", " << y;
            plate += on_plate ? 1 : 0;
            // A wall texel whose neighbour is on the plate straddles the silhouette.
            if (!on_plate && x + 1 < n) {
                const float rn = map.distance[oct::texel_index({x + 1, y}, n)];
                const glm::vec3 dn = oct::texel_direction({x + 1, y}, n);
                wall_beside_plate += std::abs(rn * dn.x - 1.0f) < 1e-3f ? 1 : 0;
            }
        }
    }
    EXPECT_GT(plate, 20);
    EXPECT_GT(wall_beside_plate, 4);
}

TEST(MeshBake, ATexelAcrossASilhouetteKnowsHowMuchOfItIsItsSurface) {
    // Coverage: the share of a texel's n×n rays on its centre ray's surface (for an empty
    // texel, that meet nothing). Against the share of 16×16 directions across the texel on the
    // same surface, it is within the 4×4 grid's resolution; a texel inside one surface covers
    // all of itself.
    const Mesh mesh = plate_before_wall();
    const EmbreeScene scene(mesh);
    const int n = 48;
    const glm::dvec3 centre{0, 0.05, 0.02};
    const ProbeMap map = bake_probe_from_mesh(scene, centre, MeshBakeSettings{n, 4});
    ASSERT_EQ(map.coverage.size(), map.texel_count());
    // 0 the plate, 1 the wall (10 m square), 2 nothing.
    const auto surface = [&](const glm::dvec3& d) {
        if (d.x <= 0.0) {
            return 2;
        }
        const glm::dvec3 p = centre + ((1.0 - centre.x) / d.x) * d;
        if (std::abs(p.y) < 0.3 && std::abs(p.z) < 0.3) {
            return 0;
        }
        const glm::dvec3 w = centre + ((3.0 - centre.x) / d.x) * d;
        return std::abs(w.y) < 5.0 && std::abs(w.z) < 5.0 ? 1 : 2;
    };
    int partial = 0;
    double error = 0.0;
    int texels = 0;
    for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
            const std::size_t i = oct::texel_index({x, y}, n);
            if (std::isnan(map.distance[i])) {
                continue;
            }
            const int own = surface(glm::dvec3(oct::texel_direction({x, y}, n)));
            int same = 0;
            for (int sy = 0; sy < 16; ++sy) {
                for (int sx = 0; sx < 16; ++sx) {
                    const glm::vec2 uv{
                        (static_cast<float>(x) + (static_cast<float>(sx) + 0.5f) / 16.0f) /
                            static_cast<float>(n),
                        (static_cast<float>(y) + (static_cast<float>(sy) + 0.5f) / 16.0f) /
                            static_cast<float>(n)};
                    same += surface(glm::dvec3(oct::decode(uv))) == own ? 1 : 0;
                }
            }
            const double expected = same / 256.0;
            const float coverage = map.coverage_at(i);
            EXPECT_NEAR(coverage, expected, 0.2) << x << ", " << y;
            if (same == 256) {
                EXPECT_EQ(coverage, 1.0f);
            }
            partial += coverage < 1.0f ? 1 : 0;
            error += std::abs(coverage - expected);
            ++texels;
        }
    }
    EXPECT_GT(partial, 20);
    EXPECT_LT(error / texels, 0.01);
    // One ray a texel knows nothing of its texel's edges: no coverage is written.
    EXPECT_TRUE(bake_probe_from_mesh(scene, centre, MeshBakeSettings{n, 1}).coverage.empty());
}

} // namespace
} // namespace lfprobe
