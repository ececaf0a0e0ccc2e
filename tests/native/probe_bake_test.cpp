// Probe bakes from clouds with a known answer (docs/DESIGN.md §4).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include <Imath/half.h>
#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "lfprobe/octahedral.hpp"
#include "lfprobe/probe_bake.hpp"
#include "lfprobe/probe_lookup.hpp"
#include "synthetic_scene.hpp"

using namespace lfprobe;
using lfprobe::testing::BoxRoomScene;

namespace {

struct BakeErrors {
    double coverage = 0.0;         // measured or inferred texels over all texels
    double within_tolerance = 0.0; // of covered texels, fraction within tolerance
    double median_error = 0.0;
    double colour_within = 0.0; // of covered texels, fraction with the right colour
};

BakeErrors measure(const ProbeMap& map, const BoxRoomScene& scene, float tolerance) {
    const int n = map.resolution;
    std::vector<double> errors;
    std::size_t covered = 0;
    std::size_t within = 0;
    std::size_t colour_ok = 0;
    const glm::vec3 centre(map.position);
    for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
            const std::size_t i = oct::texel_index({x, y}, n);
            const TexelState s = map.state(i);
            if (s != TexelState::Surface && s != TexelState::Inferred) {
                continue;
            }
            ++covered;
            const glm::vec3 dir = oct::texel_direction({x, y}, n);
            const float truth = scene.distance(centre, dir);
            const double err = std::abs(static_cast<double>(map.distance[i]) - truth);
            errors.push_back(err);
            within += err <= tolerance ? 1 : 0;
            const glm::vec3 expected = BoxRoomScene::colour_at(centre + truth * dir);
            colour_ok += glm::length(map.radiance_at(i) - expected) < 0.08f ? 1 : 0;
        }
    }
    BakeErrors e;
    e.coverage = static_cast<double>(covered) / static_cast<double>(map.texel_count());
    e.within_tolerance =
        static_cast<double>(within) / static_cast<double>(std::max<std::size_t>(covered, 1));
    e.colour_within =
        static_cast<double>(colour_ok) / static_cast<double>(std::max<std::size_t>(covered, 1));
    std::nth_element(errors.begin(), errors.begin() + static_cast<long>(errors.size() / 2),
                     errors.end());
    e.median_error = errors.empty() ? 0.0 : errors[errors.size() / 2];
    return e;
}

} // namespace

TEST(ProbeBake, BoxRoomDistancesMatchTheAnalyticScene) {
    const BoxRoomScene scene;
    const glm::dvec3 scanner(-0.4, -0.2, 1.3);
    const PointCloud cloud = scene.cloud(0.01f, scanner);
    const LocalGeometry geometry = estimate_local_geometry(cloud, {});
    BakeSettings settings;
    settings.resolution = 128;
    for (const glm::dvec3 probe :
         {scanner, glm::dvec3(0.5, -0.8, 0.6), glm::dvec3(-1.5, 1.0, 2.0)}) {
        const ProbeMap map = bake_probe_from_cloud(cloud, geometry, probe, settings);
        const BakeErrors e = measure(map, scene, 0.01f);
        std::printf("probe (%.1f %.1f %.1f): coverage %.4f, within 1 cm %.4f, median error %.2g m, "
                    "colour ok %.4f\n",
                    probe.x, probe.y, probe.z, e.coverage, e.within_tolerance, e.median_error,
                    e.colour_within);
        EXPECT_GT(e.coverage, 0.99);
        EXPECT_GT(e.within_tolerance, 0.99); // the rest sit on silhouettes and grazing walls
        EXPECT_LT(e.median_error, 1e-3);
        EXPECT_GT(e.colour_within, 0.97);
    }
}

namespace {

// A wall of points on the plane x = `x` (normal along x), pitch `pitch_y` × `pitch_z`, seen by
// a scanner at the origin.
void add_wall_x(PointCloud& cloud, float x, float pitch_y, float pitch_z, float half_extent) {
    const int ny = static_cast<int>(2.0f * half_extent / pitch_y) + 1;
    const int nz = static_cast<int>(2.0f * half_extent / pitch_z) + 1;
    for (int i = 0; i < ny; ++i) {
        for (int j = 0; j < nz; ++j) {
            cloud.positions.emplace_back(x, -half_extent + static_cast<float>(i) * pitch_y,
                                         -half_extent + static_cast<float>(j) * pitch_z);
            cloud.colors.emplace_back(0.5f);
            cloud.scan_index.push_back(0);
        }
    }
}

// The sliver tests' wall at x = 3, a point every centimetre from y = -1.5 to `y_max` and z =
// -1.5 to 1.5, but none where unseen(plate_y, plate_z) holds: (plate_y, plate_z) is where the
// ray from the origin to the point passes x = 0.6, the plane of those tests' plate.
template <class Unseen>
void add_far_wall_but(PointCloud& cloud, float y_max, Unseen&& unseen) {
    for (float y = -1.5f; y <= y_max; y += 0.01f) {
        for (float z = -1.5f; z <= 1.5f; z += 0.01f) {
            if (unseen(y * 0.2f, z * 0.2f)) {
                continue;
            }
            cloud.positions.emplace_back(3.0f, y, z);
            cloud.colors.emplace_back(0.5f);
            cloud.scan_index.push_back(0);
        }
    }
}

// Calls visit(texel index, point) for every texel of `map`, baked at `probe`, whose ray meets
// the plane x = probe.x + `wall_distance` at a point for which `on_it(point)` holds.
template <class OnIt, class Visit>
void for_each_texel_on_wall_x(const ProbeMap& map, const glm::vec3& probe, float wall_distance,
                              OnIt&& on_it, Visit&& visit) {
    for (int y = 0; y < map.resolution; ++y) {
        for (int x = 0; x < map.resolution; ++x) {
            const glm::vec3 d = oct::texel_direction({x, y}, map.resolution);
            if (d.x <= 0.0f) {
                continue;
            }
            const glm::vec3 on_plane = probe + d * (wall_distance / d.x);
            if (on_it(on_plane)) {
                visit(oct::texel_index({x, y}, map.resolution), on_plane);
            }
        }
    }
}

template <class Counts>
double fraction_on_wall_x(const ProbeMap& map, const glm::vec3& probe, float wall_distance,
                          float half_extent, Counts&& counts) {
    std::size_t inside = 0;
    std::size_t counted = 0;
    for_each_texel_on_wall_x(
        map, probe, wall_distance,
        [&](const glm::vec3& p) {
            return std::abs(p.y) <= half_extent && std::abs(p.z) <= half_extent;
        },
        [&](std::size_t i, const glm::vec3&) {
            ++inside;
            counted += counts(map.distance[i]) ? 1 : 0;
        });
    return static_cast<double>(counted) / static_cast<double>(inside);
}

} // namespace

TEST(ProbeBake, NothingBehindASurfaceShowsThroughIt) {
    // A sparsely sampled near wall (5 cm pitch, 0.6 m from the probe) in front of a dense far
    // wall (3 m): at 512² a texel is ~4 mm on the near wall, so without splats most texels
    // between near points would see the far wall.
    PointCloud cloud;
    add_wall_x(cloud, 0.6f, 0.05f, 0.05f, 0.5f);
    add_wall_x(cloud, 3.0f, 0.01f, 0.01f, 3.0f);
    cloud.scans.push_back(ScanSource{"two walls", cloud.positions.size(), glm::dvec3(0.0), true});
    const LocalGeometry geometry = estimate_local_geometry(cloud, {});

    auto leak_fraction = [&](float splat_scale) {
        BakeSettings settings;
        settings.resolution = 512;
        settings.splat_scale = splat_scale;
        settings.hole_fill_texels = 0;
        const ProbeMap map = bake_probe_from_cloud(cloud, geometry, glm::dvec3(0.0), settings);
        // Well inside the near wall's extent.
        return fraction_on_wall_x(map, glm::vec3(0.0f), 0.6f, 0.45f,
                                  [](float distance) { return !(distance < 1.0f); });
    };
    const double with_splats = leak_fraction(0.8f);
    const double without = leak_fraction(0.0f);
    std::printf("far wall seen through the near wall: %.4f with splats, %.4f without\n",
                with_splats, without);
    EXPECT_EQ(with_splats, 0.0);
    EXPECT_GT(without, 0.5); // the paper's aliasing, reproduced without splats
}

TEST(ProbeBake, AWallBesideTheProbeHidesNothingPastItsPlane) {
    // The probe 1.5 cm in front of a wall (the hard scene's probe beside a pillar), a far wall
    // behind it. Points on the near wall 1.5–30 cm away have splat cones tens of degrees wide;
    // a cone alone paints their depth over directions past the wall's plane, which then hide
    // the far wall from every ray that passes there.
    PointCloud cloud;
    add_wall_x(cloud, 0.015f, 0.02f, 0.02f, 1.5f);
    add_wall_x(cloud, -2.0f, 0.04f, 0.04f, 4.0f);
    cloud.scans.push_back(ScanSource{"walls", cloud.positions.size(), glm::dvec3(0.0), true});
    const LocalGeometry geometry = estimate_local_geometry(cloud, {});
    BakeSettings settings;
    settings.resolution = 64;
    settings.hole_fill_texels = 0;
    const ProbeMap map = bake_probe_from_cloud(cloud, geometry, glm::dvec3(0.0), settings);
    std::size_t past = 0;
    std::size_t false_occluders = 0;
    std::size_t in_front = 0;
    std::size_t on_the_wall = 0;
    for (int y = 0; y < map.resolution; ++y) {
        for (int x = 0; x < map.resolution; ++x) {
            const glm::vec3 d = oct::texel_direction({x, y}, map.resolution);
            const float dist = map.distance[oct::texel_index({x, y}, map.resolution)];
            if (d.x < -0.1f) { // past the near wall's plane by more than ~6°
                ++past;
                false_occluders += dist < 1.0f ? 1 : 0;
            } else if (d.x > 0.1f) { // toward the near wall, well inside its extent
                ++in_front;
                const float truth = 0.015f / d.x;
                on_the_wall += std::abs(dist - truth) < 0.005f + 0.05f * truth ? 1 : 0;
            }
        }
    }
    std::printf("past the wall's plane: %zu of %zu texels nearer than 1 m; toward the wall: %zu of "
                "%zu texels on it\n",
                false_occluders, past, on_the_wall, in_front);
    EXPECT_EQ(false_occluders, 0u);
    EXPECT_EQ(on_the_wall, in_front);
}

TEST(ProbeBake, ObliqueScanLinesLeaveNoHoles) {
    // A floor scanned at oblique incidence: rows 1 cm apart, points along a row 4 cm apart
    // (the beam's spacing grows as 1/cos of the incidence). The mean neighbour distance is
    // nearer the short pitch, so a splat of one splat radius in the surface's plane would not
    // reach across the long one; splat_plane_reach = 2 does.
    PointCloud cloud;
    add_wall_x(cloud, 1.0f, 0.01f, 0.04f, 1.0f);
    cloud.scans.push_back(ScanSource{"floor", cloud.positions.size(), glm::dvec3(0.0), true});
    const LocalGeometry geometry = estimate_local_geometry(cloud, {});
    auto holes = [&](float reach) {
        BakeSettings settings;
        settings.resolution = 512;
        settings.hole_fill_texels = 0;
        settings.splat_plane_reach = reach;
        // Seen at a glancing angle along the long pitch (as the floor is from a probe at eye
        // height), where the splat cone is wide enough to span the gap between rows.
        const ProbeMap map =
            bake_probe_from_cloud(cloud, geometry, glm::dvec3(0.6, 0.0, -1.5), settings);
        return fraction_on_wall_x(map, glm::vec3(0.6f, 0.0f, -1.5f), 0.4f, 0.9f,
                                  [](float distance) { return std::isnan(distance); });
    };
    const double one = holes(1.0f);
    const double two = holes(2.0f);
    std::printf("holes on an obliquely scanned floor: %.4f at one splat radius, %.4f at two\n", one,
                two);
    EXPECT_EQ(two, 0.0);
    EXPECT_GT(one, 0.01);
    BakeSettings bad;
    bad.splat_plane_reach = 0.0f;
    EXPECT_THROW((void)bake_probe_from_cloud(cloud, geometry, glm::dvec3(0.0), bad), InputError);
}

TEST(ProbeBake, APointWithoutANormalKeepsItsWholeSplat) {
    // Two points 10 cm apart, 1 m away: too few neighbours for a normal, so no plane to cut the
    // splat to; each still covers the texels of its disc seen face-on.
    PointCloud cloud;
    cloud.positions = {{1.0f, 0.0f, 0.0f}, {1.0f, 0.1f, 0.0f}};
    cloud.colors = {glm::vec3(0.5f), glm::vec3(0.5f)};
    cloud.scan_index = {0, 0};
    cloud.scans.push_back(ScanSource{"two points", 2, glm::dvec3(0.0), true});
    const LocalGeometry geometry = estimate_local_geometry(cloud, {});
    ASSERT_EQ(glm::dot(geometry.normals[0], geometry.normals[0]), 0.0f);
    BakeSettings settings;
    settings.resolution = 256;
    settings.hole_fill_texels = 0;
    const ProbeMap map = bake_probe_from_cloud(cloud, geometry, glm::dvec3(0.0), settings);
    std::size_t covered = 0;
    for (std::size_t i = 0; i < map.texel_count(); ++i) {
        covered += std::isfinite(map.distance[i]) ? 1 : 0;
    }
    // A disc of 0.8 × 10 cm at 1 m spans ~4.6° in radius; a 256² texel is ~0.8°: dozens each.
    EXPECT_GT(covered, 40u);
}

TEST(ProbeBake, SmallHolesAreInferredAndLargeHolesStayUnknown) {
    ProbeMap map(64, glm::dvec3(0.0));
    for (std::size_t i = 0; i < map.texel_count(); ++i) {
        map.set_surface(i, 2.0f, glm::vec3(0.25f), glm::vec3(0, 0, 1), 1.0f);
    }
    auto at = [&](int x, int y) { return oct::texel_index({x, y}, 64); };
    // A 2×2 hole, and a 10×10 hole.
    for (int y = 10; y < 12; ++y) {
        for (int x = 10; x < 12; ++x) {
            map.set_unknown(at(x, y));
        }
    }
    for (int y = 30; y < 40; ++y) {
        for (int x = 30; x < 40; ++x) {
            map.set_unknown(at(x, y));
        }
    }
    fill_small_holes(map, 4);
    for (int y = 10; y < 12; ++y) {
        for (int x = 10; x < 12; ++x) {
            EXPECT_EQ(map.state(at(x, y)), TexelState::Inferred);
            EXPECT_FLOAT_EQ(map.distance[at(x, y)], 2.0f);
            EXPECT_LT(static_cast<float>(map.rgba[4 * at(x, y) + 3]), 1.0f);
        }
    }
    for (int y = 30; y < 40; ++y) {
        for (int x = 30; x < 40; ++x) {
            EXPECT_EQ(map.state(at(x, y)), TexelState::Unknown);
        }
    }
    EXPECT_EQ(map.state(at(0, 0)), TexelState::Surface);
}

TEST(ProbeBake, AGapInANearSurfaceTakesTheNearSurfaceNeverABlend) {
    ProbeMap map(32, glm::dvec3(0.0));
    for (int y = 0; y < 32; ++y) {
        for (int x = 0; x < 32; ++x) {
            // A dark near object left, a bright far wall right.
            const bool near = x < 16;
            map.set_surface(oct::texel_index({x, y}, 32), near ? 1.0f : 5.0f,
                            glm::vec3(near ? 0.2f : 0.9f), glm::vec3(0, 0, 1), 1.0f);
        }
    }
    // A gap of 4 texels in the near object that reaches its silhouette: the far wall is 3 of
    // its 14 border texels, so the gap is the near object's missing points, not a view behind.
    // Its colour is the near object's too: the blend after the pull-push draws on the near
    // surface around the gap only.
    std::vector<std::size_t> gap;
    for (int x = 12; x < 16; ++x) {
        gap.push_back(oct::texel_index({x, 10}, 32));
        map.set_unknown(gap.back());
    }
    fill_small_holes(map, 4);
    for (const std::size_t i : gap) {
        EXPECT_EQ(map.state(i), TexelState::Inferred);
        EXPECT_FLOAT_EQ(map.distance[i], 1.0f); // the near surface, never a floating blend
        EXPECT_NEAR(map.radiance_at(i).x, 0.2f, 1e-3f);
    }
}

TEST(ProbeBake, AStripBetweenANearEdgeAndWhatLiesUnderItStaysUnknown) {
    // A desk's front edge seen from above (1 m, rows above 10), the floor under the desk
    // nearer than the wall (1.3 m, rows 14 and below), the wall beyond the desk's ends (5 m):
    // between the edge and the floor a strip no scan saw. Its border is mostly near, so it
    // is no disocclusion; but no one surface lies on both sides of its texels (the desk above,
    // the floor below, the wall at its ends): it is not a gap in the desk, and it stays
    // unknown rather than take the desk's colour.
    ProbeMap map(32, glm::dvec3(0.0));
    for (int y = 0; y < 32; ++y) {
        for (int x = 0; x < 32; ++x) {
            const float d = x < 4 || x > 27 ? 5.0f : y < 10 ? 1.0f : 1.3f;
            map.set_surface(oct::texel_index({x, y}, 32), d, glm::vec3(0.5f), glm::vec3(0, 0, 1),
                            1.0f);
        }
    }
    std::vector<std::size_t> strip;
    for (int y = 10; y < 14; ++y) {
        for (int x = 4; x < 28; ++x) {
            strip.push_back(oct::texel_index({x, y}, 32));
            map.set_unknown(strip.back());
        }
    }
    fill_small_holes(map, 8);
    for (const std::size_t i : strip) {
        EXPECT_EQ(map.state(i), TexelState::Unknown);
    }
    // The same strip with the desk on both sides (a gap in it): filled with the desk.
    for (int y = 14; y < 32; ++y) {
        for (int x = 4; x < 28; ++x) {
            map.set_surface(oct::texel_index({x, y}, 32), 1.0f, glm::vec3(0.5f), glm::vec3(0, 0, 1),
                            1.0f);
        }
    }
    fill_small_holes(map, 8);
    for (const std::size_t i : strip) {
        EXPECT_EQ(map.state(i), TexelState::Inferred);
        EXPECT_FLOAT_EQ(map.distance[i], 1.0f);
    }
}

TEST(ProbeBake, AFarSurfaceSeenThroughGapsInANearerOneIsAHoleInTheNearOne) {
    // A near surface (1 m) with a lattice of 2×2-texel gaps through which the far one (3 m)
    // was measured: what a surface sampled sparsely leaves between its splats. Each gap is
    // closed by the near surface in all 8 directions within 4 texels: it becomes a hole, and
    // the fill gives it the near surface.
    ProbeMap map(64, glm::dvec3(0.0));
    auto at = [](int x, int y) { return oct::texel_index({x, y}, 64); };
    std::vector<std::size_t> gaps;
    for (int y = 0; y < 64; ++y) {
        for (int x = 0; x < 64; ++x) {
            const bool gap = x > 4 && x < 59 && y > 4 && y < 59 && x % 7 < 2 && y % 7 < 2;
            map.set_surface(at(x, y), gap ? 3.0f : 1.0f, glm::vec3(gap ? 0.1f : 0.8f),
                            glm::vec3(0, 0, 1), 1.0f);
            if (gap) {
                gaps.push_back(at(x, y));
            }
        }
    }
    EXPECT_EQ(open_gaps_in_nearer_surfaces(map, 4), gaps.size());
    fill_small_holes(map, 4);
    for (const std::size_t i : gaps) {
        EXPECT_EQ(map.state(i), TexelState::Inferred);
        EXPECT_FLOAT_EQ(map.distance[i], 1.0f);
    }
    EXPECT_EQ(map.state(at(3, 3)), TexelState::Surface);
}

TEST(ProbeBake, ASlitASilhouetteAndAWideHoleKeepTheFarSurface) {
    // What a probe sees through on purpose: the slit between two slats of a blind (open along
    // its length), a near object's silhouette (the far side open), and a hole wider than the
    // reach in every direction (a window). None is touched.
    ProbeMap map(64, glm::dvec3(0.0));
    auto at = [](int x, int y) { return oct::texel_index({x, y}, 64); };
    auto far = [](int x, int y) {
        const bool slit = y >= 10 && y < 12;                        // the whole width
        const bool beside = x >= 40 && y >= 20 && y < 34;           // right of an edge
        const bool window = x >= 10 && x < 22 && y >= 40 && y < 52; // 12 × 12
        return slit || beside || window;
    };
    for (int y = 0; y < 64; ++y) {
        for (int x = 0; x < 64; ++x) {
            map.set_surface(at(x, y), far(x, y) ? 3.0f : 1.0f, glm::vec3(0.5f), glm::vec3(0, 0, 1),
                            1.0f);
        }
    }
    EXPECT_EQ(open_gaps_in_nearer_surfaces(map, 4), 0u);
    for (int y = 0; y < 64; ++y) {
        for (int x = 0; x < 64; ++x) {
            ASSERT_EQ(map.state(at(x, y)), TexelState::Surface) << x << ", " << y;
        }
    }
}

TEST(ProbeBake, AWallSeenThroughTheGapsOfANearPlatesSplatsIsNotShown) {
    // A plate 0.3 m above the probe on a 1 cm grid, a ceiling 1.5 m up (straight up is the
    // octahedral map's middle). Splats of half the default size cover the plate between grid
    // neighbours but leave a small gap at each cell's middle, where the ceiling's points won
    // (the paper's bake, no hole filling, shows it there). The default bake opens those gaps
    // and fills them from the plate.
    PointCloud cloud;
    for (const auto& [z, extent] : {std::pair{0.3f, 0.15f}, std::pair{1.5f, 1.2f}}) {
        const int count = static_cast<int>(std::lround(2.0f * extent / 0.01f)) + 1;
        for (int i = 0; i < count; ++i) {
            for (int j = 0; j < count; ++j) {
                cloud.positions.emplace_back(-extent + 0.01f * static_cast<float>(i),
                                             -extent + 0.01f * static_cast<float>(j), z);
                cloud.colors.emplace_back(0.5f);
                cloud.scan_index.push_back(0);
            }
        }
    }
    cloud.scans.push_back(ScanSource{"plate and ceiling", cloud.size(), glm::dvec3(0.0), true});
    const LocalGeometry geometry = estimate_local_geometry(cloud, {});
    auto ceiling_through_the_plate = [&](int hole_fill_texels) {
        BakeSettings settings;
        settings.resolution = 1024;
        settings.splat_scale = 0.5f;
        settings.hole_fill_texels = hole_fill_texels;
        const ProbeMap map = bake_probe_from_cloud(cloud, geometry, glm::dvec3(0.0), settings);
        std::size_t inside = 0;
        std::size_t ceiling = 0;
        for (int y = 0; y < 1024; ++y) {
            for (int x = 0; x < 1024; ++x) {
                const glm::vec3 d = oct::texel_direction({x, y}, 1024);
                const glm::vec3 on_plate = d * (0.3f / d.z);
                if (d.z > 0.0f && std::abs(on_plate.x) <= 0.12f && std::abs(on_plate.y) <= 0.12f) {
                    ++inside;
                    const float distance = map.distance[oct::texel_index({x, y}, 1024)];
                    ceiling += std::isfinite(distance) && distance > 1.0f ? 1 : 0;
                }
            }
        }
        return static_cast<double>(ceiling) / static_cast<double>(inside);
    };
    const double without_fill = ceiling_through_the_plate(0);
    const double with_fill = ceiling_through_the_plate(-1);
    std::printf(
        "ceiling seen through the plate: %.4f of its texels without hole filling, %.4f with\n",
        without_fill, with_fill);
    EXPECT_GT(without_fill, 0.01);
    EXPECT_EQ(with_fill, 0.0);
}

TEST(ProbeBake, ADisocclusionContinuesTheSurfaceBehindNeverTheNearOne) {
    // A long strip of unknown texels between a near object (red, 1 m) and the far surface
    // (blue, 5 m, facing the probe): what a scanner's shadow behind the object looks like from
    // a probe beside the scanner. 4 texels wide and 24 long: its width, not its length, is
    // what the fill limit measures.
    ProbeMap map(32, glm::dvec3(0.0));
    const glm::vec3 red(0.8f, 0.1f, 0.1f);
    const glm::vec3 blue(0.1f, 0.2f, 0.9f);
    std::vector<std::size_t> strip;
    for (int y = 0; y < 32; ++y) {
        for (int x = 0; x < 32; ++x) {
            const std::size_t i = oct::texel_index({x, y}, 32);
            const glm::vec3 dir = oct::texel_direction({x, y}, 32);
            if (x >= 8 && x < 12 && y >= 4 && y < 28) {
                map.set_unknown(i);
                strip.push_back(i);
            } else if (x < 8) {
                map.set_surface(i, 1.0f, red, -dir, 1.0f);
            } else {
                map.set_surface(i, 5.0f, blue, -dir, 1.0f);
            }
        }
    }
    fill_small_holes(map, 4);
    for (const std::size_t i : strip) {
        ASSERT_EQ(map.state(i), TexelState::Inferred);
        // The far surface's tangent planes continued (a sphere of 5 m about the probe here,
        // with texels 11° apart: the planes drift from it), never the near 1 m or a blend.
        EXPECT_GT(map.distance[i], 4.5f);
        EXPECT_LT(map.distance[i], 6.5f);
        EXPECT_LT(glm::length(map.radiance_at(i) - blue), 0.01f);
        EXPECT_LT(static_cast<float>(map.rgba[4 * i + 3]), 1.0f);
    }
}

TEST(ProbeBake, ADisocclusionsColourIsTheSmoothBlendOfTheSurfaceBehind) {
    // A hole 12 texels wide and 8 tall under a near object (red, 1 m, the rows above it) in a
    // far surface (5 m) whose colour is a ramp along x. No scan saw what is there; the guess
    // with the least squared error is the harmonic blend of the border, and that continues a
    // linear ramp exactly. Filled layer by layer alone, each texel took its nearest border
    // texels' colour: the hole's left column was the column left of it, a texel off.
    ProbeMap map(32, glm::dvec3(0.0));
    const glm::vec3 red(0.8f, 0.1f, 0.1f);
    const auto ramp = [](int x) {
        return glm::vec3(0.1f + 0.02f * static_cast<float>(x), 0.5f,
                         0.9f - 0.02f * static_cast<float>(x));
    };
    std::vector<std::pair<std::size_t, int>> hole;
    for (int y = 0; y < 32; ++y) {
        for (int x = 0; x < 32; ++x) {
            const std::size_t i = oct::texel_index({x, y}, 32);
            const glm::vec3 dir = oct::texel_direction({x, y}, 32);
            if (y < 4) {
                map.set_surface(i, 1.0f, red, -dir, 1.0f);
            } else if (x >= 8 && x < 20 && y < 12) {
                map.set_unknown(i);
                hole.emplace_back(i, x);
            } else {
                map.set_surface(i, 5.0f, ramp(x), -dir, 1.0f);
            }
        }
    }
    fill_small_holes(map, 8);
    for (const auto& [i, x] : hole) {
        ASSERT_EQ(map.state(i), TexelState::Inferred);
        EXPECT_GT(map.distance[i], 4.0f); // the surface behind, never the near one
        // The border's colours are half floats, the fill's too: a few of their steps.
        EXPECT_LT(glm::length(map.radiance_at(i) - ramp(x)), 3e-3f) << "texel column " << x;
    }
}

TEST(ProbeBake, AGapInOneSurfaceTakesTheSmoothBlendOfItsBorder) {
    // A 6×6 gap in one surface (5 m) whose colour is a saddle, harmonic for the 8-neighbour
    // mean (x y is: the neighbours' offsets cancel). The pull-push alone steps from block mean
    // to block mean (0.119 off at worst here); blended harmonically afterwards, the gap takes
    // the saddle.
    ProbeMap map(32, glm::dvec3(0.0));
    const auto saddle = [](int x, int y) {
        const auto s = 0.004f * static_cast<float>((x - 12) * (y - 12));
        return glm::vec3(0.5f + s, 0.5f, 0.5f - s);
    };
    std::vector<std::pair<std::size_t, glm::ivec2>> gap;
    for (int y = 0; y < 32; ++y) {
        for (int x = 0; x < 32; ++x) {
            const std::size_t i = oct::texel_index({x, y}, 32);
            if (x >= 13 && x < 19 && y >= 13 && y < 19) {
                map.set_unknown(i);
                gap.emplace_back(i, glm::ivec2(x, y));
            } else {
                map.set_surface(i, 5.0f, saddle(x, y), -oct::texel_direction({x, y}, 32), 1.0f);
            }
        }
    }
    fill_small_holes(map, 8);
    for (const auto& [i, at] : gap) {
        ASSERT_EQ(map.state(i), TexelState::Inferred);
        EXPECT_LT(glm::length(map.radiance_at(i) - saddle(at.x, at.y)), 3e-3f)
            << "texel " << at.x << ", " << at.y;
    }
}

TEST(ProbeBake, AScannersShadowSeenFromBesideItShowsTheWallBehind) {
    // A 40 cm plate 0.6 m before a wall 3 m away, scanned from the origin: the wall has no
    // points in the plate's shadow (|y|, |z| < 1 m). From a probe 5 cm to the side, the band of
    // the shadow the plate does not hide (y from 0.81 to 1 m) is a hole about 19 texels wide at
    // 1024²: the wall is there, and the fill must show it, not grow the plate over it.
    PointCloud cloud;
    add_wall_x(cloud, 0.6f, 0.01f, 0.01f, 0.2f);
    const std::size_t plate_points = cloud.size();
    PointCloud wall;
    add_wall_x(wall, 3.0f, 0.01f, 0.01f, 1.5f);
    for (std::size_t i = 0; i < wall.size(); ++i) {
        const glm::vec3 p = wall.positions[i];
        if (std::abs(p.y) < 1.0f && std::abs(p.z) < 1.0f) {
            continue; // in the plate's shadow
        }
        cloud.positions.push_back(p);
        cloud.colors.emplace_back(0.1f, 0.2f, 0.9f);
        cloud.scan_index.push_back(0);
    }
    for (std::size_t i = 0; i < plate_points; ++i) {
        cloud.colors[i] = glm::vec3(0.8f, 0.1f, 0.1f);
    }
    cloud.scans.push_back(ScanSource{"plate and wall", cloud.size(), glm::dvec3(0.0), true});
    const LocalGeometry geometry = estimate_local_geometry(cloud, {});
    const glm::dvec3 probe(0.0, 0.05, 0.0);

    auto band_on_the_wall = [&](int hole_fill_texels) {
        BakeSettings settings;
        settings.resolution = 1024;
        settings.hole_fill_texels = hole_fill_texels;
        const ProbeMap map = bake_probe_from_cloud(cloud, geometry, probe, settings);
        std::size_t band = 0;
        std::size_t wall_filled = 0;
        std::size_t plate = 0;
        for_each_texel_on_wall_x(
            map, glm::vec3(probe), 3.0f,
            [](const glm::vec3& p) {
                return p.y >= 0.88f && p.y <= 0.97f && std::abs(p.z) <= 0.5f;
            },
            [&](std::size_t i, const glm::vec3& on_wall) {
                ++band;
                const float truth = glm::length(on_wall - glm::vec3(probe));
                if (map.state(i) == TexelState::Inferred &&
                    std::abs(map.distance[i] - truth) < 0.02f * truth &&
                    map.radiance_at(i).z > 0.8f) {
                    ++wall_filled;
                }
                plate += map.distance[i] < 1.0f ? 1 : 0;
            });
        EXPECT_GT(band, 1000u);
        std::printf("shadow band seen from beside the scanner, hole fill %d: %zu texels, %.3f "
                    "the wall (inferred), %.3f the plate\n",
                    hole_fill_texels, band,
                    static_cast<double>(wall_filled) / static_cast<double>(band),
                    static_cast<double>(plate) / static_cast<double>(band));
        return std::pair{static_cast<double>(wall_filled) / static_cast<double>(band),
                         static_cast<double>(plate) / static_cast<double>(band)};
    };
    const auto [wall_filled, plate] = band_on_the_wall(-1); // 24 texels at 1024²
    EXPECT_GT(wall_filled, 0.99);
    EXPECT_EQ(plate, 0.0);
    // Narrower than the band, the fill leaves it unknown.
    EXPECT_EQ(band_on_the_wall(8).first, 0.0);
}

TEST(ProbeBake, TheDefaultHoleWidthIsAnAngle) {
    EXPECT_EQ(default_hole_fill_texels(64), 4); // at least 4 texels
    EXPECT_EQ(default_hole_fill_texels(256), 6);
    EXPECT_EQ(default_hole_fill_texels(512), 12);
    EXPECT_EQ(default_hole_fill_texels(1024), 24);
    EXPECT_EQ(default_hole_fill_texels(2048), 48);
    BakeSettings settings;
    settings.resolution = 2048;
    EXPECT_EQ(hole_fill_width(settings), 48);
    settings.hole_fill_texels = 0;
    EXPECT_EQ(hole_fill_width(settings), 0);
}

TEST(ProbeBake, ASurfaceScannedFromItsOtherSideIsWhatTheProbeSees) {
    // A sheet at x = 1 scanned from x = 2: its normals face its scanner, away from a probe at
    // the origin. From the probe's centre it is still the nearest thing in those directions: a
    // HIT at 1 m, not a back face; baked for the planner's classification (face_the_probe off)
    // it keeps its back faces, which is how a probe inside an object shows.
    PointCloud cloud;
    add_wall_x(cloud, 1.0f, 0.01f, 0.01f, 0.3f);
    cloud.scans.push_back(ScanSource{"sheet", cloud.size(), glm::dvec3(2.0, 0.0, 0.0), true});
    const LocalGeometry geometry = estimate_local_geometry(cloud, {});
    BakeSettings settings;
    settings.resolution = 256;
    const ProbeMap facing = bake_probe_from_cloud(cloud, geometry, glm::dvec3(0.0), settings);
    settings.face_the_probe = false;
    const ProbeMap as_scanned = bake_probe_from_cloud(cloud, geometry, glm::dvec3(0.0), settings);
    for (const glm::dvec3 dir :
         {glm::dvec3(1.0, 0.0, 0.0), glm::dvec3(1.0, 0.2, -0.1), glm::dvec3(1.0, -0.25, 0.2)}) {
        const ProbeTraceResult seen =
            lookup_probe(facing, dir, 0.0, std::numeric_limits<double>::infinity());
        ASSERT_EQ(seen.status, TraceStatus::Hit);
        EXPECT_NEAR(seen.t, 1.0 / glm::normalize(dir).x, 0.01); // the sheet's plane
        EXPECT_LT(glm::dot(glm::dvec3(seen.normal), dir), 0.0);
        EXPECT_EQ(
            lookup_probe(as_scanned, dir, 0.0, std::numeric_limits<double>::infinity()).status,
            TraceStatus::Unknown);
    }
}

TEST(ProbeBake, RejectsBadParameters) {
    const BoxRoomScene scene;
    const PointCloud cloud = scene.cloud(0.1f, glm::dvec3(0.0, 0.0, 1.0));
    const LocalGeometry geometry = estimate_local_geometry(cloud, {});
    BakeSettings settings;
    settings.resolution = 1;
    EXPECT_THROW((void)bake_probe_from_cloud(cloud, geometry, glm::dvec3(0.0), settings),
                 InputError);
    settings.resolution = 16;
    EXPECT_THROW(
        (void)bake_probe_from_cloud(cloud, geometry, glm::dvec3(std::nan(""), 0.0, 0.0), settings),
        InputError);
    EXPECT_THROW((void)bake_probe_from_cloud(cloud, LocalGeometry{}, glm::dvec3(0.0), settings),
                 InputError);
}

TEST(ProbeBake, CancelledBakeThrows) {
    const BoxRoomScene scene;
    const PointCloud cloud = scene.cloud(0.05f, glm::dvec3(0.0, 0.0, 1.0));
    const LocalGeometry geometry = estimate_local_geometry(cloud, {});
    Progress progress;
    progress.request_cancel();
    EXPECT_THROW(
        (void)bake_probe_from_cloud(cloud, geometry, glm::dvec3(0.0, 0.0, 1.0), {}, &progress),
        Cancelled);
}

TEST(LocalGeometry, NormalsFaceTheScannerAndSpacingMatchesThePattern) {
    const BoxRoomScene scene;
    const glm::dvec3 scanner(0.3, 0.2, 1.1);
    const PointCloud cloud = scene.cloud(0.02f, scanner);
    const LocalGeometry g = estimate_local_geometry(cloud, {});
    std::size_t good = 0;
    std::size_t wall_points = 0;
    double spacing_sum = 0.0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const glm::vec3 p = cloud.positions[i];
        if (glm::length(p - scene.sphere_centre) < scene.sphere_radius + 0.01f) {
            continue;
        }
        // Wall normals point into the room: toward the scanner.
        ++wall_points;
        const glm::vec3 to_scanner = glm::normalize(glm::vec3(scanner) - p);
        good += glm::dot(g.normals[i], to_scanner) > 0.0f ? 1 : 0;
        spacing_sum += g.spacing[i];
        EXPECT_TRUE(g.oriented[i]);
    }
    EXPECT_EQ(good, wall_points);
    const double mean_spacing = spacing_sum / static_cast<double>(wall_points);
    EXPECT_GT(mean_spacing, 0.02); // 4 neighbours at the pitch, 2 at √2 pitch
    EXPECT_LT(mean_spacing, 0.026);
}

TEST(LocalGeometry, SmallestEigenvectorOfKnownMatrices) {
    const double diag[3][3] = {{3, 0, 0}, {0, 1e-9, 0}, {0, 0, 2}};
    const glm::vec3 e = smallest_eigenvector(diag);
    EXPECT_NEAR(std::abs(e.y), 1.0f, 1e-6f);
    // A plane z = x: covariance of points spread in (1,0,1)/√2 and y.
    const double plane[3][3] = {{1, 0, 1}, {0, 2, 0}, {1, 0, 1}};
    const glm::vec3 n = smallest_eigenvector(plane);
    EXPECT_NEAR(std::abs(glm::dot(n, glm::normalize(glm::vec3(1, 0, -1)))), 1.0f, 1e-6f);
}

TEST(ProbeBake, ATexelsColourIsTheMeanOfTheFrontSurfacesPointsItCovers) {
    // A dense near wall (2 mm pitch, 1 m away: ~15 points across a 64² texel) of alternating
    // colours in front of a far wall of a third colour. Each near texel takes the mean of the
    // near points it covers (not the one nearest its centre, not the far wall's); a wall of one
    // colour keeps exactly that colour.
    PointCloud cloud;
    add_wall_x(cloud, 1.0f, 0.002f, 0.002f, 0.2f);
    const std::size_t near_points = cloud.positions.size();
    for (std::size_t i = 0; i < near_points; ++i) {
        const glm::vec3 p(cloud.positions[i]);
        const int column = static_cast<int>(std::lround((p.y + 0.2f) / 0.002f));
        cloud.colors[i] =
            column % 2 == 0 ? glm::vec3(0.9f, 0.1f, 0.3f) : glm::vec3(0.1f, 0.5f, 0.3f);
    }
    add_wall_x(cloud, 3.0f, 0.01f, 0.01f, 2.0f);
    for (std::size_t i = near_points; i < cloud.positions.size(); ++i) {
        cloud.colors[i] = glm::vec3(0.0f, 0.0f, 1.0f);
    }
    cloud.scans.push_back(ScanSource{"two walls", cloud.positions.size(), glm::dvec3(0.0), true});
    const LocalGeometry geometry = estimate_local_geometry(cloud, {});
    BakeSettings settings;
    settings.resolution = 64;
    const ProbeMap map = bake_probe_from_cloud(cloud, geometry, glm::dvec3(0.0), settings);
    int near_texels = 0;
    for (int y = 0; y < map.resolution; ++y) {
        for (int x = 0; x < map.resolution; ++x) {
            const glm::vec3 d = oct::texel_direction({x, y}, map.resolution);
            if (d.x <= 0.0f) {
                continue;
            }
            const glm::vec3 on_near = d / d.x;
            if (std::abs(on_near.y) > 0.15f || std::abs(on_near.z) > 0.15f) {
                continue; // near the near wall's edge the footprint is partial
            }
            const std::size_t i = oct::texel_index({x, y}, map.resolution);
            const glm::vec3 c = map.radiance_at(i);
            EXPECT_NEAR(c.x, 0.5f, 0.06f) << x << ", " << y;
            EXPECT_NEAR(c.y, 0.3f, 0.03f);
            EXPECT_NEAR(c.z, 0.3f, 1e-3f); // both near colours have blue 0.3, the far wall 1
            ++near_texels;
        }
    }
    EXPECT_GT(near_texels, 10);

    // One colour everywhere: exactly that colour, whatever the weights.
    for (glm::vec3& c : cloud.colors) {
        c = glm::vec3(0.3f, 0.55f, 0.8f);
    }
    const ProbeMap one = bake_probe_from_cloud(cloud, geometry, glm::dvec3(0.0), settings);
    const glm::vec3 expected(Imath::half(0.3f), Imath::half(0.55f), Imath::half(0.8f));
    for (std::size_t i = 0; i < one.texel_count(); ++i) {
        if (one.state(i) == TexelState::Surface) {
            ASSERT_EQ(one.radiance_at(i), expected) << i;
        }
    }
}

namespace {

// A 40 cm plate sampled every 2 cm, 0.6 m in front of a probe at the origin, before a wall 3 m
// away sampled every 1 cm, and where its texels hold the plate.
class PlateBeforeAWall {
public:
    PlateBeforeAWall() {
        add_wall_x(cloud_, 0.6f, 0.02f, 0.02f, 0.2f);
        add_wall_x(cloud_, 3.0f, 0.01f, 0.01f, 1.5f);
        cloud_.scans.push_back(
            ScanSource{"plate and wall", cloud_.positions.size(), glm::dvec3(0.0), true});
        geometry_ = estimate_local_geometry(cloud_, {});
    }

    // Of the rays that pass the plate's plane between y0 and y1 off its centre line (|z| <
    // 0.15 m), the fraction whose texel holds the plate, baked with `settings` (no hole fill).
    [[nodiscard]] double plate_between(float y0, float y1, BakeSettings settings) const {
        settings.hole_fill_texels = 0;
        const ProbeMap map = bake_probe_from_cloud(cloud_, geometry_, glm::dvec3(0.0), settings);
        std::size_t band = 0;
        std::size_t plate = 0;
        for_each_texel_on_wall_x(
            map, glm::vec3(0.0f), 0.6f,
            [&](const glm::vec3& p) { return p.y >= y0 && p.y <= y1 && std::abs(p.z) <= 0.15f; },
            [&](std::size_t i, const glm::vec3&) {
                ++band;
                plate += map.distance[i] < 1.0f ? 1 : 0;
            });
        EXPECT_GT(band, 100u);
        return static_cast<double>(plate) / static_cast<double>(std::max<std::size_t>(band, 1));
    }

private:
    PointCloud cloud_;
    LocalGeometry geometry_;
};

} // namespace

TEST(ProbeBake, SilhouettesDoNotGrowByTheSplatRadius) {
    // The plate's edge points' spacing is 2.6 cm (fewer close neighbours), and they splat half
    // of it past themselves, to 0.213 m; a full splat disc reaches 0.8 spacings past them and
    // paints the plate over the far wall there, along its whole silhouette (what made 1 % of
    // the lab room's pixels show the wrong surface). The edge margin alone does it: the full
    // discs' control also takes their whole disc as core (the next test tests the cores).
    const PlateBeforeAWall scene;
    const BakeSettings defaults;
    auto settings = [&](float edge_margin) {
        BakeSettings s;
        s.resolution = 1024;
        s.splat_edge_margin = edge_margin;
        s.splat_core_scale = defaults.splat_scale;
        return s;
    };
    const double clipped = scene.plate_between(0.214f, 0.22f, settings(defaults.splat_edge_margin));
    const double full_discs = scene.plate_between(0.214f, 0.22f, settings(-1.0f));
    std::printf("plate seen 0.214-0.22 m off its centre (edge at 0.2 m): %.3f with edge splats, "
                "%.3f with full discs\n",
                clipped, full_discs);
    EXPECT_LT(clipped, 0.02);
    EXPECT_GT(full_discs, 0.5);
}

TEST(ProbeBake, ASplatsFringeFillsOnlyWhereNoSurfacesCoreReaches) {
    // The same plate with whole discs at its edge (splat_edge_margin < 0), as a crease or a
    // thin object's points splat when no neighbour tells them they are at an edge: the edge
    // points reach 0.8 spacings past themselves, to 0.222 m, but their cores only to 0.2193 m
    // (seen obliquely). Past the core the wall's cores reach every texel (the cores cover a
    // square pattern), so the plate must not show there, though it is nearer.
    const PlateBeforeAWall scene;
    auto settings = [](float core_scale) {
        BakeSettings s;
        s.resolution = 2048;
        s.splat_edge_margin = -1.0f;
        s.splat_core_scale = core_scale;
        return s;
    };
    const double cores_first =
        scene.plate_between(0.2196f, 0.2206f, settings(BakeSettings{}.splat_core_scale));
    const double nearest_wins =
        scene.plate_between(0.2196f, 0.2206f, settings(BakeSettings{}.splat_scale));
    std::printf("plate seen 0.2196-0.2206 m off its centre (cores to 0.2193 m, discs to 0.222 m): "
                "%.3f with cores first, %.3f with the nearest splat winning\n",
                cores_first, nearest_wins);
    EXPECT_LT(cores_first, 0.02);
    EXPECT_GT(nearest_wins, 0.5);
}

TEST(ProbeBake, AThinObjectBeforeAWallDoesNotGrowOverTheTexelsItOnlyTouches) {
    // A plate sampled every 2 mm, 0.6 m from the probe, before a wall 3 m away sampled every
    // 1 cm: at 256² several points of each fall in a texel. The plate ends between its last
    // points (0.201 m off its centre line) and the next, missing ones (0.203 m). A texel whose
    // centre's ray passes the plate's plane further out sees the wall, though the plate's last
    // points may still fall inside it. Every point claimed its own texel, and the nearest
    // surface won: the plate grew over such texels along its whole silhouette (as foreground
    // objects did in the lab room's scan-baked probes, the most of its 1 % of pixels on the
    // wrong surface). A point's own texel whose centre lies past its surface's edge, or outside
    // its disc, is now claimed only where no other surface is known, as any texel there.
    PointCloud cloud;
    add_wall_x(cloud, 0.6f, 0.002f, 0.002f, 0.201f);
    const std::size_t plate_points = cloud.positions.size();
    add_wall_x(cloud, 3.0f, 0.01f, 0.01f, 1.5f);
    cloud.scans.push_back(
        ScanSource{"plate and wall", cloud.positions.size(), glm::dvec3(0.0), true});
    const LocalGeometry geometry = estimate_local_geometry(cloud, {});
    BakeSettings settings;
    settings.resolution = 256;
    settings.hole_fill_texels = 0;
    const ProbeMap map = bake_probe_from_cloud(cloud, geometry, glm::dvec3(0.0), settings);
    const int n = map.resolution;
    std::vector<std::uint8_t> holds_plate_point(map.texel_count(), 0);
    for (std::size_t i = 0; i < plate_points; ++i) {
        const oct::Texel t = oct::texel_of_direction(glm::normalize(cloud.positions[i]), n);
        holds_plate_point[oct::texel_index(t, n)] = 1;
    }
    std::size_t beside = 0;
    std::size_t plate_beside = 0;
    std::size_t inside = 0;
    std::size_t plate_inside = 0;
    for_each_texel_on_wall_x(
        map, glm::vec3(0.0f), 0.6f, [](const glm::vec3& p) { return std::abs(p.z) <= 0.15f; },
        [&](std::size_t i, const glm::vec3& p) {
            const bool plate = map.distance[i] < 1.0f;
            if (std::abs(p.y) >= 0.2035f && holds_plate_point[i] != 0) {
                ++beside;
                plate_beside += plate ? 1 : 0;
            } else if (std::abs(p.y) <= 0.196f) {
                ++inside;
                plate_inside += plate ? 1 : 0;
            }
        });
    std::printf("texels holding plate points whose centre's ray passes beside the plate: %zu of "
                "%zu show the plate; inside it %zu of %zu\n",
                plate_beside, beside, plate_inside, inside);
    ASSERT_GT(beside, 10u);
    EXPECT_EQ(plate_beside, 0u);
    EXPECT_EQ(plate_inside, inside); // the plate keeps every texel it covers
}

TEST(LocalGeometry, PointsAtASurfacesEdgeKnowWhereItsInsideIs) {
    PointCloud cloud;
    add_wall_x(cloud, 0.6f, 0.02f, 0.02f, 0.2f); // 21 × 21 points, y and z from -0.2 to 0.2
    cloud.scans.push_back(ScanSource{"plate", cloud.positions.size(), glm::dvec3(0.0), true});
    const LocalGeometry g = estimate_local_geometry(cloud, {});
    ASSERT_EQ(g.edges.size(), cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const glm::vec3 p = cloud.positions[i];
        const SurfaceEdge& e = g.edges[i];
        if (std::abs(p.y) < 0.15f && std::abs(p.z) < 0.15f) {
            EXPECT_LT(e.offset, 10) << "an inner point at " << p.y << ", " << p.z;
        } else if (p.y > 0.199f && std::abs(p.z) < 0.15f) {
            EXPECT_GE(e.offset, 38) << "the edge point at z " << p.z;
            EXPECT_LT(e.inward[1], -120); // its inside lies toward -y
            EXPECT_EQ(e.inward[0], 0);    // in the plate's plane
        }
    }
}

TEST(ProbeBake, ASliverOnlyAFringeReachesIsTheFillsFirst) {
    // The 40 cm plate of 2 cm pitch 0.6 m from the probe, before a wall 3 m away that no scan
    // saw just beside the plate's silhouette (a scanner's shadow, as the probe sees it: the
    // rays that pass the plate's plane 0.2-0.23 m off its centre line meet the wall where it
    // has no points). Only the plate's splats reach those texels: fringes and discs past its
    // edge, which used to win them and grow the plate by up to a texel there. With the fill
    // on they are its first: it continues the wall behind (a disocclusion). With the plate
    // alone, the same claims stand where nothing can be filled: the plate loses no texel.
    PointCloud plate_only;
    add_wall_x(plate_only, 0.6f, 0.02f, 0.02f, 0.2f);
    PointCloud cloud = plate_only;
    // The shadow lies beside the plate's sides, as a scanner beside the probe would leave it.
    add_far_wall_but(cloud, 1.5f, [](float plate_y, float plate_z) {
        return std::abs(plate_y) > 0.2f && std::abs(plate_y) < 0.23f && std::abs(plate_z) <= 0.2f;
    });
    for (PointCloud* c : {&plate_only, &cloud}) {
        c->scans.push_back(
            ScanSource{"plate and wall", c->positions.size(), glm::dvec3(0.0), true});
    }
    const LocalGeometry geometry = estimate_local_geometry(cloud, {});
    const LocalGeometry plate_geometry = estimate_local_geometry(plate_only, {});
    BakeSettings settings;
    settings.resolution = 1024;
    BakeSettings unfilled = settings;
    unfilled.hole_fill_texels = 0; // the fringes' claims stand, as before
    const ProbeMap filled = bake_probe_from_cloud(cloud, geometry, glm::dvec3(0.0), settings);
    const ProbeMap kept = bake_probe_from_cloud(cloud, geometry, glm::dvec3(0.0), unfilled);
    // Past the plate's end as its edge points place it (half their 2.6 cm spacing past them,
    // 0.213 m) and within their splats' reach (0.221 m).
    auto plate_beside_edge = [](const ProbeMap& map) {
        std::size_t band = 0;
        std::size_t plate = 0;
        std::size_t wall = 0;
        for_each_texel_on_wall_x(
            map, glm::vec3(0.0f), 0.6f,
            [](const glm::vec3& p) {
                return p.y >= 0.214f && p.y <= 0.22f && std::abs(p.z) <= 0.15f;
            },
            [&](std::size_t i, const glm::vec3&) {
                ++band;
                plate += map.distance[i] < 1.0f ? 1 : 0;
                wall += std::isfinite(map.distance[i]) && map.distance[i] > 2.9f ? 1 : 0;
            });
        EXPECT_GT(band, 100u);
        return std::pair{static_cast<double>(plate) / static_cast<double>(band),
                         static_cast<double>(wall) / static_cast<double>(band)};
    };
    const auto [plate_filled, wall_filled] = plate_beside_edge(filled);
    const auto [plate_kept, wall_kept] = plate_beside_edge(kept);
    std::printf(
        "past the plate's edge, over the wall's shadow: plate %.3f, wall %.3f with the fill "
        "first; plate %.3f, wall %.3f with the fringes' claims\n",
        plate_filled, wall_filled, plate_kept, wall_kept);
    EXPECT_GT(plate_kept, 0.5); // the claims grew the plate
    EXPECT_LT(plate_filled, 0.02);
    EXPECT_GT(wall_filled, 0.98);
    // The plate alone: every texel its splats won without the fill, it still holds.
    const ProbeMap alone =
        bake_probe_from_cloud(plate_only, plate_geometry, glm::dvec3(0.0), settings);
    const ProbeMap alone_kept =
        bake_probe_from_cloud(plate_only, plate_geometry, glm::dvec3(0.0), unfilled);
    std::size_t held = 0;
    for (std::size_t i = 0; i < alone.texel_count(); ++i) {
        if (alone_kept.state(i) == TexelState::Surface) {
            ++held;
            ASSERT_EQ(alone.state(i), TexelState::Surface) << "texel " << i << " lost";
            ASSERT_EQ(alone.distance[i], alone_kept.distance[i]);
        }
    }
    EXPECT_GT(held, 1000u);
}

TEST(ProbeBake, AHoleARestoredSliverClosesOffIsFilledByASecondFill) {
    // The plate and wall of ASliverOnlyAFringeReachesIsTheFillsFirst, the wall's shadow beside
    // the plate's +y edge only as wide as the plate's fringes reach (0.2-0.219 m where the rays
    // pass the plate's plane), along its whole height. Beside that sliver the wall has two more
    // unseen patches: a narrow one (out to 0.24 m, 0.08-0.12 m below the centre line), which
    // the fill fills, and a wide one (out to 0.4 m, above 0.04 m), which it must not. With the
    // sliver unknown, the first fill finds the two joined through it into one hole too wide to
    // fill; once the sliver's claims are restored, the narrow patch is a hole of its own, closed
    // off by them, and the second fill fills it.
    PointCloud cloud;
    add_wall_x(cloud, 0.6f, 0.02f, 0.02f, 0.2f);
    add_far_wall_but(cloud, 2.5f, [](float plate_y, float plate_z) {
        const bool shadow = plate_y > 0.2f && plate_y < 0.219f && std::abs(plate_z) <= 0.2f;
        const bool narrow =
            plate_y > 0.2f && plate_y < 0.24f && plate_z >= -0.12f && plate_z <= -0.08f;
        const bool wide = plate_y > 0.2f && plate_y < 0.4f && plate_z >= 0.04f && plate_z <= 0.2f;
        return shadow || narrow || wide;
    });
    cloud.scans.push_back(
        ScanSource{"plate and wall", cloud.positions.size(), glm::dvec3(0.0), true});
    const LocalGeometry geometry = estimate_local_geometry(cloud, {});
    BakeSettings settings;
    settings.resolution = 1024;
    const ProbeMap map = bake_probe_from_cloud(cloud, geometry, glm::dvec3(0.0), settings);
    // The texels over each patch, clear of its edges by about a texel (2 mm at the plate).
    auto over = [&](float y0, float y1, float z0, float z1) {
        std::size_t texels = 0;
        std::size_t wall = 0;
        std::size_t unknown = 0;
        for_each_texel_on_wall_x(
            map, glm::vec3(0.0f), 0.6f,
            [&](const glm::vec3& p) { return p.y >= y0 && p.y <= y1 && p.z >= z0 && p.z <= z1; },
            [&](std::size_t i, const glm::vec3&) {
                ++texels;
                wall += std::isfinite(map.distance[i]) && map.distance[i] > 2.9f ? 1 : 0;
                unknown += map.state(i) == TexelState::Unknown ? 1 : 0;
            });
        EXPECT_GT(texels, 50u);
        return std::pair{static_cast<double>(wall) / static_cast<double>(texels),
                         static_cast<double>(unknown) / static_cast<double>(texels)};
    };
    const auto [narrow_wall, narrow_unknown] = over(0.224f, 0.236f, -0.116f, -0.084f);
    const auto [wide_wall, wide_unknown] = over(0.26f, 0.38f, 0.06f, 0.18f);
    std::printf("narrow patch: wall %.3f, unknown %.3f; wide patch: wall %.3f, unknown %.3f\n",
                narrow_wall, narrow_unknown, wide_wall, wide_unknown);
    EXPECT_GT(narrow_wall, 0.98);  // filled: the wall continued behind the plate's edge
    EXPECT_GT(wide_unknown, 0.98); // too wide: left as what no scan saw
}
