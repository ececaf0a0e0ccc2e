// The prepared-cloud cache (prepared_cloud_cache.hpp): a second preparation of the same cloud
// reads what the first wrote and bakes the same probes bit for bit; another cloud or other
// options miss it; a damaged entry is ignored and rewritten; a cancelled preparation leaves
// nothing behind.
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "lfprobe/cloud_bake.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/prepared_cloud_cache.hpp"
#include "temp_folder.hpp"
#include "wall_cloud.hpp"

using namespace lfprobe;
using lfprobe::testing::same_bits;

namespace {

namespace fs = std::filesystem;

std::vector<fs::path> files_in(const fs::path& dir) {
    std::vector<fs::path> files;
    if (fs::exists(dir)) {
        for (const auto& entry : fs::directory_iterator(dir)) {
            files.push_back(entry.path());
        }
    }
    return files;
}

CloudBakeSource prepare(const PointCloud& cloud, const fs::path& cache,
                        const LocalGeometryOptions& options = {}, Progress* progress = nullptr) {
    return prepare_cloud_bake(std::make_shared<const PointCloud>(cloud), BakeSettings{}, options,
                              progress, cache.string());
}

ProbeMap bake(const CloudBakeSource& source) {
    BakeSettings settings;
    settings.resolution = 64;
    return bake_probe_from_hierarchy(*source.cloud, source.geometry, source.hierarchy,
                                     glm::dvec3(-1.0, 0.1, 0.2), settings);
}

} // namespace

TEST(PreparedCloudCache, ASecondPreparationReadsTheCacheAndBakesTheSameProbeBitForBit) {
    const fs::path cache = lfprobe::testing::fresh_dir("prepared_", "second");
    const PointCloud cloud = lfprobe::testing::wall_corner(0.01f);
    const CloudBakeSource first = prepare(cloud, cache);
    EXPECT_FALSE(first.from_cache);
    ASSERT_EQ(files_in(cache).size(), 1u); // the entry, no temporary
    const CloudBakeSource second = prepare(cloud, cache);
    EXPECT_TRUE(second.from_cache);
    ASSERT_GE(second.hierarchy.levels.size(), 2u);
    EXPECT_TRUE(same_bits(first.geometry.normals, second.geometry.normals));
    EXPECT_TRUE(same_bits(first.geometry.spacing, second.geometry.spacing));
    EXPECT_TRUE(same_bits(first.geometry.spatial_order, second.geometry.spatial_order));
    EXPECT_TRUE(same_bits(first.hierarchy.order, second.hierarchy.order));
    const ProbeMap a = bake(first);
    const ProbeMap b = bake(second);
    EXPECT_TRUE(same_bits(a.distance, b.distance));
    EXPECT_TRUE(same_bits(a.rgba, b.rgba));
    EXPECT_TRUE(same_bits(a.normal, b.normal));
}

TEST(PreparedCloudCache, AnotherCloudOrOtherOptionsMissTheCache) {
    const fs::path cache = lfprobe::testing::fresh_dir("prepared_", "miss");
    PointCloud cloud = lfprobe::testing::wall_corner(0.02f);
    (void)prepare(cloud, cache);
    LocalGeometryOptions other;
    other.normal_neighbours = 8;
    EXPECT_FALSE(prepare(cloud, cache, other).from_cache);
    cloud.colors[7].x = 0.5f; // one point's colour: another cloud
    EXPECT_FALSE(prepare(cloud, cache).from_cache);
    EXPECT_EQ(files_in(cache).size(), 3u);
    EXPECT_TRUE(prepare(cloud, cache).from_cache);
}

TEST(PreparedCloudCache, ADamagedEntryIsIgnoredAndRewritten) {
    const fs::path cache = lfprobe::testing::fresh_dir("prepared_", "damaged");
    const PointCloud cloud = lfprobe::testing::wall_corner(0.02f);
    const CloudBakeSource first = prepare(cloud, cache);
    const fs::path entry = files_in(cache).at(0);
    std::string bytes = lfprobe::testing::file_bytes(entry);
    for (const std::size_t at : {bytes.size() / 2, std::size_t{20}}) { // the payload; the key
        std::string damaged = bytes;
        damaged[at] = static_cast<char>(damaged[at] ^ 0x5a);
        lfprobe::testing::write_file(entry, damaged);
        const CloudBakeSource again = prepare(cloud, cache);
        EXPECT_FALSE(again.from_cache) << at;
        EXPECT_TRUE(same_bits(first.geometry.normals, again.geometry.normals));
        EXPECT_EQ(lfprobe::testing::file_bytes(entry), bytes) << at; // rewritten as it was
    }
    lfprobe::testing::write_file(entry, bytes.substr(0, bytes.size() - 1)); // truncated
    EXPECT_FALSE(prepare(cloud, cache).from_cache);
    EXPECT_TRUE(prepare(cloud, cache).from_cache);
}

TEST(PreparedCloudCache, ACancelledPreparationLeavesNoEntry) {
    const fs::path cache = lfprobe::testing::fresh_dir("prepared_", "cancelled");
    const PointCloud cloud = lfprobe::testing::wall_corner(0.02f);
    Progress progress;
    progress.request_cancel();
    EXPECT_THROW((void)prepare(cloud, cache, {}, &progress), Cancelled);
    EXPECT_TRUE(files_in(cache).empty());
}

TEST(PreparedCloudCache, ACacheThatCannotBeWrittenLeavesTheBakeAsItWas) {
    const fs::path dir = lfprobe::testing::fresh_dir("prepared_", "unwritable");
    const fs::path blocked = dir / "a file, not a folder";
    lfprobe::testing::write_file(blocked, "x");
    const PointCloud cloud = lfprobe::testing::wall_corner(0.02f);
    const CloudBakeSource source = prepare(cloud, blocked);
    EXPECT_FALSE(source.from_cache);
    const CloudBakeSource uncached = prepare(cloud, "");
    const ProbeMap a = bake(source);
    const ProbeMap b = bake(uncached);
    EXPECT_TRUE(same_bits(a.rgba, b.rgba));
}
