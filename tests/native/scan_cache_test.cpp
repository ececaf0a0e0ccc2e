// The parsed-scan cache: hits equal the parse bit for bit, anything that changes the file or
// the options misses, damaged entries are ignored, and failures never leave files behind.
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

// The entry checksum (header-only xxHash, as the cache uses it).
#define XXH_INLINE_ALL
#include <xxhash.h>

#include "lfprobe/error.hpp"
#include "lfprobe/progress.hpp"
#include "lfprobe/scan_cache.hpp"
#include "temp_folder.hpp"
#include "test_data.hpp"

using namespace lfprobe;
namespace fs = std::filesystem;

namespace {

fs::path fresh_dir(const std::string& name) {
    return lfprobe::testing::fresh_dir("lfprobe_cache_", name);
}

using lfprobe::testing::write_file;

std::string shared_scan(const std::string& name) {
    return lfprobe::testing::shared_data("scans/" + name);
}

std::vector<fs::path> files_in(const fs::path& dir) {
    std::vector<fs::path> files;
    if (fs::exists(dir)) {
        for (const fs::directory_entry& entry : fs::directory_iterator(dir)) {
            files.push_back(entry.path());
        }
    }
    return files;
}

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() &&
           (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

void expect_same(const ScanFile& a, const ScanFile& b) {
    EXPECT_EQ(a.path, b.path);
    EXPECT_EQ(a.origin, b.origin);
    EXPECT_EQ(a.scanner, b.scanner);
    EXPECT_EQ(a.has_scanner, b.has_scanner);
    EXPECT_TRUE(same_bits(a.positions, b.positions));
    EXPECT_TRUE(same_bits(a.colors, b.colors));
    EXPECT_TRUE(same_bits(a.normals, b.normals));
    EXPECT_TRUE(same_bits(a.intensities, b.intensities));
}

ScanFile cached(const fs::path& path, const fs::path& cache, bool& hit,
                const std::string& columns = "") {
    ScanReadOptions options;
    options.columns = columns;
    return read_scan_file_cached(path.string(), options, cache.string(), nullptr, &hit);
}

const std::string every_channel = "# scanner 1 2 3\n"
                                  "1.5 2 3 7 255 128 0 0 0 2\n"
                                  "4 5 6.25 8 1 2 3 0 3 4\n";

} // namespace

TEST(CacheScan, SecondReadHitsAndEqualsTheParseBitForBit) {
    const fs::path dir = fresh_dir("hit");
    const fs::path cache = dir / "cache" / "nested";
    bool hit = true;
    const ScanFile first =
        read_scan_file_cached(shared_scan("pumpA.pts"), {}, cache.string(), nullptr, &hit);
    EXPECT_FALSE(hit);
    const std::vector<fs::path> entries = files_in(cache);
    ASSERT_EQ(entries.size(), 1u);
    EXPECT_EQ(entries[0].extension(), ".lfpcache");
    EXPECT_EQ(entries[0].stem().string().size(), 16u); // 64-bit hash in hex

    Progress progress;
    const ScanFile second =
        read_scan_file_cached(shared_scan("pumpA.pts"), {}, cache.string(), &progress, &hit);
    EXPECT_TRUE(hit);
    EXPECT_EQ(progress.fraction(), 1.0);
    expect_same(first, second);
    expect_same(second, read_scan_file(shared_scan("pumpA.pts"), {}));

    // Every channel and the scanner survive the round trip.
    const fs::path small = dir / "all.xyz";
    write_file(small, every_channel);
    const ScanFile parsed = cached(small, cache, hit);
    EXPECT_FALSE(hit);
    const ScanFile again = cached(small, cache, hit);
    EXPECT_TRUE(hit);
    EXPECT_TRUE(again.has_scanner);
    EXPECT_EQ(again.normals.size(), 2u);
    EXPECT_EQ(again.intensities.size(), 2u);
    expect_same(parsed, again);
}

TEST(CacheScan, ChangedFileOrOptionsMiss) {
    const fs::path dir = fresh_dir("invalidate");
    const fs::path cache = dir / "cache";
    const fs::path path = dir / "scan.xyz";
    write_file(path, "1 2 3 4\n5 6 7 8\n");
    bool hit = false;
    (void)cached(path, cache, hit);
    (void)cached(path, cache, hit);
    EXPECT_TRUE(hit);

    // Touching the file (a new modification time) misses.
    fs::last_write_time(path, fs::last_write_time(path) + std::chrono::seconds(5));
    const ScanFile touched = cached(path, cache, hit);
    EXPECT_FALSE(hit);
    EXPECT_EQ(touched.intensities[1], 8.0f);
    (void)cached(path, cache, hit);
    EXPECT_TRUE(hit);

    // New content is read, not the old entry.
    write_file(path, "1 2 3 4\n5 6 7 8\n9 10 11 12\n");
    const ScanFile changed = cached(path, cache, hit);
    EXPECT_FALSE(hit);
    EXPECT_EQ(changed.positions.size(), 3u);

    // A changed file replaces its entry rather than adding one.
    std::size_t entries = 0;
    for (const auto& entry : fs::directory_iterator(cache)) {
        entries += entry.path().extension() == ".lfpcache" ? 1 : 0;
    }
    EXPECT_EQ(entries, 1u);

    // The columns option is part of the key.
    const ScanFile renamed = cached(path, cache, hit, "x y z _");
    EXPECT_FALSE(hit);
    EXPECT_TRUE(renamed.intensities.empty());
    (void)cached(path, cache, hit, "x y z _");
    EXPECT_TRUE(hit);
}

// A scan of every channel read once through a fresh cache: its folder, the parse, the entry.
struct CachedScan {
    fs::path cache;
    fs::path path;
    ScanFile reference;
    fs::path entry;
};

CachedScan cached_scan(const std::string& name) {
    const fs::path dir = fresh_dir(name);
    CachedScan c{dir / "cache", dir / "scan.xyz", {}, {}};
    write_file(c.path, every_channel);
    bool hit = false;
    c.reference = cached(c.path, c.cache, hit);
    const std::vector<fs::path> entries = files_in(c.cache);
    EXPECT_EQ(entries.size(), 1u);
    c.entry = entries.at(0);
    return c;
}

TEST(CacheScan, DamagedEntriesAreIgnoredAndRewritten) {
    const auto [cache, path, reference, entry] = cached_scan("corrupt");
    bool hit = false;
    const auto size = fs::file_size(entry);

    auto damage_and_check = [&](const std::string& what, auto damage) {
        damage();
        const ScanFile read = cached(path, cache, hit);
        EXPECT_FALSE(hit) << what;
        expect_same(reference, read);
        (void)cached(path, cache, hit); // the rewritten entry answers again
        EXPECT_TRUE(hit) << what;
    };
    damage_and_check("truncated", [&] { fs::resize_file(entry, size - 5); });
    damage_and_check("too long", [&] { fs::resize_file(entry, size + 12); });
    damage_and_check("empty", [&] { fs::resize_file(entry, 0); });
    damage_and_check("bad magic", [&] {
        std::fstream file(entry, std::ios::binary | std::ios::in | std::ios::out);
        file.write("XX", 2);
    });
    damage_and_check("huge point count", [&] {
        std::fstream file(entry, std::ios::binary | std::ios::in | std::ios::out);
        file.seekp(32); // CacheHeader::point_count
        const std::uint64_t huge = ~std::uint64_t{0} / 2;
        file.write(reinterpret_cast<const char*>(&huge), sizeof(huge));
    });
    damage_and_check("garbage", [&] { write_file(entry, std::string(size, '\x7f')); });
    // Issue 22, item 7: the header still matches the scan, but a point's values were changed
    // (a NaN, a 3e38): the checksum refuses the entry, and the scan is parsed again.
    const auto change_last_point = [&](float value) {
        return [&entry, value] {
            const auto bytes = fs::file_size(entry);
            std::fstream file(entry, std::ios::binary | std::ios::in | std::ios::out);
            file.seekp(static_cast<std::streamoff>(bytes - sizeof(float)));
            file.write(reinterpret_cast<const char*>(&value), sizeof(value));
        };
    };
    damage_and_check("a NaN value", change_last_point(std::numeric_limits<float>::quiet_NaN()));
    damage_and_check("a 3e38 value", change_last_point(3e38f));
    EXPECT_EQ(files_in(cache).size(), 1u); // no temporary files left behind
}

// Found by the cache's fuzz harness (tests/fuzz/scan_cache_fuzzer.cpp): an entry whose checksum
// matches but whose values no reader returns (a faulty or foreign writer) is parsed again too.
TEST(CacheScan, ChecksummedEntriesWithNonFiniteValuesAreParsedAgain) {
    const auto [cache, path, reference, entry] = cached_scan("foreign");
    bool hit = false;
    std::string bytes;
    {
        std::ifstream in(entry, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), {});
    }
    constexpr std::size_t header_bytes = 112; // CacheHeader; its last field is the checksum
    for (const float value :
         {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
        std::string changed = bytes;
        std::memcpy(changed.data() + changed.size() - sizeof(float), &value, sizeof(value));
        const std::uint64_t sum =
            XXH3_64bits(changed.data() + header_bytes, changed.size() - header_bytes);
        std::memcpy(changed.data() + header_bytes - sizeof(sum), &sum, sizeof(sum));
        write_file(entry, changed);
        const ScanFile read = cached(path, cache, hit);
        EXPECT_FALSE(hit) << value;
        expect_same(reference, read);
    }
}

TEST(CacheScan, BadInputAndCancelledParsesWriteNothing) {
    const fs::path dir = fresh_dir("failures");
    const fs::path cache = dir / "cache";
    const fs::path bad = dir / "bad.xyz";
    write_file(bad, "1 2 3\n4 5\n");
    bool hit = true;
    EXPECT_THROW((void)cached(bad, cache, hit), InputError);
    EXPECT_FALSE(hit);
    EXPECT_TRUE(files_in(cache).empty());

    Progress progress;
    progress.request_cancel();
    EXPECT_THROW((void)read_scan_file_cached(shared_scan("pumpA_xyzrgb.xyz"), {}, cache.string(),
                                             &progress, &hit),
                 Cancelled);
    EXPECT_TRUE(files_in(cache).empty());

    EXPECT_THROW((void)read_scan_file_cached((dir / "missing.xyz").string(), {}, cache.string()),
                 IoError);
    EXPECT_TRUE(files_in(cache).empty());
}

TEST(CacheScan, CachingIsBestEffortAndOptional) {
    const fs::path dir = fresh_dir("best_effort");
    const fs::path path = dir / "scan.xyz";
    write_file(path, "1 2 3\n");
    // A cache folder that cannot exist: its parent is a file.
    write_file(dir / "blocker", "");
    bool hit = true;
    const ScanFile scan = cached(path, dir / "blocker" / "cache", hit);
    EXPECT_FALSE(hit);
    EXPECT_EQ(scan.positions.size(), 1u);

    // An empty cache_dir disables the cache.
    hit = true;
    const ScanFile uncached = read_scan_file_cached(path.string(), {}, "", nullptr, &hit);
    EXPECT_FALSE(hit);
    EXPECT_EQ(uncached.positions.size(), 1u);
    EXPECT_EQ(files_in(dir).size(), 2u);
}
