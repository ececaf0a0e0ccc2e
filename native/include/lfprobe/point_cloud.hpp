// A merged point cloud in the local (offset) frame, as every stage after import sees it.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

namespace lfprobe {

// One scan that contributed to a cloud.
struct ScanSource {
    std::string path;
    std::uint64_t point_count = 0;
    // Where the scanner stood, in the cloud's local frame (world minus world_offset).
    glm::dvec3 scanner{0.0};
    bool has_scanner = false;
};

// Positions are float32 relative to a double-precision world offset (docs/DESIGN.md §3): a point's
// world position is world_offset + position, computed in double.
struct PointCloud {
    glm::dvec3 world_offset{0.0};
    std::vector<glm::vec3> positions;
    // Linear RGB in [0, 1] (8-bit sRGB decoded on import); empty when the files had no colour.
    std::vector<glm::vec3> colors;
    // Unit normals from the file, or estimated; empty when neither.
    std::vector<glm::vec3> normals;
    // Scanner intensity as stored in the file; empty when absent.
    std::vector<float> intensities;
    // Index into `scans` for every point.
    std::vector<std::uint32_t> scan_index;
    std::vector<ScanSource> scans;

    [[nodiscard]] std::size_t size() const { return positions.size(); }
    [[nodiscard]] bool has_colors() const { return !colors.empty(); }
    [[nodiscard]] bool has_normals() const { return !normals.empty(); }
};

// A cloud from arrays handed over in its local frame (the Blender add-on's objects): checks
// what a file reader would (finite positions, colours and normals one per point, every scan
// index naming one of `scanners`), fills the per-scan counts. `scanners`: one entry per scan,
// its position in the local frame or none; an empty list is one scan without a scanner.
// `scan_index` empty: every point is scan 0. `intensities`: one finite value per point, or
// empty. `scan_paths`: the file each scan came from, one per scan, or empty ("array").
// InputError names the first thing that does not fit.
[[nodiscard]] PointCloud
cloud_from_parts(std::vector<glm::vec3> positions, std::vector<glm::vec3> colors,
                 std::vector<glm::vec3> normals, std::vector<std::uint32_t> scan_index,
                 const std::vector<std::optional<glm::dvec3>>& scanners,
                 const glm::dvec3& world_offset, std::vector<float> intensities = {},
                 const std::vector<std::string>& scan_paths = {});

} // namespace lfprobe
