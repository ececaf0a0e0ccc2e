// A simulated terrestrial laser scanner (docs/DESIGN.md §4 "Ground truth and simulated scans"): the
// reference mesh scanned from a position on a regular azimuth/elevation pattern with range
// noise, written as a FARO-style "x y z r g b" file that the scan readers take back in.
//
// Parametrisation: a FARO sweeps 360° horizontally while its mirror covers ~300° vertically,
// so every direction above 90° − fov/2 is seen once. lfprobe samples the same set of
// directions as azimuth φ = k·step in [0°, 360°) and elevation θ = 90° − fov/2 + j·step up to
// 90° (default fov 300°: θ from −60° to +90°); the zenith (θ = 90°) is one ray, not one per
// azimuth. Direction = (cos θ cos φ, cos θ sin φ, sin θ), world Z up. A partial sweep (a
// scanner told to turn through part of the circle, as users do to save time) takes the
// azimuths φ = start + k·step in [start, start + horizontal fov) instead; it keeps the zenith.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "lfprobe/embree_scene.hpp"
#include "lfprobe/point_cloud.hpp"
#include "lfprobe/progress.hpp"

namespace lfprobe {

struct ScannerSettings {
    glm::dvec3 position{0.0}; // world coordinates
    double step_deg = 0.5;
    double vertical_fov_deg = 300.0;   // (0, 360]
    double horizontal_fov_deg = 360.0; // (0, 360]: the azimuths swept
    double horizontal_start_deg = 0.0; // the first azimuth (from +X toward +Y)
    // Range noise: normal, σ = noise_mm at 10 m, scaled linearly with the range.
    double noise_mm = 2.0;
    std::uint64_t seed = 1;
    double max_range = 1.0e4; // metres; farther hits are not returned, as on a real scanner
    // A point's colour as a scanner's camera records it: the texture averaged over the point's
    // footprint (the angular step times the range, texture LOD as the ground truth filters),
    // since a camera pixel integrates what it covers. False: the texture at the hit alone (a
    // point sample, which aliases fine texture the way no camera does).
    bool filter_textures = true;
};

struct ScanStats {
    std::uint64_t rays = 0;
    std::uint64_t points = 0;
    double seconds = 0.0;
};

struct SimulatedPoint {
    glm::dvec3 position{0.0}; // world
    glm::vec3 color{0.0f};    // linear base colour
};

// The points of one simulated scan, in ray order (elevation rows bottom up, azimuth within a
// row). Deterministic: the noise of ray k depends only on the seed and k.
[[nodiscard]] std::vector<SimulatedPoint> simulate_scan(const EmbreeScene& scene,
                                                        const ScannerSettings& settings,
                                                        Progress* progress = nullptr,
                                                        ScanStats* stats = nullptr);

// simulate_scan written to `path` (through write_file_atomically) with the header comment
// "# scanner X Y Z" and "x y z r g b" lines, colours as 8-bit sRGB, coordinates in world units
// with 6 decimals. Returns the stats.
ScanStats write_simulated_scan(const EmbreeScene& scene, const ScannerSettings& settings,
                               const std::string& path, Progress* progress = nullptr);

// Simulated scans from `scanners` as one cloud, with no file between: each point as
// write_simulated_scan's file reads back (load_scans), but for the 6 decimals of the positions,
// which are kept whole here. Colours are 8-bit sRGB decoded by the readers' table, the local
// frame is chosen by world_offset_for_bounds over every point, and each scanner is one scan
// with its position. What the report bakes from: at the paper's density a scan's text file
// would take gigabytes and as long to parse as to scan. `stats`, when given, gets one entry
// per scanner.
[[nodiscard]] PointCloud simulate_scans_cloud(const EmbreeScene& scene,
                                              const std::vector<ScannerSettings>& scanners,
                                              Progress* progress = nullptr,
                                              std::vector<ScanStats>* stats = nullptr);

} // namespace lfprobe
