// Probe planning on constructed cases: a probe inside a box, in empty space, 1 mm from a wall;
// the resolution a cloud supports doubling when its density doubles; planned bakes.
#include <cmath>
#include <filesystem>
#include <random>

#include <gtest/gtest.h>

#include "lfprobe/error.hpp"
#include "lfprobe/local_geometry.hpp"
#include "lfprobe/probe_classification.hpp"
#include "lfprobe/probe_field.hpp"
#include "lfprobe/probe_plan.hpp"
#include "lfprobe/probe_resolution.hpp"
#include "synthetic_scene.hpp"

namespace lfprobe {
namespace {

using testing::BoxRoomScene;

constexpr glm::dvec3 kRoomScanner{0.0, 0.0, 1.2};
constexpr glm::vec3 kBoxCentre{-1.0f, -0.5f, 1.0f};
constexpr float kBoxHalf = 0.2f;

// The box room (scanned from its centre) with a closed 0.4 m box standing in it, each face
// scanned by its own scanner 1 m in front of it: every face of the box faces out.
PointCloud room_with_box(float spacing) {
    PointCloud cloud = BoxRoomScene{}.cloud(spacing, kRoomScanner);
    const int per_side = static_cast<int>(2.0f * kBoxHalf / spacing);
    for (int axis = 0; axis < 3; ++axis) {
        for (const float side : {-1.0f, 1.0f}) {
            ScanSource scan;
            scan.path = "box face";
            scan.has_scanner = true;
            glm::dvec3 out(0.0);
            out[axis] = side;
            scan.scanner = glm::dvec3(kBoxCentre) + out * 1.0;
            const auto index = static_cast<std::uint32_t>(cloud.scans.size());
            for (int i = 0; i < per_side; ++i) {
                for (int j = 0; j < per_side; ++j) {
                    glm::vec3 p = kBoxCentre;
                    p[axis] += side * kBoxHalf;
                    p[(axis + 1) % 3] += -kBoxHalf + (static_cast<float>(i) + 0.5f) * spacing;
                    p[(axis + 2) % 3] += -kBoxHalf + (static_cast<float>(j) + 0.5f) * spacing;
                    cloud.positions.push_back(p);
                    cloud.colors.push_back(glm::vec3(0.8f, 0.2f, 0.2f));
                    cloud.scan_index.push_back(index);
                }
            }
            scan.point_count = static_cast<std::uint64_t>(per_side) * per_side;
            cloud.scans.push_back(scan);
        }
    }
    return cloud;
}

struct Scene {
    PointCloud cloud = room_with_box(0.02f);
    LocalGeometry geometry = estimate_local_geometry(cloud, {}, nullptr);
};

const Scene& scene() {
    static const Scene s;
    return s;
}

ProbeClassification classify_at(const glm::dvec3& at, ClassificationSettings settings = {}) {
    BakeSettings bake;
    bake.resolution = 64;
    bake.face_the_probe = false; // as the planner's quick bake
    return classify_probe(bake_probe_from_cloud(scene().cloud, scene().geometry, at, bake),
                          settings);
}

TEST(ProbeClassification, ProbeInsideABoxSeesBackFaces) {
    const ProbeClassification c = classify_at(glm::dvec3(kBoxCentre));
    EXPECT_EQ(c.kind, ProbeClass::Inside);
    EXPECT_GT(c.back_face_fraction, 0.9);
    EXPECT_NEAR(c.nearest_surface, kBoxHalf, 0.03);
}

TEST(ProbeClassification, ProbeInEmptySpaceIsIdleOrUseful) {
    // In the open middle of the room: walls 1.2 m and more away. Useful in general; idle when
    // its cell reaches only 0.5 m.
    EXPECT_EQ(classify_at({-0.5, 0.5, 1.5}).kind, ProbeClass::Useful);
    ClassificationSettings small_cell;
    small_cell.cell_reach = 0.5;
    const ProbeClassification c = classify_at({-0.5, 0.5, 1.5}, small_cell);
    EXPECT_EQ(c.kind, ProbeClass::Idle);
    EXPECT_GT(c.nearest_surface, 0.5);
}

TEST(ProbeClassification, ProbeWithNoDataAroundIsBlind) {
    ProbeMap nothing(32, glm::dvec3(0.0));
    for (std::size_t i = 0; i < nothing.texel_count(); ++i) {
        nothing.set_unknown(i);
    }
    EXPECT_EQ(classify_probe(nothing).kind, ProbeClass::Blind);
}

TEST(ProbeClassification, ProbeOneMillimetreFromAWallIsTooClose) {
    // The wall x = 2 m; the probe 1 mm in front of it.
    const ProbeClassification c = classify_at({1.999, 0.0, 1.2});
    EXPECT_EQ(c.kind, ProbeClass::TooClose);
    EXPECT_GT(c.near_fraction, 0.3);
    EXPECT_LT(c.away_from_near.x, -0.9); // away from the wall: toward −x
    EXPECT_THROW((void)classify_probe(ProbeMap{}), InputError);
}

// Probes inside the box, 1 mm from a wall and in the open, planned at a fixed 96².
const ProbePlacement& hard_cases() {
    static const ProbePlacement placement = ProbePlacement::from_positions(
        {glm::dvec3(kBoxCentre), glm::dvec3(1.999, 0.0, 1.2), glm::dvec3(0.3, 0.6, 1.3)});
    return placement;
}

PlanSettings fixed_resolution_plan(double max_move) {
    PlanSettings settings;
    settings.auto_resolution = false;
    settings.fixed_resolution = 96;
    settings.max_move = max_move;
    return settings;
}

TEST(ProbePlan, MovesOrDropsWhatIsNotUseful) {
    const ProbePlacement& placement = hard_cases();
    PlanSettings settings = fixed_resolution_plan(0.3);
    const ProbePlan plan = plan_probes(scene().cloud, scene().geometry, placement, settings);
    ASSERT_EQ(plan.probes.size(), 3u);
    // Inside the box: out through the nearest face, 0.2 + 0.05 m.
    EXPECT_EQ(plan.probes[0].found, ProbeClass::Inside);
    EXPECT_TRUE(plan.probes[0].moved);
    EXPECT_EQ(plan.probes[0].kind, ProbeClass::Useful);
    EXPECT_FALSE(plan.probes[0].dropped);
    EXPECT_NEAR(glm::length(plan.probes[0].position - plan.probes[0].original), 0.25, 0.04);
    // Against the wall: stepped away until clear.
    EXPECT_EQ(plan.probes[1].found, ProbeClass::TooClose);
    EXPECT_TRUE(plan.probes[1].moved);
    EXPECT_EQ(plan.probes[1].kind, ProbeClass::Useful);
    EXPECT_LT(plan.probes[1].position.x, 1.999);
    EXPECT_EQ(plan.probes[1].resolution, 96);
    // In the open: left alone.
    EXPECT_FALSE(plan.probes[2].moved);
    EXPECT_EQ(plan.probes[2].position, placement.positions[2]);

    // With moves bounded to 5 cm the box probe cannot get out: dropped, kept where it was, as
    // an 8² placeholder.
    settings.max_move = 0.05;
    const ProbePlan bounded = plan_probes(scene().cloud, scene().geometry, placement, settings);
    EXPECT_TRUE(bounded.probes[0].dropped);
    EXPECT_FALSE(bounded.probes[0].moved);
    EXPECT_EQ(bounded.probes[0].position, placement.positions[0]);
    EXPECT_EQ(bounded.probes[0].resolution, 8);
}

// The quick bakes that classify bake from the point hierarchy when the planner is given it, as
// the probes' own bakes do: the same classes, moves and drops as from every point, on the cases
// above (inside the box, against the wall, in the open, and a move bounded too short).
TEST(ProbePlan, ClassifyingFromThePointHierarchyPlansAsFromEveryPoint) {
    const ProbePlacement& placement = hard_cases();
    const PointHierarchy hierarchy =
        hierarchy_for_bakes(scene().cloud, scene().geometry, BakeSettings{}, nullptr);
    ASSERT_FALSE(hierarchy.levels.empty());
    for (const double max_move : {0.3, 0.05}) {
        const PlanSettings settings = fixed_resolution_plan(max_move);
        const ProbePlan every_point =
            plan_probes(scene().cloud, scene().geometry, placement, settings);
        const ProbePlan from_hierarchy =
            plan_probes(scene().cloud, scene().geometry, placement, settings, nullptr, &hierarchy);
        ASSERT_EQ(from_hierarchy.probes.size(), every_point.probes.size());
        for (std::size_t i = 0; i < every_point.probes.size(); ++i) {
            const PlannedProbe& a = every_point.probes[i];
            const PlannedProbe& b = from_hierarchy.probes[i];
            EXPECT_EQ(b.found, a.found) << "probe " << i << ", moves up to " << max_move;
            EXPECT_EQ(b.kind, a.kind) << "probe " << i << ", moves up to " << max_move;
            EXPECT_EQ(b.moved, a.moved) << "probe " << i << ", moves up to " << max_move;
            EXPECT_EQ(b.dropped, a.dropped) << "probe " << i << ", moves up to " << max_move;
            EXPECT_LT(glm::length(b.position - a.position), 0.02)
                << "probe " << i << ", moves up to " << max_move;
        }
    }
}

// The plan of one probe at `at` in the test scene.
PlannedProbe plan_one(const glm::dvec3& at, const PlanSettings& settings) {
    return plan_probes(scene().cloud, scene().geometry, ProbePlacement::from_positions({at}),
                       settings)
        .probes[0];
}

TEST(ProbePlan, AProbeBesideASurfaceStaysWhereItSeesEverything) {
    // 1.5 cm in front of the box's +x face (the hard scene's probe beside a pillar): too close,
    // but it sees the face and the room whole; a move would gain nothing, so it stays, kept.
    const glm::dvec3 at(kBoxCentre.x + kBoxHalf + 0.015, kBoxCentre.y, kBoxCentre.z);
    PlanSettings settings;
    settings.auto_resolution = false;
    settings.fixed_resolution = 32;
    const PlannedProbe p = plan_one(at, settings);
    EXPECT_EQ(p.found, ProbeClass::TooClose);
    EXPECT_EQ(p.kind, ProbeClass::TooClose);
    EXPECT_LT(p.classification.unknown_fraction, settings.min_coverage_gain);
    EXPECT_FALSE(p.moved);
    EXPECT_FALSE(p.dropped);
    EXPECT_EQ(p.position, at);
    EXPECT_EQ(p.resolution, 32);
}

TEST(ProbePlan, AProbeOnAWallsPlaneMovesTowardWhatItSees) {
    // On the plane of the wall x = 2: the wall is seen edge-on and the side behind it, never
    // scanned, is unknown: half the sphere. A step into the room lets it see the wall.
    const glm::dvec3 at(2.0, 0.31, 1.13);
    PlanSettings settings;
    settings.auto_resolution = false;
    settings.max_move = 0.3;
    const PlannedProbe p = plan_one(at, settings);
    EXPECT_TRUE(p.moved);
    EXPECT_LT(p.position.x, 2.0);
    EXPECT_NEAR(p.position.y, at.y, 0.01);
    EXPECT_NEAR(p.position.z, at.z, 0.01);
    EXPECT_EQ(p.kind, ProbeClass::Useful);
    EXPECT_LT(p.classification.unknown_fraction, 0.01);
}

TEST(ProbeResolution, DoublingTheDensityDoublesTheSupportedResolution) {
    // The same room at 4 cm and 2 cm pitch, probe in the middle: N ≈ sqrt(4π)·r/s.
    const PointCloud coarse = BoxRoomScene{}.cloud(0.04f, kRoomScanner);
    const PointCloud fine = BoxRoomScene{}.cloud(0.02f, kRoomScanner);
    const ResolutionChoice a =
        choose_resolution(coarse, estimate_local_geometry(coarse, {}, nullptr), {0.0, 0.0, 1.2});
    const ResolutionChoice b =
        choose_resolution(fine, estimate_local_geometry(fine, {}, nullptr), {0.0, 0.0, 1.2});
    EXPECT_NEAR(b.data_resolution / a.data_resolution, 2.0, 0.2);
    EXPECT_NEAR(a.median_spacing, 0.04, 0.008);
    EXPECT_NEAR(a.data_resolution, 3.5449 * a.median_distance / a.median_spacing,
                0.35 * a.data_resolution);
    EXPECT_EQ(b.resolution, 2 * a.resolution);
    // A footprint caps it: 5 cm texels at the median distance.
    ResolutionSettings capped;
    capped.footprint = 0.05;
    const ResolutionChoice c = choose_resolution(fine, estimate_local_geometry(fine, {}, nullptr),
                                                 {0.0, 0.0, 1.2}, capped);
    EXPECT_LT(c.resolution, b.resolution);
    EXPECT_NEAR(c.footprint_resolution, 3.5449077018110318 * c.median_distance / 0.05, 1e-9);
    ResolutionSettings bad;
    bad.quantile = 2.0;
    EXPECT_THROW(
        (void)choose_resolution(fine, estimate_local_geometry(fine, {}, nullptr), {0, 0, 1.2}, bad),
        InputError);
}

TEST(ProbePlan, PlannedBakeWritesEachProbeAtItsResolutionAndTracesAsAGrid) {
    const ProbeGrid grid = ProbeGrid::spanning({-1.0, -0.5, 1.0}, {1.0, 0.5, 1.0}, {2, 2, 1});
    const ProbePlacement placement = ProbePlacement::from_grid(grid);
    PlanSettings settings;
    settings.resolution.max_resolution = 256;
    const ProbePlan plan = plan_probes(scene().cloud, scene().geometry, placement, settings);
    // Probe 0 sits at the box's centre: moved out of it.
    EXPECT_EQ(plan.probes[0].found, ProbeClass::Inside);
    const std::filesystem::path folder =
        std::filesystem::temp_directory_path() /
        ("lfprobe_plan_test_" + std::to_string(std::random_device{}()));
    const BakeSummary summary = bake_planned_probe_set(scene().cloud, scene().geometry, placement,
                                                       plan, settings, folder.string(), {});
    EXPECT_EQ(summary.probe_count, 4u);
    const ProbeField field = ProbeField::load(folder.string());
    EXPECT_TRUE(field.is_grid());
    for (std::size_t i = 0; i < 4; ++i) {
        EXPECT_EQ(field.probe(i).resolution, plan.probes[i].resolution);
        EXPECT_EQ(field.probe(i).position, plan.probes[i].position);
    }
    EXPECT_TRUE(field.manifest().bake.contains("plan"));
    std::filesystem::remove_all(folder);
}

} // namespace
} // namespace lfprobe
