// Where a set's probes know something (docs/DESIGN.md §4 "Rays that no probe can answer"): the
// seen voxels hold every point a probe saw free, the surface walk finds the last surface voxel
// along a ray, a rebuild is bit-identical, the file round-trips and refuses damage, and a field
// that stops asking where no probe can answer gives every ray the answer of asking on.
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include "lfprobe/error.hpp"
#include "lfprobe/known_space.hpp"
#include "lfprobe/min_distance_pyramid.hpp"
#include "lfprobe/probe_field.hpp"
#include "lfprobe/probe_set.hpp"
#include "lfprobe/probe_storage.hpp"
#include "lfprobe/probe_trace.hpp"
#include "lfprobe/seen_directions.hpp"
#include "temp_folder.hpp"
#include "trace_scenes.hpp"

using namespace lfprobe;
using lfprobe::testing::BoxRoomScene;
namespace scenes = lfprobe::testing;

namespace {

// A probe of the room with what a one-station partial scan leaves: the directions with x < 0
// unknown, and a patch of holes.
ProbeMap partial_probe(const BoxRoomScene& room, const glm::dvec3& centre, int n) {
    ProbeMap map = scenes::analytic_probe_with_holes(room, centre, n);
    for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
            if (oct::texel_direction({x, y}, n).x < 0.0f) {
                map.set_unknown(oct::texel_index({x, y}, n));
            }
        }
    }
    return map;
}

std::vector<ProbeMap> partial_grid_probes(const BoxRoomScene& room, const ProbePlacement& placement,
                                          int n) {
    std::vector<ProbeMap> probes;
    for (std::size_t i = 0; i < placement.positions.size(); ++i) {
        // Every fourth probe sees the room whole: rays the others cannot answer go on to it.
        probes.push_back(i % 4 == 0 ? scenes::analytic_probe(room, placement.positions[i], n)
                                    : partial_probe(room, placement.positions[i], n));
    }
    return probes;
}

// Whether `p` lies in the mask's box.
bool inside_box(const VoxelMask& mask, const glm::dvec3& p) {
    const glm::dvec3 origin = mask.origin();
    for (int a = 0; a < 3; ++a) {
        const double u = (p[a] - origin[a]) / mask.voxel();
        if (!(u >= 0.0 && u < static_cast<double>(mask.dims()[static_cast<std::size_t>(a)]))) {
            return false;
        }
    }
    return true;
}

} // namespace

// A row's run set a word at a time sets exactly the voxels one at a time would, across word
// boundaries and within one word.
TEST(KnownSpace, ARunOfVoxelsSetsTheSameBitsAsOneAtATime) {
    const std::array<int, 3> dims{150, 3, 2};
    for (const auto& [x0, x1] : std::vector<std::pair<int, int>>{
             {0, 0}, {0, 149}, {5, 9}, {60, 70}, {63, 64}, {64, 127}, {1, 148}, {127, 128}}) {
        VoxelMask runs(glm::dvec3(0.0), 0.1, dims);
        VoxelMask single(glm::dvec3(0.0), 0.1, dims);
        runs.set_run(x0, x1, 1, 1);
        for (int x = x0; x <= x1; ++x) {
            single.set(x, 1, 1);
        }
        EXPECT_EQ(runs.set_count(), static_cast<std::size_t>(x1 - x0 + 1));
        for (int z = 0; z < dims[2]; ++z) {
            for (int y = 0; y < dims[1]; ++y) {
                for (int x = 0; x < dims[0]; ++x) {
                    ASSERT_EQ(runs.is_set(x, y, z), single.is_set(x, y, z))
                        << "run " << x0 << ".." << x1 << " at " << x << " " << y << " " << z;
                }
            }
        }
    }
}

TEST(KnownSpace, SeenVoxelsHoldEveryPointTheProbeSawFree) {
    const BoxRoomScene room = BoxRoomScene{};
    const glm::dvec3 centre(0.3, -0.2, 1.1);
    const int n = 64;
    const ProbeMap map = partial_probe(room, centre, n);
    const SeenVoxels seen(map);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::uniform_int_distribution<int> texel(0, n - 1);
    int checked = 0;
    while (checked < 20000) {
        const oct::Texel t{texel(rng), texel(rng)};
        const float d = map.distance_at(oct::texel_index(t, n));
        if (!std::isfinite(d)) {
            continue;
        }
        // Anywhere in the texel's cone, in front of its surface.
        const glm::vec2 uv((static_cast<float>(t.x) + static_cast<float>(unit(rng))) / n,
                           (static_cast<float>(t.y) + static_cast<float>(unit(rng))) / n);
        const glm::dvec3 dir(oct::decode(uv));
        const glm::dvec3 point = centre + unit(rng) * static_cast<double>(d) * dir;
        ASSERT_TRUE(seen.contains(point)) << "texel " << t.x << "," << t.y;
        ++checked;
    }
    // Not everything: behind the walls, and where the probe saw nothing (x well below it,
    // whose directions are all unknown).
    EXPECT_FALSE(seen.contains(centre + glm::dvec3(0.0, 0.0, 5.0)));
    EXPECT_FALSE(seen.contains(centre + glm::dvec3(-1.2, 0.0, 0.0)));
    EXPECT_GT(seen.voxel_count(), 0u);

    // A probe that saw far (through a window, 1 km): marked out to its region only, and
    // everything beyond that region counts as seen; inside it the walls still hold.
    ProbeMap far = map;
    const oct::Texel window{n / 2, n / 2};
    far.distance[oct::texel_index(window, n)] = 1000.0f;
    const SeenVoxels far_seen(far);
    const glm::dvec3 out(oct::texel_direction(window, n));
    EXPECT_TRUE(far_seen.contains(centre + 500.0 * out));
    EXPECT_TRUE(far_seen.contains(centre + glm::dvec3(0.0, 0.0, -40.0))); // beyond the region
    EXPECT_FALSE(far_seen.contains(centre + glm::dvec3(0.0, 5.0, 0.0)));  // the window looks up
    EXPECT_FALSE(far_seen.beyond_exact_region(centre + glm::dvec3(0.0, 5.0, 0.0)));
}

TEST(KnownSpace, TheSurfaceWalkFindsTheLastSurfaceVoxelAlongARay) {
    const BoxRoomScene room = BoxRoomScene{};
    KnownSpace space;
    space.add_probe(partial_probe(room, {0.3, -0.2, 1.1}, 128), 0);
    const KnownSpaceMask mask = space.mask(0.02, 4.0);
    ASSERT_GT(mask.surfaces.set_count(), 0u);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int i = 0; i < 2000; ++i) {
        Ray ray;
        ray.origin = glm::dvec3(1.5 * u(rng), 1.2 * u(rng), 1.2 + u(rng));
        ray.direction = glm::normalize(glm::dvec3(u(rng), u(rng), u(rng)));
        ray.t_min = 0.01;
        const double last = mask.surfaces.last_set_t(ray, ray.t_min, 20.0);
        // Sampled finely: no set voxel after `last`, and one just before it.
        double sampled = -std::numeric_limits<double>::infinity();
        for (double t = ray.t_min; t <= 20.0; t += 0.002) {
            if (mask.surfaces.contains(ray.at(t))) {
                sampled = t;
            }
        }
        // Never before a set voxel the samples met (the stop must not come early) and, where
        // there is one, at one: a set voxel within a hair before it.
        EXPECT_GE(last, sampled - 1e-9) << i;
        if (!std::isinf(last)) {
            bool at_one = false;
            for (double t = last; t > last - mask.surfaces.voxel() && !at_one; t -= 1e-5) {
                at_one = mask.surfaces.contains(ray.at(t));
            }
            EXPECT_TRUE(at_one) << i << " at " << last;
        }
        EXPECT_EQ(mask.last_surface_t(ray, ray.t_min, 20.0) == last ||
                      std::abs(mask.last_surface_t(ray, ray.t_min, 20.0) - last) < 1e-9,
                  true)
            << i;
    }
}

TEST(KnownSpace, ARebuildInAnyOrderIsBitIdenticalAndTheFileRoundTrips) {
    const BoxRoomScene room = BoxRoomScene{};
    const ProbePlacement placement = ProbePlacement::from_grid(
        ProbeGrid::spanning({-1.0, -0.5, 0.8}, {1.0, 0.5, 1.6}, {3, 2, 1}));
    const std::vector<ProbeMap> probes = partial_grid_probes(room, placement, 64);
    KnownSpace forward;
    for (std::size_t i = 0; i < probes.size(); ++i) {
        forward.add_probe(probes[i], i);
    }
    KnownSpace halves;
    KnownSpace back;
    for (std::size_t i = probes.size(); i-- > 3;) {
        back.add_probe(probes[i], i);
    }
    for (std::size_t i = 0; i < 3; ++i) {
        halves.add_probe(probes[i], i);
    }
    back.merge(halves);
    EXPECT_TRUE(forward == back);
    EXPECT_THROW(back.merge(halves), InputError); // a probe added twice

    const std::filesystem::path folder = scenes::fresh_dir("known_space", "round_trip");
    const std::string path = (folder / kKnownSpaceName).string();
    forward.write(path);
    EXPECT_TRUE(KnownSpace::read(path) == forward);
    // Damaged: cut short, and with bytes after its end.
    const std::string bytes = scenes::file_bytes(path);
    for (const std::string& damaged : {bytes.substr(0, bytes.size() - 5), bytes + "x",
                                       std::string("LFPKNOWN"), std::string("not a file")}) {
        scenes::write_file(path, damaged);
        EXPECT_THROW((void)KnownSpace::read(path), InputError) << damaged.size();
    }
}

// A probe's surfaces are one entry a voxel whatever its texels' order: a 128² probe of the box
// room puts about as many voxels in a band of rows as texels (the band's table grows), and the
// count and the farthest footprint are those of every known texel's own voxel, counted one by
// one; the same on 1 and 2 threads.
TEST(KnownSpace, EachSurfaceVoxelIsKeptOnceWithItsLargestFootprint) {
    const BoxRoomScene room = BoxRoomScene{};
    const int n = 128;
    ProbeMap map = scenes::analytic_probe(room, {-0.3, 0.2, 1.2}, n);
    for (int y = n / 5; y < n / 2; ++y) {
        for (int x = n / 3; x < n / 2; ++x) {
            map.set_unknown(oct::texel_index({x, y}, n)); // texels with nothing to add
        }
    }
    std::set<std::array<std::int64_t, 3>> voxels;
    double farthest = 0.0;
    for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
            const float d = map.distance_at(oct::texel_index({x, y}, n));
            if (!std::isfinite(d)) {
                continue;
            }
            const glm::dvec3 p =
                map.position + static_cast<double>(d) * glm::dvec3(oct::texel_direction({x, y}, n));
            const glm::dvec3 u = glm::floor(p / KnownSpace::kSurfaceVoxel);
            voxels.insert({static_cast<std::int64_t>(u.x), static_cast<std::int64_t>(u.y),
                           static_cast<std::int64_t>(u.z)});
            const double footprint_per_metre = oct::kTexelAngleTimesN / n;
            farthest = std::max(farthest,
                                static_cast<double>(static_cast<float>(d * footprint_per_metre)) /
                                    footprint_per_metre);
        }
    }
    ASSERT_GT(voxels.size(), std::size_t{8000}); // more than the tables' first 2048 a band
    KnownSpace one_thread;
    tbb::task_arena(1).execute([&] { one_thread.add_probe(map, 0); });
    KnownSpace two_threads;
    tbb::task_arena(2).execute([&] { two_threads.add_probe(map, 0); });
    EXPECT_EQ(one_thread.surface_voxel_count(), voxels.size());
    EXPECT_EQ(one_thread.farthest_distance(), farthest);
    EXPECT_TRUE(one_thread == two_threads);
}

// A probe's known directions (a bit per texel, the farthest distance per block) pass a ray over
// only where the probe's own trace stops at its first texel, UNKNOWN, proving nothing: at full
// precision and packed (its distances read a step off), from starts inside and outside the
// room; and they catch most of those rays, which a one-station scan sends to most probes.
TEST(KnownSpace, KnownDirectionsPassARayOverOnlyWhereTheProbesTraceStopsAtItsStart) {
    const BoxRoomScene room = BoxRoomScene{};
    const glm::dvec3 centre(0.3, -0.2, 1.2);
    for (const double step : {0.0, 0.004}) {
        ProbeMap map = partial_probe(room, centre, 96);
        const SeenDirections directions(map); // from the map as baked, before any packing
        ProbeStorage storage;
        storage.distance_step = step;
        double slack = 0.0;
        if (step > 0.0) {
            (void)pack_probe(map, storage);
            slack = map.packed.distance_step;
        }
        const MinDistancePyramid levels(decoded_distances(map), map.resolution);
        std::mt19937 rng(11);
        std::uniform_real_distribution<double> u(-1.0, 1.0);
        std::size_t stopped = 0;
        std::size_t passed_over = 0;
        for (int i = 0; i < 20000; ++i) {
            Ray ray;
            ray.origin = glm::dvec3(2.5 * u(rng), 2.0 * u(rng), 1.5 + 2.0 * u(rng)) - centre;
            ray.direction = glm::normalize(glm::dvec3(u(rng), u(rng), u(rng)));
            ray.t_min = 0.5 * (u(rng) + 1.0);
            const TraceSettings settings;
            const ProbeTraceResult r = trace_probe(map, &levels, ray, settings);
            const bool stops_at_start = r.status == TraceStatus::Unknown &&
                                        r.free_until == ray.t_min && !r.has_fallback &&
                                        r.steps() == 1;
            stopped += stops_at_start ? 1 : 0;
            if (directions.dismisses(ray, settings, slack)) {
                ++passed_over;
                ASSERT_TRUE(stops_at_start) << "step " << step << ", ray " << i;
            }
        }
        std::printf("step %.3f: %zu rays stop at their start, %zu of them passed over\n", step,
                    stopped, passed_over);
        EXPECT_GT(stopped, 5000u);
        EXPECT_GT(passed_over, stopped * 3 / 4);
    }
}

// A file written before the probes' directions were kept reads as it did: the same surfaces and
// seen voxels, no directions (a trace then asks such probes).
TEST(KnownSpace, AFileWithoutTheProbesDirectionsStillReads) {
    const BoxRoomScene room = BoxRoomScene{};
    KnownSpace space;
    space.add_probe(partial_probe(room, {0.3, -0.2, 1.2}, 32), 0);
    space.add_probe(partial_probe(room, {-0.3, 0.2, 1.2}, 32), 1);
    ASSERT_NE(space.directions_of(1), nullptr);
    EXPECT_EQ(space.directions_of(2), nullptr);
    const std::filesystem::path folder = scenes::fresh_dir("known_space", "old_file");
    const std::string path = (folder / kKnownSpaceName).string();
    space.write(path);
    const std::string bytes = scenes::file_bytes(path);
    const std::size_t section = bytes.rfind("DIRECTNS");
    ASSERT_NE(section, std::string::npos);
    scenes::write_file(path, bytes.substr(0, section));
    const KnownSpace old = KnownSpace::read(path);
    EXPECT_EQ(old.directions_of(0), nullptr);
    ASSERT_NE(old.seen_by(1), nullptr);
    EXPECT_TRUE(*old.seen_by(1) == *space.seen_by(1));
    EXPECT_EQ(old.surface_voxel_count(), space.surface_voxel_count());
}

// The walk that bounds where any probe can answer (SeenUnion::first_unknown_t): the point it
// returns lies outside what the probe saw free and outside every surface voxel (so no probe can
// answer past it), the forward voxel walk it uses finds the first unset voxel the samples meet,
// and rays into the half of the room the probe never saw are bounded.
TEST(KnownSpace, TheUnknownWalkStopsOnlyOutsideWhatWasSeenAndEverySurface) {
    const BoxRoomScene room = BoxRoomScene{};
    const glm::dvec3 centre(0.3, -0.2, 1.1);
    const ProbeMap map = partial_probe(room, centre, 128);
    KnownSpace space;
    space.add_probe(map, 0);
    const KnownSpaceMask mask = space.mask(0.02, 4.0);
    const SeenVoxels seen(map);
    SeenUnion seen_union;
    seen_union.add(&seen);
    seen_union.densify(std::size_t{32} << 20);
    const VoxelMask dense = seen.dense(std::size_t{32} << 20);
    ASSERT_GT(dense.set_count(), 0u);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int bounded = 0;
    int bounded_into_the_unseen_half = 0;
    for (int i = 0; i < 2000; ++i) {
        Ray ray;
        ray.origin = centre + glm::dvec3(0.5 * u(rng), 0.5 * u(rng), 0.3 * u(rng));
        ray.direction = glm::normalize(glm::dvec3(u(rng), u(rng), u(rng)));
        ray.t_min = 0.01;
        ray.t_max = 20.0;
        const auto [enter, leave] = dense.first_unset_span(ray, ray.t_min, ray.t_max);
        double sampled = std::numeric_limits<double>::infinity();
        for (double t = ray.t_min; t <= ray.t_max && std::isinf(sampled); t += 0.002) {
            const glm::dvec3 p = ray.at(t);
            if (!dense.contains(p) && inside_box(dense, p)) {
                sampled = t;
            }
        }
        // Never after an unset voxel the samples met, and where it found one, it is unset.
        EXPECT_LE(enter, sampled + 1e-9) << i;
        if (!std::isinf(enter)) {
            EXPECT_FALSE(dense.contains(ray.at(0.5 * (enter + leave)))) << i;
        }
        const double bound = seen_union.first_unknown_t(ray, ray.t_min, ray.t_max, mask.surfaces);
        if (std::isinf(bound)) {
            continue;
        }
        ++bounded;
        // Into the half the probe never saw: bounded before the wall the ray would meet.
        const double wall = room.distance(glm::vec3(ray.origin), glm::vec3(ray.direction));
        if (ray.direction.x < -0.7 && bound < wall - 0.2) {
            ++bounded_into_the_unseen_half;
        }
        const glm::dvec3 p = ray.at(bound);
        EXPECT_FALSE(seen.contains(p)) << i;
        EXPECT_FALSE(mask.surfaces.contains(p)) << i;
        EXPECT_GE(bound, ray.t_min) << i;
    }
    std::printf("%d of 2000 rays bounded, %d heading into the unseen half before its wall\n",
                bounded, bounded_into_the_unseen_half);
    EXPECT_GT(bounded_into_the_unseen_half, 100);
}

TEST(Grid, RaysNoProbeCanAnswerStopEarlyWithTheAnswersOfAskingOn) {
    // A grid most of whose probes saw half the room: rays into the unseen half end UNKNOWN
    // after fewer probes, and every ray's answer is the one asking on gives.
    const BoxRoomScene room = BoxRoomScene{};
    const ProbePlacement placement = ProbePlacement::from_grid(
        ProbeGrid::spanning({-1.5, -1.0, 0.6}, {1.5, 1.0, 1.8}, {4, 3, 2}));
    const ProbeField field(placement, partial_grid_probes(room, placement, 128));
    ASSERT_NE(field.known_space(), nullptr);
    FieldTraceSettings ask_on;
    ask_on.stop_where_no_probe_can_answer = false;
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::size_t asked = 0;
    std::size_t asked_on = 0;
    std::size_t hits = 0;
    for (int i = 0; i < 4000; ++i) {
        Ray ray;
        ray.origin = glm::dvec3(1.8 * u(rng), 1.3 * u(rng), 1.25 + 1.1 * u(rng));
        ray.direction = glm::normalize(glm::dvec3(u(rng), u(rng), u(rng)));
        ray.t_min = 0.01;
        const FieldTraceResult stopped = field.trace(ray);
        const FieldTraceResult full = field.trace(ray, ask_on);
        ASSERT_EQ(stopped.status, full.status) << i;
        ASSERT_EQ(stopped.probe, full.probe) << i;
        if (full.status == TraceStatus::Hit) {
            ++hits;
            ASSERT_EQ(stopped.t, full.t) << i;
            ASSERT_EQ(stopped.radiance, full.radiance) << i;
            ASSERT_EQ(stopped.normal, full.normal) << i;
            ASSERT_EQ(stopped.texel, full.texel) << i;
        }
        asked += stopped.probes_tried;
        asked_on += full.probes_tried;
    }
    std::printf("%zu HIT of 4000 rays; probes asked %.2f a ray, %.2f asking on\n", hits,
                static_cast<double>(asked) / 4000.0, static_cast<double>(asked_on) / 4000.0);
    EXPECT_GT(hits, 1000u);
    EXPECT_LT(asked, asked_on);

    // A set with an empty texel can answer MISS anywhere: it asks on.
    std::vector<ProbeMap> probes = partial_grid_probes(room, placement, 32);
    probes[0].distance[0] = kEmptyDistance;
    const ProbeField open(placement, std::move(probes));
    ASSERT_NE(open.known_space(), nullptr);
    EXPECT_TRUE(open.known_space()->has_empty_texels());
    EXPECT_EQ(open.known_space_mask(TraceSettings{}), nullptr);
}

TEST(Grid, ABakedSetCarriesItsKnownSpaceAndALazyOpenUsesItWithoutReadingProbes) {
    const BoxRoomScene room = BoxRoomScene{};
    const ProbePlacement placement = ProbePlacement::from_grid(
        ProbeGrid::spanning({-1.5, -1.0, 0.6}, {1.5, 1.0, 1.8}, {4, 3, 2}));
    const ProbeField field(placement, partial_grid_probes(room, placement, 64));
    const std::string set = (scenes::fresh_dir("known_space", "set") / "set").string();
    ProbeSetManifest manifest;
    manifest.placement = placement;
    (void)write_probe_set(set, manifest, [&](std::size_t i) { return field.probe(i); });
    const ProbeSetManifest written = read_manifest(set);
    EXPECT_EQ(written.known_space_file, kKnownSpaceName);
    // The probes' own known spaces were merged and removed.
    std::size_t files = 0;
    for (const auto& entry : std::filesystem::directory_iterator(set)) {
        const std::string name = entry.path().filename().string();
        EXPECT_EQ(name.find(".known"), std::string::npos) << name;
        ++files;
    }
    EXPECT_EQ(files, placement.positions.size() + 2); // probes, manifest, known space
    EXPECT_TRUE(KnownSpace::read((std::filesystem::path(set) / kKnownSpaceName).string()) ==
                *field.known_space());

    const ProbeField lazy = ProbeField::load(set, nullptr, 0, {}, true);
    ASSERT_NE(lazy.known_space(), nullptr);
    EXPECT_EQ(lazy.loaded_probe_count(), 0u);
    // A ray that starts 1 m above the ceiling, where no probe saw anything (and beyond the
    // surfaces' reach, a few footprints of these 64² probes): the known directions show that
    // the first probe would answer UNKNOWN there, so it is not asked (or read), and the known
    // space ends the ray; asking on, every probe the walk reaches is read and answers the same.
    Ray ray;
    ray.origin = glm::dvec3(0.1, 0.1, 3.5);
    ray.direction = glm::dvec3(0.0, 0.0, -1.0);
    ray.t_min = 0.01;
    FieldTraceSettings ask_on;
    ask_on.stop_where_no_probe_can_answer = false;
    const FieldTraceResult stopped = lazy.trace(ray);
    EXPECT_EQ(stopped.status, TraceStatus::Unknown);
    EXPECT_EQ(stopped.probes_tried, 0u);
    EXPECT_EQ(lazy.loaded_probe_count(), 0u);
    const FieldTraceResult full = lazy.trace(ray, ask_on);
    EXPECT_EQ(full.status, TraceStatus::Unknown);
    EXPECT_GT(full.probes_tried, 1u);
}
