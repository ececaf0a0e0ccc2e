// The file: a header and a section table (checksummed together), then every section on pages
// of its own: the points' records in Morton order (positions, colours, normals, spacing,
// orientation, edges), then per level of the hierarchy its cell keys, runs and surfels. Values
// are raw, in this machine's layout (the file is a cache for the machines of one job, as the
// prepared-cloud cache is); surfels go in as CellSurfel records with zeroed padding.
#include "lfprobe/spatial_cloud.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <type_traits>
#include <vector>

#include <unistd.h>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vector_relational.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "cache_file.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/octahedral.hpp"
#include "lfprobe/point_colours.hpp"

#define XXH_INLINE_ALL
#include <xxhash.h>

namespace lfprobe {

namespace {

namespace fs = std::filesystem;

// Raise whenever the layout or the meaning of what is stored changes.
constexpr std::uint32_t kSpatialCloudVersion = 1;
constexpr std::array<char, 8> kSpatialCloudMagic{'L', 'F', 'P', 'S', 'P', 'A', 'T', '1'};
constexpr std::size_t kPage = 4096;
constexpr std::size_t kMaxCloudLevels = 64;
constexpr std::size_t kChunk = std::size_t{1} << 16; // records per write

struct FileSection {
    std::uint64_t offset;
    std::uint64_t count;
};

enum PointSection { kPositions, kColours, kNormals, kSpacing, kOriented, kEdges, kPointSections };
enum LevelSection { kCellKeys, kFirstPoint, kFirstChild, kFirstSurfel, kSurfels, kLevelSections };

struct FileHeader {
    std::array<char, 8> magic;
    std::uint32_t version;
    std::uint32_t has_edges;
    std::array<std::uint64_t, 2> key;
    std::uint64_t point_count;
    std::array<float, 3> origin;
    float cube_size;
    std::uint32_t level_count;
    std::uint32_t reserved;
    std::uint64_t table_hash; // XXH3 of the header (this field 0) and the level table after it
    std::array<FileSection, kPointSections> points;
};

struct FileLevel {
    std::int32_t shift;
    float cell_size;
    std::array<FileSection, kLevelSections> sections;
};

// Written and read as raw bytes: no padding may carry stray bytes into the file.
static_assert(sizeof(FileHeader) == 72 + kPointSections * sizeof(FileSection));
static_assert(sizeof(FileLevel) == 8 + kLevelSections * sizeof(FileSection));
static_assert(std::is_trivially_copyable_v<CellSurfel> && std::is_standard_layout_v<CellSurfel>);

std::size_t round_up(std::size_t bytes) {
    return (bytes + kPage - 1) / kPage * kPage;
}

std::size_t table_bytes(std::size_t levels) {
    return sizeof(FileHeader) + levels * sizeof(FileLevel);
}

std::uint64_t table_hash(FileHeader header, const std::vector<FileLevel>& levels) {
    header.table_hash = 0;
    XXH3_state_t state;
    XXH3_64bits_reset(&state);
    XXH3_64bits_update(&state, &header, sizeof(header));
    if (!levels.empty()) {
        XXH3_64bits_update(&state, levels.data(), levels.size() * sizeof(FileLevel));
    }
    return XXH3_64bits_digest(&state);
}

// Appends sections to the file, each starting on a page of its own.
class SectionWriter {
public:
    SectionWriter(int fd, std::string name, std::size_t at, Progress* progress)
        : fd_(fd), name_(std::move(name)), at_(at), progress_(progress) {}

    // `count` records of `record_bytes` each; fill(first, n, out) writes records first … first
    // + n - 1 into `out`, which starts zeroed.
    template <class Fill>
    FileSection section(std::size_t count, std::size_t record_bytes, Fill&& fill) {
        pad();
        const FileSection s{at_, count};
        std::vector<char> buffer;
        for (std::size_t first = 0; first < count; first += kChunk) {
            if (progress_ != nullptr) {
                progress_->throw_if_cancelled();
            }
            const std::size_t n = std::min(kChunk, count - first);
            buffer.assign(n * record_bytes, 0);
            fill(first, n, buffer.data());
            cache_file::write_all(fd_, buffer.data(), buffer.size(), name_);
            at_ += buffer.size();
        }
        return s;
    }
    template <class T>
    FileSection array(const std::vector<T>& values) {
        return section(values.size(), sizeof(T), [&](std::size_t first, std::size_t n, char* out) {
            std::memcpy(out, values.data() + first, n * sizeof(T));
        });
    }
    // values[order[k]] for k = 0 … count - 1: the points in Morton order (`order` null: the
    // values are in that order already).
    template <class T, class Value>
    FileSection in_order(const std::uint32_t* order, std::size_t count, Value&& value) {
        return section(count, sizeof(T), [&](std::size_t first, std::size_t n, char* out) {
            for (std::size_t k = 0; k < n; ++k) {
                const T v = value(order != nullptr ? order[first + k]
                                                   : static_cast<std::uint32_t>(first + k));
                std::memcpy(out + k * sizeof(T), &v, sizeof(T));
            }
        });
    }

private:
    void pad() {
        const std::size_t to = round_up(at_);
        if (to > at_) {
            const std::vector<char> zeros(to - at_, 0);
            cache_file::write_all(fd_, zeros.data(), zeros.size(), name_);
            at_ = to;
        }
    }

    int fd_;
    std::string name_;
    std::size_t at_;
    Progress* progress_;
};

FileSection write_surfels(SectionWriter& w, const std::vector<CellSurfel>& surfels) {
    return w.section(surfels.size(), sizeof(CellSurfel),
                     [&](std::size_t first, std::size_t n, char* out) {
                         for (std::size_t k = 0; k < n; ++k) {
                             const CellSurfel& s = surfels[first + k];
                             char* r = out + k * sizeof(CellSurfel);
                             const auto put = [r](std::size_t offset, const auto& v) {
                                 std::memcpy(r + offset, &v, sizeof(v));
                             };
                             put(offsetof(CellSurfel, position), s.position);
                             put(offsetof(CellSurfel, normal), s.normal);
                             put(offsetof(CellSurfel, colour), s.colour);
                             put(offsetof(CellSurfel, spacing), s.spacing);
                             put(offsetof(CellSurfel, count), s.count);
                             put(offsetof(CellSurfel, facing), s.facing);
                             put(offsetof(CellSurfel, oriented), s.oriented);
                         }
                     });
}

// Bounds on what a genuine file holds, so that a damaged one cannot feed the bake values it
// cannot square (a length of a position beyond 1e19 overflows a float): every point and surfel
// lies in the hierarchy's bounding cube, every spacing is less than a few cubes.
constexpr float kMaxCoordinate = 1e12f;

struct PlausibleRange {
    glm::vec3 lo;
    glm::vec3 hi;
    float max_spacing;

    PlausibleRange(const glm::vec3& origin, float cube) {
        const float slack = 1e-3f * cube;
        lo = origin - glm::vec3(slack);
        hi = origin + glm::vec3(cube + slack);
        max_spacing = 4.0f * cube;
    }
    [[nodiscard]] bool holds(const glm::vec3& p) const {
        return p.x >= lo.x && p.y >= lo.y && p.z >= lo.z && p.x <= hi.x && p.y <= hi.y &&
               p.z <= hi.z;
    }
    [[nodiscard]] bool spacing(float s) const { return s >= 0.0f && s <= max_spacing; }
};

// An edge that claims an offset names a direction (surface_edge's inward is a unit vector ×127).
bool plausible_edge(const SurfaceEdge& e) {
    return e.offset == 0 || e.inward[0] != 0 || e.inward[1] != 0 || e.inward[2] != 0;
}

[[noreturn]] void damaged(const std::string& path, const std::string& what) {
    throw IoError(path + ": not a usable spatial cloud (" + what + ")");
}

} // namespace

std::string spatial_cloud_entry_path(const PreparedCloudKey& key, const std::string& cache_dir) {
    if (cache_dir.empty()) {
        return {};
    }
    return (fs::path(cache_dir) / ("spatial-" + prepared_cloud_key_hex(key) + ".lfpspatial"))
        .string();
}

namespace {

// write_spatial_cloud of `cloud` and `geometry` in their own order (`in_curve_order` false: the
// hierarchy's order permutes them) or already in curve order (a CurveOrderedCloud).
void write_spatial_cloud_of_points(const std::string& path, const PreparedCloudKey& key,
                                   const PointCloud& cloud, const LocalGeometry& geometry,
                                   const PointHierarchy& hierarchy, bool in_curve_order,
                                   Progress* progress) {
    const std::size_t n = cloud.size();
    if (hierarchy.levels.empty() || hierarchy.levels.size() > kMaxCloudLevels ||
        hierarchy.order.size() != n || geometry.normals.size() != n ||
        geometry.spacing.size() != n || geometry.oriented.size() != n ||
        (!geometry.edges.empty() && geometry.edges.size() != n) || key.point_count != n) {
        throw InputError("spatial cloud: needs the cloud's geometry and a point hierarchy with "
                         "levels, all of the same cloud");
    }
    if (progress != nullptr) {
        progress->begin_stage("writing the spatial cloud", 1);
    }
    const fs::path target(path);
    std::error_code error;
    fs::create_directories(target.parent_path(), error);
    if (error) {
        throw IoError(target.parent_path().string() + ": cannot create the cache folder (" +
                      error.message() + ")");
    }
    cache_file::TemporaryFile temporary(target);
    const std::string name = temporary.path().string();
    const int fd = cache_file::create_for_writing(name);
    try {
        const std::size_t table = table_bytes(hierarchy.levels.size());
        const std::vector<char> placeholder(round_up(table), 0);
        cache_file::write_all(fd, placeholder.data(), placeholder.size(), name);
        SectionWriter w(fd, name, placeholder.size(), progress);

        FileHeader header{};
        header.magic = kSpatialCloudMagic;
        header.version = kSpatialCloudVersion;
        header.has_edges = geometry.edges.empty() ? 0 : 1;
        header.key = key.hash;
        header.point_count = n;
        header.origin = {hierarchy.origin.x, hierarchy.origin.y, hierarchy.origin.z};
        header.cube_size = hierarchy.cube_size;
        header.level_count = static_cast<std::uint32_t>(hierarchy.levels.size());
        const std::uint32_t* order = in_curve_order ? nullptr : hierarchy.order.data();
        const PointColours colour_of(cloud, hierarchy.intensity);
        header.points[kPositions] =
            w.in_order<glm::vec3>(order, n, [&](std::uint32_t i) { return cloud.positions[i]; });
        header.points[kColours] =
            w.in_order<glm::vec3>(order, n, [&](std::uint32_t i) { return colour_of(i); });
        header.points[kNormals] =
            w.in_order<glm::vec3>(order, n, [&](std::uint32_t i) { return geometry.normals[i]; });
        header.points[kSpacing] =
            w.in_order<float>(order, n, [&](std::uint32_t i) { return geometry.spacing[i]; });
        header.points[kOriented] = w.in_order<std::uint8_t>(
            order, n, [&](std::uint32_t i) { return geometry.oriented[i]; });
        header.points[kEdges] = geometry.edges.empty()
                                    ? FileSection{0, 0}
                                    : w.in_order<SurfaceEdge>(order, n, [&](std::uint32_t i) {
                                          return geometry.edges[i];
                                      });
        std::vector<FileLevel> levels;
        for (const PointHierarchy::Level& level : hierarchy.levels) {
            FileLevel l{};
            l.shift = level.shift;
            l.cell_size = level.cell_size;
            l.sections[kCellKeys] = w.array(level.cell_keys);
            l.sections[kFirstPoint] = w.array(level.first_point);
            l.sections[kFirstChild] = w.array(level.first_child);
            l.sections[kFirstSurfel] = w.array(level.first_surfel);
            l.sections[kSurfels] = write_surfels(w, level.surfels);
            levels.push_back(l);
        }
        header.table_hash = table_hash(header, levels);
        if (::pwrite(fd, &header, sizeof(header), 0) != static_cast<ssize_t>(sizeof(header)) ||
            ::pwrite(fd, levels.data(), levels.size() * sizeof(FileLevel), sizeof(header)) !=
                static_cast<ssize_t>(levels.size() * sizeof(FileLevel))) {
            throw IoError(name + ": cannot write the section table");
        }
    } catch (...) {
        ::close(fd);
        throw;
    }
    cache_file::close_written(fd, name);
    temporary.commit_as(target);
}

} // namespace

void write_spatial_cloud(const std::string& path, const PreparedCloudKey& key,
                         const PointCloud& cloud, const LocalGeometry& geometry,
                         const PointHierarchy& hierarchy, Progress* progress) {
    write_spatial_cloud_of_points(path, key, cloud, geometry, hierarchy, false, progress);
}

void write_spatial_cloud(const std::string& path, const PreparedCloudKey& key,
                         const CurveOrderedCloud& curve, const PointHierarchy& hierarchy,
                         Progress* progress) {
    write_spatial_cloud_of_points(path, key, curve.points, curve.geometry, hierarchy, true,
                                  progress);
}

SpatialCloud::SpatialCloud(const std::string& path, const std::string& key_hex)
    : file_(path, MappedFile::Access::in_parts) {
    FileHeader header{};
    if (file_.size() < sizeof(header)) {
        damaged(path, "shorter than its header");
    }
    std::memcpy(&header, file_.data(), sizeof(header));
    if (header.magic != kSpatialCloudMagic) {
        damaged(path, "not a spatial cloud file");
    }
    if (header.version != kSpatialCloudVersion) {
        damaged(path, "version " + std::to_string(header.version) + ", this build reads " +
                          std::to_string(kSpatialCloudVersion));
    }
    if (prepared_cloud_key_hex({header.key, header.point_count}) != key_hex) {
        damaged(path, "written for another cloud than " + key_hex);
    }
    if (header.level_count == 0 || header.level_count > kMaxCloudLevels ||
        file_.size() < table_bytes(header.level_count)) {
        damaged(path, "its section table is cut short");
    }
    std::vector<FileLevel> levels(header.level_count);
    std::memcpy(levels.data(), file_.data() + sizeof(header), levels.size() * sizeof(FileLevel));
    if (table_hash(header, levels) != header.table_hash) {
        damaged(path, "its section table fails its checksum");
    }
    const std::size_t n = header.point_count;
    const glm::vec3 origin(header.origin[0], header.origin[1], header.origin[2]);
    if (n > std::numeric_limits<std::uint32_t>::max() || header.has_edges > 1 ||
        !cache_file::finite(origin) ||
        glm::any(glm::greaterThan(glm::abs(origin), glm::vec3(kMaxCoordinate))) ||
        !(header.cube_size > 0.0f && header.cube_size <= kMaxCoordinate)) {
        damaged(path, "its header's values are out of range");
    }
    // A section of `count` records of `size` bytes, on a page boundary and within the file.
    const auto check = [&](const FileSection& s, std::size_t count, std::size_t size) {
        if (s.count != count || (count > 0 && (s.offset % kPage != 0 || s.offset > file_.size() ||
                                               count > (file_.size() - s.offset) / size))) {
            damaged(path, "a section lies outside the file or has the wrong length");
        }
        return Section{static_cast<std::size_t>(s.offset), count};
    };
    positions_ = check(header.points[kPositions], n, sizeof(glm::vec3));
    colours_ = check(header.points[kColours], n, sizeof(glm::vec3));
    normals_ = check(header.points[kNormals], n, sizeof(glm::vec3));
    spacing_ = check(header.points[kSpacing], n, sizeof(float));
    oriented_ = check(header.points[kOriented], n, sizeof(std::uint8_t));
    edges_ = check(header.points[kEdges], header.has_edges != 0 ? n : 0, sizeof(SurfaceEdge));

    hierarchy_.origin = glm::vec3(header.origin[0], header.origin[1], header.origin[2]);
    hierarchy_.cube_size = header.cube_size;
    hierarchy_.point_count = n;
    for (std::size_t l = 0; l < levels.size(); ++l) {
        const FileLevel& fl = levels[l];
        if (fl.shift < 0 || fl.shift > 63 ||
            !(std::isfinite(fl.cell_size) && fl.cell_size > 0.0f)) {
            damaged(path, "a level's cell size is out of range");
        }
        const std::size_t cells = fl.sections[kCellKeys].count;
        const std::size_t runs = cells + 1;
        const Section keys = check(fl.sections[kCellKeys], cells, sizeof(std::uint64_t));
        const Section first_point = check(fl.sections[kFirstPoint], runs, sizeof(std::uint32_t));
        const Section first_child =
            check(fl.sections[kFirstChild], l == 0 ? 0 : runs, sizeof(std::uint32_t));
        const Section first_surfel = check(fl.sections[kFirstSurfel], runs, sizeof(std::uint32_t));
        const std::size_t surfel_count = fl.sections[kSurfels].count;
        const Section surfels = check(fl.sections[kSurfels], surfel_count, sizeof(CellSurfel));
        const auto* base = reinterpret_cast<const std::byte*>(file_.data());
        const auto u32 = [&](const Section& s) {
            return std::span<const std::uint32_t>(
                reinterpret_cast<const std::uint32_t*>(base + s.offset), s.count);
        };
        PointHierarchyView::Level level;
        level.shift = fl.shift;
        level.cell_size = fl.cell_size;
        level.cell_keys = std::span<const std::uint64_t>(
            reinterpret_cast<const std::uint64_t*>(base + keys.offset), keys.count);
        level.first_point = u32(first_point);
        level.first_child = u32(first_child);
        level.first_surfel = u32(first_surfel);
        level.surfels = base + surfels.offset;
        level.surfel_count = surfels.count;
        hierarchy_.levels.push_back(level);
    }
}

template <class T>
T SpatialCloud::read(const Section& section, std::size_t i) const {
    T value;
    std::memcpy(&value, file_.data() + section.offset + i * sizeof(T), sizeof(T));
    return value;
}

void SpatialCloud::gather(HierarchyCut& cut, PointCloud& points, LocalGeometry& geometry) const {
    const std::size_t m = cut.points.size();
    points = PointCloud{};
    geometry = LocalGeometry{};
    points.positions.resize(m);
    points.colors.resize(m);
    geometry.normals.resize(m);
    geometry.spacing.resize(m);
    geometry.oriented.resize(m);
    geometry.edges.resize(edges_.count > 0 ? m : 0);
    const PlausibleRange plausible(hierarchy_.origin, hierarchy_.cube_size);
    std::atomic<bool> bad{false};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m, 4096),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          bool ok = true;
                          for (std::size_t j = range.begin(); j < range.end(); ++j) {
                              const std::uint32_t k = cut.points[j];
                              if (k >= point_count()) {
                                  ok = false;
                                  break;
                              }
                              points.positions[j] = read<glm::vec3>(positions_, k);
                              points.colors[j] = read<glm::vec3>(colours_, k);
                              geometry.normals[j] = read<glm::vec3>(normals_, k);
                              geometry.spacing[j] = read<float>(spacing_, k);
                              geometry.oriented[j] = read<std::uint8_t>(oriented_, k);
                              if (!geometry.edges.empty()) {
                                  geometry.edges[j] = read<SurfaceEdge>(edges_, k);
                              }
                              ok = ok && plausible.holds(points.positions[j]) &&
                                   cache_file::finite(points.colors[j]) &&
                                   cache_file::plausible_normal(geometry.normals[j]) &&
                                   plausible.spacing(geometry.spacing[j]) &&
                                   geometry.oriented[j] <= 1 &&
                                   (geometry.edges.empty() || plausible_edge(geometry.edges[j]));
                              cut.points[j] = static_cast<std::uint32_t>(j);
                          }
                          if (!ok) {
                              bad = true;
                          }
                      });
    if (bad) {
        damaged(path(), "a point's values are not finite or out of range");
    }
    const bool surfels_ok =
        std::all_of(cut.surfels.begin(), cut.surfels.end(), [&](const CellSurfel& s) {
            return plausible.holds(s.position) && cache_file::plausible_normal(s.normal) &&
                   cache_file::finite(s.colour) && plausible.spacing(s.spacing) && s.facing <= 6 &&
                   s.oriented <= 1;
        });
    if (!surfels_ok) {
        damaged(path(), "a surfel's values are not finite or out of range");
    }
}

ProbeMap bake_probe_from_spatial_cloud(const SpatialCloud& cloud, const glm::dvec3& centre,
                                       const BakeSettings& settings, Progress* progress) {
    HierarchyCut cut =
        cut_for_bake(cloud.hierarchy(), centre, settings, "a spatial cloud", progress);
    PointCloud points;
    LocalGeometry geometry;
    cloud.gather(cut, points, geometry);
    return bake_probe_from_gathered_cut(points, geometry, cut, centre, settings, progress);
}

} // namespace lfprobe
