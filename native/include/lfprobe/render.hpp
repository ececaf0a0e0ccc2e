// Rendering a view by tracing camera rays against a probe field (docs/DESIGN.md §1, §4): one ray
// per pixel through the camera of docs/DESIGN.md §3, in tiles on all cores. Every pixel is computed
// on its own from the same inputs, so the image is bit-identical for any number of threads.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "lfprobe/camera.hpp"
#include "lfprobe/probe_field.hpp"
#include "lfprobe/progress.hpp"
#include "lfprobe/rendered_image.hpp"
#include "lfprobe/throughput.hpp"

namespace lfprobe {

struct ImageMetadata;

struct RenderSettings {
    FieldTraceSettings trace;
    int tile_size = 32; // pixels per tile side: the unit of parallel work and of progress
    // Where in the pixel its ray passes, in pixels from the pixel's top-left corner.
    double sample_x = 0.5;
    double sample_y = 0.5;
    // 1: one ray per pixel, at (sample_x, sample_y). A square n×n > 1: colour and coverage are
    // the mean over the n×n stratified sample positions of the ground truth
    // (ground_truth.hpp), while depth, normal, status and probe are the pixel centre's; the
    // steps channel sums every ray of the pixel.
    int samples_per_pixel = 1;
    // Holes at most this many pixels across, regions of pixels whose samples ended UNKNOWN, are
    // given a colour inferred from the HIT pixels around them (unknown_fill.hpp); their status
    // stays UNKNOWN. -1: default_hole_fill_pixels of the image (5 % of its larger side); 0: none
    // (UNKNOWN samples add black, the image before filling existed).
    int hole_fill_pixels = -1;
};

// Counts that do not depend on the clock (docs/DESIGN.md §6), and the time it took. hits, misses
// and unknown count pixels by their centre ray; rays and steps count every ray traced.
struct RenderStats {
    std::uint64_t rays = 0;
    std::uint64_t hits = 0;
    std::uint64_t misses = 0;
    std::uint64_t unknown = 0;
    std::uint64_t steps = 0;        // texels visited over all rays
    std::uint64_t probes_tried = 0; // probe traces over all rays
    std::uint64_t holes_filled = 0; // pixels with no HIT sample given a colour by the hole fill
    std::uint64_t holes_left = 0;   // such pixels in holes wider than the fill reaches
    std::uint64_t guessed = 0; // HIT pixels showing a hole-filled texel (RenderedImage::guessed)
    double seconds = 0.0;      // wall time of the trace (not of loading or writing)

    [[nodiscard]] double rays_per_second() const {
        return seconds > 0.0 ? static_cast<double>(rays) / seconds : 0.0;
    }
    [[nodiscard]] double mean_steps() const {
        return rays > 0 ? static_cast<double>(steps) / static_cast<double>(rays) : 0.0;
    }
    [[nodiscard]] double mean_probes() const {
        return rays > 0 ? static_cast<double>(probes_tried) / static_cast<double>(rays) : 0.0;
    }
    [[nodiscard]] nlohmann::json to_json() const;
};

// Traces every pixel of `camera` (world coordinates) against `field` (its local frame: the
// field's world offset is subtracted from each ray in double). Progress counts pixels;
// cancellation is checked per tile and throws Cancelled. InputError when the settings ask for
// grid tracing of a set that is not a grid, or for a tile size below 1.
[[nodiscard]] RenderedImage render_probe_view(const ProbeField& field, const Camera& camera,
                                              const RenderSettings& settings = {},
                                              Progress* progress = nullptr,
                                              RenderStats* stats = nullptr);

// Where the rays probe_trace_throughput times start.
enum class ThroughputStart {
    // At the camera: the figure compared with Embree's.
    Camera,
    // Where each ray's own trace from the camera ended (its HIT, or as far as an UNKNOWN proved
    // it free; a MISS starts at the camera), so that no empty space is left to skip: what a
    // trace costs however little it walks, the floor under the figure above.
    Answer,
};

// The camera's pixel-centre rays in the field's local frame, each started where its own trace
// from the camera ended: t_min moved to its HIT, or as far as an UNKNOWN proved it free (a MISS
// keeps its start). Traced again, they have no empty space left to skip.
[[nodiscard]] std::vector<Ray> rays_started_at_answers(const ProbeField& field,
                                                       const Camera& camera,
                                                       const RenderSettings& settings = {});

// Probe-trace throughput measured exactly as embree_throughput measures Embree's (throughput.hpp):
// the same rays, trace only, so that the two figures make a fair ratio.
[[nodiscard]] ThroughputResult
probe_trace_throughput(const ProbeField& field, const Camera& camera,
                       const RenderSettings& settings = {}, int repeats = 3,
                       ThroughputStart start = ThroughputStart::Camera);

// The counts of an image already rendered (status and steps channels; seconds left 0).
[[nodiscard]] RenderStats stats_of(const RenderedImage& image);

// The render every caller runs (the CLI, the Blender add-on's F12 and batch render, the
// report): renders `field` from `camera` and, when `output_path` is not empty, writes the EXR
// with probe_view_metadata. Returns the image; fills `stats` when given.
RenderedImage render_probe_view_to_exr(const ProbeField& field, const Camera& camera,
                                       const RenderSettings& settings,
                                       const std::string& output_path, Progress* progress = nullptr,
                                       RenderStats* stats = nullptr);

// Loads the probe set in `folder` (held in memory as `storage` says; none: as its manifest
// says), then render_probe_view_to_exr. Returns the stats.
RenderStats render_probe_set_to_exr(const std::string& folder, const Camera& camera,
                                    const RenderSettings& settings,
                                    const std::optional<ProbeStorage>& storage,
                                    const std::string& output_path, Progress* progress = nullptr);

// What a probe view's EXR records: the set's folder, how its probes are held and their memory,
// the mode the trace resolved to, the camera, the settings and the stats.
[[nodiscard]] ImageMetadata probe_view_metadata(const ProbeField& field, const Camera& camera,
                                                const RenderSettings& settings,
                                                const RenderStats& stats);

// The settings as JSON (for metadata and reports).
[[nodiscard]] nlohmann::json render_settings_json(const RenderSettings& settings);

} // namespace lfprobe
