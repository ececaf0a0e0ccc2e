// How a HIT's radiance is read from the probe that saw it (the fidelity of docs/DESIGN.md §5).
// Visibility is decided texel by texel (probe_trace.hpp); the colour of the decided surface point
// may then be reconstructed from more than the one texel met.
//
// Nearest: the texel met, as the paper does. Bilinear: the four texels around the point's
// direction, weighted bilinearly in the map, keeping only texels whose stored surface point
// lies on the surface of the texel met (within the trace's thickness of its plane, normals on
// the same side): a silhouette is never smeared into the surface behind it, and a surface of
// one colour reads exactly that colour. Footprint: as bilinear while the eye's sample covers
// at most a texel; wider, the probe's prefiltered levels (radiance_mips.hpp) at the level whose
// texels match the sample's width where it meets the surface, interpolated between the two
// nearest levels, as texture LOD does: one ray per pixel then averages what the pixel sees.
// Bicubic: the 4×4 texels around the point's direction, Catmull-Rom weights, when all sixteen
// lie on the surface met; bilinear otherwise (near a silhouette, the unknown or the empty).
// A texel's radiance is its footprint's mean, so bilinear blurs it a second time; the cubic's
// negative lobes undo part of that blur.
#pragma once

#include <string>

#include <glm/vec3.hpp>

#include "lfprobe/octahedral.hpp"
#include "lfprobe/probe_map.hpp"
#include "lfprobe/radiance_mips.hpp"

namespace lfprobe {

enum class RadianceFilter {
    Nearest,
    Bilinear,
    Footprint,
    Bicubic,
};

// "nearest", "bilinear", "footprint", "bicubic"; InputError for anything else.
[[nodiscard]] RadianceFilter radiance_filter_from_name(const std::string& name);
[[nodiscard]] const char* radiance_filter_name(RadianceFilter filter);

// The radiance `map` holds for the surface point in `direction` from the probe centre (any
// length > 0), met in texel `texel` (which holds a surface). `tolerance` (metres): how far a
// neighbour's stored point may lie from the plane of the texel met and still be the same
// surface. Nearest: texel's radiance, bit for bit.
// The eye's sample where it meets the surface, as the footprint filter reads it.
struct RadianceFootprint {
    const RadianceMips* mips = nullptr; // the probe's prefiltered levels; none: bilinear
    double texels = 0.0;                // the sample's width in the probe's level-0 texels
};

// How many of a probe's texels (map resolution n) the eye's sample spans at a surface point
// `eye_distance` from the eye and `probe_distance` from the probe, for a sample that spans
// `sample_angle` radians at the eye.
[[nodiscard]] double footprint_in_texels(double eye_distance, double sample_angle,
                                         double probe_distance, int n);

// Which texel's surface a ray from the probe centre in `direction` sees, at finer than a
// texel: the four texels around the direction (the bilinear cell) are grouped by surface (the
// same-surface test of the filters, within `tolerance` of a plane, normals on the same side;
// the empty texels as one group; an unknown texel in none), and the ray sees the group that
// holds most of the four's bilinear weight. Returns `met` (the texel the direction falls in)
// unless another group outweighs its own; then that group's heaviest texel. The texel the
// direction falls in decides an edge half-way between texel centres along each axis, so a
// slanted edge steps at the texels' pitch; the weight's majority cuts the steps' corners.
[[nodiscard]] oct::Texel majority_surface_texel(const ProbeMap& map, const glm::dvec3& direction,
                                                oct::Texel met, double tolerance);

[[nodiscard]] glm::vec3 filtered_radiance(const ProbeMap& map, const glm::dvec3& direction,
                                          oct::Texel texel, double tolerance, RadianceFilter filter,
                                          const RadianceFootprint& footprint = {});

} // namespace lfprobe
