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
