// libFuzzer harness: the text scan readers (.xyz family and .pts). The first byte picks the
// extension and the columns option; the rest is the file's bytes.
#include <array>
#include <cstdint>
#include <string_view>

#include "lfprobe/error.hpp"
#include "lfprobe/scan_reader.hpp"
#include "scan_checks.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace lfprobe;
    if (size == 0) {
        return 0;
    }
    static constexpr std::array<const char*, 4> extensions{".xyz", ".pts", ".txt", ".csv"};
    static constexpr std::array<const char*, 6> columns{
        "", "x y z r g b", "x y z i r g b", "x y z nx ny nz r g b", "_ x y z i", "x y z"};
    const std::uint8_t selector = data[0];
    // From memory, as the file's mapping would be (no file written per execution; a read past
    // the end is an ASan report here, where a mapping's page would hide it).
    const std::string name = std::string("scan") + extensions[selector % extensions.size()];
    const std::string_view bytes(reinterpret_cast<const char*>(data) + 1, size - 1);
    ScanReadOptions options;
    options.columns = columns[(selector / extensions.size()) % columns.size()];
    try {
        fuzz::check_scan(read_scan_bytes(name, bytes, options));
    } catch (const InputError&) {
    } catch (const IoError&) {
    }
    return 0;
}
