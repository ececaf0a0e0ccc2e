// The bake from a cloud's points copied into curve order (curve_ordered_cloud.hpp) against the
// bake through the cloud's own arrays: the same cut, so the same probe, bit for bit.
#include <algorithm>
#include <fstream>
#include <iterator>
#include <memory>
#include <numeric>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "lfprobe/cloud_bake.hpp"
#include "lfprobe/curve_ordered_cloud.hpp"
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

// The cloud's points in a shuffled order: the curve order then differs from the file's
// everywhere, as it does for a scanner's lines.
PointCloud shuffled(const PointCloud& cloud) {
    std::vector<std::size_t> order(cloud.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::shuffle(order.begin(), order.end(), std::mt19937(5));
    PointCloud out = cloud;
    for (std::size_t k = 0; k < order.size(); ++k) {
        out.positions[k] = cloud.positions[order[k]];
        if (cloud.has_colors()) {
            out.colors[k] = cloud.colors[order[k]];
        }
        if (!cloud.intensities.empty()) {
            out.intensities[k] = cloud.intensities[order[k]];
        }
    }
    return out;
}

} // namespace

TEST(CurveOrderedCloud, ABakeFromTheCopyIsTheBakeThroughTheCloudBitForBit) {
    const CloudBakeSource source = prepare_cloud_bake(
        std::make_shared<const PointCloud>(shuffled(lfprobe::testing::wall_corner(0.01f))),
        BakeSettings{}, {});
    ASSERT_GE(source.hierarchy.levels.size(), 2u);
    ASSERT_FALSE(source.curve.empty());
    EXPECT_EQ(source.curve.points.size(), source.cloud->size());
    for (const glm::dvec3 centre :
         {glm::dvec3(-1.0, 0.1, 0.2), glm::dvec3(-0.05, 0.45, 0.0), glm::dvec3(-6.0, -3.0, 2.0)}) {
        for (const int resolution : {32, 128}) {
            const ProbeMap expected = bake_probe_from_hierarchy(
                *source.cloud, source.geometry, source.hierarchy, centre, at(resolution));
            expect_same_probe(bake_probe_from_curve_ordered(source.curve, source.hierarchy, centre,
                                                            at(resolution)),
                              expected);
        }
    }
}

TEST(CurveOrderedCloud, IntensityColoursAreResolvedAsTheCloudResolvesThem) {
    PointCloud cloud = lfprobe::testing::wall_corner(0.02f);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        cloud.intensities.push_back(static_cast<float>(i % 97) * 3.0f - 40.0f);
    }
    cloud.colors.clear();
    const CloudBakeSource source =
        prepare_cloud_bake(std::make_shared<const PointCloud>(shuffled(cloud)), at(64), {});
    const glm::dvec3 centre(-0.7, 0.2, 0.1);
    expect_same_probe(bake_probe(source, centre),
                      bake_probe_from_hierarchy(*source.cloud, source.geometry, source.hierarchy,
                                                centre, at(64)));
}

TEST(CurveOrderedCloud, ABakeOfEveryPointHasNoCopy) {
    BakeSettings every_point = at(32);
    every_point.lod_texels = 0.0f;
    const CloudBakeSource source = prepare_cloud_bake(
        std::make_shared<const PointCloud>(lfprobe::testing::wall_corner(0.02f)), every_point, {});
    EXPECT_TRUE(source.curve.empty());
    const glm::dvec3 centre(-0.7, 0.2, 0.1);
    expect_same_probe(bake_probe(source, centre),
                      bake_probe_from_cloud(*source.cloud, source.geometry, centre, every_point));
}

TEST(CurveOrderedCloud, ACopyOfAnotherCloudIsRefused) {
    const CloudBakeSource small = prepare_cloud_bake(
        std::make_shared<const PointCloud>(lfprobe::testing::wall_corner(0.02f)), at(32), {});
    const CloudBakeSource large = prepare_cloud_bake(
        std::make_shared<const PointCloud>(lfprobe::testing::wall_corner(0.01f)), at(32), {});
    ASSERT_NE(small.curve.points.size(), large.curve.points.size());
    EXPECT_THROW((void)bake_probe_from_curve_ordered(small.curve, large.hierarchy,
                                                     glm::dvec3(-0.7, 0.2, 0.1), at(32)),
                 InputError);
    BakeSettings every_point = at(32);
    every_point.lod_texels = 0.0f;
    EXPECT_THROW((void)bake_probe_from_curve_ordered(small.curve, small.hierarchy,
                                                     glm::dvec3(-0.7, 0.2, 0.1), every_point),
                 InputError);
}

TEST(CurveOrderedCloud, ASpatialCloudWrittenFromTheCopyIsTheSameFile) {
    const CloudBakeSource source = prepare_cloud_bake(
        std::make_shared<const PointCloud>(shuffled(lfprobe::testing::wall_corner(0.02f))), at(64),
        {});
    ASSERT_FALSE(source.curve.empty());
    const auto folder = lfprobe::testing::fresh_dir("curve_", "spatial");
    const PreparedCloudKey key = prepared_cloud_key(*source.cloud, source.geometry_options, true);
    const std::string gathered = (folder / "gathered.lfpspatial").string();
    const std::string copied = (folder / "copied.lfpspatial").string();
    write_spatial_cloud(gathered, key, *source.cloud, source.geometry, source.hierarchy);
    write_spatial_cloud(copied, key, source.curve, source.hierarchy);
    auto bytes = [](const std::string& path) {
        std::ifstream in(path, std::ios::binary);
        return std::vector<char>(std::istreambuf_iterator<char>(in), {});
    };
    const std::vector<char> a = bytes(gathered);
    EXPECT_GT(a.size(), 0u);
    EXPECT_EQ(a, bytes(copied));
}
