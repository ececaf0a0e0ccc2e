// How a HIT's radiance is read from the probe that saw it (the fidelity of docs/DESIGN.md §5).
// Visibility is decided texel by texel (probe_trace.hpp); the colour of the decided surface point
// may then be reconstructed from more than the one texel met.
//
// Nearest: the texel met, as the paper does. Bilinear: the four texels around the point's
// direction, weighted bilinearly in the map, keeping only texels whose stored surface point
// lies on the surface of the texel met (within the trace's thickness of its plane, normals on
// the same side): a silhouette is never smeared into the surface behind it, and a surface of
// one colour reads exactly that colour.
#pragma once

#include <string>

#include <glm/vec3.hpp>

#include "lfprobe/octahedral.hpp"
#include "lfprobe/probe_map.hpp"

namespace lfprobe {

enum class RadianceFilter {
    Nearest,
    Bilinear,
};

// "nearest", "bilinear"; InputError for anything else.
[[nodiscard]] RadianceFilter radiance_filter_from_name(const std::string& name);
[[nodiscard]] const char* radiance_filter_name(RadianceFilter filter);

// The radiance `map` holds for the surface point in `direction` from the probe centre (any
// length > 0), met in texel `texel` (which holds a surface). `tolerance` (metres): how far a
// neighbour's stored point may lie from the plane of the texel met and still be the same
// surface. Nearest: texel's radiance, bit for bit.
[[nodiscard]] glm::vec3 filtered_radiance(const ProbeMap& map, const glm::dvec3& direction,
                                          oct::Texel texel, double tolerance,
                                          RadianceFilter filter);

} // namespace lfprobe
