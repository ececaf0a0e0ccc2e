// The entry: a fixed header (magic, version, key, payload size and checksum), then the payload:
// arrays as a 64-bit count and their elements, values raw, surfels field by field (no padding
// bytes reach the file). The header is written last, over a placeholder, once the payload's
// checksum is known.
#include "lfprobe/prepared_cloud_cache.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <vector>

#include <unistd.h>

#include <glm/geometric.hpp>

#include "cache_file.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/mapped_file.hpp"

#define XXH_INLINE_ALL
#include <xxhash.h>

namespace lfprobe {

namespace {

namespace fs = std::filesystem;

// Raise whenever the layout or the meaning of what is stored changes (a change to how normals,
// spacing or the hierarchy are computed included).
constexpr std::uint32_t kPreparedCloudVersion = 1;
constexpr std::array<char, 8> kPreparedCloudMagic{'L', 'F', 'P', 'P', 'R', 'E', 'P', '1'};

struct Header {
    std::array<char, 8> magic;
    std::uint32_t version;
    std::uint32_t reserved;
    std::array<std::uint64_t, 2> key;
    std::uint64_t point_count;
    std::uint64_t payload_bytes;
    std::uint64_t payload_hash;
};

// Buffers small values, hashes everything written, and writes large arrays straight through.
class EntryWriter {
public:
    EntryWriter(int fd, std::string name) : fd_(fd), name_(std::move(name)) {
        XXH3_64bits_reset(&state_);
        buffer_.reserve(kBuffer);
    }

    void bytes(const void* data, std::size_t size) {
        if (size == 0) {
            return;
        }
        XXH3_64bits_update(&state_, data, size);
        written_ += size;
        if (buffer_.size() + size > kBuffer) {
            flush();
        }
        if (size >= kBuffer) {
            cache_file::write_all(fd_, data, size, name_);
            return;
        }
        const auto* p = static_cast<const char*>(data);
        buffer_.insert(buffer_.end(), p, p + size);
    }
    template <class T>
    void value(const T& v) {
        bytes(&v, sizeof(T));
    }
    template <class T>
    void array(const std::vector<T>& v) {
        value(static_cast<std::uint64_t>(v.size()));
        bytes(v.data(), v.size() * sizeof(T));
    }
    void flush() {
        cache_file::write_all(fd_, buffer_.data(), buffer_.size(), name_);
        buffer_.clear();
    }
    [[nodiscard]] std::uint64_t hash() const { return XXH3_64bits_digest(&state_); }
    [[nodiscard]] std::uint64_t written() const { return written_; }

private:
    static constexpr std::size_t kBuffer = 1 << 20;
    int fd_;
    std::string name_;
    XXH3_state_t state_{};
    std::vector<char> buffer_;
    std::uint64_t written_ = 0;
};

// Reads the payload back; every read checks the bytes left, so a damaged entry is refused.
class EntryReader {
public:
    EntryReader(const char* data, std::size_t size) : p_(data), left_(size) {}

    template <class T>
    bool value(T& out) {
        if (left_ < sizeof(T)) {
            return false;
        }
        std::memcpy(&out, p_, sizeof(T));
        p_ += sizeof(T);
        left_ -= sizeof(T);
        return true;
    }
    template <class T>
    bool array(std::vector<T>& out) {
        std::uint64_t count = 0;
        if (!value(count) || count > left_ / std::max<std::size_t>(sizeof(T), 1)) {
            return false;
        }
        out.resize(static_cast<std::size_t>(count));
        const std::size_t size = out.size() * sizeof(T);
        if (size > 0) { // an empty vector's data() may be null, which memcpy must not get
            std::memcpy(out.data(), p_, size);
        }
        p_ += size;
        left_ -= size;
        return true;
    }
    [[nodiscard]] bool done() const { return left_ == 0; }
    [[nodiscard]] std::size_t left() const { return left_; }

private:
    const char* p_;
    std::size_t left_;
};

// Calls `field` on each of a surfel's fields in the entry's order, while it returns true: the
// writer and the reader walk the same list.
template <class Surfel, class Field>
bool each_surfel_field(Surfel& s, Field&& field) {
    return field(s.position) && field(s.normal) && field(s.colour) && field(s.spacing) &&
           field(s.count) && field(s.facing) && field(s.oriented);
}

void write_surfels(EntryWriter& w, const std::vector<CellSurfel>& surfels) {
    w.value(static_cast<std::uint64_t>(surfels.size()));
    for (const CellSurfel& s : surfels) {
        each_surfel_field(s, [&](const auto& v) {
            w.value(v);
            return true;
        });
    }
}

bool read_surfels(EntryReader& r, std::vector<CellSurfel>& surfels) {
    std::uint64_t count = 0;
    constexpr std::size_t kSurfelBytes = 3 * sizeof(glm::vec3) + sizeof(float) + 4 + 2;
    if (!r.value(count) || count > r.left() / kSurfelBytes) {
        return false;
    }
    surfels.resize(static_cast<std::size_t>(count));
    return std::all_of(surfels.begin(), surfels.end(), [&](CellSurfel& s) {
        return each_surfel_field(s, [&](auto& v) { return r.value(v); });
    });
}

// Runs of `runs` (entries + 1 offsets) that are nondecreasing and end within `limit`.
bool valid_runs(const std::vector<std::uint32_t>& runs, std::size_t entries, std::size_t limit,
                bool exact_end) {
    if (runs.size() != entries + 1 || runs.front() != 0) {
        return false;
    }
    if (!std::is_sorted(runs.begin(), runs.end())) {
        return false;
    }
    return exact_end ? runs.back() == limit : runs.back() <= limit;
}

bool all_below(const std::vector<std::uint32_t>& indices, std::size_t limit) {
    return std::all_of(indices.begin(), indices.end(), [&](std::uint32_t i) { return i < limit; });
}

// What the computation gives: finite unit-or-zero normals, finite spacings of 0 or more.
bool plausible(const std::vector<glm::vec3>& normals, const std::vector<float>& spacing) {
    return std::all_of(normals.begin(), normals.end(), cache_file::plausible_normal) &&
           std::all_of(spacing.begin(), spacing.end(),
                       [](float s) { return std::isfinite(s) && s >= 0.0f; });
}

bool plausible(const std::vector<CellSurfel>& surfels) {
    return std::all_of(surfels.begin(), surfels.end(), [](const CellSurfel& s) {
        return cache_file::finite(s.position) && cache_file::plausible_normal(s.normal) &&
               cache_file::finite(s.colour) && std::isfinite(s.spacing) && s.spacing >= 0.0f &&
               s.facing <= 6 && s.oriented <= 1;
    });
}

// What the bake relies on of a geometry and a hierarchy it did not compute itself: the
// checksum proves an entry is what was written, these that a writer other than this one (or
// a faulty one) cannot make the bake read out of bounds or convert non-finite values.
bool consistent(const PreparedCloud& p, std::size_t n) {
    const LocalGeometry& g = p.geometry;
    if (g.normals.size() != n || g.spacing.size() != n || g.oriented.size() != n ||
        (!g.edges.empty() && g.edges.size() != n) || g.spatial_order.size() != n ||
        !all_below(g.spatial_order, n) || !plausible(g.normals, g.spacing)) {
        return false;
    }
    const PointHierarchy& h = p.hierarchy;
    if (h.levels.empty()) {
        return h.order.empty() || (h.order.size() == n && all_below(h.order, n));
    }
    if (h.order.size() != n || !all_below(h.order, n) || !cache_file::finite(h.origin) ||
        !(std::isfinite(h.cube_size) && h.cube_size > 0.0f) ||
        !(std::isfinite(h.intensity.min) && std::isfinite(h.intensity.scale))) {
        return false;
    }
    for (std::size_t l = 0; l < h.levels.size(); ++l) {
        const PointHierarchy::Level& level = h.levels[l];
        const std::size_t cells = level.cell_count();
        if (!valid_runs(level.first_point, cells, n, false) ||
            !valid_runs(level.first_surfel, cells, level.surfels.size(), true) ||
            !(std::isfinite(level.cell_size) && level.cell_size > 0.0f) || level.shift < 0 ||
            level.shift > 63 || !plausible(level.surfels)) {
            return false;
        }
        if (l == 0 ? !level.first_child.empty()
                   : !valid_runs(level.first_child, cells, h.levels[l - 1].cell_count(), false)) {
            return false;
        }
    }
    return true;
}

} // namespace

PreparedCloudKey prepared_cloud_key(const PointCloud& cloud, const LocalGeometryOptions& options,
                                    bool with_hierarchy) {
    XXH3_state_t state;
    XXH3_128bits_reset(&state);
    const auto add = [&](const void* data, std::size_t size) {
        if (size > 0) {
            XXH3_128bits_update(&state, data, size);
        }
    };
    const auto add_array = [&](const auto& v) {
        const auto count = static_cast<std::uint64_t>(v.size());
        add(&count, sizeof(count));
        add(v.data(), v.size() * sizeof(v[0]));
    };
    add(&kPreparedCloudVersion, sizeof(kPreparedCloudVersion));
    const std::array<std::int32_t, 4> settings{
        options.normal_neighbours, options.spacing_neighbours, options.keep_file_normals ? 1 : 0,
        with_hierarchy ? 1 : 0};
    add(settings.data(), sizeof(settings));
    add(&cloud.world_offset, sizeof(cloud.world_offset));
    add_array(cloud.positions);
    add_array(cloud.colors);
    add_array(cloud.normals);
    add_array(cloud.intensities);
    add_array(cloud.scan_index);
    for (const ScanSource& scan : cloud.scans) {
        const std::array<double, 4> scanner{scan.scanner.x, scan.scanner.y, scan.scanner.z,
                                            scan.has_scanner ? 1.0 : 0.0};
        add(scanner.data(), sizeof(scanner));
        add(&scan.point_count, sizeof(scan.point_count));
    }
    const XXH128_hash_t hash = XXH3_128bits_digest(&state);
    return {{hash.high64, hash.low64}, static_cast<std::uint64_t>(cloud.size())};
}

std::string prepared_cloud_key_hex(const PreparedCloudKey& key) {
    std::array<char, 33> name{};
    std::snprintf(name.data(), name.size(), "%016llx%016llx",
                  static_cast<unsigned long long>(key.hash[0]),
                  static_cast<unsigned long long>(key.hash[1]));
    return name.data();
}

std::string prepared_cloud_entry_path(const PreparedCloudKey& key, const std::string& cache_dir) {
    if (cache_dir.empty()) {
        return {};
    }
    return (fs::path(cache_dir) / ("prepared-" + prepared_cloud_key_hex(key) + ".lfpprep"))
        .string();
}

std::optional<PreparedCloud> read_prepared_cloud(const std::string& entry,
                                                 const PreparedCloudKey& key) {
    std::error_code error;
    if (entry.empty() || !fs::is_regular_file(entry, error)) {
        return std::nullopt;
    }
    try {
        const MappedFile file(entry);
        Header header{};
        if (file.size() < sizeof(Header)) {
            return std::nullopt;
        }
        std::memcpy(&header, file.data(), sizeof(Header));
        if (header.magic != kPreparedCloudMagic || header.version != kPreparedCloudVersion ||
            header.key != key.hash || header.point_count != key.point_count ||
            header.payload_bytes != file.size() - sizeof(Header)) {
            return std::nullopt;
        }
        const char* payload = file.data() + sizeof(Header);
        if (XXH3_64bits(payload, header.payload_bytes) != header.payload_hash) {
            return std::nullopt;
        }
        EntryReader r(payload, header.payload_bytes);
        PreparedCloud p;
        LocalGeometry& g = p.geometry;
        PointHierarchy& h = p.hierarchy;
        std::uint64_t levels = 0;
        bool ok = r.array(g.normals) && r.array(g.spacing) && r.array(g.oriented) &&
                  r.array(g.edges) && r.array(g.spatial_order) && r.value(h.intensity) &&
                  r.value(h.origin) && r.value(h.cube_size) && r.array(h.order) &&
                  r.value(levels) && levels <= 64;
        if (ok) {
            h.levels.resize(static_cast<std::size_t>(levels));
        }
        for (std::size_t l = 0; ok && l < h.levels.size(); ++l) {
            PointHierarchy::Level& level = h.levels[l];
            ok = r.value(level.shift) && r.value(level.cell_size) && r.array(level.cell_keys) &&
                 r.array(level.first_point) && r.array(level.first_child) &&
                 r.array(level.first_surfel) && read_surfels(r, level.surfels);
        }
        if (!ok || !r.done() || !consistent(p, static_cast<std::size_t>(key.point_count))) {
            return std::nullopt;
        }
        return p;
    } catch (const IoError&) {
        return std::nullopt; // unreadable: computed again
    }
}

void write_prepared_cloud(const std::string& entry, const PreparedCloudKey& key,
                          const LocalGeometry& geometry, const PointHierarchy& hierarchy) {
    const fs::path path(entry);
    std::error_code error;
    fs::create_directories(path.parent_path(), error);
    if (error) {
        throw IoError(path.parent_path().string() + ": cannot create the cache folder (" +
                      error.message() + ")");
    }
    cache_file::TemporaryFile temporary(path);
    const std::string name = temporary.path().string();
    const int fd = cache_file::create_for_writing(name);
    try {
        Header header{};
        cache_file::write_all(fd, &header, sizeof(header), name); // a placeholder
        EntryWriter w(fd, name);
        w.array(geometry.normals);
        w.array(geometry.spacing);
        w.array(geometry.oriented);
        w.array(geometry.edges);
        w.array(geometry.spatial_order);
        w.value(hierarchy.intensity);
        w.value(hierarchy.origin);
        w.value(hierarchy.cube_size);
        w.array(hierarchy.order);
        w.value(static_cast<std::uint64_t>(hierarchy.levels.size()));
        for (const PointHierarchy::Level& level : hierarchy.levels) {
            w.value(level.shift);
            w.value(level.cell_size);
            w.array(level.cell_keys);
            w.array(level.first_point);
            w.array(level.first_child);
            w.array(level.first_surfel);
            write_surfels(w, level.surfels);
        }
        w.flush();
        header.magic = kPreparedCloudMagic;
        header.version = kPreparedCloudVersion;
        header.key = key.hash;
        header.point_count = key.point_count;
        header.payload_bytes = w.written();
        header.payload_hash = w.hash();
        if (::pwrite(fd, &header, sizeof(header), 0) != static_cast<ssize_t>(sizeof(header))) {
            throw IoError(name + ": cannot write the header");
        }
    } catch (...) {
        ::close(fd);
        throw;
    }
    cache_file::close_written(fd, name);
    temporary.commit_as(path);
}

bool try_write_prepared_cloud(const std::string& entry, const PreparedCloudKey& key,
                              const LocalGeometry& geometry, const PointHierarchy& hierarchy) {
    try {
        write_prepared_cloud(entry, key, geometry, hierarchy);
        return true;
    } catch (const IoError&) {
    } catch (const std::filesystem::filesystem_error&) {
    }
    return false;
}

LocalGeometry cached_local_geometry(const PointCloud& cloud, const std::string& cache_dir,
                                    Progress* progress) {
    if (cache_dir.empty()) {
        return estimate_local_geometry(cloud, {}, progress);
    }
    const LocalGeometryOptions options;
    PreparedCloudKey key;
    for (const bool with_hierarchy : {true, false}) {
        key = prepared_cloud_key(cloud, options, with_hierarchy);
        if (std::optional<PreparedCloud> cached =
                read_prepared_cloud(prepared_cloud_entry_path(key, cache_dir), key)) {
            return std::move(cached->geometry);
        }
    }
    // `key` is now the geometry-only entry's.
    LocalGeometry geometry = estimate_local_geometry(cloud, options, progress);
    (void)try_write_prepared_cloud(prepared_cloud_entry_path(key, cache_dir), key, geometry, {});
    return geometry;
}

} // namespace lfprobe
