// The spatial cloud (spatial_cloud.hpp): a probe baked from the mapped file is the probe baked
// from the cloud in memory, bit for bit; a probe at one end of a long cloud reads only part of
// the file; a damaged file or one of another cloud is refused with IoError; a cancelled write
// leaves nothing; the same cloud writes the same bytes.
#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <fcntl.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "lfprobe/cloud_bake.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/spatial_cloud.hpp"
#include "same_probe.hpp"
#include "temp_folder.hpp"
#include "wall_cloud.hpp"

using namespace lfprobe;
using lfprobe::testing::at;
using lfprobe::testing::expect_same_probe;
using lfprobe::testing::same_bits;

namespace {

namespace fs = std::filesystem;

CloudBakeSource prepare(const PointCloud& cloud) {
    return prepare_cloud_bake(std::make_shared<const PointCloud>(cloud), BakeSettings{}, {});
}

// A corridor's floor, `length` metres along x and 2 m wide, scanned every `pitch` from
// scanners along its middle.
PointCloud corridor_floor(float length, float pitch) {
    PointCloud cloud;
    std::mt19937 random(11);
    std::uniform_real_distribution<float> jitter(-0.3f * pitch, 0.3f * pitch);
    std::uniform_real_distribution<float> shade(0.2f, 0.8f);
    for (float x = 0.0f; x < length; x += pitch) {
        for (float y = -1.0f; y < 1.0f; y += pitch) {
            cloud.positions.emplace_back(x + jitter(random), y + jitter(random), 0.0f);
            cloud.colors.emplace_back(shade(random), 0.5f, 0.5f);
            cloud.scan_index.push_back(0);
        }
    }
    cloud.scans.push_back(
        ScanSource{"corridor", cloud.positions.size(), glm::dvec3(length / 2, 0.0, 1.5), true});
    return cloud;
}

// Drops the file's pages from the page cache (they were just written), so that the pages a
// mapping holds afterwards are the ones it read, not also their cached neighbours (the
// kernel maps those in around each fault).
void drop_from_page_cache(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    ASSERT_GE(fd, 0);
    ::fdatasync(fd);
    ::posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED);
    ::close(fd);
}

SpatialCloudEntry written(const CloudBakeSource& source, const fs::path& cache) {
    const std::optional<SpatialCloudEntry> entry = write_spatial_cloud_of(source, cache.string());
    if (!entry) {
        throw std::runtime_error("no spatial cloud written");
    }
    return *entry;
}

} // namespace

TEST(SpatialCloud, AProbeBakedFromTheMappedFileIsTheInMemoryBakeBitForBit) {
    const fs::path cache = lfprobe::testing::fresh_dir("spatial_", "same");
    const CloudBakeSource source = prepare(lfprobe::testing::wall_corner(0.01f));
    ASSERT_GE(source.hierarchy.levels.size(), 2u);
    const SpatialCloudEntry entry = written(source, cache);
    EXPECT_TRUE(entry.written);
    const SpatialCloud cloud(entry.path, entry.key_hex);
    EXPECT_EQ(cloud.point_count(), source.cloud->size());
    for (const glm::dvec3 centre :
         {glm::dvec3(-1.0, 0.1, 0.2), glm::dvec3(-0.05, 0.45, 0.0), glm::dvec3(-6.0, -3.0, 2.0)}) {
        for (const int resolution : {32, 128}) {
            const ProbeMap expected = bake_probe_from_hierarchy(
                *source.cloud, source.geometry, source.hierarchy, centre, at(resolution));
            expect_same_probe(bake_probe_from_spatial_cloud(cloud, centre, at(resolution)),
                              expected);
        }
    }
    // A second call finds the file and keeps it.
    EXPECT_FALSE(written(source, cache).written);
}

TEST(SpatialCloud, IntensityColoursAreResolvedAsTheCloudResolvesThem) {
    const fs::path cache = lfprobe::testing::fresh_dir("spatial_", "intensity");
    PointCloud cloud = lfprobe::testing::wall_corner(0.02f);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        cloud.intensities.push_back(static_cast<float>(i % 97) * 3.0f - 40.0f);
    }
    cloud.colors.clear();
    const CloudBakeSource source = prepare(cloud);
    const SpatialCloudEntry entry = written(source, cache);
    const SpatialCloud mapped(entry.path, entry.key_hex);
    const glm::dvec3 centre(-0.7, 0.2, 0.1);
    expect_same_probe(bake_probe_from_spatial_cloud(mapped, centre, at(64)),
                      bake_probe_from_hierarchy(*source.cloud, source.geometry, source.hierarchy,
                                                centre, at(64)));
}

TEST(SpatialCloud, AProbeAtOneEndOfALongCloudReadsOnlyPartOfTheFile) {
    const fs::path cache = lfprobe::testing::fresh_dir("spatial_", "corridor");
    const CloudBakeSource source = prepare(corridor_floor(40.0f, 0.02f));
    const SpatialCloudEntry entry = written(source, cache);
    drop_from_page_cache(entry.path);
    const SpatialCloud near_end(entry.path, entry.key_hex);
    if (!near_end.resident_bytes()) {
        GTEST_SKIP() << "this system does not report a mapping's resident pages";
    }
    const glm::dvec3 centre(1.0, 0.0, 1.2);
    const ProbeMap probe = bake_probe_from_spatial_cloud(near_end, centre, at(256));
    // 17 % here (2.4 of 13.8 MB): the floor within a few metres at full density, surfels of
    // coarser cells with distance.
    const double touched = static_cast<double>(*near_end.resident_bytes()) /
                           static_cast<double>(near_end.file_bytes());
    EXPECT_LT(touched, 0.45) << *near_end.resident_bytes() << " of " << near_end.file_bytes();
    expect_same_probe(probe, bake_probe_from_hierarchy(*source.cloud, source.geometry,
                                                       source.hierarchy, centre, at(256)));
    // The same probe in the middle reads more of it: what is read follows where the probe is.
    drop_from_page_cache(entry.path);
    const SpatialCloud middle(entry.path, entry.key_hex);
    (void)bake_probe_from_spatial_cloud(middle, glm::dvec3(20.0, 0.0, 1.2), at(256));
    EXPECT_GT(*middle.resident_bytes(), *near_end.resident_bytes());
}

TEST(SpatialCloud, AFileOfAnotherCloudOrADamagedOneIsRefused) {
    const fs::path cache = lfprobe::testing::fresh_dir("spatial_", "damaged");
    const CloudBakeSource source = prepare(lfprobe::testing::wall_corner(0.02f));
    const SpatialCloudEntry entry = written(source, cache);
    const std::string good = lfprobe::testing::file_bytes(entry.path);
    EXPECT_THROW(SpatialCloud(entry.path, std::string(32, '0')), IoError);
    EXPECT_THROW(SpatialCloud((cache / "missing.lfpspatial").string(), entry.key_hex), IoError);

    const fs::path copy = cache / "copy.lfpspatial";
    // The section table's checksum.
    std::string bytes = good;
    bytes[100] = static_cast<char>(bytes[100] ^ 1);
    lfprobe::testing::write_file(copy, bytes);
    EXPECT_THROW(SpatialCloud(copy.string(), entry.key_hex), IoError);
    // Cut short: the sections no longer fit.
    lfprobe::testing::write_file(copy, good.substr(0, good.size() / 2));
    EXPECT_THROW(SpatialCloud(copy.string(), entry.key_hex), IoError);
    // The sections themselves are not checksummed: what a cut reads of them is checked. All
    // ones over the file's second half turn the coarse levels' runs and surfels to nonsense.
    bytes = good;
    std::fill(bytes.begin() + static_cast<std::ptrdiff_t>(bytes.size() / 2), bytes.end(), '\xff');
    lfprobe::testing::write_file(copy, bytes);
    const SpatialCloud damaged(copy.string(), entry.key_hex);
    EXPECT_THROW((void)bake_probe_from_spatial_cloud(damaged, glm::dvec3(-1.0, 0.1, 0.2), at(32)),
                 IoError);
    // All ones over the first half after the table: the points' values are NaN.
    bytes = good;
    std::fill(bytes.begin() + 8192, bytes.begin() + static_cast<std::ptrdiff_t>(bytes.size() / 2),
              '\xff');
    lfprobe::testing::write_file(copy, bytes);
    const SpatialCloud nan_points(copy.string(), entry.key_hex);
    EXPECT_THROW(
        (void)bake_probe_from_spatial_cloud(nan_points, glm::dvec3(-0.05, 0.1, 0.2), at(32)),
        IoError);
}

TEST(SpatialCloud, ACancelledWriteLeavesNothingAndARewriteIsBitIdentical) {
    const fs::path cache = lfprobe::testing::fresh_dir("spatial_", "cancel");
    const CloudBakeSource source = prepare(lfprobe::testing::wall_corner(0.02f));
    Progress progress;
    progress.request_cancel();
    EXPECT_THROW((void)write_spatial_cloud_of(source, cache.string(), &progress), Cancelled);
    EXPECT_TRUE(fs::is_empty(cache));
    const SpatialCloudEntry first = written(source, cache);
    const std::string bytes = lfprobe::testing::file_bytes(first.path);
    fs::remove(first.path);
    const CloudBakeSource again = prepare(lfprobe::testing::wall_corner(0.02f));
    EXPECT_EQ(lfprobe::testing::file_bytes(written(again, cache).path), bytes);
}

TEST(SpatialCloud, ABakeOfEveryPointHasNoSpatialCloud) {
    const fs::path cache = lfprobe::testing::fresh_dir("spatial_", "lod0");
    BakeSettings every_point;
    every_point.lod_texels = 0.0f;
    const CloudBakeSource source = prepare_cloud_bake(
        std::make_shared<const PointCloud>(lfprobe::testing::wall_corner(0.02f)), every_point, {});
    EXPECT_FALSE(write_spatial_cloud_of(source, cache.string()).has_value());
    EXPECT_TRUE(fs::is_empty(cache));
}
