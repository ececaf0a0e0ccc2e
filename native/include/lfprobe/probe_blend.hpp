// The colour of a HIT (docs/DESIGN.md §5): read from the probe that answered through
// its radiance filter (radiance_filter.hpp) and, where other probes see the same surface point,
// blended with theirs.
//
// A probe sees a point when the texel toward it stores a surface at the point's distance
// (within the trace's thickness) facing the probe. Each probe that sees the point weighs by
// how finely it sampled it, its texel density there ((N / r)² × cos θ for a map of N² texels
// at distance r seen at angle θ to the surface normal), and by how close its line of sight to
// the point is to the eye's (over (α + one texel's angle)², α the angle between the two), as
// unstructured lumigraph rendering weighs its cameras: as the eye reaches a probe, the colour
// becomes that probe's lookup. The sum runs over the probes in the
// order of their positions, so the answer depends neither on which probe answered first nor
// on the probes' order in the set, and a surface of one colour stays exactly that colour.
#pragma once

#include "lfprobe/probe_field.hpp"
#include "lfprobe/ray.hpp"

namespace lfprobe {

// Replaces `hit.radiance` (a HIT of `ray`, both in the field's local frame) with its filtered
// and blended colour per `settings.filter` and `settings.blend`. Nothing else changes: the
// status, depth, normal, probe and texel stay the visibility's answer.
void shade_hit(const ProbeField& field, const Ray& ray, FieldTraceResult& hit,
               const FieldTraceSettings& settings);

// The blend of every probe of `probes` (indices into the field, at most 8; the probe that
// answered among them) that sees the local point `point` whose surface has normal `normal`,
// seen by the eye along unit `view`.
// `answered`/`answered_radiance`: the probe that met the point and its filtered colour, used
// when no probe passes the test. `eye_distance`: how far the point is from the eye, for the
// footprint filter. For tests and for shade_hit.
[[nodiscard]] glm::vec3 blend_probes(const ProbeField& field, const glm::dvec3& point,
                                     const glm::dvec3& normal, const glm::dvec3& view,
                                     const std::size_t* probes, std::size_t count,
                                     std::size_t answered, const glm::vec3& answered_radiance,
                                     const FieldTraceSettings& settings, double eye_distance = 0.0);

// The footprint filter's input for probe `probe` of `field` at a point `probe_distance` from it
// and `eye_distance` from the eye: none unless settings.filter is Footprint.
[[nodiscard]] RadianceFootprint footprint_of(const ProbeField& field, std::size_t probe,
                                             double probe_distance, double eye_distance,
                                             const FieldTraceSettings& settings);

} // namespace lfprobe
