// The geometry-free baseline the probes must beat (docs/DESIGN.md §6): the raw point cloud drawn as
// z-buffered screen-space squares, each the size of its point's patch (the local spacing) at
// its depth, nearest point winning per pixel. Same camera and same image channels as a probe
// trace; covered pixels are HIT, the rest MISS. Deterministic for any thread count: every
// pixel keeps the minimum of (distance bits, point index) packed in 64 bits, which does not
// depend on the order the points arrive in.
#pragma once

#include <cstdint>
#include <string>

#include <nlohmann/json_fwd.hpp>

#include "lfprobe/camera.hpp"
#include "lfprobe/local_geometry.hpp"
#include "lfprobe/point_cloud.hpp"
#include "lfprobe/progress.hpp"
#include "lfprobe/rendered_image.hpp"

namespace lfprobe {

struct SplatSettings {
    // Half the square's side as a multiple of the point's local spacing (LocalGeometry), as
    // the probe bake sizes its splats: 0.8 covers a square sampling pattern with margin.
    double radius_scale = 0.8;
    // A fixed half side in metres for every point; > 0 overrides the spacing.
    double fixed_radius = 0.0;
    // Largest half side in pixels (points right in front of the camera).
    int max_radius_pixels = 64;
};

struct SplatStats {
    std::uint64_t points = 0;    // points in the cloud
    std::uint64_t drawn = 0;     // points inside the view and the clip range
    std::uint64_t fragments = 0; // pixels written over all points
    std::uint64_t covered = 0;   // pixels with a point
    double seconds = 0.0;

    [[nodiscard]] double points_per_second() const {
        return seconds > 0.0 ? static_cast<double>(points) / seconds : 0.0;
    }
    [[nodiscard]] nlohmann::json to_json() const;
};

// Renders `cloud` (local frame; world = cloud.world_offset + position) from `camera` (world).
// `geometry` gives the spacing that sizes each splat and normals when the cloud has none; it
// may be null when settings.fixed_radius > 0 (or points are one pixel). Progress counts
// points; cancellation throws Cancelled.
[[nodiscard]] RenderedImage render_splats(const PointCloud& cloud, const LocalGeometry* geometry,
                                          const Camera& camera, const SplatSettings& settings = {},
                                          Progress* progress = nullptr,
                                          SplatStats* stats = nullptr);

// The splat render every caller runs: takes the local geometry that sizes the splats (unless
// settings.fixed_radius > 0) from the prepared-cloud cache in `cache_dir` when a bake or an
// earlier splat of the same cloud left it there, estimates and caches it otherwise ("": no
// cache), renders and writes the EXR to `output_path` (atomically) with the one metadata
// layout (image_metadata.hpp). Returns the stats; the geometry's time (estimate or cache read)
// goes to `geometry_seconds` when given.
SplatStats splat_cloud_to_exr(const PointCloud& cloud, const Camera& camera,
                              const SplatSettings& settings, const std::string& output_path,
                              Progress* progress = nullptr, double* geometry_seconds = nullptr,
                              const std::string& cache_dir = "");

// The settings as JSON (for metadata and reports).
[[nodiscard]] nlohmann::json splat_settings_json(const SplatSettings& settings);

} // namespace lfprobe
