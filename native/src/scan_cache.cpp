// Binary cache of parsed scan files. An entry is named by a hash of the file's absolute path,
// the read options and the cache format version, so a changed file rewrites its one entry
// instead of leaving stale ones behind; the header repeats those fields with the file's size
// and modification time, so that a hash collision or a stale entry is recognised and ignored.
// The arrays follow the header raw, read back with one copy each.
#include "lfprobe/scan_cache.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <optional>
#include <type_traits>

#include <sys/stat.h>
#include <unistd.h>

#include <tbb/parallel_for.h>

#include "cache_file.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/huge_pages.hpp"
#include "lfprobe/mapped_file.hpp"

// xxHash as a header-only library (Debian's libxxhash-dev): nothing to link.
#define XXH_INLINE_ALL
#include <xxhash.h>

namespace lfprobe {

namespace {

namespace fs = std::filesystem;

// Raise whenever the layout below or the meaning of parsed values changes. 2: the payload's
// checksum.
constexpr std::uint32_t cache_version = 2;
constexpr std::array<char, 8> cache_magic{'L', 'F', 'P', 'C', 'A', 'C', 'H', 'E'};

enum CacheFlags : std::uint32_t {
    has_colors = 1u << 0,
    has_normals = 1u << 1,
    has_intensities = 1u << 2,
    has_scanner = 1u << 3,
};

// The entry's fixed-size header; the path and the columns option follow it, then the arrays.
struct CacheHeader {
    std::array<char, 8> magic;
    std::uint32_t version;
    std::uint32_t format;
    std::uint64_t file_size;
    std::int64_t mtime_ns;
    std::uint64_t point_count;
    std::uint32_t flags;
    std::uint32_t path_bytes;
    std::uint32_t columns_bytes;
    std::uint32_t reserved;
    std::array<double, 3> origin;
    std::array<double, 3> scanner;
    // XXH3-64 of everything after the header (path, columns, arrays): an entry whose values
    // were changed after it was written (a NaN or 3e38 where the scan had a point) is not
    // trusted, but parsed again, as the readers' checks would refuse it.
    std::uint64_t payload_hash;
};
static_assert(std::is_trivially_copyable_v<CacheHeader>);
static_assert(sizeof(CacheHeader) == 112, "the header layout is part of the cache format");

// What identifies the content of a parsed file.
struct CacheKey {
    std::string absolute_path;
    std::uint64_t file_size = 0;
    std::int64_t mtime_ns = 0;
    ScanFormat format = ScanFormat::Auto;
    std::string columns;

    bool operator==(const CacheKey&) const = default;
};

[[nodiscard]] std::optional<CacheKey> key_of(const std::string& path,
                                             const ScanReadOptions& options) {
    const ScanFormat format =
        options.format == ScanFormat::Auto ? scan_format_from_path(path) : options.format;
    struct stat info {};
    if (format == ScanFormat::Auto || ::stat(path.c_str(), &info) != 0 || !S_ISREG(info.st_mode)) {
        return std::nullopt; // let the reader say what is wrong
    }
    std::error_code error;
    fs::path absolute = fs::absolute(path, error);
    if (error) {
        return std::nullopt;
    }
    CacheKey key;
    key.absolute_path = absolute.lexically_normal().string();
    key.file_size = static_cast<std::uint64_t>(info.st_size);
    key.mtime_ns = static_cast<std::int64_t>(info.st_mtim.tv_sec) * 1'000'000'000 +
                   static_cast<std::int64_t>(info.st_mtim.tv_nsec);
    key.format = format;
    key.columns = options.columns;
    return key;
}

// FNV-1a, 64 bits: plenty to name entries; the header fields settle collisions.
class Fnv1a {
public:
    void add(const void* data, std::size_t size) {
        const auto* bytes = static_cast<const unsigned char*>(data);
        for (std::size_t i = 0; i < size; ++i) {
            hash_ = (hash_ ^ bytes[i]) * 0x100000001b3ull;
        }
    }
    template <class T>
    void add_value(const T& value) {
        add(&value, sizeof(value));
    }
    void add_string(const std::string& text) {
        add_value(static_cast<std::uint64_t>(text.size())); // keeps "ab"+"c" apart from "a"+"bc"
        add(text.data(), text.size());
    }
    [[nodiscard]] std::uint64_t value() const { return hash_; }

private:
    std::uint64_t hash_ = 0xcbf29ce484222325ull;
};

[[nodiscard]] fs::path entry_path(const std::string& cache_dir, const CacheKey& key) {
    Fnv1a hash;
    hash.add_value(cache_version);
    hash.add_string(key.absolute_path);
    hash.add_value(static_cast<std::uint32_t>(key.format));
    hash.add_string(key.columns);
    std::array<char, 17> name{};
    std::snprintf(name.data(), name.size(), "%016llx",
                  static_cast<unsigned long long>(hash.value()));
    return fs::path(cache_dir) / (std::string(name.data()) + ".lfpcache");
}

template <class T>
[[nodiscard]] std::size_t array_bytes(std::uint64_t count) {
    return static_cast<std::size_t>(count) * sizeof(T);
}

// Whether a value an entry holds (a coordinate, a point's position, colour or normal, an
// intensity) is finite in every component.
template <typename T, glm::qualifier Q>
[[nodiscard]] bool finite(const glm::vec<3, T, Q>& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

[[nodiscard]] bool finite(float v) {
    return std::isfinite(v);
}

// Copies `count` values from `from` into `values` on all cores, each block checked while it is
// in cache: every value a scan reader returns is finite, so an entry written by a faulty or
// foreign writer is parsed again rather than trusted. A 10 M-point entry took 0.17 s read by one
// thread, a third of it in the page faults of the arrays it filled (now in huge pages).
template <class T>
[[nodiscard]] bool copy_finite(const char* from, std::size_t count, std::vector<T>& values) {
    resize_in_huge_pages(values, count);
    constexpr std::size_t kCopyBlock = std::size_t{1} << 16;
    std::atomic<bool> finite_all{true};
    tbb::parallel_for(
        std::size_t{0}, (count + kCopyBlock - 1) / kCopyBlock, [&](std::size_t block) {
            const std::size_t begin = block * kCopyBlock;
            const std::size_t end = std::min(count, begin + kCopyBlock);
            std::memcpy(values.data() + begin, from + begin * sizeof(T), (end - begin) * sizeof(T));
            bool block_finite = true;
            for (std::size_t i = begin; i < end; ++i) {
                block_finite = block_finite && finite(values[i]);
            }
            if (!block_finite) {
                finite_all.store(false, std::memory_order_relaxed);
            }
        });
    return finite_all.load();
}

// The entry's content when it is complete and matches `key`, else nullopt.
[[nodiscard]] std::optional<ScanFile> load_entry(const fs::path& entry, const CacheKey& key,
                                                 const std::string& path) {
    std::error_code error;
    if (!fs::is_regular_file(entry, error)) {
        return std::nullopt;
    }
    try {
        const MappedFile mapped(entry.string());
        CacheHeader header{};
        if (mapped.size() < sizeof(header)) {
            return std::nullopt;
        }
        std::memcpy(&header, mapped.data(), sizeof(header));
        if (header.magic != cache_magic || header.version != cache_version ||
            header.format != static_cast<std::uint32_t>(key.format) ||
            header.file_size != key.file_size || header.mtime_ns != key.mtime_ns ||
            header.path_bytes != key.absolute_path.size() ||
            header.columns_bytes != key.columns.size()) {
            return std::nullopt;
        }
        // Sizes are checked in a way that cannot overflow, whatever the header says.
        const std::uint64_t n = header.point_count;
        const std::uint64_t per_point = sizeof(glm::vec3) +
                                        ((header.flags & has_colors) ? sizeof(glm::vec3) : 0) +
                                        ((header.flags & has_normals) ? sizeof(glm::vec3) : 0) +
                                        ((header.flags & has_intensities) ? sizeof(float) : 0);
        const std::size_t strings = header.path_bytes + header.columns_bytes;
        const std::size_t fixed = sizeof(header) + strings;
        if (mapped.size() < fixed || n > (mapped.size() - fixed) / per_point ||
            fixed + n * per_point != mapped.size()) {
            return std::nullopt;
        }
        const char* cursor = mapped.data() + sizeof(header);
        if (XXH3_64bits(cursor, mapped.size() - sizeof(header)) != header.payload_hash) {
            return std::nullopt;
        }
        if (std::string_view(cursor, header.path_bytes) != key.absolute_path ||
            std::string_view(cursor + header.path_bytes, header.columns_bytes) != key.columns) {
            return std::nullopt;
        }
        cursor += strings;

        ScanFile scan;
        scan.path = path;
        scan.origin = glm::dvec3(header.origin[0], header.origin[1], header.origin[2]);
        scan.scanner = glm::dvec3(header.scanner[0], header.scanner[1], header.scanner[2]);
        scan.has_scanner = (header.flags & has_scanner) != 0;
        if (!finite(scan.origin) || (scan.has_scanner && !finite(scan.scanner))) {
            return std::nullopt;
        }
        bool values_finite = true;
        auto take = [&](auto& values) {
            using T = typename std::remove_reference_t<decltype(values)>::value_type;
            values_finite =
                values_finite && copy_finite(cursor, static_cast<std::size_t>(n), values);
            cursor += array_bytes<T>(n);
        };
        take(scan.positions);
        if (header.flags & has_colors) {
            take(scan.colors);
        }
        if (header.flags & has_normals) {
            take(scan.normals);
        }
        if (header.flags & has_intensities) {
            take(scan.intensities);
        }
        if (!values_finite) {
            return std::nullopt;
        }
        return scan;
    } catch (const IoError&) {
        return std::nullopt; // unreadable entry: parse instead
    }
}

void write_entry(const fs::path& entry, const CacheKey& key, const ScanFile& scan) {
    cache_file::TemporaryFile temporary(entry);
    const std::string name = temporary.path().string();

    CacheHeader header{};
    header.magic = cache_magic;
    header.version = cache_version;
    header.format = static_cast<std::uint32_t>(key.format);
    header.file_size = key.file_size;
    header.mtime_ns = key.mtime_ns;
    header.point_count = scan.positions.size();
    header.flags =
        (scan.colors.empty() ? 0u : has_colors) | (scan.normals.empty() ? 0u : has_normals) |
        (scan.intensities.empty() ? 0u : has_intensities) | (scan.has_scanner ? has_scanner : 0u);
    header.path_bytes = static_cast<std::uint32_t>(key.absolute_path.size());
    header.columns_bytes = static_cast<std::uint32_t>(key.columns.size());
    header.origin = {scan.origin.x, scan.origin.y, scan.origin.z};
    header.scanner = {scan.scanner.x, scan.scanner.y, scan.scanner.z};
    {
        XXH3_state_t state;
        XXH3_64bits_reset(&state);
        const auto add = [&](const void* data, std::size_t bytes) {
            if (bytes > 0) {
                XXH3_64bits_update(&state, data, bytes);
            }
        };
        add(key.absolute_path.data(), key.absolute_path.size());
        add(key.columns.data(), key.columns.size());
        add(scan.positions.data(), scan.positions.size() * sizeof(glm::vec3));
        add(scan.colors.data(), scan.colors.size() * sizeof(glm::vec3));
        add(scan.normals.data(), scan.normals.size() * sizeof(glm::vec3));
        add(scan.intensities.data(), scan.intensities.size() * sizeof(float));
        header.payload_hash = XXH3_64bits_digest(&state);
    }

    const int fd = cache_file::create_for_writing(name);
    try {
        cache_file::write_all(fd, &header, sizeof(header), name);
        cache_file::write_all(fd, key.absolute_path.data(), key.absolute_path.size(), name);
        cache_file::write_all(fd, key.columns.data(), key.columns.size(), name);
        cache_file::write_all(fd, scan.positions.data(), scan.positions.size() * sizeof(glm::vec3),
                              name);
        cache_file::write_all(fd, scan.colors.data(), scan.colors.size() * sizeof(glm::vec3), name);
        cache_file::write_all(fd, scan.normals.data(), scan.normals.size() * sizeof(glm::vec3),
                              name);
        cache_file::write_all(fd, scan.intensities.data(), scan.intensities.size() * sizeof(float),
                              name);
    } catch (...) {
        ::close(fd);
        throw;
    }
    cache_file::close_written(fd, name);
    temporary.commit_as(entry);
}

} // namespace

std::string scan_cache_entry_path(const std::string& path, const ScanReadOptions& options,
                                  const std::string& cache_dir) {
    const std::optional<CacheKey> key = cache_dir.empty() ? std::nullopt : key_of(path, options);
    return key ? entry_path(cache_dir, *key).string() : std::string();
}

ScanFile read_scan_file_cached(const std::string& path, const ScanReadOptions& options,
                               const std::string& cache_dir, Progress* progress, bool* hit) {
    if (hit != nullptr) {
        *hit = false;
    }
    const std::optional<CacheKey> key = cache_dir.empty() ? std::nullopt : key_of(path, options);
    if (!key) {
        return read_scan_file(path, options, progress);
    }
    const fs::path entry = entry_path(cache_dir, *key);
    if (std::optional<ScanFile> cached = load_entry(entry, *key, path)) {
        if (progress != nullptr) {
            progress->begin_stage("reading cached " + path, 1);
            progress->advance(1);
        }
        if (hit != nullptr) {
            *hit = true;
        }
        return std::move(*cached);
    }

    // Parse errors and cancellation propagate; nothing is written for bad input.
    ScanFile scan = read_scan_file(path, options, progress);

    // A file that changed while it was parsed must not be cached under its old stamp.
    if (key_of(path, options) == key) {
        try {
            std::error_code error;
            fs::create_directories(cache_dir, error);
            if (error) {
                throw IoError("cannot create the folder: " + error.message());
            }
            write_entry(entry, *key, scan);
        } catch (const std::exception& e) {
            // Caching is best-effort: a read-only or full cache disk must not fail the import,
            // but the user hears why the next import will parse again.
            if (progress != nullptr) {
                progress->warn(path + ": the parse cache could not be written in " + cache_dir +
                               " (" + e.what() + "); the scan was read, and will be parsed again " +
                               "next time");
            }
        }
    }
    return scan;
}

PointCloud load_scans(const std::vector<std::string>& paths, const ScanReadOptions& read_options,
                      const MergeOptions& merge_options, const std::string& cache_dir,
                      Progress* progress) {
    if (paths.empty()) {
        throw InputError("load_scans: no scan files given");
    }
    std::vector<ScanFile> files;
    files.reserve(paths.size());
    for (const std::string& path : paths) {
        files.push_back(read_scan_file_cached(path, read_options, cache_dir, progress));
    }
    return merge_scans(std::move(files), merge_options);
}

} // namespace lfprobe
