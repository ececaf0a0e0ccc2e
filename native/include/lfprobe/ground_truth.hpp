// Ground truth views (docs/DESIGN.md §4 "Ground truth and simulated scans"): Embree renders the
// reference mesh with the same camera rays as the probe renderer (Camera::local_pixel_ray with
// the mesh's world offset) and the same quantity the probes hold, the unlit base colour.
// Every pixel is computed on its own from the same inputs, so the image is bit-identical for
// any number of threads.
#pragma once

#include <cstdint>
#include <string>

#include <nlohmann/json_fwd.hpp>

#include "lfprobe/camera.hpp"
#include "lfprobe/embree_scene.hpp"
#include "lfprobe/progress.hpp"
#include "lfprobe/rendered_image.hpp"
#include "lfprobe/throughput.hpp"

namespace lfprobe {

struct GroundTruthSettings {
    // 1: the pixel centre only. Otherwise a perfect square n×n: colour and coverage are the
    // mean over an n×n stratified grid of sample positions (sample centres), while depth,
    // normal, status and object come from the pixel-centre ray, the ray the probe renderer
    // traces, so that depth comparisons are per ray.
    int samples_per_pixel = 1;
    int tile_size = 32; // pixels per tile side: the unit of parallel work and of progress
    // Each sample's texture colour filtered over the sample's footprint (an n×n stratum of
    // the pixel; texture LOD, as a renderer's reference does): n×n samples then estimate the
    // pixel's mean colour without the textures' own aliasing. False: textures point-sampled
    // (bilinear at the hit), as before this setting existed.
    bool filter_textures = true;
};

struct GroundTruthStats {
    std::uint64_t rays = 0; // every ray traced, samples included
    std::uint64_t hits = 0; // pixels whose centre ray hit
    std::uint64_t pixels = 0;
    double seconds = 0.0; // wall time of the trace (not of loading, building or writing)

    [[nodiscard]] double rays_per_second() const {
        return seconds > 0.0 ? static_cast<double>(rays) / seconds : 0.0;
    }
    [[nodiscard]] nlohmann::json to_json() const;
};

// Renders `camera` (world coordinates) against `scene` (its mesh's local frame). The image:
// R,G,B = unlit linear base colour (premultiplied by coverage), A = coverage, Z = distance
// along the centre ray (+inf on a miss), N = the surface normal (shading normal when the mesh
// has vn, else geometric) turned to face the camera, status HIT/MISS, probe -1, steps 0,
// object = the mesh object index (-1 on a miss). Progress counts pixels; cancellation is
// checked per tile. InputError for a samples_per_pixel that is not a square or a tile_size < 1.
[[nodiscard]] RenderedImage render_ground_truth(const EmbreeScene& scene, const Camera& camera,
                                                const GroundTruthSettings& settings = {},
                                                Progress* progress = nullptr,
                                                GroundTruthStats* stats = nullptr);

// The ground truth render every caller runs: renders `scene` (the mesh read from `mesh_path`)
// and writes the EXR to `output_path` (atomically) with the one metadata layout
// (image_metadata.hpp). Returns the stats.
GroundTruthStats ground_truth_to_exr(const EmbreeScene& scene, const std::string& mesh_path,
                                     const Camera& camera, const GroundTruthSettings& settings,
                                     const std::string& output_path, Progress* progress = nullptr);

// Primary-ray throughput of Embree on a view, for the "probe trace vs Embree" ratio: the
// pixel-centre rays are generated first, then only rtcIntersect1 over all of them is timed,
// `repeats` times; the figures are of the fastest repeat (the least disturbed on a shared
// machine). Runs on the threads of the calling TBB arena.
// `packet`: rays per Embree call, 1 (rtcIntersect1) or 4, 8, 16 (its packet API, flagged
// coherent: the fairer match for a tracer that works on runs of camera rays).
[[nodiscard]] ThroughputResult embree_throughput(const EmbreeScene& scene, const Camera& camera,
                                                 int repeats = 3, int packet = 1);

} // namespace lfprobe
