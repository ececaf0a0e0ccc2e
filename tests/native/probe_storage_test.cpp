// Storage sized to the data (probe_storage.hpp): the codes keep the three texel states apart,
// quantisation stays within its step, and a packed field traces what the full one traces up to
// that quantisation, in 7 bytes a texel instead of 18.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <tuple>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "lfprobe/color.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/probe_field.hpp"
#include "lfprobe/probe_set.hpp"
#include "lfprobe/probe_storage.hpp"
#include "lfprobe/render.hpp"
#include "trace_scenes.hpp"

using namespace lfprobe;
using lfprobe::testing::BoxRoomScene;
namespace scenes = lfprobe::testing;
namespace fs = std::filesystem;

TEST(ProbeStorage, DistanceCodesKeepTheThreeStates) {
    const double step = 0.001;
    EXPECT_EQ(encode_distance(kUnknownDistance, step), kUnknownDistanceCode);
    EXPECT_EQ(encode_distance(kEmptyDistance, step), kEmptyDistanceCode);
    // A surface nearer than half a step is still a surface, and one beyond the last code
    // clamps to it instead of becoming empty.
    EXPECT_EQ(encode_distance(1e-7f, step), 1);
    EXPECT_EQ(encode_distance(0.0f, step), 1);
    EXPECT_EQ(encode_distance(1e6f, step), kLargestDistanceCode);
    EXPECT_TRUE(std::isnan(decode_distance(kUnknownDistanceCode, step)));
    EXPECT_TRUE(std::isinf(decode_distance(kEmptyDistanceCode, step)));
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.01f, 60.0f);
    for (int i = 0; i < 10000; ++i) {
        const float d = u(rng);
        const float back = decode_distance(encode_distance(d, step), step);
        EXPECT_LE(std::abs(back - d), 0.5 * step + 1e-6) << d;
    }
}

TEST(ProbeStorage, NormalsWithinADegreeAndAxesExact) {
    for (const glm::vec3 axis : {glm::vec3(1, 0, 0), glm::vec3(-1, 0, 0), glm::vec3(0, 1, 0),
                                 glm::vec3(0, -1, 0), glm::vec3(0, 0, 1), glm::vec3(0, 0, -1)}) {
        const glm::vec3 back = decode_normal_oct16(encode_normal_oct16(axis));
        EXPECT_NEAR(glm::dot(back, axis), 1.0f, 1e-6f) << axis.x << " " << axis.y << " " << axis.z;
    }
    std::mt19937 rng(3);
    double worst = 0.0;
    for (int i = 0; i < 100000; ++i) {
        const glm::vec3 n(scenes::random_unit(rng));
        const glm::vec3 back = decode_normal_oct16(encode_normal_oct16(n));
        const double angle =
            std::acos(std::clamp(static_cast<double>(glm::dot(n, back)), -1.0, 1.0));
        worst = std::max(worst, angle);
    }
    std::printf("oct16 normals: worst error %.3f degrees over 100000 directions\n",
                worst * 180.0 / M_PI);
    EXPECT_LT(worst * 180.0 / M_PI, 1.0);
}

TEST(ProbeStorage, EverySrgbCodeRoundTrips) {
    for (int code = 0; code < 256; ++code) {
        const auto c = static_cast<std::uint8_t>(code);
        EXPECT_EQ(linear_to_srgb8(srgb8_to_linear(c)), c);
    }
    EXPECT_EQ(linear_to_srgb8(-1.0f), 0);
    EXPECT_EQ(linear_to_srgb8(7.0f), 255);
}

TEST(ProbeStorage, PackingKeepsStatesAndBoundsTheErrors) {
    const BoxRoomScene scene;
    ProbeMap full = scenes::analytic_probe_with_holes(scene, {0.1, -0.2, 1.3}, 96);
    ProbeMap packed = full;
    const ProbeStorage storage = ProbeStorage::compact(0.001);
    const PackSummary summary = pack_probe(packed, storage);
    EXPECT_TRUE(packed.is_packed());
    EXPECT_TRUE(packed.is_complete());
    EXPECT_TRUE(packed.distance.empty() && packed.rgba.empty() && packed.normal.empty());
    EXPECT_EQ(packed.memory_bytes(), full.texel_count() * 7);
    EXPECT_EQ(storage.bytes_per_texel(), 7u);
    EXPECT_EQ(ProbeStorage::full().bytes_per_texel(), 18u);
    EXPECT_EQ(full.memory_bytes(), full.texel_count() * 18);
    EXPECT_LE(summary.max_distance_error, 0.0005 + 1e-6);
    for (std::size_t i = 0; i < full.texel_count(); ++i) {
        const TexelState a = full.state(i);
        const TexelState b = packed.state(i);
        ASSERT_EQ(a == TexelState::Unknown, b == TexelState::Unknown) << i;
        ASSERT_EQ(a == TexelState::Empty, b == TexelState::Empty) << i;
        if (a == TexelState::Unknown || a == TexelState::Empty) {
            continue;
        }
        EXPECT_NEAR(packed.distance_at(i), full.distance_at(i), 0.0005 + 1e-6);
        const glm::vec3 ca = full.radiance_at(i);
        const glm::vec3 cb = packed.radiance_at(i);
        for (int c = 0; c < 3; ++c) {
            // Half a step of 8-bit sRGB, in linear terms (largest near white).
            EXPECT_NEAR(srgb_to_linear(linear_to_srgb(ca[c])), cb[c], 0.0045f) << i;
        }
        EXPECT_GT(glm::dot(glm::normalize(full.normal_at(i)), packed.normal_at(i)),
                  std::cos(0.0175f))
            << i;
    }
    EXPECT_THROW((void)pack_probe(packed, storage), InputError);
}

// Any mix of channel precisions takes the bytes it says it takes.
TEST(ProbeStorage, MixedStorageTakesTheBytesItStates) {
    const BoxRoomScene scene;
    for (const auto& [radiance, normal, step] :
         {std::tuple{RadiancePrecision::Half, NormalPrecision::Oct16, 0.001},
          std::tuple{RadiancePrecision::Srgb8, NormalPrecision::Half, 0.0},
          std::tuple{RadiancePrecision::Half, NormalPrecision::Half, 0.002}}) {
        ProbeStorage storage;
        storage.radiance = radiance;
        storage.normal = normal;
        storage.distance_step = step;
        storage.keep_confidence = false;
        ProbeMap map = scenes::analytic_probe(scene, {0.0, 0.0, 1.2}, 32);
        (void)pack_probe(map, storage);
        EXPECT_EQ(map.memory_bytes(), map.texel_count() * storage.bytes_per_texel());
        EXPECT_TRUE(map.is_complete());
    }
}

TEST(ProbeStorage, AFarProbeTakesACoarserStepInsteadOfClamping) {
    ProbeMap map = scenes::custom_probe(
        16, glm::dvec3(0.0), [](const glm::vec3& d, std::size_t i, ProbeMap& m) {
            m.set_surface(i, d.z > 0.0f ? 150.0f : 2.0f, glm::vec3(0.5f), -d, 1.0f);
        });
    const PackSummary summary = pack_probe(map, ProbeStorage::compact(0.001));
    EXPECT_NEAR(summary.distance_step, 150.0 / kLargestDistanceCode, 1e-9);
    EXPECT_LE(summary.max_distance_error, 0.5 * summary.distance_step + 1e-5);
}

TEST(ProbeStorage, ManifestJsonRoundTripAndBadInput) {
    const ProbeStorage compact = ProbeStorage::compact(0.002);
    const ProbeStorage back = ProbeStorage::from_json(compact.to_json(), "test");
    EXPECT_EQ(back.radiance, RadiancePrecision::Srgb8);
    EXPECT_EQ(back.normal, NormalPrecision::Oct16);
    EXPECT_EQ(back.distance_step, 0.002);
    EXPECT_FALSE(back.keep_confidence);
    EXPECT_TRUE(ProbeStorage::from_json(nlohmann::json::object(), "test").is_full());
    EXPECT_THROW((void)ProbeStorage::from_json({{"radiance", "rgb4"}}, "test"), InputError);
    EXPECT_THROW((void)ProbeStorage::from_json({{"normal", 3}}, "test"), InputError);
    EXPECT_THROW((void)ProbeStorage::from_json({{"distance_step", -1.0}}, "test"), InputError);
    EXPECT_THROW((void)ProbeStorage::from_name("tiny"), InputError);
    EXPECT_EQ(ProbeStorage::from_name("compact").distance_step, kDefaultDistanceStep);
}

// The same analytic field, full and packed: every ray gets the same status (the states are
// exact), hits land within the distance step plus the texel's own quantisation, and colours
// within 8-bit sRGB.
TEST(ProbeStorage, PackedFieldTracesWhatTheFullFieldTraces) {
    const BoxRoomScene scene;
    const ProbeGrid grid = ProbeGrid::spanning({-1.0, -0.6, 0.7}, {0.6, 0.6, 1.7}, {2, 2, 2});
    const ProbePlacement placement = ProbePlacement::from_grid(grid);
    std::vector<ProbeMap> full_probes;
    std::vector<ProbeMap> packed_probes;
    for (const glm::dvec3& p : placement.positions) {
        full_probes.push_back(scenes::analytic_probe_with_holes(scene, p, 128));
        packed_probes.push_back(full_probes.back());
        (void)pack_probe(packed_probes.back(), ProbeStorage::compact(0.001));
    }
    const ProbeField full(placement, std::move(full_probes));
    const ProbeField packed(placement, std::move(packed_probes));
    EXPECT_LT(static_cast<double>(packed.memory_bytes()),
              0.5 * static_cast<double>(full.memory_bytes()));
    for (const Camera& camera :
         {Camera::look_at({-0.2, 0.0, 1.2}, {0.5, 0.8, 1.0}, 96, 72, 20.0),
          Camera::look_at(full.probe(0).position, {0.5, 0.8, 1.0}, 96, 72, 20.0),
          Camera::look_at({1.7, -1.2, 2.0}, {-1.0, 0.5, 0.8}, 96, 72, 20.0)}) {
        const RenderedImage a = render_probe_view(full, camera, {});
        const RenderedImage b = render_probe_view(packed, camera, {});
        std::size_t same_status = 0;
        std::size_t both_hit = 0;
        std::size_t depth_apart = 0;  // hits more than a step and a bit apart: another texel
        std::size_t colour_apart = 0; // colours more than 8-bit sRGB apart
        double median_depth = 0.0;
        std::vector<double> depth_differences;
        for (std::size_t i = 0; i < a.pixel_count(); ++i) {
            same_status += a.status[i] == b.status[i] ? 1 : 0;
            if (a.status[i] != 1 || b.status[i] != 1) {
                continue;
            }
            ++both_hit;
            const double dd =
                std::abs(static_cast<double>(a.depth[i]) - static_cast<double>(b.depth[i]));
            depth_differences.push_back(dd);
            depth_apart += dd > 0.002 ? 1 : 0;
            float dc = 0.0f;
            for (std::size_t c = 0; c < 3; ++c) {
                dc = std::max(dc, std::abs(a.rgba[4 * i + c] - b.rgba[4 * i + c]));
            }
            colour_apart += dc > 0.0045f ? 1 : 0;
        }
        std::sort(depth_differences.begin(), depth_differences.end());
        if (!depth_differences.empty()) {
            median_depth = depth_differences[depth_differences.size() / 2];
        }
        const auto rate = [](std::size_t k, std::size_t n) {
            return n == 0 ? 0.0 : static_cast<double>(k) / static_cast<double>(n);
        };
        const double agreement = rate(same_status, a.pixel_count());
        std::printf("packed vs full: status agrees on %.4f of pixels; over %zu common hits the "
                    "depth differs by %.5f m (median), by more than 2 mm on %.4f, the colour by "
                    "more than 8-bit sRGB on %.4f (another texel at a silhouette)\n",
                    agreement, both_hit, median_depth, rate(depth_apart, both_hit),
                    rate(colour_apart, both_hit));
        EXPECT_GE(agreement, 0.995);
        EXPECT_GT(both_hit, a.pixel_count() / 2);
        EXPECT_LE(median_depth, 0.0005 + 1e-6);
        EXPECT_LT(rate(depth_apart, both_hit), 0.02);
        EXPECT_LT(rate(colour_apart, both_hit), 0.02);
    }
}

TEST(ProbeStorage, LoadHonoursTheManifestAndTheCallersChoice) {
    const BoxRoomScene scene;
    const fs::path folder = fs::temp_directory_path() / "lfprobe_storage_test_set";
    fs::remove_all(folder);
    const ProbePlacement placement =
        ProbePlacement::from_positions({{0.0, 0.0, 1.2}, {0.4, 0.1, 1.0}});
    ProbeSetManifest manifest;
    manifest.placement = placement;
    (void)write_probe_set(folder.string(), manifest, [&](std::size_t i) {
        return scenes::analytic_probe(scene, placement.positions[i], 64);
    });
    const ProbeField as_baked = ProbeField::load(folder.string());
    EXPECT_TRUE(as_baked.storage().is_full());
    EXPECT_FALSE(as_baked.probe(0).is_packed());

    const ProbeSetManifest stored =
        set_probe_set_storage(folder.string(), ProbeStorage::compact(0.001));
    EXPECT_EQ(stored.probes[0].memory_bytes, 64u * 64u * 7u);
    const ProbeField compact = ProbeField::load(folder.string());
    EXPECT_FALSE(compact.storage().is_full());
    EXPECT_TRUE(compact.probe(1).is_packed());
    EXPECT_LT(compact.memory_bytes(), as_baked.memory_bytes());
    // The files keep full precision: the caller can still ask for it.
    const ProbeField forced = ProbeField::load(folder.string(), nullptr, 0, ProbeStorage::full());
    EXPECT_FALSE(forced.probe(1).is_packed());
    EXPECT_EQ(forced.memory_bytes(), as_baked.memory_bytes());
    fs::remove_all(folder);
}
