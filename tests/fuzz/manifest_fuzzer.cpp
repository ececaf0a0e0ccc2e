// libFuzzer harness: a probe set's manifest.json, read and then opened as a field (lazily, so
// the probe files it names, which are not there, are not needed to open it). A manifest that is
// read promises counts and resolutions inside their limits and a grid that fits its probes.
#include <cstdint>
#include <filesystem>
#include <string_view>

#include "fuzz_support.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/probe_field.hpp"
#include "lfprobe/probe_set.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace lfprobe;
    static const std::string folder = [] {
        const std::filesystem::path made = fuzz::scratch_folder() / "set";
        std::filesystem::create_directories(made);
        return made.string();
    }();
    fuzz::write_scratch_file("set/manifest.json",
                             std::string_view(reinterpret_cast<const char*>(data), size));
    try {
        const ProbeSetManifest manifest = read_manifest(folder);
        for (const ProbeRecord& probe : manifest.probes) {
            fuzz::expect(probe.resolution >= 1 && probe.resolution <= 16384,
                         "an accepted probe resolution is outside 1..16384");
        }
        if (manifest.placement.is_grid) {
            fuzz::expect(manifest.placement.grid.probe_count() == manifest.probes.size(),
                         "an accepted grid does not fit the probes listed");
        }
        const ProbeField field = ProbeField::load(folder, nullptr, 0, {}, /*lazy=*/true);
        (void)field;
    } catch (const InputError&) {
    } catch (const IoError&) {
    }
    return 0;
}
