// libFuzzer harness: the PLY readers, both on the same bytes: the scan reader (points) and the
// mesh reader (vertices and faces), each held to what it promises.
#include <cstdint>
#include <string_view>

#include "lfprobe/error.hpp"
#include "lfprobe/mesh_reader.hpp"
#include "lfprobe/scan_reader.hpp"
#include "mesh_checks.hpp"
#include "scan_checks.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace lfprobe;
    // From memory, as the file's mapping would be (see text_scan_fuzzer.cpp).
    const std::string_view bytes(reinterpret_cast<const char*>(data), size);
    try {
        fuzz::check_scan(read_scan_bytes("cloud.ply", bytes, ScanReadOptions{}));
    } catch (const InputError&) {
    } catch (const IoError&) {
    }
    try {
        fuzz::check_mesh(read_ply_mesh_bytes("cloud.ply", bytes));
    } catch (const InputError&) {
    } catch (const IoError&) {
    }
    return 0;
}
