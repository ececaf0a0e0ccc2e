// Texture LOD: a ray's sample reads the texture's mean over its footprint. Named cases: a
// footprint of a texel or less is the plain bilinear sample bit for bit; a footprint as wide as
// the image reads its mean; odd sizes halve down to one texel; a far checkerboard in the ground
// truth reads grey with filtered textures and aliases without them, and so do a simulated
// scanner's points; one colour stays one colour.
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "lfprobe/camera.hpp"
#include "lfprobe/embree_scene.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/ground_truth.hpp"
#include "lfprobe/mesh.hpp"
#include "lfprobe/scanner_sim.hpp"
#include "lfprobe/texture.hpp"

namespace lfprobe {
namespace {

// A w×h checkerboard of squares `square` texels wide, black and white (linear 0 and 1).
Texture checkerboard(int w, int h, int square = 1) {
    std::vector<float> pixels(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 3);
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            for (int c = 0; c < 3; ++c) {
                pixels[(static_cast<std::size_t>(y) * static_cast<std::size_t>(w) +
                        static_cast<std::size_t>(x)) *
                           3 +
                       static_cast<std::size_t>(c)] =
                    static_cast<float>((x / square + y / square) % 2);
            }
        }
    }
    return Texture::from_pixels("checker", w, h, pixels.data(), 3, false, false);
}

TEST(TextureLod, AFootprintOfATexelOrLessIsTheBilinearSampleBitForBit) {
    const Texture t = checkerboard(16, 16);
    for (const float u : {0.013f, 0.27f, 0.5f, 0.8123f}) {
        for (const float v : {0.04f, 0.333f, 0.91f}) {
            const glm::vec2 uv{u, v};
            EXPECT_EQ(t.sample(uv, 0.0), t.sample(uv));
            EXPECT_EQ(t.sample(uv, 0.7), t.sample(uv));
            EXPECT_EQ(t.sample(uv, 1.0), t.sample(uv));
        }
    }
}

TEST(TextureLod, AFootprintAsWideAsTheImageReadsItsMean) {
    const Texture t = checkerboard(16, 16);
    ASSERT_EQ(t.mips.size(), 4u); // 8², 4², 2², 1²
    for (const float u : {0.013f, 0.27f, 0.5f}) {
        const glm::vec2 uv{u, 0.61f};
        EXPECT_NEAR(t.sample(uv, 16.0).x, 0.5f, 1e-6f);
        EXPECT_NEAR(t.sample(uv, 1000.0).y, 0.5f, 1e-6f);
        // Two texels wide: level 1, where every texel already averages two black and two white.
        EXPECT_NEAR(t.sample(uv, 2.0).z, 0.5f, 1e-6f);
    }
    // Between a texel and two the sample moves from the checks towards grey, never beyond.
    const glm::vec2 on_white{(1.0f + 0.5f) / 16.0f, 1.0f - 0.5f / 16.0f}; // texel (1, 0)
    const float sharp = t.sample(on_white).x;
    const float between = t.sample(on_white, std::sqrt(2.0)).x;
    EXPECT_EQ(sharp, 1.0f);
    EXPECT_LT(between, sharp);
    EXPECT_GT(between, 0.5f);
}

TEST(TextureLod, OddSizesHalveDownToOneTexelAndOneColourStaysThatColour) {
    std::vector<float> pixels(5 * 3 * 3);
    for (std::size_t i = 0; i < pixels.size(); i += 3) {
        pixels[i] = 0.25f;
        pixels[i + 1] = 0.5f;
        pixels[i + 2] = 0.75f;
    }
    const Texture t = Texture::from_pixels("flat", 5, 3, pixels.data(), 3, false, false);
    ASSERT_EQ(t.mips.size(), 3u); // 3×2, 2×1, 1×1
    EXPECT_EQ(t.mips[0].width, 3);
    EXPECT_EQ(t.mips[0].height, 2);
    EXPECT_EQ(t.mips[2].width, 1);
    EXPECT_EQ(t.mips[2].height, 1);
    for (const double footprint : {0.5, 1.5, 3.0, 4.7, 100.0}) {
        const glm::vec3 c = t.sample({0.37f, 0.8f}, footprint);
        EXPECT_EQ(c, glm::vec3(0.25f, 0.5f, 0.75f)) << footprint;
    }
}

// A floor z = 0 over [-L, L]², its texture a 256² checkerboard of 4-texel squares repeated
// `repeats` times.
Mesh checkered_floor(double half, float repeats) {
    Mesh mesh;
    const auto h = static_cast<float>(half);
    mesh.vertices = {{-h, -h, 0.0f}, {h, -h, 0.0f}, {h, h, 0.0f}, {-h, h, 0.0f}};
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
    const glm::vec2 uv[4] = {{0.0f, 0.0f}, {repeats, 0.0f}, {repeats, repeats}, {0.0f, repeats}};
    mesh.corner_uvs = {uv[0], uv[1], uv[2], uv[0], uv[2], uv[3]};
    mesh.material = {0, 0};
    mesh.object = {0, 0};
    Material m;
    m.name = "checker";
    m.texture = std::make_shared<const Texture>(checkerboard(256, 256, 4));
    mesh.materials = {m};
    mesh.object_names = {"floor"};
    return mesh;
}

double mean_abs_from_grey(const RenderedImage& image) {
    double sum = 0.0;
    std::size_t count = 0;
    for (std::size_t i = 0; i < image.pixel_count(); ++i) {
        if (image.rgba[4 * i + 3] == 1.0f) {
            sum += std::abs(image.rgba[4 * i] - 0.5);
            ++count;
        }
    }
    return count > 0 ? sum / static_cast<double>(count) : 1.0;
}

TEST(TextureLod, AFarCheckerboardIsGreyInTheGroundTruthAndAliasesWithPointSamples) {
    // 40 m of floor with 8 mm checks seen from 1.6 m up: each pixel spans many checks.
    const Mesh mesh = checkered_floor(20.0, 78.0f);
    const EmbreeScene scene(mesh);
    const Camera camera = Camera::look_at({0.0, -6.0, 1.6}, {0.0, 4.0, 0.0}, 64, 40);
    GroundTruthSettings filtered;
    GroundTruthSettings point;
    point.filter_textures = false;
    const double grey_filtered = mean_abs_from_grey(render_ground_truth(scene, camera, filtered));
    const double grey_point = mean_abs_from_grey(render_ground_truth(scene, camera, point));
    EXPECT_LT(grey_filtered, 0.05);
    EXPECT_GT(grey_point, 0.3); // a point sample reads a check: 0 or 1, near enough
    // At 4×4 samples the filtered strata stay grey as well.
    filtered.samples_per_pixel = 16;
    EXPECT_LT(mean_abs_from_grey(render_ground_truth(scene, camera, filtered)), 0.05);
}

TEST(TextureLod, ARayWithoutSpreadIsTheUnfilteredHitBitForBit) {
    const Mesh mesh = checkered_floor(2.0, 4.0f);
    const EmbreeScene scene(mesh);
    Ray ray;
    ray.origin = {0.1, -0.3, 1.2};
    ray.direction = glm::normalize(glm::dvec3(0.2, 0.7, -1.0));
    const MeshHit plain = scene.intersect(ray);
    const MeshHit zero = scene.intersect(ray, 0.0);
    ASSERT_TRUE(plain.hit);
    EXPECT_EQ(plain.base_color, zero.base_color);
    EXPECT_EQ(plain.t, zero.t);
    // A wide spread reads towards the checks' mean.
    const MeshHit wide = scene.intersect(ray, 0.05);
    EXPECT_NEAR(wide.base_color.x, 0.5f, 0.05f);
}

// The mesh bake traces a texel's strata in Embree's packets: every attribute of every hit
// (and every miss) must be what single rays give, for full and partial packets and for rays
// that leave the floor, so that a bake's maps do not depend on how its rays were grouped.
TEST(TextureLod, RaysTracedInAPacketHitExactlyWhatSingleRaysHit) {
    const Mesh mesh = checkered_floor(2.0, 4.0f);
    const EmbreeScene scene(mesh);
    std::vector<Ray> rays;
    for (int i = 0; i < 21; ++i) {
        Ray ray;
        ray.origin = {0.1, -0.3, 1.2};
        // Rays 0-16 fan out over the floor; the later ones point up and miss.
        const double a = 0.15 * i;
        ray.direction = glm::normalize(glm::dvec3(std::cos(a), std::sin(a), i < 17 ? -0.8 : 0.5));
        rays.push_back(ray);
    }
    for (const double spread : {0.0, 0.004}) {
        for (std::size_t first = 0; first < rays.size(); first += EmbreeScene::kPacket) {
            const std::size_t count = std::min(EmbreeScene::kPacket, rays.size() - first);
            std::vector<MeshHit> packet(EmbreeScene::kPacket);
            packet[0].base_color = glm::vec3(7.0f); // what a previous packet left is overwritten
            scene.intersect_packet(rays.data() + first, count, spread, packet.data());
            for (std::size_t k = 0; k < count; ++k) {
                const MeshHit one = scene.intersect(rays[first + k], spread);
                const MeshHit& p = packet[k];
                ASSERT_EQ(p.hit, one.hit) << "ray " << first + k;
                if (!one.hit) {
                    continue;
                }
                EXPECT_EQ(p.t, one.t);
                EXPECT_EQ(p.triangle, one.triangle);
                EXPECT_EQ(p.u, one.u);
                EXPECT_EQ(p.v, one.v);
                EXPECT_EQ(p.uv, one.uv);
                EXPECT_EQ(p.geometric_normal, one.geometric_normal);
                EXPECT_EQ(p.shading_normal, one.shading_normal);
                EXPECT_EQ(p.base_color, one.base_color);
                EXPECT_EQ(p.object, one.object);
            }
        }
    }
    std::vector<MeshHit> too_many(EmbreeScene::kPacket + 1);
    std::vector<Ray> seventeen(EmbreeScene::kPacket + 1, rays[0]);
    EXPECT_THROW(scene.intersect_packet(seventeen.data(), seventeen.size(), 0.0, too_many.data()),
                 InputError);
}

// A scanner's colour comes from a camera whose pixel integrates what it covers: on checks much
// finer than its step, its points read grey, where point samples read the checks and alias.
TEST(TextureLod, AScannersPointsOnFineChecksAreGreyWithItsCameraFootprintAndAliasWithout) {
    const Mesh mesh = checkered_floor(20.0, 78.0f); // 8 mm checks; the footprint is ≥ 2.8 cm
    const EmbreeScene scene(mesh);
    ScannerSettings filtered;
    filtered.position = {0.0, 0.0, 1.6};
    filtered.step_deg = 1.0;
    filtered.noise_mm = 0.0;
    ScannerSettings point = filtered;
    point.filter_textures = false;
    const auto grey_of = [&](const ScannerSettings& s) {
        const std::vector<SimulatedPoint> points = simulate_scan(scene, s);
        double sum = 0.0;
        for (const SimulatedPoint& q : points) {
            sum += std::abs(q.color.x - 0.5);
        }
        EXPECT_GT(points.size(), 1000u);
        return points.empty() ? 1.0 : sum / static_cast<double>(points.size());
    };
    EXPECT_LT(grey_of(filtered), 0.05);
    EXPECT_GT(grey_of(point), 0.3);
}

} // namespace
} // namespace lfprobe
