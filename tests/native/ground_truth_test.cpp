// Ground truth renders: analytic depth in a box room, MTL colours, object ids, bit-identical
// output for any thread count, and the EXR object channel round trip.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include "lfprobe/ground_truth.hpp"
#include "lfprobe/image_exr.hpp"
#include "lfprobe/mesh_reader.hpp"
#include "lfprobe/probe_trace.hpp"
#include "temp_folder.hpp"
#include "test_data.hpp"

namespace lfprobe {
namespace {

const std::string kMeshes = lfprobe::testing::shared_data("meshes");

// A closed box room [-2,2] × [-3,3] × [0,2.5], one object and one material per wall.
// Each test writes its own copy: ctest runs the tests as processes side by side, and one
// rewriting a shared file while another read it made the reader fail now and then.
std::filesystem::path test_dir() {
    return lfprobe::testing::fresh_dir(
        "lfprobe_ground_truth_", ::testing::UnitTest::GetInstance()->current_test_info()->name());
}

std::string box_room_obj() {
    const auto dir = test_dir();
    std::ofstream(dir / "room.mtl")
        << "newmtl floor\nKd 0.5 0.5 0.5\nnewmtl wall\nKd 0.2 0.4 0.6\n";
    std::ofstream(dir / "room.obj")
        << "mtllib room.mtl\n"
           "v -2 -3 0\nv 2 -3 0\nv 2 3 0\nv -2 3 0\n"
           "v -2 -3 2.5\nv 2 -3 2.5\nv 2 3 2.5\nv -2 3 2.5\n"
           "usemtl floor\no floor\nf 1 2 3 4\n"
           "usemtl wall\no ceiling\nf 5 8 7 6\n"
           "o south\nf 1 5 6 2\no north\nf 4 3 7 8\no west\nf 1 4 8 5\no east\nf 2 6 7 3\n";
    return (dir / "room.obj").string();
}

TEST(GroundTruth, BoxRoomDepthIsAnalytic) {
    const Mesh mesh = read_mesh(box_room_obj());
    const EmbreeScene scene(mesh);
    const Camera cam = Camera::look_at({0.3, -1.0, 1.2}, {0.5, 3.0, 1.0}, 64, 48);
    GroundTruthStats stats;
    const RenderedImage img = render_ground_truth(scene, cam, {}, nullptr, &stats);
    EXPECT_EQ(stats.rays, 64u * 48u);
    EXPECT_EQ(stats.hits, 64u * 48u); // a closed room: every ray hits
    for (int y = 0; y < img.height; ++y) {
        for (int x = 0; x < img.width; ++x) {
            const Ray ray = cam.pixel_ray(x, y);
            // The nearest of the six planes along the ray, in double.
            double best = INFINITY;
            const double planes[3][2] = {{-2, 2}, {-3, 3}, {0, 2.5}};
            for (int a = 0; a < 3; ++a) {
                for (const double p : planes[a]) {
                    if (ray.direction[a] != 0.0) {
                        const double t = (p - ray.origin[a]) / ray.direction[a];
                        if (t > 0.0) {
                            best = std::min(best, t);
                        }
                    }
                }
            }
            const std::size_t i = img.index(x, y);
            EXPECT_NEAR(img.depth[i], best, 1e-6 * best) << x << "," << y;
            EXPECT_EQ(img.status[i], static_cast<std::uint8_t>(TraceStatus::Hit));
            EXPECT_EQ(img.probe[i], -1);
            EXPECT_FLOAT_EQ(img.rgba[4 * i + 3], 1.0f);
            // Normals face the camera.
            const glm::dvec3 n(img.normal[3 * i], img.normal[3 * i + 1], img.normal[3 * i + 2]);
            EXPECT_LT(glm::dot(n, ray.direction), 0.0);
        }
    }
    // The centre pixel looks at the north wall (object 3, material "wall").
    const std::size_t c = img.index(32, 24);
    EXPECT_EQ(img.object[c], 3);
    EXPECT_FLOAT_EQ(img.rgba[4 * c + 2], 0.6f);
}

TEST(GroundTruth, CornellBoxColoursMatchKd) {
    const Mesh mesh = read_mesh(kMeshes + "/cornell_box/CornellBox-Original.obj");
    const EmbreeScene scene(mesh);
    // The box is Y up in its file; look at it from the open side (+Z).
    Camera cam = Camera::look_at({0.0, 1.0, 3.5}, {0.0, 1.0, 0.0}, 80, 60, 35.0);
    const RenderedImage img = render_ground_truth(scene, cam);
    int red = 0;
    int green = 0;
    for (std::size_t i = 0; i < img.pixel_count(); ++i) {
        if (img.object[i] < 0) {
            continue;
        }
        const std::string& name = mesh.object_names[static_cast<std::size_t>(img.object[i])];
        const glm::vec3 rgb{img.rgba[4 * i], img.rgba[4 * i + 1], img.rgba[4 * i + 2]};
        if (name == "leftWall") {
            EXPECT_EQ(rgb, glm::vec3(0.63f, 0.065f, 0.05f));
            ++red;
        } else if (name == "rightWall") {
            EXPECT_EQ(rgb, glm::vec3(0.14f, 0.45f, 0.091f));
            ++green;
        }
    }
    EXPECT_GT(red, 50);
    EXPECT_GT(green, 50);
}

TEST(GroundTruth, OneAndTwoThreadsBitIdentical) {
    const Mesh mesh = read_mesh(kMeshes + "/spot/spot_triangulated_textured.obj");
    const EmbreeScene scene(mesh);
    const Camera cam = Camera::look_at({2.0, 1.5, 1.0}, {0.0, 0.0, 0.3}, 96, 72);
    GroundTruthSettings settings;
    settings.samples_per_pixel = 4;
    settings.tile_size = 8;
    const RenderedImage one =
        tbb::task_arena(1).execute([&] { return render_ground_truth(scene, cam, settings); });
    const RenderedImage two =
        tbb::task_arena(2).execute([&] { return render_ground_truth(scene, cam, settings); });
    EXPECT_EQ(one.rgba, two.rgba);
    EXPECT_EQ(one.depth, two.depth);
    EXPECT_EQ(one.normal, two.normal);
    EXPECT_EQ(one.object, two.object);
    // 4×4 and 8×8 strata, traced in coherent packets (2×2 go one by one): the same.
    for (const int spp : {16, 64}) {
        GroundTruthSettings packed = settings;
        packed.samples_per_pixel = spp;
        const RenderedImage a =
            tbb::task_arena(1).execute([&] { return render_ground_truth(scene, cam, packed); });
        const RenderedImage b =
            tbb::task_arena(2).execute([&] { return render_ground_truth(scene, cam, packed); });
        EXPECT_EQ(a.rgba, b.rgba) << spp;
        EXPECT_EQ(a.depth, b.depth) << spp;
    }
    // Textured: some colour other than white, some coverage between 0 and 1 at silhouettes.
    bool partial = false;
    for (std::size_t i = 0; i < one.pixel_count(); ++i) {
        partial = partial || (one.rgba[4 * i + 3] > 0.0f && one.rgba[4 * i + 3] < 1.0f);
    }
    EXPECT_TRUE(partial);
    EXPECT_THROW((void)render_ground_truth(scene, cam, GroundTruthSettings{3, 32}), InputError);
}

TEST(GroundTruth, ObjectChannelRoundTripsAndThroughput) {
    const Mesh mesh = read_mesh(box_room_obj());
    const EmbreeScene scene(mesh);
    const Camera cam = Camera::look_at({0.0, 0.0, 1.0}, {1.0, 2.0, 0.5}, 32, 24);
    const RenderedImage img = render_ground_truth(scene, cam);
    const auto path = (test_dir() / "gt.exr").string();
    write_rendered_exr(path, img);
    const RenderedImage back = read_rendered_exr(path);
    EXPECT_EQ(back.object, img.object);
    EXPECT_EQ(back.depth, img.depth);
    const ThroughputResult t = embree_throughput(scene, cam, 2);
    EXPECT_EQ(t.rays, 32u * 24u);
    EXPECT_EQ(t.hits, t.rays);
    EXPECT_GT(t.rays_per_second, 0.0);
}

TEST(GroundTruth, EmbreePacketsCountTheHitsOfSingleRays) {
    // From outside the closed room, with the room's edge in view: hits and misses, 33 × 7 rays
    // (not a multiple of any packet width, so the last packet of a run has masked-off lanes).
    const Mesh mesh = read_mesh(box_room_obj());
    const EmbreeScene scene(mesh);
    const Camera cam = Camera::look_at({0.0, -10.0, 1.2}, {2.0, 0.0, 1.2}, 33, 7);
    const ThroughputResult single = embree_throughput(scene, cam, 1, 1);
    EXPECT_GT(single.hits, 0u);
    EXPECT_LT(single.hits, single.rays);
    for (const int packet : {4, 8, 16}) {
        const ThroughputResult packed = embree_throughput(scene, cam, 1, packet);
        EXPECT_EQ(packed.rays, single.rays);
        EXPECT_EQ(packed.hits, single.hits) << packet;
    }
    EXPECT_THROW((void)embree_throughput(scene, cam, 1, 3), InputError);
}

} // namespace
} // namespace lfprobe

namespace lfprobe {
namespace {

TEST(GroundTruth, ACameraWhoseRaysAreNotFiniteIsAClearErrorNotAnEmbreeAbort) {
    // Each key passes the camera file's checks on its own; together they make rays of inf/NaN,
    // which Embree's debug assertion aborts on.
    const Mesh mesh = read_mesh(box_room_obj());
    const EmbreeScene scene(mesh);
    Camera tiny_lens = Camera::look_at({0.3, -1.0, 1.2}, {0.5, 3.0, 1.0}, 16, 12);
    tiny_lens.lens = 1e-300;
    Camera huge_shift = Camera::look_at({0.3, -1.0, 1.2}, {0.5, 3.0, 1.0}, 16, 12);
    huge_shift.shift_x = 1e300;
    for (const Camera& camera : {tiny_lens, huge_shift}) {
        EXPECT_THROW((void)render_ground_truth(scene, camera), InputError);
        EXPECT_THROW((void)embree_throughput(scene, camera, 1), InputError);
    }
}

} // namespace
} // namespace lfprobe
