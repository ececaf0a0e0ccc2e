// Readers for scan point clouds: FARO-style .xyz/.txt, Leica .pts, and .ply (ascii, binary
// little and big endian). Files are memory-mapped and parsed on all cores; coordinates are read
// in double and stored as float32 relative to a per-file origin, so georeferenced coordinates
// keep their precision until the merge chooses the cloud's world offset.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec3.hpp>

#include "lfprobe/point_cloud.hpp"
#include "lfprobe/progress.hpp"

namespace lfprobe {

enum class ScanFormat { Auto, Xyz, Pts, Ply };

// "xyz" (also .txt, .asc, .csv), "pts", "ply"; Auto picks by extension.
[[nodiscard]] ScanFormat scan_format_from_path(const std::string& path);

struct ScanReadOptions {
    ScanFormat format = ScanFormat::Auto;
    // Text formats only: the meaning of each column, space separated, overriding the header
    // line and the guess from the column count. Names: x y z r g b i (intensity)
    // nx ny nz, and _ for a column to ignore. Example: "x y z i r g b".
    std::string columns;
};

// One file, parsed. World position of point i = origin + positions[i] (in double).
struct ScanFile {
    std::string path;
    glm::dvec3 origin{0.0};
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> colors;  // linear RGB; empty when the file has no colour
    std::vector<glm::vec3> normals; // empty when the file has no normals
    std::vector<float> intensities; // empty when the file has no intensity
    // Scanner position in world coordinates, where the file says it (a PLY or text header
    // comment "scanner X Y Z", or PCL's "sensor origin at (X,Y,Z)").
    glm::dvec3 scanner{0.0};
    bool has_scanner = false;
};

// Parses one file. Throws InputError naming the file, the line or byte offset, and what was
// expected; IoError when the file cannot be opened; Cancelled when progress asks to stop.
[[nodiscard]] ScanFile read_scan_file(const std::string& path, const ScanReadOptions& options,
                                      Progress* progress = nullptr);
// The same for a file's bytes already in memory: `name` picks the format by its extension (unless
// the options name one) and stands for the file in errors.
[[nodiscard]] ScanFile read_scan_bytes(const std::string& name, std::string_view bytes,
                                       const ScanReadOptions& options,
                                       Progress* progress = nullptr);

struct MergeOptions {
    // Subtracted from world coordinates before they become float32. When not forced, it is 0
    // for clouds within ±1024 units of the origin, else the bounding box centre rounded to
    // whole units.
    glm::dvec3 world_offset{0.0};
    bool force_world_offset = false;
    // Scanner positions in world coordinates, one per file, overriding what the files say.
    std::vector<glm::dvec3> scanners;
};

// Merges parsed files into one cloud that remembers which scan each point came from.
// Colours, normals or intensities present in only some files are kept for all points
// (mid grey, zero normal, zero intensity where a file lacks them).
[[nodiscard]] PointCloud merge_scans(std::vector<ScanFile> files, const MergeOptions& options);

} // namespace lfprobe
