// Baking a probe set from a point cloud, in one process or in parts (docs/DESIGN.md §4). The
// cloud is made ready once per process (its normals, spacing and point hierarchy), and then any
// probe of the set bakes from it alone: the same probe comes out bit for bit whichever process
// bakes it, which is what lets a cluster (core/cluster_bake.py) share a set's probes out.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lfprobe/curve_ordered_cloud.hpp"
#include "lfprobe/local_geometry.hpp"
#include "lfprobe/point_cloud.hpp"
#include "lfprobe/point_hierarchy.hpp"
#include "lfprobe/prepared_cloud_cache.hpp"
#include "lfprobe/probe_bake.hpp"
#include "lfprobe/probe_placement.hpp"
#include "lfprobe/probe_set.hpp"
#include "lfprobe/probe_set_staging.hpp"
#include "lfprobe/progress.hpp"
#include "lfprobe/spatial_cloud.hpp"

namespace lfprobe {

// A cloud ready to bake probes from: what every probe's bake reads besides the points.
struct CloudBakeSource {
    std::shared_ptr<const PointCloud> cloud;
    BakeSettings settings;
    LocalGeometryOptions geometry_options;
    LocalGeometry geometry;
    PointHierarchy hierarchy;
    // The points in the hierarchy's curve order, which every probe's bake reads (empty when
    // the bake takes every point: lod_texels 0, or a cloud too sparse for a hierarchy; and for
    // clouds over 32 M points, whose cuts are copied out of the cloud's arrays per probe).
    CurveOrderedCloud curve;
    double normals_seconds = 0.0;
    double hierarchy_seconds = 0.0; // the hierarchy and the curve-ordered copy
    // True when the geometry and the hierarchy were read from the prepared-cloud cache
    // (prepared_cloud_cache.hpp); normals_seconds is then the read.
    bool from_cache = false;
    // The prepared-cloud cache entry read or written ("" without a cache folder), and the key
    // that names it (the spatial cloud is named by it too).
    std::string cache_entry;
    std::optional<PreparedCloudKey> key;
};

// Estimates the cloud's local geometry and builds the hierarchy `settings` bake from, on all
// cores; cancellable through `progress`. InputError for an empty cloud. With a `cache_dir`,
// both are read from the prepared-cloud cache there when it holds them for this cloud and
// these options, and written to it otherwise (a cache that cannot be written is skipped).
[[nodiscard]] CloudBakeSource prepare_cloud_bake(std::shared_ptr<const PointCloud> cloud,
                                                 const BakeSettings& settings,
                                                 const LocalGeometryOptions& geometry_options,
                                                 Progress* progress = nullptr,
                                                 const std::string& cache_dir = {});

// One probe at `centre` (local frame) from `source`, the same probe whichever process bakes it.
[[nodiscard]] ProbeMap bake_probe(const CloudBakeSource& source, const glm::dvec3& centre,
                                  Progress* progress = nullptr);

// The manifest of a cloud bake before its probes are listed: world offset, placement, the bake
// settings and the sources as given.
[[nodiscard]] ProbeSetManifest cloud_bake_manifest(const PointCloud& cloud,
                                                   const ProbePlacement& placement,
                                                   const BakeSettings& settings,
                                                   const LocalGeometryOptions& geometry_options,
                                                   const nlohmann::json& sources);

// Bakes the probes `indices` of `placement` from `source` into the staging folder `staging`
// (open_probe_set_staging), one at a time, each file written atomically; returns what each
// wrote, in the order of `indices`. Stops with IoError once the staging folder is removed.
[[nodiscard]] std::vector<StagedProbe> bake_staged_probes(const CloudBakeSource& source,
                                                          const ProbePlacement& placement,
                                                          const std::vector<std::size_t>& indices,
                                                          const std::string& staging,
                                                          Progress* progress = nullptr);

// The spatial cloud of `source` (spatial_cloud.hpp) in `cache_dir`, written unless a file of its
// key is there already: what lets a cluster's workers bake from only the parts of the cloud
// their probes read. None when `source` bakes from every point (lod_texels 0, or a cloud too
// sparse for a hierarchy), which a spatial cloud does not serve. Cancellable; IoError when it
// cannot be written.
struct SpatialCloudEntry {
    std::string path;
    std::string key_hex;
    bool written = false; // false: the file was there already
};
[[nodiscard]] std::optional<SpatialCloudEntry> write_spatial_cloud_of(const CloudBakeSource& source,
                                                                      const std::string& cache_dir,
                                                                      Progress* progress = nullptr);

// bake_staged_probes from a spatial cloud with `settings`: the same files, bit for bit, as
// from the CloudBakeSource the file was written from.
[[nodiscard]] std::vector<StagedProbe>
bake_staged_probes(const SpatialCloud& cloud, const BakeSettings& settings,
                   const ProbePlacement& placement, const std::vector<std::size_t>& indices,
                   const std::string& staging, Progress* progress = nullptr);

// Bakes every probe of `placement` from `cloud` into `folder` (created when missing), one probe
// at a time so memory stays at one probe's maps, and writes the manifest last. `sources` goes
// into the manifest as given. On cancellation or error no partial probe file is left behind.
// `cache_dir`: the prepared-cloud cache, as for prepare_cloud_bake.
[[nodiscard]] BakeSummary bake_probe_set_from_cloud(
    const PointCloud& cloud, const ProbePlacement& placement, const BakeSettings& settings,
    const LocalGeometryOptions& geometry_options, const std::string& folder,
    const nlohmann::json& sources, Progress* progress = nullptr, const std::string& cache_dir = {});

} // namespace lfprobe
