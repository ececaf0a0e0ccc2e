// libFuzzer harness: the spatial cloud's reader (spatial_cloud.hpp), which maps a file and reads
// only the parts a probe's cut needs, so it cannot check the file whole first. A small cloud is
// prepared and its genuine file written once. With the input's first byte even the rest is the
// file as it is; odd, it is the genuine file with the rest written over its sections from the
// first one on (the header and section table stay genuine, so their checksum matches and the
// cut's checks are reached). Whatever the file, opening it and baking a probe from it either
// works or gives IoError: never a crash, a read out of bounds, or a cut that never ends.
#include <cstdint>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "fuzz_support.hpp"
#include "lfprobe/cloud_bake.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/spatial_cloud.hpp"
#include "walls_cloud.hpp"

namespace {

// The sections start on the first page after the header and the section table.
constexpr std::size_t kSectionsAt = 4096;

struct Genuine {
    std::string path;
    std::string key;
    std::string bytes;
};

const Genuine& genuine() {
    using namespace lfprobe;
    static const Genuine g = [] {
        const CloudBakeSource source = prepare_cloud_bake(fuzz::walls_cloud(), {}, {});
        const std::optional<SpatialCloudEntry> entry =
            write_spatial_cloud_of(source, (fuzz::scratch_folder() / "spatial").string());
        fuzz::expect(entry.has_value(), "the genuine cloud has no spatial cloud");
        Genuine made{entry->path, entry->key_hex, fuzz::file_bytes(entry->path)};
        fuzz::expect(made.bytes.size() > kSectionsAt, "the genuine file was not written");
        return made;
    }();
    return g;
}

std::string over_the_sections(std::string_view sections) {
    std::string file = genuine().bytes;
    const std::size_t n = std::min(sections.size(), file.size() - kSectionsAt);
    std::memcpy(file.data() + kSectionsAt, sections.data(), n);
    return file;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace lfprobe;
    const Genuine& g = genuine();
    if (!fuzz::write_cache_entry(data, size, g.path, over_the_sections)) {
        return 0;
    }
    try {
        const SpatialCloud cloud(g.path, g.key);
        BakeSettings settings;
        settings.resolution = 16;
        for (const glm::dvec3 centre : {glm::dvec3(0.3), glm::dvec3(0.9, 0.5, 0.5)}) {
            const ProbeMap map = bake_probe_from_spatial_cloud(cloud, centre, settings);
            fuzz::expect(map.resolution == 16, "the bake from the file gave no map");
        }
    } catch (const IoError&) {
        // Refused: what a damaged file gives.
    }
    return 0;
}
