// Mesh readers: the OBJ/MTL/texture test data of shared/data/meshes, PLY meshes, and errors
// that name the file and line.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <limits>
#include <utility>

#include <gtest/gtest.h>
#include <sys/stat.h>

#include "lfprobe/color.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/mesh_reader.hpp"
#include "lfprobe/scan_reader.hpp"
#include "lfprobe/texture.hpp"
#include "test_data.hpp"

namespace lfprobe {
namespace {

const std::string kMeshes = lfprobe::testing::shared_data("meshes");

std::string temp_file(const std::string& name, const std::string& text) {
    const auto dir = std::filesystem::temp_directory_path() / "lfprobe_mesh_reader_test";
    std::filesystem::create_directories(dir);
    const std::string path = (dir / name).string();
    std::ofstream(path, std::ios::binary) << text;
    return path;
}

std::size_t material_named(const Mesh& m, const std::string& name) {
    for (std::size_t i = 0; i < m.materials.size(); ++i) {
        if (m.materials[i].name == name) {
            return i;
        }
    }
    return m.materials.size();
}

TEST(MeshReader, CornellBoxTrianglesMaterialsObjects) {
    const Mesh m = read_mesh(kMeshes + "/cornell_box/CornellBox-Original.obj");
    // 18 quads in the file (walls, two boxes, the light), each fan-triangulated into two.
    EXPECT_EQ(m.triangle_count(), 36u);
    EXPECT_EQ(m.object_names.size(), 8u);
    const std::size_t left = material_named(m, "leftWall");
    ASSERT_LT(left, m.materials.size());
    EXPECT_FLOAT_EQ(m.materials[left].base_color.x, 0.63f);
    EXPECT_FLOAT_EQ(m.materials[left].base_color.y, 0.065f);
    EXPECT_FLOAT_EQ(m.materials[left].base_color.z, 0.05f);
    EXPECT_FALSE(m.has_uvs());
    const MeshBounds b = m.bounds();
    EXPECT_FLOAT_EQ(b.min.y, 0.0f);
    EXPECT_FLOAT_EQ(b.max.y, 1.99f);
}

TEST(MeshReader, SpotTextureLoadsAndSamples) {
    const Mesh m = read_mesh(kMeshes + "/spot/spot_triangulated_textured.obj");
    EXPECT_EQ(m.triangle_count(), 5856u);
    ASSERT_TRUE(m.has_uvs());
    ASSERT_EQ(m.materials.size(), 1u);
    const auto& tex = m.materials[0].texture;
    ASSERT_TRUE(tex);
    EXPECT_GT(tex->width, 0);
    // The centre of texel (x, y) (y = 0 the top row of the file) is uv ((x+.5)/w, 1-(y+.5)/h):
    // sampling there returns that texel exactly.
    const int x = tex->width / 3;
    const int y = tex->height / 5;
    const glm::vec2 uv{(static_cast<float>(x) + 0.5f) / static_cast<float>(tex->width),
                       1.0f - (static_cast<float>(y) + 0.5f) / static_cast<float>(tex->height)};
    const glm::vec3 s = tex->sample(uv);
    const glm::vec3 t = tex->texel(x, y);
    EXPECT_NEAR(s.x, t.x, 1e-4f);
    EXPECT_NEAR(s.y, t.y, 1e-4f);
    EXPECT_NEAR(s.z, t.z, 1e-4f);
    // Repeat wrap: one period over gives the same value.
    const glm::vec3 w = tex->sample(uv + glm::vec2(1.0f, -2.0f));
    EXPECT_NEAR(w.x, t.x, 1e-3f);
}

TEST(MeshReader, CrateQuadsWithJpgTexture) {
    const Mesh m = read_mesh(kMeshes + "/crate/crate.obj");
    EXPECT_EQ(m.triangle_count(), 12u);
    ASSERT_TRUE(m.materials[0].texture);
    EXPECT_FLOAT_EQ(m.materials[0].base_color.x, 0.64f);
    EXPECT_EQ(m.object_names[0], "Cube_Cube.001");
}

TEST(MeshReader, TextureIsSrgbDecodedAndVFlipped) {
    // A 1×2 image through stb's PNM support: top row red (255,0,0), bottom row grey 128.
    const std::string path = temp_file("two.ppm", std::string("P6\n1 2\n255\n") +
                                                      std::string("\xff\x00\x00\x80\x80\x80", 6));
    const Texture t = Texture::load(path);
    ASSERT_EQ(t.width, 1);
    ASSERT_EQ(t.height, 2);
    // v near 0 is the bottom row (grey), v near 1 the top row (red).
    EXPECT_NEAR(t.sample({0.5f, 0.25f}).x, srgb_to_linear(128.0f / 255.0f), 1e-6f);
    EXPECT_NEAR(t.sample({0.5f, 0.75f}).x, 1.0f, 1e-6f);
    EXPECT_NEAR(t.sample({0.5f, 0.75f}).y, 0.0f, 1e-6f);
}

TEST(MeshReader, ObjNegativeIndicesPolygonsAndObjects) {
    const std::string path = temp_file("poly.obj", "o first\n"
                                                   "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 2 0\n"
                                                   "f -5 -4 -3 -2 -1\n"
                                                   "g second\nf 1 2 3\n");
    const Mesh m = read_obj(path);
    EXPECT_EQ(m.triangle_count(), 4u);
    ASSERT_EQ(m.object_names.size(), 2u);
    EXPECT_EQ(m.object[0], 0u);
    EXPECT_EQ(m.object[3], 1u);
    EXPECT_EQ(m.triangles[2][2], 4u);
}

TEST(MeshReader, ObjErrorsNameFileAndLine) {
    const std::string path = temp_file("bad.obj", "v 0 0 0\nv 1 0 0\nf 1 2 7\n");
    try {
        (void)read_obj(path);
        FAIL() << "expected InputError";
    } catch (const InputError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find(path + ":3:"), std::string::npos) << what;
        EXPECT_NE(what.find("expected"), std::string::npos) << what;
    }
    const std::string bad_v = temp_file("bad_v.obj", "v 0 zero 0\n");
    EXPECT_THROW((void)read_obj(bad_v), InputError);
    EXPECT_THROW((void)read_mesh(temp_file("x.stl", "")), InputError);
}

TEST(MeshReader, GeoreferencedObjKeepsMillimetres) {
    // UTM-sized coordinates: float32 alone would round y = 5400000.123 to 5400000.0 (spacing
    // 0.5 m there). Read in double, offset by the rounded bbox centre, the millimetres survive.
    const std::string path = temp_file("utm.obj", "v 512000.001 5400000.123 230.5\n"
                                                  "v 512003.002 5400000.123 230.5\n"
                                                  "v 512000.001 5400004.125 232.75\n"
                                                  "f 1 2 3\n");
    const Mesh m = read_obj(path);
    EXPECT_EQ(m.world_offset, glm::dvec3(512002.0, 5400002.0, 232.0));
    const glm::dvec3 first = m.world_offset + glm::dvec3(m.vertices[0]);
    const glm::dvec3 third = m.world_offset + glm::dvec3(m.vertices[2]);
    EXPECT_NEAR(first.x, 512000.001, 1e-6);
    EXPECT_NEAR(first.y, 5400000.123, 1e-6);
    EXPECT_NEAR(third.y, 5400004.125, 1e-6);
    EXPECT_NEAR(third.z, 232.75, 1e-6);
}

TEST(MeshReader, MeshNearOriginHasNoOffset) {
    const std::string path =
        temp_file("small.obj", "v -1000 0 0\nv 1000 0 0\nv 0 1 1023\nf 1 2 3\n");
    EXPECT_EQ(read_obj(path).world_offset, glm::dvec3(0.0));
}

TEST(MeshReader, FilesThatAreNotRegularOrTooLargeAreRefusedBeforeReading) {
    // A material library naming /dev/zero (endless) or a FIFO (blocks forever).
    const std::string fifo =
        (std::filesystem::temp_directory_path() / "lfprobe_mesh_reader_test" / "lib.fifo").string();
    std::filesystem::remove(fifo);
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    for (const std::string& library : {std::string("/dev/zero"), fifo}) {
        const std::string obj = temp_file(
            "special_mtllib.obj", "mtllib " + library + "\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        try {
            (void)read_mesh(obj);
            ADD_FAILURE() << "read a material library from " << library;
        } catch (const IoError& e) {
            EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos);
        }
    }
    std::filesystem::remove(fifo);
    // A PNG of a few bytes that declares 16384 × 16384 pixels (3 GB decoded): refused from its
    // header, before any pixel is decoded.
    std::string png("\x89PNG\r\n\x1a\n", 8);
    const unsigned char ihdr[] = {0, 0,    0, 13, 'I', 'H', 'D', 'R', 0, 0, 0x40, 0, 0,
                                  0, 0x40, 0, 8,  2,   0,   0,   0,   0, 0, 0,    0};
    png.append(reinterpret_cast<const char*>(ihdr), sizeof ihdr);
    const std::string huge = temp_file("huge.png", png);
    try {
        (void)Texture::load(huge);
        ADD_FAILURE() << "loaded a 16384² texture";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("16384"), std::string::npos) << e.what();
    }
}

// Found by the OBJ/MTL fuzz harness: a 2 × 2 PNG whose second IDAT chunk declares 1.2 GB made
// the texture decoder allocate 2 GB before finding the file short. Refused from the chunk walk.
TEST(MeshReader, APngChunkLongerThanItsFileIsRefusedBeforeDecoding) {
    std::string png("\x89PNG\r\n\x1a\n", 8);
    const unsigned char ihdr[] = {0, 0, 0, 13, 'I', 'H', 'D', 'R', 0, 0, 0, 2, 0,
                                  0, 0, 2, 8,  2,   0,   0,   0,   0, 0, 0, 0};
    png.append(reinterpret_cast<const char*>(ihdr), sizeof ihdr);
    const unsigned char idat[] = {0x49, 0x49, 0x49, 0x10, 'I', 'D', 'A', 'T', 1, 2, 3, 4};
    png.append(reinterpret_cast<const char*>(idat), sizeof idat);
    try {
        (void)Texture::load(temp_file("long_chunk.png", png));
        ADD_FAILURE() << "decoded a PNG whose chunk is longer than the file";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("more than the file holds"), std::string::npos)
            << e.what();
    }
    std::string twice = png.substr(0, 8 + sizeof ihdr);
    twice.append(reinterpret_cast<const char*>(ihdr), sizeof ihdr);
    EXPECT_THROW((void)Texture::load(temp_file("two_headers.png", twice)), InputError);
}

// Issue 22, item 12: values read as doubles reach no undefined cast. A face index of 1.8e19
// (was cast to int64 as it was) and a NaN list length are errors naming the file, in the mesh
// reader and in the scan reader, which skips a vertex's list properties.
TEST(MeshReader, PlyIndicesAndListLengthsBeyondTheirTypesAreErrors) {
    const std::string header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                               "property float y\nproperty float z\nelement face 1\n";
    const std::string vertices = "0 0 0\n1 0 0\n0 1 0\n";
    const std::string huge_index = header +
                                   "property list uchar double vertex_indices\nend_header\n" +
                                   vertices + "3 0 1 1.8e19\n";
    const std::string nan_count =
        header + "property list float int vertex_indices\nend_header\n" + vertices + "nan 0 1 2\n";
    for (const auto& [name, text] :
         {std::pair{"huge_index.ply", huge_index}, std::pair{"nan_count.ply", nan_count}}) {
        try {
            (void)read_ply_mesh(temp_file(name, text));
            ADD_FAILURE() << name << ": accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
        }
    }
    std::string binary = "ply\nformat binary_little_endian 1.0\nelement vertex 1\n"
                         "property float x\nproperty float y\nproperty float z\n"
                         "property list float uchar extra\nend_header\n";
    const float point[3] = {0.0f, 0.0f, 0.0f};
    const float nan = std::numeric_limits<float>::quiet_NaN();
    binary.append(reinterpret_cast<const char*>(point), sizeof point);
    binary.append(reinterpret_cast<const char*>(&nan), sizeof nan);
    EXPECT_THROW((void)read_scan_bytes("nan_list.ply", binary, ScanReadOptions{}), InputError);
}

// Found by the PLY harness (a 34 s timeout): an element of 422,222,222,222,222 items without
// properties was walked item by item, reading nothing. Binary: skipped at once (its items take
// no bytes); ASCII: each is a line, which the file must hold. The scan reader too.
TEST(MeshReader, PlyElementsWithoutPropertiesAreNotWalkedItemByItem) {
    const std::string vertices = "element vertex 3\nproperty float x\nproperty float y\n"
                                 "property float z\nelement face 1\n"
                                 "property list uchar int vertex_indices\n";
    const std::string ascii = "ply\nformat ascii 1.0\nelement ex 422222222222222\n" + vertices +
                              "end_header\n\n\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    // Its third "empty line" holds the first vertex: refused there, at once.
    EXPECT_THROW((void)read_ply_mesh(temp_file("empty_items_ascii.ply", ascii)), InputError);
    std::string binary = "ply\nformat binary_big_endian 1.0\nelement ex 422222222222222\n" +
                         vertices + "end_header\n";
    const unsigned char big_endian_triangle[] = {
        0, 0, 0, 0,    0,    0, 0, 0, 0, 0, 0, 0, 0x3f, 0x80, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
        0, 0, 0, 0x3f, 0x80, 0, 0, 0, 0, 0, 0, 3, 0,    0,    0, 0, 0, 0, 0, 1, 0, 0, 0, 2};
    binary.append(reinterpret_cast<const char*>(big_endian_triangle), sizeof big_endian_triangle);
    const Mesh mesh = read_ply_mesh(temp_file("empty_items_binary.ply", binary));
    EXPECT_EQ(mesh.vertices.size(), 3u);
    EXPECT_EQ(mesh.triangles.size(), 1u);
    // The harness's input itself: no vertex element after the empty one, refused as such.
    const std::string found = "ply\nformat binary_big_endian 1.0\nelement ex 422222222222222\n\n"
                              "end_header\n" +
                              std::string("\0\0blu\0\xb4y_lit\0", 12);
    EXPECT_THROW((void)read_ply_mesh_bytes("fuzz_input.ply", found), InputError);
    EXPECT_THROW((void)read_scan_bytes("fuzz_input.ply", found, ScanReadOptions{}), InputError);
    EXPECT_THROW((void)read_scan_bytes("empty_items_ascii.ply", ascii, ScanReadOptions{}),
                 InputError);
}

TEST(MeshReader, NonFiniteVertexIsAnError) {
    EXPECT_THROW((void)read_obj(temp_file("nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")),
                 InputError);
}

TEST(MeshReader, TextureFromPixelsBottomUpAndSrgb) {
    // 1×2 pixels bottom-up as Blender holds them: row 0 (bottom) grey 0.5 sRGB, row 1 (top) red.
    const float pixels[] = {0.5f, 0.5f, 0.5f, 1.0f, 1.0f, 0.0f, 0.0f, 1.0f};
    const Texture t = Texture::from_pixels("t", 1, 2, pixels, 4, true, true);
    EXPECT_NEAR(t.texel(0, 0).x, 1.0f, 1e-6f); // top row of the texture = red
    EXPECT_NEAR(t.texel(0, 1).x, srgb_to_linear(0.5f), 1e-6f);
    const Texture linear = Texture::from_pixels("t", 1, 2, pixels, 4, false, false);
    EXPECT_NEAR(linear.texel(0, 0).x, 0.5f, 1e-6f);
    const float bad[] = {NAN, 0.0f, 0.0f};
    EXPECT_THROW((void)Texture::from_pixels("t", 1, 1, bad, 3, true, true), InputError);
    EXPECT_THROW((void)Texture::from_pixels("t", 0, 1, pixels, 4, true, true), InputError);
}

TEST(MeshReader, PlyAsciiAndBinaryAgree) {
    const std::string header_fmt = "ply\nformat %s 1.0\nelement vertex 4\nproperty float x\n"
                                   "property float y\nproperty float z\nproperty uchar red\n"
                                   "property uchar green\nproperty uchar blue\n"
                                   "element face 1\nproperty list uchar int vertex_indices\n"
                                   "end_header\n";
    char header[512];
    std::snprintf(header, sizeof header, header_fmt.c_str(), "ascii");
    const std::string ascii = temp_file(
        "quad_ascii.ply", std::string(header) + "0 0 0 255 0 0\n1 0 0 255 0 0\n1 1 0 255 0 0\n"
                                                "0 1 0 255 0 0\n4 0 1 2 3\n");
    std::snprintf(header, sizeof header, header_fmt.c_str(), "binary_little_endian");
    std::string bin(header);
    const float xyz[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    for (const auto& v : xyz) {
        bin.append(reinterpret_cast<const char*>(v), sizeof v);
        bin.append("\xff\x00\x00", 3);
    }
    bin.push_back('\x04');
    const std::int32_t idx[4] = {0, 1, 2, 3};
    bin.append(reinterpret_cast<const char*>(idx), sizeof idx);
    const std::string binary = temp_file("quad_binary.ply", bin);
    for (const std::string& path : {ascii, binary}) {
        const Mesh m = read_mesh(path);
        ASSERT_EQ(m.triangle_count(), 2u) << path;
        ASSERT_TRUE(m.has_colors());
        EXPECT_FLOAT_EQ(m.corner_colors[0].x, 1.0f);
        EXPECT_FLOAT_EQ(m.vertices[2].y, 1.0f);
        EXPECT_EQ(m.triangles[1][2], 3u);
    }
    const std::string bad = temp_file(
        "bad.ply", std::string(header).replace(std::string(header).find("binary"), 20, "ascii") +
                       "0 0 0 255 0 0\n");
    EXPECT_THROW((void)read_mesh(bad), InputError);
}

} // namespace
} // namespace lfprobe
