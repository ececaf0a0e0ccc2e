// Several probes (docs/DESIGN.md §4 "Many probes"): grid walks with any counts, cameras outside the
// grid, rays through probe centres, nearest-first tracing that carries the free distance, and
// loading a baked set from disk.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "lfprobe/cloud_bake.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/probe_field.hpp"
#include "lfprobe/probe_set.hpp"
#include "lfprobe/render.hpp"
#include "trace_scenes.hpp"

using namespace lfprobe;
using lfprobe::testing::BoxRoomScene;
namespace scenes = lfprobe::testing;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

Ray make_ray(const glm::dvec3& origin, const glm::dvec3& dir, double t_min = 0.0) {
    Ray ray;
    ray.origin = origin;
    ray.direction = glm::normalize(dir);
    ray.t_min = t_min;
    ray.t_max = kInf;
    return ray;
}

double truth(const BoxRoomScene& scene, const Ray& ray) {
    return static_cast<double>(scene.distance(glm::vec3(ray.origin), glm::vec3(ray.direction)));
}

struct Tally {
    std::size_t rays = 0;
    std::size_t counts[3] = {0, 0, 0};
    std::vector<double> errors;
    std::uint64_t steps = 0;
    std::uint64_t probes = 0;

    void add(const FieldTraceResult& r, double exact) {
        ++rays;
        ++counts[static_cast<int>(r.status)];
        steps += r.steps;
        probes += r.probes_tried;
        if (r.status == TraceStatus::Hit) {
            errors.push_back(std::abs(r.t - exact));
        }
    }
    [[nodiscard]] double rate(TraceStatus s) const {
        return static_cast<double>(counts[static_cast<int>(s)]) / static_cast<double>(rays);
    }
    [[nodiscard]] double percentile(double q) {
        std::sort(errors.begin(), errors.end());
        return errors.empty()
                   ? 0.0
                   : errors[static_cast<std::size_t>(q * static_cast<double>(errors.size() - 1))];
    }
    void print(const char* what) {
        std::printf("%s: %zu rays, hit %.4f, unknown %.4f, miss %.4f; depth error median %.3g m, "
                    "95%% %.3g m; %.1f steps and %.2f probes per ray\n",
                    what, rays, rate(TraceStatus::Hit), rate(TraceStatus::Unknown),
                    rate(TraceStatus::Miss), percentile(0.5), percentile(0.95),
                    static_cast<double>(steps) / static_cast<double>(rays),
                    static_cast<double>(probes) / static_cast<double>(rays));
    }
};

} // namespace

TEST(Grid, CountsThatAreNotPowersOfTwo) {
    const BoxRoomScene scene;
    const ProbeGrid grid = ProbeGrid::spanning({-1.5, -1.0, 0.3}, {1.5, 1.0, 2.2}, {3, 2, 5});
    const ProbeField field = scenes::analytic_field(scene, ProbePlacement::from_grid(grid), 128);
    ASSERT_EQ(field.probe_count(), 30u);
    std::mt19937 rng(17);
    Tally grid_tally;
    Tally nearest_tally;
    FieldTraceSettings nearest;
    nearest.mode = FieldMode::Nearest;
    for (int i = 0; i < 3000; ++i) {
        const Ray ray =
            make_ray(scenes::random_point_in_room(scene, rng, 0.05), scenes::random_unit(rng));
        const double exact = truth(scene, ray);
        const FieldTraceResult g = field.trace(ray);
        const FieldTraceResult n = field.trace(ray, nearest);
        grid_tally.add(g, exact);
        nearest_tally.add(n, exact);
        if (g.status != TraceStatus::Unknown) {
            ASSERT_GE(g.probe, 0);
            ASSERT_LT(g.probe, 30);
        } else {
            EXPECT_EQ(g.probe, -1);
        }
    }
    grid_tally.print("grid 3x2x5, grid walk");
    nearest_tally.print("grid 3x2x5, 8 nearest");
    EXPECT_EQ(grid_tally.counts[0], 0u); // a closed room: never a MISS
    EXPECT_GT(grid_tally.rate(TraceStatus::Hit), 0.97);
    // The maps' quantisation: a 128² texel spans about 1.6°, 5-7 cm at the far walls.
    EXPECT_LT(grid_tally.percentile(0.5), 0.01);
    EXPECT_LT(grid_tally.percentile(0.95), 0.07);
}

TEST(Grid, CameraOutsideTheGrid) {
    const BoxRoomScene room = scenes::empty_box_room();
    const ProbeGrid grid = ProbeGrid::spanning({-0.5, -0.4, 0.8}, {0.5, 0.4, 1.6}, {2, 2, 2});
    const ProbeField field = scenes::analytic_field(room, ProbePlacement::from_grid(grid), 128);
    std::mt19937 rng(23);
    Tally through_box;
    Tally beside_box;
    for (int i = 0; i < 500; ++i) {
        // From the far end of the room toward the grid, and along the walls beside it.
        const glm::dvec3 eye(1.8, std::uniform_real_distribution<double>(-1.2, 1.2)(rng),
                             std::uniform_real_distribution<double>(0.2, 2.3)(rng));
        const glm::dvec3 target(std::uniform_real_distribution<double>(-0.4, 0.4)(rng),
                                std::uniform_real_distribution<double>(-0.3, 0.3)(rng),
                                std::uniform_real_distribution<double>(0.9, 1.5)(rng));
        const Ray in = make_ray(eye, target - eye);
        through_box.add(field.trace(in), truth(room, in));
        const Ray beside =
            make_ray(eye, glm::dvec3(-1.0, 0.0, 0.0) + 0.3 * scenes::random_unit(rng));
        beside_box.add(field.trace(beside), truth(room, beside));
    }
    through_box.print("camera outside the grid, rays through it");
    beside_box.print("camera outside the grid, any direction");
    EXPECT_EQ(through_box.counts[static_cast<int>(TraceStatus::Hit)], through_box.rays);
    EXPECT_GT(beside_box.rate(TraceStatus::Hit), 0.99);
    EXPECT_LT(through_box.percentile(0.95), 0.06);
    // A ray that never meets the grid's box is traced nearest-first.
    const Ray away = make_ray({1.5, 1.0, 0.3}, {0.0, -1.0, 0.0});
    const FieldTraceResult a = field.trace(away);
    EXPECT_EQ(a.status, TraceStatus::Hit);
    EXPECT_NEAR(a.t, 2.5, 0.01);
    // From behind a wall: the probes saw its front, never a HIT through it.
    EXPECT_EQ(field.trace(make_ray({2.3, 0.0, 1.2}, {-1.0, 0.02, 0.0})).status,
              TraceStatus::Unknown);

    // An object between the camera and the grid is not looked through: the sphere stands
    // between a camera at x = 1.8 and probes at x <= -0.5, which see only its far side.
    const BoxRoomScene scene;
    const ProbeGrid behind = ProbeGrid::spanning({-1.5, -0.4, 0.6}, {-0.5, 0.4, 1.4}, {2, 2, 2});
    const ProbeField hidden = scenes::analytic_field(scene, ProbePlacement::from_grid(behind), 128);
    for (int i = 0; i < 100; ++i) {
        const glm::dvec3 eye(1.8, 0.4, 1.0);
        const glm::dvec3 on_sphere =
            glm::dvec3(scene.sphere_centre) + 0.3 * scenes::random_unit(rng) * 0.5;
        const Ray ray = make_ray(eye, on_sphere - eye);
        const double exact = truth(scene, ray);
        const FieldTraceResult r = hidden.trace(ray);
        EXPECT_NE(r.status, TraceStatus::Miss);
        if (r.status == TraceStatus::Hit) {
            EXPECT_LT(r.t, exact + 0.05) << "looked through the sphere";
        }
    }
}

TEST(Grid, RaysThroughOtherProbesCentres) {
    const BoxRoomScene room = scenes::empty_box_room();
    const ProbeGrid grid = ProbeGrid::spanning({-1.0, -0.6, 0.6}, {1.0, 0.6, 1.8}, {2, 2, 2});
    const ProbeField field = scenes::analytic_field(room, ProbePlacement::from_grid(grid), 128);
    const std::vector<glm::dvec3> p = grid.positions();
    Tally tally;
    for (std::size_t a = 0; a < p.size(); ++a) {
        for (std::size_t b = 0; b < p.size(); ++b) {
            if (a == b) {
                continue;
            }
            const glm::dvec3 d = glm::normalize(p[b] - p[a]);
            // From probe a itself (one lookup), from a point before a, and from the middle.
            for (const glm::dvec3& eye : {p[a], p[a] - 0.2 * d, 0.5 * (p[a] + p[b])}) {
                const Ray ray = make_ray(eye, d);
                const FieldTraceResult r = field.trace(ray);
                tally.add(r, truth(room, ray));
                EXPECT_EQ(r.status, TraceStatus::Hit);
            }
        }
    }
    tally.print("rays through probe centres");
    EXPECT_LT(tally.percentile(0.95), 0.05);
    EXPECT_LT(tally.percentile(1.0), 0.15); // diagonals end in the room's corners
    // At a probe the answer is that probe's lookup.
    const Ray at = make_ray(p[3], {0.3, -0.2, 0.9});
    const FieldTraceResult r = field.trace(at);
    EXPECT_EQ(r.probe, 3);
    EXPECT_EQ(r.steps, 1u);
}

TEST(Grid, LinesAndSingleProbes) {
    const BoxRoomScene room = scenes::empty_box_room();
    std::mt19937 rng(31);
    for (const std::array<int, 3> counts :
         {std::array<int, 3>{4, 1, 1}, std::array<int, 3>{1, 3, 1}, std::array<int, 3>{1, 1, 1}}) {
        const ProbeGrid grid = ProbeGrid::spanning({-1.2, -0.8, 1.0}, {1.2, 0.8, 1.4}, counts);
        const ProbeField field = scenes::analytic_field(room, ProbePlacement::from_grid(grid), 96);
        Tally tally;
        for (int i = 0; i < 400; ++i) {
            const Ray ray =
                make_ray(scenes::random_point_in_room(room, rng, 0.1), scenes::random_unit(rng));
            tally.add(field.trace(ray), truth(room, ray));
        }
        tally.print("line / single-probe grid");
        EXPECT_EQ(tally.counts[0], 0u);
        EXPECT_GT(tally.rate(TraceStatus::Hit), 0.99);
    }
}

TEST(Grid, NearestCarriesTheProvenFreeDistanceToTheNextProbe) {
    const BoxRoomScene room = scenes::empty_box_room();
    const glm::dvec3 a(-0.5, 0.0, 1.2);
    const glm::dvec3 b(0.5, 0.3, 1.2);
    std::vector<ProbeMap> probes{scenes::analytic_probe(room, a, 128),
                                 scenes::analytic_probe(room, b, 128)};
    // Probe a knows nothing toward +x beyond 30° of the axis.
    const int n = probes[0].resolution;
    for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
            if (glm::dot(oct::texel_direction({x, y}, n), glm::vec3(1, 0, 0)) > 0.866f) {
                probes[0].set_unknown(oct::texel_index({x, y}, n));
            }
        }
    }
    const ProbeField field(ProbePlacement::from_positions({a, b}), std::move(probes));
    const Ray ray = make_ray({-0.45, 0.0, 1.1}, {1.0, 0.1, 0.05});
    const FieldTraceResult only_a = [&] {
        FieldTraceSettings s;
        s.max_probes = 1;
        return field.trace(ray, s);
    }();
    EXPECT_EQ(only_a.status, TraceStatus::Unknown);
    EXPECT_EQ(only_a.probe, -1);
    const FieldTraceResult r = field.trace(ray);
    EXPECT_EQ(r.status, TraceStatus::Hit);
    EXPECT_EQ(r.probe, 1);
    EXPECT_EQ(r.probes_tried, 2u);
    EXPECT_NEAR(r.t, truth(room, ray), 0.02);
    // A bound of one probe a ray stops the ray at probe a; two let probe b answer as before.
    FieldTraceSettings bounded;
    bounded.max_probes_per_ray = 1;
    const FieldTraceResult one_probe = field.trace(ray, bounded);
    EXPECT_EQ(one_probe.status, TraceStatus::Unknown);
    EXPECT_EQ(one_probe.probes_tried, 1u);
    bounded.max_probes_per_ray = 2;
    EXPECT_EQ(field.trace(ray, bounded).t, r.t);
    // Probe b was asked from where probe a stopped, not from the start.
    Ray from_free = ray;
    from_free.t_min = only_a.free_until;
    const ProbeTraceResult b_alone = field.trace_one(1, from_free);
    EXPECT_EQ(b_alone.t, r.t);
    EXPECT_EQ(r.steps, only_a.steps + b_alone.steps());
}

TEST(Grid, AFallbackAnswersOnlyWhereNoProbeDoes) {
    // A ray that runs 2 cm behind the wall probe a saw, as one passing just behind a near
    // object's edge seen from one station does: probe a answers UNKNOWN, keeping the wall as a
    // fallback. Alone, the field answers HIT on it. Probe b saw a room whose wall lies further
    // out (what a second station saw behind the edge): asked after a, its answer stands.
    const BoxRoomScene room = scenes::empty_box_room();
    BoxRoomScene wider = room;
    wider.room_max.x = 2.5f;
    const glm::dvec3 a(0.0, 0.0, 1.0);
    const glm::dvec3 b(-1.0, 0.0, 1.0);
    const Ray ray = make_ray(a + glm::dvec3(2.02, 0.1, 0.1), {0.0, 1.0, 0.05});
    const ProbeField alone(ProbePlacement::from_positions({a}),
                           std::vector<ProbeMap>{scenes::analytic_probe(room, a, 1024)});
    const FieldTraceResult fallback = alone.trace(ray);
    EXPECT_EQ(fallback.status, TraceStatus::Hit);
    EXPECT_EQ(fallback.probe, 0);
    EXPECT_NEAR(fallback.t, 0.0, 1e-9);
    EXPECT_NE(fallback.texel, (oct::Texel{-1, -1}));
    FieldTraceSettings off;
    off.probe.fallback_thickness = off.probe.thickness;
    EXPECT_EQ(alone.trace(ray, off).status, TraceStatus::Unknown);

    const ProbeField both(ProbePlacement::from_positions({a, b}),
                          std::vector<ProbeMap>{scenes::analytic_probe(room, a, 1024),
                                                scenes::analytic_probe(wider, b, 1024)});
    const FieldTraceResult answered = both.trace(ray);
    EXPECT_EQ(answered.status, TraceStatus::Hit);
    EXPECT_EQ(answered.probe, 1);
    EXPECT_EQ(answered.probes_tried, 2u);
    EXPECT_NEAR(answered.t, truth(wider, ray), 0.02);
}

TEST(Grid, ACellWhoseProbesKnowNothingIsSkipped) {
    // Three probes along x; the two of the cell x in [0.5, 1.5] know nothing (a part of the
    // room no scan reached). A ray that stays in that cell asks no probe; one that runs from it
    // into the next cell asks only the probe that knows something there. The answers are those
    // of asking every probe.
    const BoxRoomScene room = scenes::empty_box_room();
    const ProbeGrid grid = ProbeGrid::spanning({-0.5, 0.0, 1.2}, {1.5, 0.0, 1.2}, {3, 1, 1});
    const ProbePlacement placement = ProbePlacement::from_grid(grid);
    std::vector<ProbeMap> probes;
    for (const glm::dvec3& p : placement.positions) {
        probes.push_back(scenes::analytic_probe(room, p, 64));
    }
    for (std::size_t k = 1; k < 3; ++k) {
        for (std::size_t i = 0; i < probes[k].texel_count(); ++i) {
            probes[k].set_unknown(i);
        }
    }
    const ProbeField field(placement, std::move(probes));
    EXPECT_FALSE(field.knows_nothing(0));
    EXPECT_TRUE(field.knows_nothing(1));
    EXPECT_TRUE(field.knows_nothing(2));
    FieldTraceSettings ask_all;
    ask_all.skip_probes_that_know_nothing = false;
    ask_all.stop_where_no_probe_can_answer = false;

    const Ray stays = make_ray({0.9, 0.05, 1.25}, {1.0, 0.02, 0.01});
    const FieldTraceResult skipped = field.trace(stays);
    const FieldTraceResult asked = field.trace(stays, ask_all);
    EXPECT_EQ(skipped.status, TraceStatus::Unknown);
    EXPECT_EQ(skipped.probes_tried, 0u);
    EXPECT_EQ(skipped.steps, 0u);
    EXPECT_EQ(asked.status, TraceStatus::Unknown);
    EXPECT_EQ(asked.probes_tried, 2u);
    EXPECT_EQ(skipped.free_until, asked.free_until);

    const Ray leaves = make_ray({0.9, 0.05, 1.25}, {-1.0, 0.03, 0.02});
    const FieldTraceResult one = field.trace(leaves);
    const FieldTraceResult all = field.trace(leaves, ask_all);
    EXPECT_EQ(one.status, TraceStatus::Hit);
    EXPECT_EQ(one.probe, 0);
    EXPECT_EQ(one.probes_tried, 1u);
    EXPECT_GT(all.probes_tried, one.probes_tried);
    EXPECT_EQ(one.t, all.t);
    EXPECT_EQ(one.radiance, all.radiance);
    EXPECT_NEAR(one.t, truth(room, leaves), 0.02);
    // Asking every probe but at most one a ray, the walk stops in the first cell: the probe
    // that knows nothing was the one asked.
    FieldTraceSettings bounded = ask_all;
    bounded.max_probes_per_ray = 1;
    const FieldTraceResult cut_short = field.trace(leaves, bounded);
    EXPECT_EQ(cut_short.status, TraceStatus::Unknown);
    EXPECT_EQ(cut_short.probes_tried, 1u);

    // Opened lazily from disk, the probes' manifest records say which know nothing, before
    // any probe is read; a ray that stays in the cell reads none.
    const std::filesystem::path folder =
        std::filesystem::temp_directory_path() /
        ("lfprobe_field_test_nothing_" + std::to_string(std::random_device{}()));
    ProbeSetManifest manifest;
    manifest.placement = placement;
    (void)write_probe_set(folder.string(), manifest, [&](std::size_t i) { return field.probe(i); });
    const ProbeField lazy = ProbeField::load(folder.string(), nullptr, 0, {}, true);
    EXPECT_TRUE(lazy.knows_nothing(1) && lazy.knows_nothing(2) && !lazy.knows_nothing(0));
    EXPECT_EQ(lazy.trace(stays).probes_tried, 0u);
    EXPECT_EQ(lazy.loaded_probe_count(), 0u);
    EXPECT_EQ(lazy.trace(leaves).t, one.t);
    std::filesystem::remove_all(folder);
}

TEST(Grid, ProbeSetsLoadFromDiskAndModesAreChecked) {
    const BoxRoomScene room;
    const PointCloud cloud = room.cloud(0.05f, glm::dvec3(0.0, 0.0, 1.2));
    const ProbeGrid grid = ProbeGrid::spanning({-0.6, -0.3, 1.0}, {0.6, 0.3, 1.4}, {2, 1, 1});
    BakeSettings bake;
    bake.resolution = 48;
    const std::filesystem::path folder =
        std::filesystem::temp_directory_path() /
        ("lfprobe_field_test_" + std::to_string(std::random_device{}()));
    const BakeSummary summary = bake_probe_set_from_cloud(
        cloud, ProbePlacement::from_grid(grid), bake, {}, folder.string(), nlohmann::json::array());
    ASSERT_EQ(summary.probe_count, 2u);
    Progress progress;
    const ProbeField field = ProbeField::load(folder.string(), &progress);
    EXPECT_EQ(progress.fraction(), 1.0);
    EXPECT_EQ(field.probe_count(), 2u);
    EXPECT_TRUE(field.is_grid());
    EXPECT_EQ(field.levels(0).levels().front().resolution, 24);
    EXPECT_GT(field.memory_bytes(), 2u * 48u * 48u * 16u);
    const Ray ray = make_ray({0.0, 0.0, 1.2}, {0.3, 1.0, -0.2});
    const FieldTraceResult r = field.trace(ray);
    EXPECT_EQ(r.status, TraceStatus::Hit);
    EXPECT_NEAR(r.t, truth(room, ray), 0.1);
    // A coarser start keeps fewer levels (less memory) and gives the same answer; the step count
    // may go either way (fewer levels to climb, less skipped per step).
    const ProbeField shallow = ProbeField::load(folder.string(), nullptr, 12);
    EXPECT_EQ(shallow.levels(0).levels().back().resolution, 12);
    EXPECT_LT(shallow.memory_bytes(), field.memory_bytes());
    const FieldTraceResult rs = shallow.trace(ray);
    EXPECT_EQ(rs.status, r.status);
    EXPECT_EQ(rs.t, r.t);
    EXPECT_THROW((void)ProbeField::load(folder.string(), nullptr, -1), InputError);
    std::filesystem::remove_all(folder);

    const ProbeField loose(ProbePlacement::from_positions({glm::dvec3(0.0, 0.0, 1.2)}),
                           {scenes::analytic_probe(room, glm::dvec3(0.0, 0.0, 1.2), 16)});
    FieldTraceSettings grid_mode;
    grid_mode.mode = FieldMode::Grid;
    EXPECT_THROW((void)loose.trace(ray, grid_mode), InputError);
    EXPECT_EQ(loose.resolve_mode({}), FieldMode::Nearest);
    EXPECT_EQ(field_mode_from_name("grid"), FieldMode::Grid);
    EXPECT_THROW((void)field_mode_from_name("octree"), InputError);
    EXPECT_THROW(ProbeField(ProbePlacement::from_grid(grid), {}), InputError);
}

TEST(Grid, ALazilyOpenedSetReadsOnlyTheProbesARayReachesAndRendersTheSameImage) {
    // A row of 4 probes; a view from the first probe's side looking along the row's axis away
    // from the others reaches few of them. Opened lazily, the set reads no probe until a ray
    // needs it, renders the image an eager load renders bit for bit, and names a missing probe
    // file when it opens.
    const BoxRoomScene room;
    const PointCloud cloud = room.cloud(0.05f, glm::dvec3(0.0, 0.0, 1.2));
    const ProbeGrid grid = ProbeGrid::spanning({-1.2, 0.0, 1.2}, {1.2, 0.0, 1.2}, {4, 1, 1});
    BakeSettings bake;
    bake.resolution = 32;
    const std::filesystem::path folder =
        std::filesystem::temp_directory_path() /
        ("lfprobe_lazy_test_" + std::to_string(std::random_device{}()));
    (void)bake_probe_set_from_cloud(cloud, ProbePlacement::from_grid(grid), bake, {},
                                    folder.string(), nlohmann::json::array());
    const ProbeField eager = ProbeField::load(folder.string());
    const ProbeField lazy = ProbeField::load(folder.string(), nullptr, 0, {}, true);
    EXPECT_EQ(eager.loaded_probe_count(), 4u);
    EXPECT_EQ(lazy.loaded_probe_count(), 0u);
    EXPECT_EQ(lazy.memory_bytes(), 0u);
    EXPECT_EQ(lazy.probe_position(3), eager.probe_position(3));
    const Camera camera = Camera::look_at({-1.3, 0.0, 1.2}, {-2.0, 0.3, 1.0}, 48, 32, 20.0);
    const RenderSettings settings;
    const RenderedImage a = render_probe_view(eager, camera, settings);
    const RenderedImage b = render_probe_view(lazy, camera, settings);
    EXPECT_GT(lazy.loaded_probe_count(), 0u);
    EXPECT_LT(lazy.loaded_probe_count(), 4u) << "the view reaches only the probes near it";
    ASSERT_EQ(a.rgba, b.rgba);
    ASSERT_EQ(a.status, b.status);
    ASSERT_EQ(a.probe, b.probe);
    // A copy shares what is loaded; the rest loads on its first use.
    const ProbeField copy = lazy;
    EXPECT_EQ(copy.loaded_probe_count(), lazy.loaded_probe_count());
    EXPECT_EQ(copy.probe(3).resolution, 32);
    EXPECT_EQ(lazy.probe(3).resolution, 32);

    // A probe file that went missing: opening lazily says which.
    std::filesystem::remove(folder / eager.manifest().probes[2].file);
    try {
        (void)ProbeField::load(folder.string(), nullptr, 0, {}, true);
        ADD_FAILURE() << "a missing probe file must be an error of opening the set";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find(eager.manifest().probes[2].file), std::string::npos)
            << e.what();
    }
    // A probe file that cannot be decoded: the trace that reaches it fails, and so does the
    // next one (the slot stays empty), with the file named.
    {
        std::FILE* f = std::fopen((folder / eager.manifest().probes[2].file).c_str(), "wb");
        ASSERT_NE(f, nullptr);
        std::fputs("not an EXR", f);
        std::fclose(f);
    }
    const ProbeField damaged = ProbeField::load(folder.string(), nullptr, 0, {}, true);
    for (int attempt = 0; attempt < 2; ++attempt) {
        try {
            (void)damaged.probe(2);
            ADD_FAILURE() << "a damaged probe file must be an error of the trace that reads it";
        } catch (const std::exception& e) {
            EXPECT_NE(std::string(e.what()).find(eager.manifest().probes[2].file),
                      std::string::npos)
                << e.what();
        }
    }
    EXPECT_EQ(damaged.probe(1).resolution, 32);
    std::filesystem::remove_all(folder);
}
