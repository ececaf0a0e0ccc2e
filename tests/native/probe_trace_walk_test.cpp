// The octant walk of one probe checked two ways: against a dense brute-force march that uses
// the same definitions but none of the walk's geometry, and with and without the coarse levels,
// which must never change an answer.
#include <cmath>
#include <cstdio>
#include <random>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "lfprobe/min_distance_pyramid.hpp"
#include "lfprobe/octahedral.hpp"
#include "lfprobe/probe_trace.hpp"
#include "trace_scenes.hpp"

using namespace lfprobe;
using lfprobe::testing::BoxRoomScene;
namespace scenes = lfprobe::testing;
using lfprobe::testing::probe_ray;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

} // namespace

TEST(Trace, CoarseSkipNeverChangesTheAnswer) {
    const BoxRoomScene scene;
    std::mt19937 rng(21);
    for (const int n : {128, 100, 77}) {
        const glm::dvec3 centre(-0.4, 0.3, 1.4);
        // Holes of both kinds, so that coarse cells over unknown and empty texels are met.
        const ProbeMap map = scenes::analytic_probe_with_holes(scene, centre, n);
        const MinDistancePyramid levels(map.distance, n);
        TraceSettings fine_only;
        fine_only.use_coarse_levels = false;
        std::uint64_t fine_steps_walk = 0;
        std::uint64_t steps_coarse = 0;
        std::uint64_t fine_steps_coarse = 0;
        std::size_t counts[3] = {0, 0, 0};
        const int rays = 6000;
        for (int i = 0; i < rays; ++i) {
            const glm::dvec3 o = scenes::random_point_in_room(scene, rng, 0.05) - centre;
            const double t_min = std::uniform_real_distribution<double>(0.0, 0.5)(rng);
            const double t_max =
                i % 3 == 0 ? std::uniform_real_distribution<double>(0.5, 4.0)(rng) : kInf;
            const Ray ray = probe_ray(o, scenes::random_unit(rng), t_min, t_max);
            const ProbeTraceResult a = trace_probe(map, &levels, ray);
            const ProbeTraceResult b = trace_probe(map, &levels, ray, fine_only);
            ASSERT_EQ(a.status, b.status) << "ray " << i;
            ASSERT_EQ(a.texel, b.texel) << "ray " << i;
            ASSERT_EQ(a.t, b.t) << "ray " << i;
            ASSERT_EQ(a.free_until, b.free_until) << "ray " << i;
            ASSERT_EQ(b.coarse_steps, 0u);
            ++counts[static_cast<int>(a.status)];
            fine_steps_walk += b.fine_steps;
            steps_coarse += a.steps();
            fine_steps_coarse += a.fine_steps;
        }
        std::printf("N = %d: %d rays (%zu miss, %zu hit, %zu unknown); texels per ray: %.1f fine "
                    "walk, %.1f with coarse levels (%.1f of them fine)\n",
                    n, rays, counts[0], counts[1], counts[2],
                    static_cast<double>(fine_steps_walk) / rays,
                    static_cast<double>(steps_coarse) / rays,
                    static_cast<double>(fine_steps_coarse) / rays);
        EXPECT_LT(fine_steps_coarse, fine_steps_walk);
    }
}

// A ray that starts on an unknown texel, or on or behind its texel's surface, cannot skip any
// coarse cell around that texel: the walk goes to the texel without testing each level (a
// partial scan's re-asked probes mostly start there), and answers as the walk without coarse
// levels does. The start dismissal is off, so that the walk itself judges every start.
TEST(Trace, AStartOnOrBehindItsTexelsSurfaceGoesStraightToTheTexel) {
    const BoxRoomScene scene;
    std::mt19937 rng(5);
    for (const int n : {128, 77}) {
        const glm::dvec3 centre(-0.4, 0.3, 1.4);
        const ProbeMap map = scenes::analytic_probe_with_holes(scene, centre, n);
        const MinDistancePyramid levels(map.distance, n);
        TraceSettings walk;
        walk.dismiss_unknown_start = false;
        TraceSettings fine_only = walk;
        fine_only.use_coarse_levels = false;
        int behind = 0;
        int behind_straight = 0;
        int on_unknown = 0;
        for (int i = 0; i < 4000; ++i) {
            const glm::dvec3 u = scenes::random_unit(rng);
            const oct::Texel home = oct::texel_of_direction(glm::vec3(u), n);
            const double r = static_cast<double>(map.distance[oct::texel_index(home, n)]);
            if (std::isinf(r)) {
                continue; // an empty texel: nothing to start behind
            }
            const bool unknown = std::isnan(r);
            // Behind the surface by up to 20 cm, or anywhere along an unknown texel.
            const double along = unknown
                                     ? std::uniform_real_distribution<double>(0.3, 2.0)(rng)
                                     : r + std::uniform_real_distribution<double>(-0.02, 0.2)(rng);
            const Ray ray = probe_ray(along * u, scenes::random_unit(rng));
            const ProbeTraceResult a = trace_probe(map, &levels, ray, walk);
            const ProbeTraceResult b = trace_probe(map, &levels, ray, fine_only);
            ASSERT_EQ(a.status, b.status) << "ray " << i;
            ASSERT_EQ(a.texel, b.texel) << "ray " << i;
            ASSERT_EQ(a.t, b.t) << "ray " << i;
            ASSERT_EQ(a.free_until, b.free_until) << "ray " << i;
            ASSERT_EQ(a.has_fallback, b.has_fallback) << "ray " << i;
            if (unknown) {
                ++on_unknown;
                EXPECT_EQ(a.status, TraceStatus::Unknown) << "ray " << i;
                EXPECT_EQ(a.coarse_steps, 0u) << "ray " << i;
            } else if (along > r + 0.1) {
                ++behind;
                behind_straight += a.coarse_steps == 0 && a.fine_steps == 1 ? 1 : 0;
            }
        }
        std::printf("N = %d: %d starts on unknown texels, %d 10-20 cm behind their texel's "
                    "surface (%d of them decided at that texel with no coarse test)\n",
                    n, on_unknown, behind, behind_straight);
        EXPECT_GT(on_unknown, 0);
        EXPECT_GT(behind_straight, behind * 9 / 10);
    }
}

// The walk orders texel edges along the ray's straight image in the map and solves only the
// edge crossed; comparing every crossing time instead must give the same answers bit for bit,
// on random rays and on the rays where the image's rounding matters: along texel edges,
// through texel corners, from next to the probe centre, with zero components, and ending on
// an edge.
TEST(Trace, OrderingEdgesAlongTheImageNeverChangesTheAnswer) {
    const BoxRoomScene scene;
    const int n = 128;
    const glm::dvec3 centre(-0.4, 0.3, 1.4);
    const ProbeMap map = scenes::analytic_probe_with_holes(scene, centre, n);
    const MinDistancePyramid levels(map.distance, n);
    std::vector<Ray> rays;
    std::mt19937 rng(7);
    for (int i = 0; i < 4000; ++i) {
        const glm::dvec3 o = scenes::random_point_in_room(scene, rng, 0.05) - centre;
        const double t_max =
            i % 3 == 0 ? std::uniform_real_distribution<double>(0.5, 4.0)(rng) : kInf;
        rays.push_back(probe_ray(o, scenes::random_unit(rng), 0.0, t_max));
    }
    auto uv_of = [n](double k) { return static_cast<float>(k / n); };
    for (int k = 1; k < n; k += 5) {
        for (int m = 2; m < n; m += 7) {
            // Along the edge u = k/N, and through the corner (k/N, m/N).
            const glm::dvec3 e1(oct::decode({uv_of(k), uv_of(m + 0.3)}));
            const glm::dvec3 e2(oct::decode({uv_of(k), uv_of(m + 2.6)}));
            rays.push_back(probe_ray(0.3 * e1, 2.0 * e2 - 0.3 * e1));
            const glm::dvec3 corner(oct::decode({uv_of(k), uv_of(m)}));
            const glm::dvec3 from(oct::decode({uv_of(k + 0.37), uv_of(m + 0.61)}));
            rays.push_back(probe_ray(0.25 * from, 1.7 * corner - 0.25 * from));
            // Ending exactly where the ray crosses the corner's direction.
            const Ray to_corner = probe_ray(0.25 * from, corner - 0.25 * from);
            rays.push_back(probe_ray(to_corner.origin, to_corner.direction, 0.0,
                                     glm::length(corner - 0.25 * from)));
        }
    }
    for (const double near : {1e-7, 1e-5, 1e-3}) {
        for (int i = 0; i < 200; ++i) {
            const glm::dvec3 d = scenes::random_unit(rng);
            rays.push_back(probe_ray(near * scenes::random_unit(rng), d));
            // Passing the centre at `near`.
            const glm::dvec3 side = glm::normalize(glm::cross(d, scenes::random_unit(rng)));
            rays.push_back(probe_ray(near * side - 0.5 * d, d));
        }
    }
    for (const glm::dvec3& d : {glm::dvec3(1, 0, 0), glm::dvec3(0, -1, 0), glm::dvec3(0, 0, -1),
                                glm::dvec3(1, 1, 0), glm::dvec3(0, 1, -1), glm::dvec3(-1, 0, 1)}) {
        for (const glm::dvec3& o : {glm::dvec3(0.2, 0.3, 0.4), glm::dvec3(0.0, 0.3, 0.0),
                                    glm::dvec3(-0.2, 0.0, 0.1), glm::dvec3(0.0, 0.0, -0.3)}) {
            rays.push_back(probe_ray(o, d));
        }
    }
    TraceSettings by_times;
    by_times.order_by_image = false;
    TraceSettings fine_only;
    fine_only.use_coarse_levels = false;
    std::size_t counts[3] = {0, 0, 0};
    for (std::size_t i = 0; i < rays.size(); ++i) {
        const ProbeTraceResult a = trace_probe(map, &levels, rays[i]);
        const ProbeTraceResult b = trace_probe(map, &levels, rays[i], by_times);
        const ProbeTraceResult c = trace_probe(map, &levels, rays[i], fine_only);
        for (const ProbeTraceResult* other : {&b, &c}) {
            ASSERT_EQ(a.status, other->status) << "ray " << i;
            ASSERT_EQ(a.texel, other->texel) << "ray " << i;
            ASSERT_EQ(a.t, other->t) << "ray " << i;
            ASSERT_EQ(a.free_until, other->free_until) << "ray " << i;
        }
        ++counts[static_cast<int>(a.status)];
    }
    std::printf("%zu rays (%zu miss, %zu hit, %zu unknown): the same answers with edges ordered "
                "along the image, by crossing times, and without coarse levels\n",
                rays.size(), counts[0], counts[1], counts[2]);
    EXPECT_GT(counts[static_cast<int>(TraceStatus::Hit)], rays.size() / 2);
}

namespace {

struct MarchAnswer {
    TraceStatus status = TraceStatus::Miss;
    double t = kInf;
    oct::Texel texel{-1, -1};
};

// The probe's answer by brute force, with the walk's definitions but none of its geometry:
// sample the ray every dt, find each sample's texel with oct::encode, and judge every run of
// samples in one texel by the range of their distances: all in front of the stored distance
// passes, all behind is UNKNOWN, both is a HIT where the side changes; unknown data is
// UNKNOWN, empty passes.
MarchAnswer dense_march(const ProbeMap& map, const Ray& ray, double t_end, double dt) {
    const int n = map.resolution;
    oct::Texel run_texel{-1, -1};
    double run_start = 0.0;
    double run_first = 0.0; // distance minus stored distance at the run's first sample
    bool run_judged = true;
    for (double t = ray.t_min; t <= t_end; t += dt) {
        const glm::dvec3 p = ray.at(t);
        const double len = glm::length(p);
        if (len < 1e-9) {
            run_texel = {-1, -1};
            continue;
        }
        const oct::Texel texel = oct::texel_of_direction(glm::vec3(p / len), n);
        const double r = static_cast<double>(map.distance[oct::texel_index(texel, n)]);
        if (!(texel == run_texel)) {
            if (!run_judged && run_first > 0.0) {
                return {TraceStatus::Unknown, run_start, run_texel}; // a run wholly behind
            }
            run_texel = texel;
            run_start = t;
            run_first = len - r;
            run_judged = false;
            if (std::isnan(r)) {
                return {TraceStatus::Unknown, t, texel};
            }
            if (len == r) {
                return {TraceStatus::Hit, t, texel};
            }
            continue;
        }
        if (run_judged || std::isinf(r)) {
            continue;
        }
        if ((len - r > 0.0) != (run_first > 0.0) || len == r) {
            return {TraceStatus::Hit, t, texel};
        }
    }
    if (!run_judged && run_first > 0.0) {
        return {TraceStatus::Unknown, run_start, run_texel};
    }
    return {};
}

} // namespace

TEST(Trace, TheWalkAgreesWithADenseMarch) {
    const BoxRoomScene scene;
    std::mt19937 rng(99);
    TraceSettings exact;
    exact.thickness = 0.0;
    exact.thickness_texels = 0.0;
    const double dt = 2e-4;
    for (const int n : {64, 96}) {
        const glm::dvec3 centre(0.6, -0.3, 1.1);
        const ProbeMap map = scenes::analytic_probe_with_holes(scene, centre, n);
        const MinDistancePyramid levels(map.distance, n);
        std::size_t agree = 0;
        std::size_t rays = 0;
        std::size_t counts[3] = {0, 0, 0};
        for (int i = 0; i < 300; ++i) {
            const glm::dvec3 o = scenes::random_point_in_room(scene, rng, 0.05) - centre;
            const Ray ray = probe_ray(o, scenes::random_unit(rng));
            const ProbeTraceResult walk = trace_probe(map, &levels, ray, exact);
            const double t_end = 8.0;
            if (walk.free_until > t_end) {
                continue; // decided beyond the march (through the empty patch)
            }
            const MarchAnswer march = dense_march(map, ray, t_end, dt);
            ++rays;
            ++counts[static_cast<int>(walk.status)];
            bool same = walk.status == march.status;
            if (same && walk.status == TraceStatus::Hit) {
                same = walk.texel == march.texel && std::abs(walk.t - march.t) <= dt;
            }
            if (same && walk.status == TraceStatus::Unknown) {
                same = walk.texel == march.texel && std::abs(march.t - walk.free_until) <= dt;
            }
            agree += same ? 1 : 0;
        }
        std::printf("N = %d: the walk agrees with a %.0e m march on %zu of %zu rays (%zu miss, "
                    "%zu hit, %zu unknown)\n",
                    n, dt, agree, rays, counts[0], counts[1], counts[2]);
        EXPECT_GE(agree * 100, rays * 99);
    }
}

TEST(Trace, ARayThroughAFullyUnknownProbeIsDismissedWithoutWalkingItsTexels) {
    // A probe that saw nothing: every ray is UNKNOWN from its start, answered by one look (one
    // texel counted, no coarse level descended), before the walk is set up. The walk itself
    // (the look turned off) also goes straight to its unknown first texel.
    const BoxRoomScene scene;
    const int n = 64;
    ProbeMap blind = scenes::analytic_probe(scene, glm::dvec3(0.2, -0.1, 1.3), n);
    for (std::size_t i = 0; i < blind.texel_count(); ++i) {
        blind.set_unknown(i);
    }
    const MinDistancePyramid levels(blind.distance, n);
    TraceSettings walk;
    walk.dismiss_unknown_start = false;
    std::mt19937 rng(5);
    for (int i = 0; i < 200; ++i) {
        const glm::dvec3 o = scenes::random_point_in_room(scene, rng, 0.05) - blind.position;
        const Ray ray = probe_ray(o, scenes::random_unit(rng), 0.1, kInf);
        const ProbeTraceResult quick = trace_probe(blind, &levels, ray);
        const ProbeTraceResult walked = trace_probe(blind, &levels, ray, walk);
        ASSERT_EQ(quick.status, TraceStatus::Unknown);
        ASSERT_EQ(quick.free_until, walked.free_until) << "ray " << i;
        ASSERT_EQ(quick.fine_steps, 1u);
        ASSERT_EQ(quick.coarse_steps, 0u);
        ASSERT_EQ(walked.fine_steps, 1u);
        ASSERT_EQ(walked.coarse_steps, 0u);
    }
}

TEST(Trace, DismissingUnknownStartsNeverChangesTheAnswer) {
    // Partly seen probes (holes of unknown and of empty texels), rays from anywhere in the room
    // (behind the sphere too): the quick look answers exactly what the walk answers, fallback
    // included, where it answers at all.
    const BoxRoomScene scene;
    std::mt19937 rng(33);
    std::size_t dismissed = 0;
    std::size_t behind = 0; // dismissed from behind a surface the probe saw
    for (const int n : {96, 61}) {
        const glm::dvec3 centre(0.3, -0.2, 1.1);
        ProbeMap map = scenes::analytic_probe_with_holes(scene, centre, n);
        // Half the sphere unknown too, as a probe beside a one-station scan sees it.
        for (int y = 0; y < n; ++y) {
            for (int x = 0; x < n; ++x) {
                if (oct::texel_direction({x, y}, n).y > 0.2f) {
                    map.set_unknown(oct::texel_index({x, y}, n));
                }
            }
        }
        const MinDistancePyramid levels(map.distance, n);
        TraceSettings walk;
        walk.dismiss_unknown_start = false;
        for (int i = 0; i < 4000; ++i) {
            const glm::dvec3 o = scenes::random_point_in_room(scene, rng, 0.05) - centre;
            const double t_min = std::uniform_real_distribution<double>(0.0, 0.8)(rng);
            const Ray ray = probe_ray(o, scenes::random_unit(rng), t_min, kInf);
            const ProbeTraceResult quick = trace_probe(map, &levels, ray);
            const ProbeTraceResult walked = trace_probe(map, &levels, ray, walk);
            ASSERT_EQ(quick.status, walked.status) << "ray " << i;
            ASSERT_EQ(quick.t, walked.t) << "ray " << i;
            ASSERT_EQ(quick.free_until, walked.free_until) << "ray " << i;
            ASSERT_EQ(quick.radiance, walked.radiance) << "ray " << i;
            ASSERT_EQ(quick.has_fallback, walked.has_fallback) << "ray " << i;
            ASSERT_EQ(quick.t_fallback, walked.t_fallback) << "ray " << i;
            // Decided at the first texel, UNKNOWN: where the quick look applies (the walk now
            // goes straight to that texel too, so the two take the same steps).
            const bool at_first = quick.status == TraceStatus::Unknown && quick.steps() == 1;
            dismissed += at_first ? 1 : 0;
            behind +=
                at_first && !std::isnan(map.distance_at(oct::texel_index(quick.texel, n))) ? 1 : 0;
        }
    }
    EXPECT_GT(dismissed, 1000u) << "starts the quick look applies to must be met often";
    EXPECT_GT(behind, 100u) << "starts behind the sphere must be met too";
}
