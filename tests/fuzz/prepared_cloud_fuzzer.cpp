// libFuzzer harness: the prepared-cloud cache's entry reader (prepared_cloud_cache.hpp). A
// small cloud is prepared once, which writes its genuine entry. With the input's first byte
// even the rest is the entry as it is; odd, it is the genuine header with the rest as the
// payload and a checksum that matches, so the reader's checks after the checksum are reached.
// Whatever the entry, what the reader accepts bakes a probe without error (a rejected entry is
// computed again: PreparedCloudCache.ADamagedEntryIsIgnoredAndRewritten).
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <string_view>

#define XXH_INLINE_ALL
#include <xxhash.h>

#include "fuzz_support.hpp"
#include "lfprobe/cloud_bake.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/prepared_cloud_cache.hpp"
#include "lfprobe/probe_bake.hpp"
#include "walls_cloud.hpp"

namespace {

// The header (prepared_cloud_cache.cpp, version 1): 56 bytes, payload size and XXH3-64 last.
constexpr std::size_t kHeaderBytes = 56;
constexpr std::size_t kPayloadBytesAt = 40;
constexpr std::size_t kHashAt = 48;

struct Genuine {
    std::shared_ptr<const lfprobe::PointCloud> cloud;
    std::string cache_dir;
    lfprobe::PreparedCloudKey key;
    std::string entry_path;
    std::string entry;
};

const Genuine& genuine() {
    using namespace lfprobe;
    static const Genuine g = [] {
        Genuine made;
        made.cloud = fuzz::walls_cloud();
        made.cache_dir = (fuzz::scratch_folder() / "prepared").string();
        const CloudBakeSource first =
            prepare_cloud_bake(made.cloud, {}, {}, nullptr, made.cache_dir);
        fuzz::expect(!first.hierarchy.levels.empty(), "the genuine cloud has no hierarchy");
        made.key = prepared_cloud_key(*made.cloud, {}, true);
        made.entry_path = prepared_cloud_entry_path(made.key, made.cache_dir);
        made.entry = fuzz::file_bytes(made.entry_path);
        fuzz::expect(made.entry.size() > kHeaderBytes, "the genuine entry was not written");
        return made;
    }();
    return g;
}

std::string structured_entry(std::string_view payload) {
    std::string entry = genuine().entry.substr(0, kHeaderBytes);
    entry.append(payload);
    const std::uint64_t bytes = payload.size();
    const std::uint64_t hash = XXH3_64bits(payload.data(), payload.size());
    std::memcpy(entry.data() + kPayloadBytesAt, &bytes, sizeof(bytes));
    std::memcpy(entry.data() + kHashAt, &hash, sizeof(hash));
    return entry;
}

void bake_from(const lfprobe::PointCloud& cloud, const lfprobe::LocalGeometry& geometry,
               const lfprobe::PointHierarchy& hierarchy) {
    lfprobe::BakeSettings settings;
    settings.resolution = 16;
    const lfprobe::ProbeMap map =
        lfprobe::bake_probe_from_hierarchy(cloud, geometry, hierarchy, glm::dvec3(0.3), settings);
    lfprobe::fuzz::expect(map.resolution == 16, "the bake from the entry gave no map");
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace lfprobe;
    const Genuine& g = genuine();
    if (!fuzz::write_cache_entry(data, size, g.entry_path, structured_entry)) {
        return 0;
    }
    try {
        if (const std::optional<PreparedCloud> read = read_prepared_cloud(g.entry_path, g.key)) {
            bake_from(*g.cloud, read->geometry, read->hierarchy);
        }
    } catch (const InputError&) {
        fuzz::broken_promise("a damaged prepared-cloud entry made the cloud unbakeable");
    } catch (const IoError&) {
        fuzz::broken_promise("a damaged prepared-cloud entry made the cloud unbakeable");
    }
    return 0;
}
