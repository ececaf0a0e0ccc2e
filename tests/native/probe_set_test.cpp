// The probe set on disk: bit-for-bit round trips, the manifest, and interrupted bakes.
#include <atomic>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <string>
#include <thread>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfTiledOutputFile.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include "lfprobe/cloud_bake.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/probe_exr.hpp"
#include "lfprobe/probe_set.hpp"
#include "synthetic_scene.hpp"
#include "temp_folder.hpp"

using namespace lfprobe;
namespace fs = std::filesystem;

namespace {

fs::path fresh_dir(const std::string& name) {
    return lfprobe::testing::fresh_dir("lfprobe_", name);
}

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

// The probe file at `from` written again at `to` as another writer might: every channel as
// `type`, with `compression`, in tiles or scanlines; the attributes kept.
void rewrite_exr(const std::string& from, const std::string& to, Imf::PixelType type,
                 Imf::Compression compression, bool tiled) {
    Imf::InputFile in(from.c_str());
    const Imath::Box2i window = in.header().dataWindow();
    const std::size_t w = static_cast<std::size_t>(window.max.x - window.min.x + 1);
    const std::size_t h = static_cast<std::size_t>(window.max.y - window.min.y + 1);
    Imf::Header header = in.header();
    header.compression() = compression;
    Imf::ChannelList channels;
    Imf::FrameBuffer frame;
    std::vector<std::vector<float>> planes;
    for (auto it = in.header().channels().begin(); it != in.header().channels().end(); ++it) {
        channels.insert(it.name(), Imf::Channel(type));
        planes.emplace_back(w * h);
    }
    std::size_t k = 0;
    for (auto it = in.header().channels().begin(); it != in.header().channels().end(); ++it) {
        frame.insert(it.name(), Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(planes[k++].data()),
                                           sizeof(float), sizeof(float) * w));
    }
    in.setFrameBuffer(frame);
    in.readPixels(window.min.y, window.max.y);
    header.channels() = channels;
    if (tiled) {
        header.setTileDescription(Imf::TileDescription(16, 16, Imf::ONE_LEVEL));
        Imf::TiledOutputFile out(to.c_str(), header);
        out.setFrameBuffer(frame);
        out.writeTiles(0, out.numXTiles() - 1, 0, out.numYTiles() - 1);
    } else {
        Imf::OutputFile out(to.c_str(), header);
        out.setFrameBuffer(frame);
        out.writePixels(static_cast<int>(h));
    }
}

} // namespace

TEST(ProbeSet, ProbeSurvivesWriteReadBitForBit) {
    ProbeMap map(33, glm::dvec3(1.5, -2.25, 0.125));
    for (std::size_t i = 0; i < map.texel_count(); ++i) {
        switch (i % 5) {
        case 0:
            map.set_unknown(i);
            break;
        case 1:
            map.set_empty(i);
            break;
        default:
            map.set_surface(i, 0.1f + static_cast<float>(i) * 1e-3f,
                            glm::vec3(static_cast<float>(i % 7) / 7.0f, 0.3f, 0.9f),
                            glm::vec3(0.0f, 0.6f, -0.8f), i % 5 == 4 ? 0.5f : 1.0f);
        }
    }
    const fs::path dir = fresh_dir("roundtrip");
    const std::string path = (dir / "p.exr").string();
    write_probe_exr(path, map);
    const ProbeMap back = read_probe_exr(path);
    EXPECT_EQ(back.resolution, 33);
    EXPECT_EQ(back.position, map.position);
    EXPECT_TRUE(same_bits(back.rgba, map.rgba));
    EXPECT_TRUE(same_bits(back.distance, map.distance)); // NaN and +inf kept, bit for bit
    EXPECT_TRUE(same_bits(back.normal, map.normal));
    EXPECT_EQ(back.state(0), TexelState::Unknown);
    EXPECT_EQ(back.state(1), TexelState::Empty);
    EXPECT_EQ(back.state(2), TexelState::Surface);
    EXPECT_EQ(back.state(4), TexelState::Inferred);
    EXPECT_TRUE(back.coverage.empty()); // written without coverage: none read, 1 everywhere
    EXPECT_EQ(back.coverage_at(7), 1.0f);
    for (const auto& entry : fs::directory_iterator(dir)) {
        EXPECT_EQ(entry.path().filename(), "p.exr"); // no temporary left behind
    }
    // With coverage, that channel too, bit for bit.
    map.coverage.assign(map.texel_count(), Imath::half(1.0f));
    for (std::size_t i = 0; i < map.texel_count(); i += 3) {
        map.coverage[i] = Imath::half(static_cast<float>(i % 16) / 16.0f);
    }
    write_probe_exr(path, map);
    const ProbeMap covered = read_probe_exr(path);
    EXPECT_TRUE(same_bits(covered.coverage, map.coverage));
    EXPECT_TRUE(same_bits(covered.rgba, map.rgba));
}

// A probe file another writer made reads as the one lfprobe writes: channels stored as float,
// other compressions, and tiles (read by the C++ API where the core reader takes scanlines
// only); a file cut short is refused naming it.
TEST(ProbeSet, AProbeFileWithOtherChannelTypesCompressionsOrTilesReadsTheSame) {
    ProbeMap map(40, glm::dvec3(0.5, 0.25, -1.0));
    for (std::size_t i = 0; i < map.texel_count(); ++i) {
        if (i % 7 == 0) {
            map.set_unknown(i);
        } else {
            map.set_surface(i, 0.5f + static_cast<float>(i) * 0.01f,
                            glm::vec3(static_cast<float>(i % 11) / 11.0f, 0.25f, 0.75f),
                            glm::vec3(0.0f, 0.8f, 0.6f), i % 3 == 0 ? 0.5f : 1.0f);
        }
    }
    map.coverage.assign(map.texel_count(), Imath::half(0.75f));
    const fs::path dir = fresh_dir("other_writers");
    const std::string ours = (dir / "ours.exr").string();
    write_probe_exr(ours, map);
    const std::string other = (dir / "other.exr").string();
    for (const bool tiled : {false, true}) {
        for (const Imf::Compression compression : {Imf::NO_COMPRESSION, Imf::RLE_COMPRESSION,
                                                   Imf::PIZ_COMPRESSION, Imf::ZIPS_COMPRESSION}) {
            rewrite_exr(ours, other, Imf::FLOAT, compression, tiled);
            const ProbeMap back = read_probe_exr(other);
            EXPECT_EQ(back.position, map.position);
            EXPECT_TRUE(same_bits(back.rgba, map.rgba)) << compression << " " << tiled;
            EXPECT_TRUE(same_bits(back.distance, map.distance)) << compression << " " << tiled;
            EXPECT_TRUE(same_bits(back.normal, map.normal)) << compression << " " << tiled;
            EXPECT_TRUE(same_bits(back.coverage, map.coverage)) << compression << " " << tiled;
        }
    }
    std::ifstream in(ours, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (const std::size_t keep : {bytes.size() / 2, bytes.size() - 10}) {
        std::ofstream(other, std::ios::binary).write(bytes.data(), static_cast<long>(keep));
        try {
            (void)read_probe_exr(other);
            ADD_FAILURE() << "a probe file cut to " << keep << " bytes was read";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(other), std::string::npos) << e.what();
        }
    }
}

// Issue 22, item 13: a probe EXR whose texels no bake writes (a negative or -inf distance, a
// confidence that is not a number from 0 to 1, a surface with a NaN radiance) is refused naming
// the file and the texel, instead of rendering without complaint; NaN (unknown) and +inf
// (empty) distances are the format's own and still read.
TEST(ProbeSet, ProbeTexelsNoBakeWritesAreRefusedNamingTheTexel) {
    const fs::path dir = fresh_dir("bad_texels");
    const auto written = [&](const std::function<void(ProbeMap&)>& change) {
        ProbeMap map(8, glm::dvec3(0.0));
        for (std::size_t i = 0; i < map.texel_count(); ++i) {
            map.set_surface(i, 2.0f, glm::vec3(0.5f), glm::vec3(0.0f, 0.0f, 1.0f), 1.0f);
        }
        map.set_unknown(0);
        map.set_empty(1);
        change(map);
        const std::string path = (dir / "p.exr").string();
        write_probe_exr(path, map);
        return path;
    };
    EXPECT_NO_THROW((void)read_probe_exr(written([](ProbeMap&) {})));
    const auto refused = [&](const char* what, const std::function<void(ProbeMap&)>& change,
                             const std::string& expected) {
        try {
            (void)read_probe_exr(written(change));
            ADD_FAILURE() << what << ": accepted";
        } catch (const InputError& e) {
            const std::string message = e.what();
            EXPECT_NE(message.find("p.exr: texel (3, 2)"), std::string::npos) << message;
            EXPECT_NE(message.find(expected), std::string::npos) << message;
        }
    };
    constexpr std::size_t texel = 3 + 8 * 2;
    refused(
        "negative distance", [](ProbeMap& m) { m.distance[texel] = -0.5f; }, "distance");
    refused(
        "-inf distance",
        [](ProbeMap& m) { m.distance[texel] = -std::numeric_limits<float>::infinity(); },
        "distance");
    refused(
        "NaN confidence",
        [](ProbeMap& m) {
            m.rgba[4 * texel + 3] = Imath::half(std::numeric_limits<float>::quiet_NaN());
        },
        "confidence");
    refused(
        "confidence above 1", [](ProbeMap& m) { m.rgba[4 * texel + 3] = Imath::half(2.0f); },
        "confidence");
    refused(
        "coverage above 1",
        [](ProbeMap& m) {
            m.coverage.assign(m.texel_count(), Imath::half(1.0f));
            m.coverage[texel] = Imath::half(1.5f);
        },
        "coverage");
    refused(
        "NaN radiance",
        [](ProbeMap& m) {
            m.rgba[4 * texel] = Imath::half(std::numeric_limits<float>::quiet_NaN());
        },
        "NaN");
}

TEST(ProbeSet, BakedSetRoundTripsThroughTheManifest) {
    const lfprobe::testing::BoxRoomScene scene;
    const PointCloud cloud = scene.cloud(0.05f, glm::dvec3(0.0, 0.0, 1.2));
    BakeSettings settings;
    settings.resolution = 32;
    const ProbePlacement placement = ProbePlacement::from_grid(
        ProbeGrid::spanning(glm::dvec3(-1.0, -0.5, 0.8), glm::dvec3(1.0, 0.5, 1.6), {3, 2, 1}));
    const fs::path dir = fresh_dir("set");
    const nlohmann::json sources =
        nlohmann::json::array({{{"path", "synthetic"}, {"sha256", "00"}}});
    const BakeSummary summary =
        bake_probe_set_from_cloud(cloud, placement, settings, {}, dir.string(), sources);
    EXPECT_EQ(summary.probe_count, 6u);
    const ProbeSetManifest manifest = read_manifest(dir.string());
    ASSERT_EQ(manifest.probes.size(), 6u);
    EXPECT_TRUE(manifest.placement.is_grid);
    EXPECT_EQ(manifest.placement.grid.counts, (std::array<int, 3>{3, 2, 1}));
    EXPECT_EQ(manifest.placement.grid.origin, placement.grid.origin);
    EXPECT_NEAR(manifest.placement.grid.origin.z, 1.2, 1e-12); // one probe: the box's centre
    EXPECT_EQ(manifest.sources, sources);
    EXPECT_EQ(manifest.bake["resolution"], 32);
    for (std::size_t i = 0; i < 6; ++i) {
        const ProbeMap map = read_probe(dir.string(), manifest, i);
        EXPECT_EQ(map.position, placement.positions[i]);
        EXPECT_GT(manifest.probes[i].coverage.surface, 0.9);
    }
    // Writing the manifest again gives the same bytes (stable, human-diffable).
    const auto text = [&] {
        std::ifstream in(dir / kManifestName);
        return std::string(std::istreambuf_iterator<char>(in), {});
    };
    const std::string before = text();
    write_manifest(dir.string(), manifest);
    EXPECT_EQ(text(), before);
}

TEST(ProbeSet, InterruptedRebakeLeavesTheEarlierSetExactlyAsItWas) {
    const lfprobe::testing::BoxRoomScene scene;
    const PointCloud cloud = scene.cloud(0.01f, glm::dvec3(0.0, 0.0, 1.2));
    BakeSettings settings;
    settings.resolution = 32;
    const fs::path dir = fresh_dir("interrupted");
    // The earlier set: two probes.
    (void)bake_probe_set_from_cloud(
        cloud, ProbePlacement::from_positions({{-0.5, 0.1, 1.2}, {0.5, 0.1, 1.2}}), settings, {},
        dir.string(), {});
    const auto bytes_of = [](const fs::path& path) {
        std::ifstream in(path, std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(in), {});
    };
    const std::string manifest_before = bytes_of(dir / kManifestName);
    const std::string probe_before = bytes_of(dir / probe_file_name(1));

    settings.resolution = 128;
    std::vector<glm::dvec3> positions;
    for (int i = 0; i < 40; ++i) {
        positions.emplace_back(-1.5 + 0.075 * i, 0.1, 1.2);
    }
    const fs::path staging = dir.parent_path() / (dir.filename().string() + ".partial");
    Progress progress;
    std::atomic<bool> finished{false};
    std::thread canceller([&] {
        // Cancel once the new set's first probe is written, in the middle of the next one.
        while (!finished && !fs::exists(staging / probe_file_name(0))) {
            std::this_thread::sleep_for(std::chrono::milliseconds(1));
        }
        progress.request_cancel();
    });
    EXPECT_THROW((void)bake_probe_set_from_cloud(cloud, ProbePlacement::from_positions(positions),
                                                 settings, {}, dir.string(), {}, &progress),
                 Cancelled);
    finished = true;
    canceller.join();
    EXPECT_FALSE(fs::exists(staging));
    EXPECT_FALSE(fs::exists(dir.parent_path() / (dir.filename().string() + ".previous")));
    EXPECT_EQ(bytes_of(dir / kManifestName), manifest_before);
    EXPECT_EQ(bytes_of(dir / probe_file_name(1)), probe_before);
    EXPECT_EQ(read_manifest(dir.string()).probes.size(), 2u);

    // Finished, the new set replaces the earlier one as a whole: no probe of it is left.
    (void)bake_probe_set_from_cloud(cloud, ProbePlacement::from_positions({positions[0]}), settings,
                                    {}, dir.string() + "/", {});
    EXPECT_EQ(read_manifest(dir.string()).probes.size(), 1u);
    EXPECT_FALSE(fs::exists(dir / probe_file_name(1)));
}

TEST(ProbeSet, ABakeIntoAFolderOfOtherFilesIsRefusedAndTheFilesStay) {
    const lfprobe::testing::BoxRoomScene scene;
    const PointCloud cloud = scene.cloud(0.05f, glm::dvec3(0.0, 0.0, 1.2));
    const fs::path dir = fresh_dir("foreign");
    std::ofstream(dir / "notes.txt") << "mine";
    BakeSettings settings;
    settings.resolution = 16;
    EXPECT_THROW((void)bake_probe_set_from_cloud(cloud,
                                                 ProbePlacement::from_positions({{0.0, 0.1, 1.2}}),
                                                 settings, {}, dir.string(), {}),
                 InputError);
    EXPECT_TRUE(fs::exists(dir / "notes.txt"));
    EXPECT_FALSE(fs::exists(dir / kManifestName));
}

TEST(ProbeSet, ManifestValuesThatWouldSizeAnAllocationAreRefused) {
    const fs::path dir = fresh_dir("hostile_manifest");
    const std::string probe =
        R"({"file": "probe_00000.exr", "position": [0, 0, 0], "resolution": 64})";
    const auto manifest = [&](const std::string& probes, const std::string& extra) {
        std::ofstream(dir / kManifestName)
            << R"({"format": "lfprobe-probe-set", "format_version": 1, "world_offset": [0, 0, 0],)"
            << R"("probes": [)" << probes << "]" << extra << "}";
    };
    const auto refused = [&](const std::string& what) {
        try {
            (void)read_manifest(dir.string());
            ADD_FAILURE() << "accepted: " << what;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("manifest.json"), std::string::npos) << what;
        }
    };
    manifest(probe, R"(, "layout": "grid", "grid": {"origin": [0, 0, 0], "spacing": [1, 1, 1],)"
                    R"( "counts": [100000, 100000, 100000]}})");
    refused("grid counts far beyond the probes listed");
    manifest(probe, R"(, "layout": "grid", "grid": {"origin": [0, 0, 0], "spacing": [1, 1, 1],)"
                    R"( "counts": [2147483648, 1, 1]}})");
    refused("a count beyond int");
    manifest(R"({"file": "probe_00000.exr", "position": [0, 0, 0], "resolution": 1e10})", "");
    refused("a resolution of 1e10");
    manifest(R"({"file": "probe_00000.exr", "position": [0, 0, 0], "resolution": 0})", "");
    refused("a resolution of 0");
    manifest(probe, R"(, "bake": )" + std::string(200000, '[') + std::string(200000, ']'));
    refused("JSON nested 200,000 deep");
    // Numbers a cast to an integer would make undefined (the fuzz harness's find).
    std::ofstream(dir / kManifestName)
        << R"({"format": "lfprobe-probe-set", "format_version": 1e300, "world_offset": [0, 0, 0],)"
        << R"("probes": [)" << probe << "]}";
    refused("a format_version of 1e300");
    manifest(R"({"file": "probe_00000.exr", "position": [0, 0, 0], "resolution": 64,)"
             R"( "memory_bytes": 1e30})",
             "");
    refused("memory_bytes of 1e30");
    manifest(R"({"file": "probe_00000.exr", "position": [0, 0, 0], "resolution": 64,)"
             R"( "memory_bytes": -5})",
             "");
    refused("a negative memory_bytes");
}

TEST(ProbeSet, AWriteRemovesTheTemporariesAKilledWriterLeft) {
    const fs::path dir = fresh_dir("orphans");
    const fs::path target = dir / "view.exr";
    // 999999999: no such process (above any pid_max); this process's own temporary is in use.
    const fs::path orphan = dir / "view.exr.tmp.999999999.0";
    const fs::path in_use = dir / ("view.exr.tmp." + std::to_string(::getpid()) + ".99");
    const fs::path other = dir / "other.exr.tmp.999999999.0";
    for (const fs::path& p : {orphan, in_use, other}) {
        std::ofstream(p) << "partial";
    }
    write_file_atomically(target.string(), "complete");
    EXPECT_FALSE(fs::exists(orphan));
    EXPECT_TRUE(fs::exists(in_use));
    EXPECT_TRUE(fs::exists(other)); // another file's: its own next write clears it
    EXPECT_TRUE(fs::exists(target));
}

TEST(ProbeSet, ManifestErrorsNameTheFile) {
    const fs::path dir = fresh_dir("bad_manifest");
    {
        std::ofstream(dir / kManifestName)
            << "{\"format\": \"lfprobe-probe-set\", \"format_version\": 1, "
               "\"world_offset\": [0, 0], \"probes\": []}";
    }
    try {
        (void)read_manifest(dir.string());
        FAIL() << "expected an InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("manifest.json"), std::string::npos);
        EXPECT_NE(std::string(e.what()).find("world_offset"), std::string::npos);
    }
    { std::ofstream(dir / kManifestName) << "not json"; }
    EXPECT_THROW((void)read_manifest(dir.string()), InputError);
    { std::ofstream(dir / "junk.exr") << "not an exr"; }
    EXPECT_THROW((void)read_probe_exr((dir / "junk.exr").string()), InputError);
}
