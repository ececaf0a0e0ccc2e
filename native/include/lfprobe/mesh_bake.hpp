// Probes baked from a mesh with Embree (docs/DESIGN.md §4 "Bake from a mesh"): the reference that
// separates tracing error from scan error. One ray per texel centre from the probe gives the
// exact radial distance, the surface normal and the base colour; a ray that escapes leaves the
// texel empty (+inf). Nothing is ever unknown: the mesh is the whole truth.
#pragma once

#include <string>

#include <nlohmann/json_fwd.hpp>

#include "lfprobe/embree_scene.hpp"
#include "lfprobe/probe_map.hpp"
#include "lfprobe/probe_placement.hpp"
#include "lfprobe/probe_set.hpp"
#include "lfprobe/progress.hpp"

namespace lfprobe {

struct MeshBakeSettings {
    int resolution = 512;
    // 1: the texel-centre ray only. n > 1: the colour is the mean over an n×n stratified grid
    // of rays across the texel (the texel's radiance prefiltered over its footprint), counting
    // only the rays that meet the centre ray's surface, while the distance, normal and the
    // surface/empty decision stay those of the centre ray, the direction every consumer of the
    // map assumes for the texel.
    int supersample = 4;
    // Each ray's texture colour filtered over its footprint (a texel, or a texel's n×n
    // stratum; texture LOD), as the ground truth filters its samples. False: point-sampled.
    bool filter_textures = true;
};

// One probe at `position` (the mesh's local frame). Normals are the shading normal (vn) where
// the mesh has one, else the geometric normal, turned to face the probe: a probe only sees the
// side of a surface facing it, and a one-sided mesh seen from behind (an open room) still
// stores a normal pointing at the observer, as scan normals are oriented toward the scanner.
// Progress counts texel rows; cancellation is checked per row.
[[nodiscard]] ProbeMap bake_probe_from_mesh(const EmbreeScene& scene, const glm::dvec3& position,
                                            const MeshBakeSettings& settings,
                                            Progress* progress = nullptr);

// Every probe of `placement` into `folder` in the probe set format of probe_set.hpp (manifest
// written last, atomic writes, "bake": {"source": "mesh", ...}); the world offset is the
// mesh's. `sources` goes into the manifest as given.
[[nodiscard]] BakeSummary
bake_probe_set_from_mesh(const EmbreeScene& scene, const ProbePlacement& placement,
                         const MeshBakeSettings& settings, const std::string& folder,
                         const nlohmann::json& sources, Progress* progress = nullptr);

} // namespace lfprobe
