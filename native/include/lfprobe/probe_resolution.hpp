// The finest map resolution a probe's data supports, and no finer (issue "model only what a
// scene needs"; the paper's 3072² maps came out worse than 2048² because its scans did not
// hold enough points to fill them). A texel of an N×N octahedral map subtends about sqrt(4π)/N
// radians; a surface at distance r sampled every s metres gives a point every s/r radians. So
// the data fills texels down to N ≈ sqrt(4π)·r/s, and a finer map only splats the same points
// over more texels. The estimate takes the front-most point per direction as the probe sees it
// and a quantile of the N each such point supports; a footprint in metres, when given, caps N
// where the texels would be finer than wanted at the probe's typical distance.
//
// The chosen N samples the data at `samples_per_spacing` texels per point spacing along each
// axis: a baked probe holds the splatted surface (each point a disc of its spacing), and a
// surface known at spacing s needs samples every s/2 or finer to keep the detail between its
// points and the edges of its discs. One texel per point (factor 1) loses that detail. The
// default 2.5 is measured on the demo scenes (report preset demo): since splats are cut to
// their surface's plane (probe_bake.hpp), silhouettes are sharp and finer maps gain more (lab
// room, 1° scan: 256² 16.65, 512² 17.28, 1024² 17.42 dB). Factor 2 (mostly 512²) fell
// 0.13 dB short of 1024²; 2.5 (mostly 768²) is within 0.05 dB, and on the hard scene, where
// 512² is best, it chooses 512².
#pragma once

#include <cstddef>
#include <vector>

#include <glm/vec3.hpp>

#include "lfprobe/local_geometry.hpp"
#include "lfprobe/point_cloud.hpp"

namespace lfprobe {

struct ResolutionSettings {
    int min_resolution = 64;
    int max_resolution = 4096;
    double quantile = 0.5;            // of the per-direction supported resolutions
    double samples_per_spacing = 2.5; // texels per point spacing, along each axis
    double footprint = 0.0;           // metres per texel wanted at the median distance; 0: no cap
    int survey_resolution = 256;      // the map the front-most points are found in
};

struct ResolutionChoice {
    int resolution = 0;              // the chosen size (one of kResolutionSteps, clamped)
    double data_resolution = 0.0;    // N at one texel per point (the quantile, before the
                                     // samples per spacing, rounding and caps)
    double footprint_resolution = 0; // the footprint's cap (0: none)
    double median_distance = 0.0;    // of the front-most points, metres
    double median_spacing = 0.0;     // of the front-most points, metres
    std::size_t directions = 0;      // survey texels with a point
};

// The sizes a choice is rounded to: powers of two and the halves between them. The wanted N is
// a sampling rate, so it goes to the nearest size in ratio (the step within ±~20 % of it),
// not always down: rounding down would leave most probes below the rate asked for.
[[nodiscard]] const std::vector<int>& resolution_steps();

// Chooses the resolution for a probe at `centre` (local frame). Throws InputError on bad
// settings or when no point is seen.
[[nodiscard]] ResolutionChoice choose_resolution(const PointCloud& cloud,
                                                 const LocalGeometry& geometry,
                                                 const glm::dvec3& centre,
                                                 const ResolutionSettings& settings = {});

} // namespace lfprobe
