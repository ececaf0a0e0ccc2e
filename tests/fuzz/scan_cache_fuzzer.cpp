// libFuzzer harness: the parse cache's entry reader. One small scan is parsed once, which writes
// its genuine entry; every input then replaces that entry before the scan is read through the
// cache again. With the first byte even the rest is the entry as it is; odd, it is structured:
// the genuine header with the fuzzer's point count, flags, origin and scanner, the genuine path
// and columns, the fuzzer's arrays, and a checksum that matches, so the reader's checks after
// the checksum are reached too. Whatever the entry, the scan read back is a valid scan.
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <string_view>

#define XXH_INLINE_ALL
#include <xxhash.h>

#include "lfprobe/error.hpp"
#include "lfprobe/scan_cache.hpp"
#include "scan_checks.hpp"

namespace {

// The header's layout (scan_cache.cpp, cache format 2): 112 bytes, the payload's XXH3-64 last.
constexpr std::size_t kHeaderBytes = 112;
constexpr std::size_t kPointCountAt = 32; // point_count, flags
constexpr std::size_t kOriginAt = 56;     // origin, scanner: 6 doubles
constexpr std::size_t kHashAt = 104;
constexpr std::size_t kPathBytesAt = 44;
constexpr std::size_t kColumnsBytesAt = 48;

struct Genuine {
    std::string scan_path;
    std::string cache_dir;
    std::string entry_path;
    std::string entry;
};

const Genuine& genuine() {
    using namespace lfprobe;
    static const Genuine g = [] {
        Genuine made;
        made.scan_path = fuzz::write_scratch_file(
            "scan.xyz", "0 0 0 255 0 0\n1 0 0 0 255 0\n0 1 0 0 0 255\n0 0 1 9 9 9\n");
        made.cache_dir = (fuzz::scratch_folder() / "cache").string();
        const ScanFile first = read_scan_file_cached(made.scan_path, {}, made.cache_dir);
        (void)first;
        made.entry_path = scan_cache_entry_path(made.scan_path, {}, made.cache_dir);
        made.entry = fuzz::file_bytes(made.entry_path);
        fuzz::expect(made.entry.size() > kHeaderBytes, "the genuine cache entry was not written");
        return made;
    }();
    return g;
}

std::string structured_entry(std::string_view input) {
    const Genuine& g = genuine();
    std::string entry = g.entry.substr(0, kHeaderBytes);
    std::uint32_t path_bytes = 0;
    std::uint32_t columns_bytes = 0;
    std::memcpy(&path_bytes, entry.data() + kPathBytesAt, sizeof(path_bytes));
    std::memcpy(&columns_bytes, entry.data() + kColumnsBytesAt, sizeof(columns_bytes));
    // point_count (8) and flags (4), then origin and scanner (48) from the input.
    const std::size_t counts = std::min<std::size_t>(input.size(), 12);
    std::memcpy(entry.data() + kPointCountAt, input.data(), counts);
    input.remove_prefix(counts);
    const std::size_t placement = std::min<std::size_t>(input.size(), 48);
    std::memcpy(entry.data() + kOriginAt, input.data(), placement);
    input.remove_prefix(placement);
    entry.append(g.entry, kHeaderBytes, path_bytes + columns_bytes);
    entry.append(input);
    const std::uint64_t hash =
        XXH3_64bits(entry.data() + kHeaderBytes, entry.size() - kHeaderBytes);
    std::memcpy(entry.data() + kHashAt, &hash, sizeof(hash));
    return entry;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace lfprobe;
    const Genuine& g = genuine();
    if (!fuzz::write_cache_entry(data, size, g.entry_path, structured_entry)) {
        return 0;
    }
    try {
        bool hit = false;
        const ScanFile scan = read_scan_file_cached(g.scan_path, {}, g.cache_dir, nullptr, &hit);
        fuzz::check_scan(scan);
        if (!hit) {
            fuzz::expect(scan.positions.size() == 4, "a re-parse of the scan lost points");
        }
    } catch (const InputError&) {
        fuzz::broken_promise("a damaged cache entry made the scan unreadable");
    } catch (const IoError&) {
        fuzz::broken_promise("a damaged cache entry made the scan unreadable");
    }
    return 0;
}
