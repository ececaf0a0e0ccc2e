// One ray against one probe (docs/DESIGN.md §4): the hard cases of the octant walk and the three
// answers kept apart.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "lfprobe/error.hpp"
#include "lfprobe/min_distance_pyramid.hpp"
#include "lfprobe/octahedral.hpp"
#include "lfprobe/probe_lookup.hpp"
#include "lfprobe/probe_storage.hpp"
#include "lfprobe/probe_trace.hpp"
#include "trace_scenes.hpp"

using namespace lfprobe;
using lfprobe::testing::BoxRoomScene;
namespace scenes = lfprobe::testing;
using lfprobe::testing::probe_ray;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The empty box room's exact probe at (0, 0, 1), n² texels, with its coarse levels: what many
// tests below trace against.
struct EmptyRoomProbe {
    BoxRoomScene scene = scenes::empty_box_room();
    glm::dvec3 centre{0.0, 0.0, 1.0};
    ProbeMap map;
    MinDistancePyramid levels;
    explicit EmptyRoomProbe(int n)
        : map(scenes::analytic_probe(scene, centre, n)), levels(map.distance, n) {}
};

// The exact distance along a ray given in the probe's frame.
double true_depth(const BoxRoomScene& scene, const glm::dvec3& centre, const Ray& ray) {
    return static_cast<double>(
        scene.distance(glm::vec3(centre + ray.origin), glm::vec3(ray.direction)));
}

// Error of a traced hit against the exact distance along the same ray.
double depth_error(const BoxRoomScene& scene, const glm::dvec3& centre, const Ray& ray,
                   const ProbeTraceResult& r) {
    return std::abs(r.t - true_depth(scene, centre, ray));
}

struct Figures {
    std::size_t rays = 0;
    std::size_t hits = 0;
    std::size_t misses = 0;
    std::size_t unknown = 0;
    double max_error = 0.0;
    double max_relative_error = 0.0;
    std::vector<double> errors;

    void add(const ProbeTraceResult& r, double error, double truth = 1.0) {
        ++rays;
        if (r.status == TraceStatus::Hit) {
            ++hits;
            errors.push_back(error);
            max_error = std::max(max_error, error);
            max_relative_error = std::max(max_relative_error, error / truth);
        } else if (r.status == TraceStatus::Miss) {
            ++misses;
        } else {
            ++unknown;
        }
    }
    [[nodiscard]] double percentile(double q) {
        if (errors.empty()) {
            return 0.0;
        }
        std::sort(errors.begin(), errors.end());
        return errors[static_cast<std::size_t>(q * static_cast<double>(errors.size() - 1))];
    }
};

} // namespace

TEST(Trace, EyeAtTheProbeIsOneLookupAndNearbyEyesConvergeToIt) {
    const BoxRoomScene scene;
    const glm::dvec3 centre(0.3, -0.2, 1.2);
    const int n = 128;
    const ProbeMap map = scenes::analytic_probe(scene, centre, n);
    const MinDistancePyramid levels(map.distance, n);
    std::mt19937 rng(7);
    std::size_t checked = 0;
    std::size_t same_texel_1e3 = 0;
    double worst_depth[3] = {0.0, 0.0, 0.0};
    for (int y = 1; y < n; y += 5) {
        for (int x = 2; x < n; x += 7) {
            const oct::Texel texel{x, y};
            const glm::dvec3 dir = glm::dvec3(oct::texel_direction(texel, n));
            const ProbeTraceResult lookup = lookup_probe(map, dir, 0.0, kInf);
            const std::size_t i = oct::texel_index(texel, n);
            ASSERT_EQ(lookup.status, TraceStatus::Hit);
            ASSERT_EQ(lookup.texel, texel);
            EXPECT_EQ(lookup.t, static_cast<double>(map.distance[i]));
            EXPECT_EQ(lookup.radiance, map.radiance_at(i));
            EXPECT_EQ(lookup.steps(), 1u); // O(1)

            const ProbeTraceResult at = trace_probe(map, &levels, probe_ray(glm::dvec3(0.0), dir));
            EXPECT_EQ(at.status, lookup.status);
            EXPECT_EQ(at.texel, lookup.texel);
            EXPECT_EQ(at.t, lookup.t);

            const double offsets[3] = {1e-3, 1e-5, 1e-7};
            for (int k = 0; k < 3; ++k) {
                const glm::dvec3 eye = offsets[k] * scenes::random_unit(rng);
                const ProbeTraceResult near = trace_probe(map, &levels, probe_ray(eye, dir));
                ASSERT_EQ(near.status, TraceStatus::Hit);
                const double dt = std::abs(near.t - lookup.t);
                if (k == 0) {
                    same_texel_1e3 += near.texel == lookup.texel ? 1 : 0;
                } else {
                    ASSERT_EQ(near.texel, lookup.texel) << "offset " << offsets[k];
                    EXPECT_EQ(near.radiance, lookup.radiance);
                }
                if (near.texel == lookup.texel) {
                    // |o + t d| = r with |o| = offset: t is within offset of r.
                    EXPECT_LE(dt, offsets[k] * (1.0 + 1e-6) + 1e-12);
                    worst_depth[k] = std::max(worst_depth[k], dt);
                }
            }
            ++checked;
        }
    }
    std::printf("eye at probe: %zu directions; same texel at 1e-3 m: %.4f; largest depth change "
                "%.3g / %.3g / %.3g m at 1e-3 / 1e-5 / 1e-7 m\n",
                checked, static_cast<double>(same_texel_1e3) / static_cast<double>(checked),
                worst_depth[0], worst_depth[1], worst_depth[2]);
    EXPECT_GE(same_texel_1e3, checked * 99 / 100);
}

TEST(Trace, RayThroughTheProbeCentreSwitchesToTheAntipodalTexel) {
    const BoxRoomScene scene;
    const glm::dvec3 centre(0.3, -0.2, 1.2);
    const int n = 64;
    const ProbeMap map = scenes::analytic_probe(scene, centre, n);
    const MinDistancePyramid levels(map.distance, n);
    std::vector<glm::dvec3> dirs;
    for (int a = 0; a < 3; ++a) {
        for (const double s : {1.0, -1.0}) {
            glm::dvec3 d(0.0);
            d[a] = s;
            dirs.push_back(d);
        }
    }
    for (const double sx : {1.0, -1.0}) {
        for (const double sy : {1.0, -1.0}) {
            for (const double sz : {1.0, -1.0}) {
                dirs.push_back(glm::normalize(glm::dvec3(sx, sy, sz)));
                dirs.push_back(glm::normalize(glm::dvec3(sx, sy, 0.0)));
                dirs.push_back(glm::normalize(glm::dvec3(0.0, sy, sz)));
            }
        }
    }
    std::mt19937 rng(3);
    for (int i = 0; i < 200; ++i) {
        dirs.push_back(scenes::random_unit(rng));
    }
    for (const glm::dvec3& d : dirs) {
        for (const double back : {0.25, 0.1, 1e-4}) {
            const Ray ray = probe_ray(-back * d, d);
            const ProbeTraceResult r = trace_probe(map, &levels, ray);
            const oct::Texel expected = oct::texel_of_direction(glm::vec3(d), n);
            ASSERT_EQ(r.status, TraceStatus::Hit)
                << "d = (" << d.x << ", " << d.y << ", " << d.z << ")";
            EXPECT_EQ(r.texel, expected) << "d = (" << d.x << ", " << d.y << ", " << d.z << ")";
            const double r_stored =
                static_cast<double>(map.distance[oct::texel_index(expected, n)]);
            EXPECT_NEAR(r.t, back + r_stored, 1e-9);
        }
    }
}

TEST(Trace, RaysWithZeroComponentsAndRaysInAxisPlanes) {
    const BoxRoomScene scene = scenes::empty_box_room();
    const glm::dvec3 centre(0.3, -0.2, 1.2);
    const int n = 256;
    const ProbeMap map = scenes::analytic_probe(scene, centre, n);
    const MinDistancePyramid levels(map.distance, n);
    std::vector<glm::dvec3> origins;
    std::vector<glm::dvec3> dirs;
    for (int a = 0; a < 3; ++a) {
        for (const double s : {1.0, -1.0}) {
            glm::dvec3 v(0.0);
            v[a] = s;
            dirs.push_back(v);
            origins.push_back(0.2 * v);
            glm::dvec3 w(0.0);
            w[a] = s;
            w[(a + 1) % 3] = 1.0;
            dirs.push_back(glm::normalize(w));
            w[(a + 1) % 3] = -1.0;
            dirs.push_back(glm::normalize(w));
            origins.push_back(0.15 * w);
        }
    }
    origins.push_back(glm::dvec3(0.0, 0.0, 1e-3));
    Figures f;
    for (const glm::dvec3& o : origins) {
        for (const glm::dvec3& d : dirs) {
            const Ray ray = probe_ray(o, d);
            const ProbeTraceResult r = trace_probe(map, &levels, ray);
            f.add(r, depth_error(scene, centre, ray, r));
            // A convex room: every ray from inside meets a wall the probe saw.
            EXPECT_EQ(r.status, TraceStatus::Hit)
                << "o = (" << o.x << ", " << o.y << ", " << o.z << "), d = (" << d.x << ", " << d.y
                << ", " << d.z << ")";
        }
    }
    std::printf("axis rays: %zu rays, %zu hits, median depth error %.3g m, max %.3g m\n", f.rays,
                f.hits, f.percentile(0.5), f.max_error);
    EXPECT_LT(f.max_error, 0.05);
}

TEST(Trace, RaysAlongTexelEdgesAndThroughTexelCorners) {
    const BoxRoomScene scene = scenes::empty_box_room();
    const glm::dvec3 centre(0.3, -0.2, 1.2);
    const int n = 128;
    const ProbeMap map = scenes::analytic_probe(scene, centre, n);
    const MinDistancePyramid levels(map.distance, n);
    Figures f;
    std::size_t on_edge_texel = 0;
    std::size_t along_edge = 0;
    auto uv_of = [n](int k) { return static_cast<float>(k) / static_cast<float>(n); };
    for (int k = 1; k < n; k += 9) {
        for (int m = 3; m < n; m += 11) {
            // Along the edge u = k/N: both the origin and the target lie on its plane.
            const glm::dvec3 e1(oct::decode({uv_of(k), uv_of(m) + 0.3f / static_cast<float>(n)}));
            const glm::dvec3 e2(oct::decode({uv_of(k), uv_of(m) + 2.6f / static_cast<float>(n)}));
            if (glm::dot(e1, e2) < 0.9) {
                continue; // different octants: not one straight edge
            }
            const glm::dvec3 o = 0.3 * e1;
            const Ray along = probe_ray(o, 2.0 * e2 - o);
            const ProbeTraceResult ra = trace_probe(map, &levels, along);
            f.add(ra, depth_error(scene, centre, along, ra), true_depth(scene, centre, along));
            EXPECT_EQ(ra.status, TraceStatus::Hit);
            ++along_edge;
            on_edge_texel += (ra.texel.x == k || ra.texel.x == k - 1) ? 1 : 0;
            // Through the corner (k/N, m/N) from a point off both edges.
            const glm::dvec3 corner(oct::decode({uv_of(k), uv_of(m)}));
            const glm::dvec3 from(oct::decode({uv_of(k) + 0.37f / static_cast<float>(n),
                                               uv_of(m) + 0.61f / static_cast<float>(n)}));
            if (glm::dot(corner, from) < 0.9) {
                continue;
            }
            const glm::dvec3 oc = 0.25 * from;
            const Ray through = probe_ray(oc, 1.7 * corner - oc);
            const ProbeTraceResult rc = trace_probe(map, &levels, through);
            f.add(rc, depth_error(scene, centre, through, rc), true_depth(scene, centre, through));
            EXPECT_EQ(rc.status, TraceStatus::Hit);
            const ProbeTraceResult fine = trace_probe(map, nullptr, through);
            EXPECT_EQ(fine.texel, rc.texel);
            EXPECT_EQ(fine.t, rc.t);
        }
    }
    std::printf("edge and corner rays: %zu rays (%zu along edges, %zu ending on the edge's "
                "texels), %zu hits, median depth error %.3g m, max %.3g m (%.2f%% of the depth)\n",
                f.rays, along_edge, on_edge_texel, f.hits, f.percentile(0.5), f.max_error,
                100.0 * f.max_relative_error);
    EXPECT_EQ(f.hits, f.rays);
    EXPECT_EQ(on_edge_texel, along_edge);
    // The map's own quantisation: a 128² texel spans about 1.6°, more along the map's edges.
    EXPECT_LT(f.percentile(0.5), 0.02);
    EXPECT_LT(f.max_relative_error, 0.06);
}

TEST(Trace, DirectionsAtTheMapEdgesAndStraightDown) {
    const BoxRoomScene scene = scenes::empty_box_room();
    const glm::dvec3 centre(0.3, -0.2, 1.2);
    const int n = 128;
    const ProbeMap map = scenes::analytic_probe(scene, centre, n);
    const MinDistancePyramid levels(map.distance, n);
    // Straight down lands on the lower pole: the corner texels of the map.
    const ProbeTraceResult down = lookup_probe(map, glm::dvec3(0, 0, -1), 0.0, kInf);
    ASSERT_EQ(down.status, TraceStatus::Hit);
    EXPECT_EQ(down.texel, (oct::Texel{n - 1, n - 1}));
    EXPECT_NEAR(down.t, 1.2, 0.01);
    Figures f;
    std::vector<glm::dvec3> dirs{{0, 0, -1}};
    for (int i = 1; i < 40; ++i) {
        const double a = 0.5 * 3.14159265358979 * static_cast<double>(i) / 40.0;
        // Lower hemisphere with x = 0 or y = 0: the map's outer edges.
        dirs.push_back(glm::dvec3(0.0, std::sin(a), -std::cos(a)));
        dirs.push_back(glm::dvec3(0.0, -std::sin(a), -std::cos(a)));
        dirs.push_back(glm::dvec3(std::sin(a), 0.0, -std::cos(a)));
        dirs.push_back(glm::dvec3(-std::sin(a), 0.0, -std::cos(a)));
    }
    for (const glm::dvec3& eye :
         {glm::dvec3(0.0), glm::dvec3(0.0, 0.0, 1e-3), glm::dvec3(1e-3, 0.0, 0.0),
          glm::dvec3(0.1, 0.0, 0.0), glm::dvec3(0.0, -0.1, 0.05), glm::dvec3(0.0, 0.0, -0.3)}) {
        for (const glm::dvec3& d : dirs) {
            const Ray ray = probe_ray(eye, d);
            const ProbeTraceResult r = trace_probe(map, &levels, ray);
            EXPECT_EQ(r.status, TraceStatus::Hit);
            f.add(r, depth_error(scene, centre, ray, r), true_depth(scene, centre, ray));
        }
    }
    std::printf("map-edge rays: %zu rays, %zu hits, median depth error %.3g m, max %.3g m (%.2f%% "
                "of the depth)\n",
                f.rays, f.hits, f.percentile(0.5), f.max_error, 100.0 * f.max_relative_error);
    EXPECT_LT(f.percentile(0.5), 0.02);
    EXPECT_LT(f.max_relative_error, 0.06); // texels along the map's outer edges are the longest
}

TEST(Trace, GrazingSurfacesAreHitNotLost) {
    const EmptyRoomProbe probe(256);
    const BoxRoomScene& scene = probe.scene;
    const glm::dvec3& centre = probe.centre;
    const ProbeMap& map = probe.map;
    const MinDistancePyramid& levels = probe.levels;
    Figures f;
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> angle(0.5, 8.0); // degrees above the floor
    std::uniform_real_distribution<double> azimuth(0.0, 6.283185307179586);
    std::uniform_real_distribution<double> height(0.02, 0.3);
    std::uniform_real_distribution<double> across(-0.6, 0.6);
    for (int i = 0; i < 2000; ++i) {
        const double elevation = angle(rng) * 3.14159265358979 / 180.0;
        const double az = azimuth(rng);
        const glm::dvec3 eye(across(rng), across(rng), height(rng) - 1.0); // near the floor
        const glm::dvec3 d(std::cos(elevation) * std::cos(az), std::cos(elevation) * std::sin(az),
                           -std::sin(elevation));
        const Ray ray = probe_ray(eye, d);
        const ProbeTraceResult r = trace_probe(map, &levels, ray);
        f.add(r, depth_error(scene, centre, ray, r));
    }
    const double p50 = f.percentile(0.5);
    const double p95 = f.percentile(0.95);
    std::printf("grazing rays (0.5-8 degrees over the floor): %zu rays, hit %.4f, unknown %.4f, "
                "miss %.4f; depth error median %.3g m, 95%% %.3g m, max %.3g m\n",
                f.rays, static_cast<double>(f.hits) / static_cast<double>(f.rays),
                static_cast<double>(f.unknown) / static_cast<double>(f.rays),
                static_cast<double>(f.misses) / static_cast<double>(f.rays), p50, p95, f.max_error);
    EXPECT_EQ(f.misses, 0u); // a closed room: never a MISS
    EXPECT_GT(static_cast<double>(f.hits) / static_cast<double>(f.rays), 0.97);
    EXPECT_LT(p50, 0.05);
}

TEST(Trace, EmptyTexelsMissAndUnknownTexelsNeverHitNorMiss) {
    const int n = 64;
    // A sphere of radius 3 around the probe; directions with x > 0.5 (and y <= 0.5) see nothing,
    // directions with y > 0.5 have no data.
    const ProbeMap map = scenes::custom_probe(
        n, glm::dvec3(0.0), [](const glm::vec3& d, std::size_t i, ProbeMap& m) {
            if (d.y > 0.5f) {
                m.set_unknown(i);
            } else if (d.x > 0.5f) {
                m.set_empty(i);
            } else {
                m.set_surface(i, 3.0f, glm::vec3(0.5f), -d, 1.0f);
            }
        });
    const MinDistancePyramid levels(map.distance, n);
    // At the probe.
    EXPECT_EQ(lookup_probe(map, {1, 0, 0}, 0.0, kInf).status, TraceStatus::Miss);
    EXPECT_EQ(lookup_probe(map, {0, 1, 0}, 0.0, kInf).status, TraceStatus::Unknown);
    EXPECT_EQ(lookup_probe(map, {-1, 0, 0}, 0.0, kInf).status, TraceStatus::Hit);
    // Through the empty cap only: MISS, free to t_max.
    const ProbeTraceResult through_empty =
        trace_probe(map, &levels, probe_ray({0.5, -0.2, 0.0}, {1.0, 0.1, 0.05}));
    EXPECT_EQ(through_empty.status, TraceStatus::Miss);
    EXPECT_EQ(through_empty.free_until, kInf);
    // From the empty cap into the unknown cap: never a MISS across the unknown texels.
    const ProbeTraceResult across =
        trace_probe(map, &levels, probe_ray({1.0, -1.0, 0.0}, {0.0, 1.0, 0.0}));
    EXPECT_EQ(across.status, TraceStatus::Unknown);
    EXPECT_GT(across.free_until, 1.0);  // the empty part before was proven free
    EXPECT_LT(across.free_until, 1.75); // it stopped where y/|p| passed 0.5
    // A ray that would meet the surface inside the unknown cap: never a HIT.
    const ProbeTraceResult into_unknown =
        trace_probe(map, &levels, probe_ray({0.0, 0.3, 0.2}, {0.1, 1.0, 0.0}));
    EXPECT_EQ(into_unknown.status, TraceStatus::Unknown);
    // Random rays: HIT only where the texel met is a surface, MISS only if no unknown texel was
    // crossed (checked by tracing with a finer walk of the same ray).
    std::mt19937 rng(5);
    std::size_t counts[3] = {0, 0, 0};
    for (int i = 0; i < 3000; ++i) {
        const double radius =
            2.5 * std::cbrt(std::uniform_real_distribution<double>(0.0, 1.0)(rng));
        const glm::dvec3 o = radius * scenes::random_unit(rng);
        const Ray ray = probe_ray(o, scenes::random_unit(rng));
        const ProbeTraceResult r = trace_probe(map, &levels, ray);
        ++counts[static_cast<int>(r.status)];
        if (r.status == TraceStatus::Hit) {
            EXPECT_EQ(map.state(oct::texel_index(r.texel, n)), TexelState::Surface);
        }
        if (r.status == TraceStatus::Miss) {
            // Sample the ray densely: no direction on it may fall into the unknown cap while
            // the ray is still inside the sphere of surfaces.
            for (int k = 0; k <= 2000; ++k) {
                const double t = 6.0 * static_cast<double>(k) / 2000.0;
                const glm::dvec3 p = ray.at(t);
                const double len = glm::length(p);
                if (len > 1e-6 && len < 3.0) {
                    EXPECT_LE(p.y / len, 0.5 + 0.05) << "MISS across unknown texels";
                }
            }
        }
    }
    std::printf("empty/unknown probe: %zu miss, %zu hit, %zu unknown of 3000 random rays\n",
                counts[0], counts[1], counts[2]);
    // All unknown: nothing is ever decided.
    const ProbeMap unknown_map = scenes::custom_probe(
        n, glm::dvec3(0.0), [](const glm::vec3&, std::size_t i, ProbeMap& m) { m.set_unknown(i); });
    const MinDistancePyramid unknown_levels(unknown_map.distance, n);
    for (int i = 0; i < 200; ++i) {
        const Ray ray = probe_ray(scenes::random_unit(rng), scenes::random_unit(rng));
        EXPECT_EQ(trace_probe(unknown_map, &unknown_levels, ray).status, TraceStatus::Unknown);
    }
}

TEST(Trace, BackFacesAndRaysFromBehindASurfaceAreUnknown) {
    const BoxRoomScene scene = scenes::empty_box_room();
    const glm::dvec3 centre(0.0, 0.0, 1.0);
    const int n = 128;
    const ProbeMap map = scenes::analytic_probe(scene, centre, n);
    const MinDistancePyramid levels(map.distance, n);
    // From outside the room through the wall x = 2: behind what the probe saw.
    const ProbeTraceResult outside =
        trace_probe(map, &levels, probe_ray({2.5, 0.3, 0.2}, {-1.0, 0.05, 0.0}));
    EXPECT_EQ(outside.status, TraceStatus::Unknown);
    // Normals turned away from the probe: what would be a hit is a back face.
    ProbeMap flipped = map;
    for (auto& h : flipped.normal) {
        h = -h;
    }
    const Ray inside = probe_ray({0.2, 0.1, 0.0}, {1.0, 0.2, 0.1});
    EXPECT_EQ(trace_probe(map, &levels, inside).status, TraceStatus::Hit);
    EXPECT_EQ(trace_probe(flipped, &levels, inside).status, TraceStatus::Unknown);
}

TEST(Trace, ARayTwoCentimetresBehindASurfaceDoesNotMeetIt) {
    // A ray that runs 2 cm behind what the probe saw, as one passing just behind a near
    // object's silhouette does, is not on that surface: it must go on (UNKNOWN, the next probe
    // asked), not meet it and show the object where what lies behind belongs. At 1024² the
    // default tolerance is 1 cm plus a texel footprint (7 mm at the wall's 2 m); the 2 cm of
    // the earlier default met it (the wrong-surface pixels along the lab room's silhouettes).
    const EmptyRoomProbe probe(1024);
    const ProbeMap& map = probe.map;
    const MinDistancePyramid& levels = probe.levels;
    const Ray behind = probe_ray({2.02, 0.1, 0.1}, {0.0, 1.0, 0.05}, 0.0, 0.3);
    const ProbeTraceResult unknown = trace_probe(map, &levels, behind);
    EXPECT_EQ(unknown.status, TraceStatus::Unknown);
    // It keeps the wall as its fallback (2 cm plus the footprint): the field answers with it
    // only where no other probe answers the ray (Grid.AFallbackAnswersOnlyWhereNoProbeDoes).
    EXPECT_TRUE(unknown.has_fallback);
    EXPECT_NEAR(unknown.t_fallback, 0.0, 1e-9); // where the ray comes nearest the wall
    TraceSettings no_fallback;
    no_fallback.fallback_thickness = no_fallback.thickness;
    EXPECT_FALSE(trace_probe(map, &levels, behind, no_fallback).has_fallback);
    const Ray far_behind = probe_ray({2.05, 0.1, 0.1}, {0.0, 1.0, 0.05}, 0.0, 0.3);
    const ProbeTraceResult far = trace_probe(map, &levels, far_behind);
    EXPECT_EQ(far.status, TraceStatus::Unknown);
    EXPECT_FALSE(far.has_fallback);
    TraceSettings two_centimetres;
    two_centimetres.thickness = 0.02;
    EXPECT_EQ(trace_probe(map, &levels, behind, two_centimetres).status, TraceStatus::Hit);
    // The same ray 5 mm behind the wall is on it.
    const Ray on = probe_ray({2.005, 0.1, 0.1}, {0.0, 1.0, 0.05}, 0.0, 0.3);
    EXPECT_EQ(trace_probe(map, &levels, on).status, TraceStatus::Hit);
}

TEST(Trace, ARayJustInFrontOfAnEdgeKeepsTheFarSurfaceAsItsFallback) {
    // A ray running 1.9-2.2 cm in front of a wall (beyond the 1 cm thickness, within the 2 cm
    // fallback, plus a 1024² texel's footprint each) until a nearer surface's edge, where it is
    // far behind: UNKNOWN, with the wall it passed just in front of as the fallback. The
    // earlier 2 cm thickness met the wall there; the pump room's one-station silhouettes are
    // made of such rays.
    const BoxRoomScene scene = scenes::empty_box_room();
    const glm::dvec3 centre(0.0, 0.0, 1.0);
    const int n = 1024;
    ProbeMap map = scenes::analytic_probe(scene, centre, n);
    for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
            const glm::vec3 d = oct::texel_direction({x, y}, n);
            const std::size_t i = oct::texel_index({x, y}, n);
            if (d.x > 0.0f && d.y > 0.5f * d.x) {
                map.distance[i] = 0.8f * map.distance_at(i); // the near surface past the edge
            }
        }
    }
    const MinDistancePyramid levels(map.distance, n);
    const Ray along = probe_ray({1.981, 0.0, 0.1}, {0.0, 1.0, 0.0}, 0.0, 1.5);
    const ProbeTraceResult r = trace_probe(map, &levels, along);
    EXPECT_EQ(r.status, TraceStatus::Unknown);
    ASSERT_TRUE(r.has_fallback);
    EXPECT_NEAR(r.t_fallback, 0.99, 0.02); // at the edge, y = x / 2
    const glm::vec3 edge = oct::texel_direction(r.fallback_texel, n);
    EXPECT_NEAR(edge.y / edge.x, 0.5, 0.01);
    TraceSettings no_fallback;
    no_fallback.fallback_thickness = no_fallback.thickness;
    EXPECT_FALSE(trace_probe(map, &levels, along, no_fallback).has_fallback);
    TraceSettings two_centimetres;
    two_centimetres.thickness = 0.02;
    const ProbeTraceResult met = trace_probe(map, &levels, along, two_centimetres);
    EXPECT_EQ(met.status, TraceStatus::Hit);
    EXPECT_EQ(met.texel, r.fallback_texel);
    // Without the coarse levels the walk keeps the same fallback (a skip never passes it).
    TraceSettings fine_only;
    fine_only.use_coarse_levels = false;
    const ProbeTraceResult fine = trace_probe(map, &levels, along, fine_only);
    EXPECT_EQ(fine.fallback_texel, r.fallback_texel);
    EXPECT_EQ(fine.t_fallback, r.t_fallback);
}

TEST(Trace, StartsAtTMinAndStopsAtTMax) {
    const BoxRoomScene scene;
    const glm::dvec3 centre(0.3, -0.2, 1.2);
    const int n = 128;
    const ProbeMap map = scenes::analytic_probe(scene, centre, n);
    const MinDistancePyramid levels(map.distance, n);
    const glm::dvec3 eye(0.05, 0.02, -0.03);
    const glm::dvec3 to_sphere = glm::dvec3(scene.sphere_centre) - centre - eye;
    const Ray full = probe_ray(eye, to_sphere);
    const ProbeTraceResult hit = trace_probe(map, &levels, full);
    ASSERT_EQ(hit.status, TraceStatus::Hit);
    // Starting a little later changes nothing before the hit.
    const ProbeTraceResult later = trace_probe(map, &levels, probe_ray(eye, to_sphere, 0.1));
    EXPECT_EQ(later.status, TraceStatus::Hit);
    EXPECT_EQ(later.texel, hit.texel);
    EXPECT_NEAR(later.t, hit.t, 1e-12);
    // Starting inside the sphere: behind the surface the probe saw.
    const ProbeTraceResult inside =
        trace_probe(map, &levels, probe_ray(eye, to_sphere, hit.t + 0.2));
    EXPECT_EQ(inside.status, TraceStatus::Unknown);
    // Stopping before the sphere: nothing in between.
    const ProbeTraceResult short_ray =
        trace_probe(map, &levels, probe_ray(eye, to_sphere, 0.0, hit.t - 0.1));
    EXPECT_EQ(short_ray.status, TraceStatus::Miss);
    EXPECT_EQ(short_ray.free_until, hit.t - 0.1);
}

TEST(Trace, BatchedLookupsAnswerAsSingleLookups) {
    const int n = 64;
    // Surfaces at several distances, some facing away, with empty and unknown texels between.
    ProbeMap map = scenes::custom_probe(
        n, glm::dvec3(0.0), [](const glm::vec3& d, std::size_t i, ProbeMap& m) {
            if (d.y > 0.6f) {
                m.set_unknown(i);
            } else if (d.x > 0.6f) {
                m.set_empty(i);
            } else {
                const float r = 1.0f + 2.0f * std::abs(d.z);
                const glm::vec3 normal = d.x < -0.7f ? d : -d; // a back face where x < -0.7
                m.set_surface(i, r, glm::vec3(0.25f, 0.5f, 0.75f) * r, normal, 1.0f);
            }
        });
    ProbeMap packed = map;
    (void)pack_probe(packed, ProbeStorage::compact(kDefaultDistanceStep));
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    for (const ProbeMap* m : {&map, &packed}) {
        const TraceSettings settings;
        const ProbeLookup lookup(*m, settings);
        // Odd lengths, intervals that start before, at and beyond the surfaces, empty ones.
        std::vector<Ray> rays(37 * ProbeLookup::kBatch / 8);
        for (Ray& ray : rays) {
            ray.direction = (0.5 + 2.0 * uniform(rng)) * scenes::random_unit(rng);
            ray.t_min = uniform(rng) < 0.5 ? 0.0 : 4.0 * uniform(rng);
            ray.t_max = uniform(rng) < 0.5 ? kInf : 4.0 * uniform(rng);
        }
        std::vector<ProbeTraceResult> batch(rays.size());
        lookup.lookup_batch(rays.data(), rays.size(), batch.data());
        std::size_t counts[3] = {0, 0, 0};
        for (std::size_t i = 0; i < rays.size(); ++i) {
            const ProbeTraceResult one =
                lookup_probe(*m, rays[i].direction, rays[i].t_min, rays[i].t_max, settings);
            ++counts[static_cast<int>(one.status)];
            EXPECT_EQ(batch[i].status, one.status);
            EXPECT_EQ(std::memcmp(&batch[i].t, &one.t, sizeof one.t), 0);
            EXPECT_EQ(std::memcmp(&batch[i].free_until, &one.free_until, sizeof one.t), 0);
            EXPECT_EQ(batch[i].texel, one.texel);
            EXPECT_EQ(batch[i].radiance, one.radiance);
            EXPECT_EQ(batch[i].normal, one.normal);
            EXPECT_EQ(batch[i].steps(), one.steps());
        }
        // Every answer came up.
        EXPECT_GT(counts[0], 0u);
        EXPECT_GT(counts[1], 0u);
        EXPECT_GT(counts[2], 0u);
    }
    EXPECT_THROW((void)lookup_probe(map, {0.0, 0.0, 0.0}, 0.0, kInf), InputError);
    EXPECT_THROW(ProbeLookup(ProbeMap{}, TraceSettings{}), InputError);
}
