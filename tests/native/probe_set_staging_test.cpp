// A cloud bake in parts (cloud_bake.hpp, probe_set_staging.hpp): probes baked in any order and
// grouping, by separate calls as separate processes would, finish into the set one bake writes.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "lfprobe/cloud_bake.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/probe_set_staging.hpp"
#include "synthetic_scene.hpp"
#include "temp_folder.hpp"

using namespace lfprobe;
namespace fs = std::filesystem;

namespace {

fs::path fresh_dir(const std::string& name) {
    return lfprobe::testing::fresh_dir("lfprobe_staging_", name);
}

using lfprobe::testing::file_bytes;

struct PartsBake {
    lfprobe::testing::BoxRoomScene scene;
    std::shared_ptr<const PointCloud> cloud =
        std::make_shared<PointCloud>(scene.cloud(0.05f, glm::dvec3(0.0, 0.0, 1.2)));
    BakeSettings settings = [] {
        BakeSettings s;
        s.resolution = 32;
        return s;
    }();
    ProbePlacement placement = ProbePlacement::from_grid(
        ProbeGrid::spanning(glm::dvec3(-1.0, -0.5, 0.8), glm::dvec3(1.0, 0.5, 1.6), {3, 2, 1}));
    nlohmann::json sources = nlohmann::json::array({{{"path", "synthetic"}}});
};

} // namespace

TEST(ProbeSetStaging, ProbesBakedInPartsGiveTheSetOfOneBakeBitForBit) {
    const PartsBake bake;
    const fs::path root = fresh_dir("parts");
    const std::string whole = (root / "whole").string();
    (void)bake_probe_set_from_cloud(*bake.cloud, bake.placement, bake.settings, {}, whole,
                                    bake.sources);

    // Two "workers", each with its own prepared cloud, baking probes out of order.
    const std::string parts = (root / "parts").string();
    const std::string staging = open_probe_set_staging(parts);
    EXPECT_EQ(staging, probe_set_staging_path(parts));
    std::vector<StagedProbe> staged;
    for (const std::vector<std::size_t>& indices :
         {std::vector<std::size_t>{5, 1, 3}, std::vector<std::size_t>{0, 4, 2}}) {
        const CloudBakeSource source = prepare_cloud_bake(bake.cloud, bake.settings, {});
        for (StagedProbe& s : bake_staged_probes(source, bake.placement, indices, staging)) {
            staged.push_back(std::move(s));
        }
    }
    ProbeSetManifest manifest =
        cloud_bake_manifest(*bake.cloud, bake.placement, bake.settings, {}, bake.sources);
    std::sort(staged.begin(), staged.end(),
              [](const StagedProbe& a, const StagedProbe& b) { return a.index < b.index; });
    for (const StagedProbe& s : staged) {
        manifest.probes.push_back(s.record);
    }
    finish_probe_set_staging(parts, manifest);
    EXPECT_FALSE(fs::exists(staging));

    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(whole)) {
        names.push_back(entry.path().filename().string());
    }
    std::sort(names.begin(), names.end());
    ASSERT_EQ(names.size(), 8u); // six probes, their known space and the manifest
    for (const std::string& name : names) {
        EXPECT_EQ(file_bytes(fs::path(whole) / name), file_bytes(fs::path(parts) / name)) << name;
    }
    EXPECT_EQ(std::distance(fs::directory_iterator(parts), fs::directory_iterator{}), 8);
}

TEST(ProbeSetStaging, AnIncompleteSetIsNotFinished) {
    const PartsBake bake;
    const fs::path root = fresh_dir("incomplete");
    const std::string folder = (root / "set").string();
    const std::string staging = open_probe_set_staging(folder);
    const CloudBakeSource source = prepare_cloud_bake(bake.cloud, bake.settings, {});
    ProbeSetManifest manifest =
        cloud_bake_manifest(*bake.cloud, bake.placement, bake.settings, {}, bake.sources);
    for (const StagedProbe& s : bake_staged_probes(source, bake.placement, {0, 1, 2}, staging)) {
        manifest.probes.push_back(s.record);
    }
    EXPECT_THROW(finish_probe_set_staging(folder, manifest), InputError); // 3 of 6 listed
    // All six listed, but probe 4's file was never written (a worker that died).
    for (const StagedProbe& s : bake_staged_probes(source, bake.placement, {3, 5}, staging)) {
        manifest.probes.push_back(s.record);
    }
    manifest.probes.insert(manifest.probes.begin() + 4, manifest.probes[3]);
    manifest.probes[4].file = probe_file_name(4);
    try {
        finish_probe_set_staging(folder, manifest);
        FAIL() << "a set missing probe 4 was finished";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("probe_00004.exr"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(folder));
    EXPECT_FALSE(fs::exists(fs::path(staging) / kManifestName));
}

TEST(ProbeSetStaging, RemovingTheStagingFolderCallsTheBakeOffAndFinishDropsStrays) {
    const PartsBake bake;
    const fs::path root = fresh_dir("strays");
    const std::string folder = (root / "set").string();
    const std::string staging = open_probe_set_staging(folder);
    const CloudBakeSource source = prepare_cloud_bake(bake.cloud, bake.settings, {});
    discard_probe_set_staging(folder);
    EXPECT_THROW((void)bake_staged_probes(source, bake.placement, {0}, staging), IoError);
    EXPECT_FALSE(fs::exists(staging)); // the bake did not bring it back

    (void)open_probe_set_staging(folder);
    ProbeSetManifest manifest =
        cloud_bake_manifest(*bake.cloud, bake.placement, bake.settings, {}, bake.sources);
    const std::vector<std::size_t> all{0, 1, 2, 3, 4, 5};
    for (const StagedProbe& s : bake_staged_probes(source, bake.placement, all, staging)) {
        manifest.probes.push_back(s.record);
    }
    // What a killed worker leaves: a temporary of a dead process.
    std::ofstream(fs::path(staging) / "probe_00002.exr.tmp.999999999.0") << "half";
    finish_probe_set_staging(folder, manifest);
    // Six probes, their known space (merged from the probes' own) and the manifest.
    EXPECT_EQ(std::distance(fs::directory_iterator(folder), fs::directory_iterator{}), 8);
}

// A set's writes run beside its next probe's bake (OverlappedProbeWrites): the probes come back
// in the order handed over, and a write that fails (its staging folder removed, as a cancelled
// bake does) is reported by the next call rather than lost on its worker.
TEST(ProbeSetStaging, OverlappedWritesKeepTheOrderAndReportAFailedWrite) {
    const fs::path root = fresh_dir("overlapped");
    const std::string staging = open_probe_set_staging((root / "set").string());
    {
        OverlappedProbeWrites writes(staging);
        for (const std::size_t index : {std::size_t{2}, std::size_t{0}, std::size_t{1}}) {
            writes.write(index, ProbeMap(8, glm::dvec3(static_cast<double>(index), 0.0, 0.0)));
        }
        const std::vector<StagedProbe> staged = writes.finish();
        ASSERT_EQ(staged.size(), 3u);
        EXPECT_EQ(staged[0].index, 2u);
        EXPECT_EQ(staged[1].index, 0u);
        EXPECT_EQ(staged[2].index, 1u);
        EXPECT_EQ(staged[1].record.position, glm::dvec3(0.0, 0.0, 0.0));
        EXPECT_TRUE(fs::exists(fs::path(staging) / staged[0].record.file));
    }
    OverlappedProbeWrites writes(staging);
    fs::remove_all(staging);
    writes.write(3, ProbeMap(8, glm::dvec3(0.0)));
    EXPECT_THROW((void)writes.finish(), IoError);
}
