// Format dispatch and the merge of parsed scan files into one cloud with a world offset.
#include "lfprobe/scan_reader.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>

#include <glm/common.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "lfprobe/color.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/huge_pages.hpp"
#include "lfprobe/mapped_file.hpp"
#include "lfprobe/world_offset.hpp"
#include "ply_reader.hpp"
#include "scan_parsing.hpp"
#include "text_scan_reader.hpp"

namespace lfprobe {

namespace {

struct Bounds {
    glm::dvec3 min{std::numeric_limits<double>::infinity()};
    glm::dvec3 max{-std::numeric_limits<double>::infinity()};

    void add(const Bounds& other) {
        min = glm::min(min, other.min);
        max = glm::max(max, other.max);
    }
    [[nodiscard]] bool empty() const { return min.x > max.x; }
};

// World bounds of one file: float bounds found in parallel, then moved by the origin in
// double (adding a constant keeps the order, so the extremes stay the extremes).
[[nodiscard]] Bounds world_bounds(const ScanFile& file) {
    Bounds local = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, file.positions.size(), 1 << 16), Bounds{},
        [&](const tbb::blocked_range<std::size_t>& block, Bounds bounds) {
            for (std::size_t i = block.begin(); i != block.end(); ++i) {
                const glm::dvec3 p(file.positions[i]);
                bounds.min = glm::min(bounds.min, p);
                bounds.max = glm::max(bounds.max, p);
            }
            return bounds;
        },
        [](Bounds a, const Bounds& b) {
            a.add(b);
            return a;
        });
    if (!local.empty()) {
        local.min += file.origin;
        local.max += file.origin;
    }
    return local;
}

[[nodiscard]] glm::dvec3 choose_world_offset(const std::vector<ScanFile>& files) {
    Bounds bounds;
    for (const ScanFile& file : files) {
        bounds.add(world_bounds(file));
    }
    return world_offset_for_bounds(bounds.min, bounds.max);
}

template <class T>
void release(std::vector<T>& values) {
    std::vector<T>().swap(values);
}

} // namespace

ScanFormat scan_format_from_path(const std::string& path) {
    std::string extension = std::filesystem::path(path).extension().string();
    for (char& c : extension) {
        c = detail::ascii_lower(c);
    }
    if (extension == ".xyz" || extension == ".txt" || extension == ".asc" || extension == ".csv") {
        return ScanFormat::Xyz;
    }
    if (extension == ".pts") {
        return ScanFormat::Pts;
    }
    if (extension == ".ply") {
        return ScanFormat::Ply;
    }
    return ScanFormat::Auto; // unknown: the caller must name the format
}

namespace {

[[nodiscard]] ScanFormat format_to_read(const std::string& path, const ScanReadOptions& options) {
    const ScanFormat format =
        options.format == ScanFormat::Auto ? scan_format_from_path(path) : options.format;
    if (format == ScanFormat::Auto) {
        throw InputError(path + ": cannot tell the scan format from the file name: expected "
                                ".xyz, .txt, .asc, .csv, .pts or .ply, or a format in the options");
    }
    return format;
}

[[nodiscard]] ScanFile read_scan(const MappedFile& file, ScanFormat format,
                                 const ScanReadOptions& options, Progress* progress) {
    switch (format) {
    case ScanFormat::Pts:
        return detail::read_pts_scan(file, options.columns, progress);
    case ScanFormat::Ply:
        return detail::read_ply_scan(file, progress);
    default:
        return detail::read_xyz_scan(file, options.columns, progress);
    }
}

} // namespace

ScanFile read_scan_file(const std::string& path, const ScanReadOptions& options,
                        Progress* progress) {
    const ScanFormat format = format_to_read(path, options);
    return read_scan(MappedFile(path), format, options, progress);
}

ScanFile read_scan_bytes(const std::string& name, std::string_view bytes,
                         const ScanReadOptions& options, Progress* progress) {
    const ScanFormat format = format_to_read(name, options);
    return read_scan(MappedFile(name, bytes), format, options, progress);
}

PointCloud merge_scans(std::vector<ScanFile> files, const MergeOptions& options) {
    if (!options.scanners.empty() && options.scanners.size() != files.size()) {
        throw InputError("merge_scans: " + std::to_string(options.scanners.size()) +
                         " scanner positions for " + std::to_string(files.size()) +
                         " files: expected one per file, or none");
    }
    if (files.size() > std::numeric_limits<std::uint32_t>::max()) {
        throw InputError("merge_scans: too many files for a 32-bit scan index");
    }
    PointCloud cloud;
    cloud.world_offset =
        options.force_world_offset ? options.world_offset : choose_world_offset(files);

    std::size_t total = 0;
    bool any_colour = false;
    bool any_normal = false;
    bool any_intensity = false;
    for (const ScanFile& file : files) {
        total += file.positions.size();
        any_colour = any_colour || !file.colors.empty();
        any_normal = any_normal || !file.normals.empty();
        any_intensity = any_intensity || !file.intensities.empty();
    }
    // One file: its positions are moved to the cloud and shifted to the world offset in place
    // (a new array of a 10 M-point scan costs its page faults as much as the shift).
    const bool single = files.size() == 1;
    if (single) {
        cloud.positions = std::move(files[0].positions);
    } else {
        resize_in_huge_pages(cloud.positions, total);
    }
    resize_in_huge_pages(cloud.scan_index, total);
    // One file: its colours, normals and intensities are the cloud's as they are (moved, not
    // copied: a copy of a 10 M-point scan's colours costs as much as parsing a fifth of it).
    if (single) {
        cloud.colors = std::move(files[0].colors);
        cloud.normals = std::move(files[0].normals);
        cloud.intensities = std::move(files[0].intensities);
    } else {
        resize_in_huge_pages(cloud.colors, any_colour ? total : 0);
        resize_in_huge_pages(cloud.normals, any_normal ? total : 0);
        resize_in_huge_pages(cloud.intensities, any_intensity ? total : 0);
    }

    // sRGB mid grey, decoded: what a point shows when its file had no colour.
    const glm::vec3 grey(srgb_to_linear(0.5f));
    std::size_t first = 0;
    for (std::size_t f = 0; f < files.size(); ++f) {
        ScanFile& file = files[f];
        const std::size_t count = single ? cloud.positions.size() : file.positions.size();
        const auto index = static_cast<std::uint32_t>(f);
        tbb::parallel_for(
            tbb::blocked_range<std::size_t>(0, count, 1 << 16),
            [&](const tbb::blocked_range<std::size_t>& block) {
                const std::vector<glm::vec3>& from = single ? cloud.positions : file.positions;
                for (std::size_t i = block.begin(); i != block.end(); ++i) {
                    const glm::dvec3 p(from[i]);
                    cloud.positions[first + i] =
                        glm::vec3(static_cast<float>(file.origin.x + p.x - cloud.world_offset.x),
                                  static_cast<float>(file.origin.y + p.y - cloud.world_offset.y),
                                  static_cast<float>(file.origin.z + p.z - cloud.world_offset.z));
                    cloud.scan_index[first + i] = index;
                }
            });
        const auto begin = static_cast<std::ptrdiff_t>(first);
        if (single) {
            // Colours, normals and intensities were moved above.
        } else if (any_colour) {
            if (file.colors.empty()) {
                std::fill_n(cloud.colors.begin() + begin, count, grey);
            } else {
                std::copy(file.colors.begin(), file.colors.end(), cloud.colors.begin() + begin);
            }
        }
        if (any_normal && !single) {
            if (file.normals.empty()) {
                std::fill_n(cloud.normals.begin() + begin, count, glm::vec3(0.0f));
            } else {
                std::copy(file.normals.begin(), file.normals.end(), cloud.normals.begin() + begin);
            }
        }
        if (any_intensity && !single) {
            if (file.intensities.empty()) {
                std::fill_n(cloud.intensities.begin() + begin, count, 0.0f);
            } else {
                std::copy(file.intensities.begin(), file.intensities.end(),
                          cloud.intensities.begin() + begin);
            }
        }

        ScanSource source;
        source.path = file.path;
        source.point_count = count;
        if (!options.scanners.empty()) {
            source.scanner = options.scanners[f] - cloud.world_offset;
            source.has_scanner = true;
        } else if (file.has_scanner) {
            source.scanner = file.scanner - cloud.world_offset;
            source.has_scanner = true;
        }
        cloud.scans.push_back(std::move(source));

        // The cloud now holds this file's points; give its memory back before the next.
        release(file.positions);
        release(file.colors);
        release(file.normals);
        release(file.intensities);
        first += count;
    }
    return cloud;
}

} // namespace lfprobe
