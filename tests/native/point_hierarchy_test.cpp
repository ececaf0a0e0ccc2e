// The point hierarchy (docs/DESIGN.md §4, "Point hierarchy"): a probe baked from its cut sees
// what a probe baked from every point sees, at a cost that follows its texels.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include "lfprobe/octahedral.hpp"
#include "lfprobe/point_hierarchy.hpp"
#include "lfprobe/probe_bake.hpp"
#include "wall_cloud.hpp"

using namespace lfprobe;
using lfprobe::testing::dense_wall;
using lfprobe::testing::same_bits;

namespace {

bool known(TexelState s) {
    return s == TexelState::Surface || s == TexelState::Inferred;
}

void expect_same_surfels(const std::vector<CellSurfel>& a, const std::vector<CellSurfel>& b) {
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        ASSERT_EQ(a[i].position, b[i].position) << i;
        ASSERT_EQ(a[i].normal, b[i].normal) << i;
        ASSERT_EQ(a[i].colour, b[i].colour) << i;
        ASSERT_EQ(a[i].spacing, b[i].spacing) << i;
        ASSERT_EQ(a[i].count, b[i].count) << i;
        ASSERT_EQ(a[i].facing, b[i].facing) << i;
        ASSERT_EQ(a[i].oriented, b[i].oriented) << i;
    }
}

} // namespace

TEST(PointHierarchy, TheCutNeverLeavesAHoleTheFullCloudFills) {
    // A wall of 2 mm pitch, 1.2 m square, seen face-on from 0.3 m to 12 m at 128²: from 1 m on,
    // a texel spans many points and the cut stands in cell surfels for them.
    const glm::vec3 colour(0.3f, 0.55f, 0.8f);
    const PointCloud cloud = dense_wall(0.002f, 0.6f, colour);
    const LocalGeometry geometry = estimate_local_geometry(cloud, {});
    const PointHierarchy hierarchy = build_point_hierarchy(cloud, geometry);
    ASSERT_GE(hierarchy.levels.size(), 3u);
    BakeSettings settings;
    settings.resolution = 128;
    const float texel_angle = static_cast<float>(oct::kTexelAngleTimesN) / 128.0f;
    for (const double d : {0.3, 1.0, 3.0, 12.0}) {
        SCOPED_TRACE("probe " + std::to_string(d) + " m from the wall");
        const glm::dvec3 probe(-d, 0.05, -0.03);
        const HierarchyCut cut =
            cut_for_probe(hierarchy, probe, CutRule{texel_angle, settings.lod_texels, 0.0f});
        if (d >= 1.0) {
            EXPECT_LT(cut.size(), cloud.size() / 20) << "the cut must stand in for the points";
        }
        const ProbeMap full = bake_probe_from_cloud(cloud, geometry, probe, settings);
        const ProbeMap lod = bake_probe_from_hierarchy(cloud, geometry, hierarchy, probe, settings);
        std::size_t full_known = 0;
        std::size_t holes = 0;
        for (std::size_t t = 0; t < full.texel_count(); ++t) {
            if (!known(full.state(t))) {
                continue;
            }
            // Texels whose centre ray passes beside the wall are its silhouette, which the
            // full cloud widens by up to a texel (a point claims the texel it lies in): a cut
            // may draw it tighter. Every texel whose ray meets the wall must stay known.
            const glm::vec3 dir = oct::texel_direction(
                {static_cast<int>(t % 128), static_cast<int>(t / 128)}, settings.resolution);
            const glm::vec3 on_wall = glm::vec3(probe) + dir * (static_cast<float>(d) / dir.x);
            const bool meets_wall =
                dir.x > 0.0f && std::abs(on_wall.y) <= 0.6f && std::abs(on_wall.z) <= 0.6f;
            if (!meets_wall) {
                continue;
            }
            ++full_known;
            if (!known(lod.state(t))) {
                ++holes;
                continue;
            }
            // The plane x = 0 at the texel's ray: the depth is the plane's, the colour exact.
            const float truth = static_cast<float>(d) / dir.x;
            EXPECT_NEAR(lod.distance_at(t), truth, 0.01f * truth) << t;
            if (lod.state(t) == TexelState::Surface) {
                EXPECT_EQ(lod.radiance_at(t), full.radiance_at(t)) << t;
            }
        }
        EXPECT_GT(full_known, 10u);
        EXPECT_EQ(holes, 0u) << "of " << full_known << " texels the full cloud fills";
    }
}

TEST(PointHierarchy, AThinPlatesBackNeverColoursItsFront) {
    // A plate 1 cm thick, red in front (scanned from x < 0), blue behind (scanned from x > 0),
    // seen from 3 m in front at 128²: the cut's cells are wider than the plate, and hold both
    // sides. The facings keep them apart, and the back's surfels, facing away from the probe,
    // give the front no colour.
    const glm::vec3 red(0.8f, 0.1f, 0.1f);
    const glm::vec3 blue(0.1f, 0.1f, 0.8f);
    PointCloud cloud = dense_wall(0.003f, 0.4f, red);
    const std::size_t front = cloud.size();
    const PointCloud back = dense_wall(0.003f, 0.4f, blue);
    for (const glm::vec3& p : back.positions) {
        cloud.positions.emplace_back(0.01f, p.y, p.z);
        cloud.colors.push_back(blue);
        cloud.scan_index.push_back(1);
    }
    cloud.scans[0].point_count = front;
    cloud.scans.push_back(ScanSource{"back", back.size(), glm::dvec3(2.0, 0.0, 0.0), true});
    const LocalGeometry geometry = estimate_local_geometry(cloud, {});
    const PointHierarchy hierarchy = build_point_hierarchy(cloud, geometry);
    BakeSettings settings;
    settings.resolution = 128;
    const glm::dvec3 probe(-3.0, 0.02, 0.01);
    const float texel_angle = static_cast<float>(oct::kTexelAngleTimesN) / 128.0f;
    const HierarchyCut cut =
        cut_for_probe(hierarchy, probe, CutRule{texel_angle, settings.lod_texels, 0.0f});
    ASSERT_TRUE(cut.points.empty());
    const ProbeMap lod = bake_probe_from_hierarchy(cloud, geometry, hierarchy, probe, settings);
    std::size_t front_texels = 0;
    for (std::size_t t = 0; t < lod.texel_count(); ++t) {
        if (lod.state(t) == TexelState::Surface) {
            EXPECT_LT(lod.radiance_at(t).z, 0.11f) << t;
            const glm::vec3 dir = oct::texel_direction(
                {static_cast<int>(t % 128), static_cast<int>(t / 128)}, settings.resolution);
            EXPECT_NEAR(lod.distance_at(t), 3.0f / dir.x, 0.01f * 3.0f / dir.x) << t;
            ++front_texels;
        }
    }
    EXPECT_GT(front_texels, 20u);
}

TEST(PointHierarchy, ARebuildIsBitIdenticalForAnyThreadCount) {
    const PointCloud cloud = lfprobe::testing::wall_corner(0.004f);
    const LocalGeometry geometry = estimate_local_geometry(cloud, {});
    const PointHierarchy a = build_point_hierarchy(cloud, geometry);
    PointHierarchy b;
    tbb::task_arena one_thread(1);
    one_thread.execute([&] { b = build_point_hierarchy(cloud, geometry); });
    ASSERT_EQ(a.order, b.order);
    ASSERT_EQ(a.levels.size(), b.levels.size());
    ASSERT_GE(a.levels.size(), 2u);
    for (std::size_t l = 0; l < a.levels.size(); ++l) {
        ASSERT_EQ(a.levels[l].cell_keys, b.levels[l].cell_keys);
        ASSERT_EQ(a.levels[l].first_point, b.levels[l].first_point);
        ASSERT_EQ(a.levels[l].first_child, b.levels[l].first_child);
        ASSERT_EQ(a.levels[l].first_surfel, b.levels[l].first_surfel);
        expect_same_surfels(a.levels[l].surfels, b.levels[l].surfels);
    }
    // Every cell's surfels stand for all of its points, on every level.
    for (const PointHierarchy::Level& level : a.levels) {
        std::uint64_t counted = 0;
        for (const CellSurfel& s : level.surfels) {
            counted += s.count;
        }
        EXPECT_EQ(counted, cloud.size());
    }
    // And a probe's bake from it is the same, bit for bit.
    BakeSettings settings;
    settings.resolution = 64;
    const glm::dvec3 probe(-2.0, 0.1, 0.2);
    const ProbeMap many = bake_probe_from_hierarchy(cloud, geometry, a, probe, settings);
    ProbeMap single;
    one_thread.execute(
        [&] { single = bake_probe_from_hierarchy(cloud, geometry, b, probe, settings); });
    ASSERT_TRUE(same_bits(many.distance, single.distance));
    ASSERT_TRUE(same_bits(many.rgba, single.rgba));
}

TEST(PointHierarchy, LodZeroBakesEveryPointBitForBit) {
    const PointCloud cloud = dense_wall(0.005f, 0.5f, glm::vec3(0.4f, 0.5f, 0.6f));
    const LocalGeometry geometry = estimate_local_geometry(cloud, {});
    const PointHierarchy hierarchy = build_point_hierarchy(cloud, geometry);
    BakeSettings settings;
    settings.resolution = 64;
    settings.lod_texels = 0.0f;
    const glm::dvec3 probe(-1.5, 0.0, 0.1);
    const ProbeMap full = bake_probe_from_cloud(cloud, geometry, probe, settings);
    const ProbeMap lod = bake_probe_from_hierarchy(cloud, geometry, hierarchy, probe, settings);
    ASSERT_TRUE(same_bits(full.distance, lod.distance));
    ASSERT_TRUE(same_bits(full.rgba, lod.rgba));
    ASSERT_TRUE(same_bits(full.normal, lod.normal));
}

TEST(PointHierarchy, ACancelledBuildThrows) {
    const PointCloud cloud = dense_wall(0.01f, 0.5f, glm::vec3(0.5f));
    const LocalGeometry geometry = estimate_local_geometry(cloud, {});
    Progress progress;
    progress.request_cancel();
    EXPECT_THROW((void)build_point_hierarchy(cloud, geometry, &progress), Cancelled);
}

TEST(PointHierarchy, RejectsGeometryOfAnotherCloud) {
    const PointCloud cloud = dense_wall(0.05f, 0.5f, glm::vec3(0.5f));
    const PointCloud other = dense_wall(0.1f, 0.5f, glm::vec3(0.5f));
    const LocalGeometry geometry = estimate_local_geometry(other, {});
    EXPECT_THROW((void)build_point_hierarchy(cloud, geometry), InputError);
}

TEST(PointHierarchy, AColourToleranceCoarsensOnlyWhereTheChildrenAgree) {
    // Two walls of 2 mm pitch seen face-on at 128²: one of one colour, one striped across y in
    // a triangle wave of 10 cm period (no flat part). With a colour tolerance, the plain wall's
    // cut takes the wider cells (far fewer surfels); on both, every texel keeps within about
    // the tolerance of the colour the cut without it gives, and none is lost.
    constexpr float kTolerance = 0.01f;
    const float texel_angle = static_cast<float>(oct::kTexelAngleTimesN) / 128.0f;
    BakeSettings plain_settings;
    plain_settings.resolution = 128;
    BakeSettings tolerant_settings = plain_settings;
    tolerant_settings.lod_colour_tolerance = kTolerance;
    for (const bool striped : {false, true}) {
        PointCloud cloud = dense_wall(0.002f, 0.6f, glm::vec3(0.3f, 0.55f, 0.8f));
        if (striped) {
            for (std::size_t i = 0; i < cloud.size(); ++i) {
                const float y = cloud.positions[i].y / 0.1f;
                const float phase = y - std::floor(y);
                cloud.colors[i].x = 0.1f + 0.8f * (1.0f - std::abs(2.0f * phase - 1.0f));
            }
        }
        const LocalGeometry geometry = estimate_local_geometry(cloud, {});
        const PointHierarchy hierarchy = build_point_hierarchy(cloud, geometry);
        for (const double d : {0.5, 1.0, 3.0}) {
            SCOPED_TRACE(std::string(striped ? "striped" : "plain") + " wall, probe " +
                         std::to_string(d) + " m away");
            const glm::dvec3 probe(-d, 0.05, -0.03);
            const HierarchyCut plain =
                cut_for_probe(hierarchy, probe, CutRule{texel_angle, 1.0f, 0.0f});
            const HierarchyCut tolerant =
                cut_for_probe(hierarchy, probe, CutRule{texel_angle, 1.0f, kTolerance});
            EXPECT_LE(tolerant.size(), plain.size());
            if (!striped && d < 2.0) { // from 3 m the cut is the coarsest level's cells already
                EXPECT_LT(2 * tolerant.size(), plain.size())
                    << "the plain wall's wider cells agree";
            }
            const ProbeMap a =
                bake_probe_from_hierarchy(cloud, geometry, hierarchy, probe, plain_settings);
            const ProbeMap b =
                bake_probe_from_hierarchy(cloud, geometry, hierarchy, probe, tolerant_settings);
            std::size_t compared = 0;
            for (std::size_t t = 0; t < a.texel_count(); ++t) {
                if (a.state(t) != TexelState::Surface) {
                    continue;
                }
                ASSERT_TRUE(known(b.state(t))) << "texel " << t << " lost";
                EXPECT_NEAR(b.distance_at(t), a.distance_at(t), 0.01f * a.distance_at(t)) << t;
                const glm::vec3 delta = glm::abs(b.radiance_at(t) - a.radiance_at(t));
                EXPECT_LE(std::max({delta.x, delta.y, delta.z}), 2.0f * kTolerance) << t;
                ++compared;
            }
            EXPECT_GT(compared, 10u);
        }
    }
}
