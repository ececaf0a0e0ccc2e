#include "lfprobe/cloud_bake.hpp"

#include <chrono>
#include <optional>

#include "lfprobe/bake_scratch.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/prepared_cloud_cache.hpp"
#include "seconds_since.hpp"

namespace lfprobe {

using nlohmann::json;

namespace {

// Clouds up to this many points get their points copied into curve order (CurveOrderedCloud, 45
// bytes a point: up to 1.4 GiB). Above it a probe's cut is so large that its bake is bound by
// the cut's size whichever way the points are read (100 M points, a 2048² probe's cut of 16 M
// points: 4.7-5.1 s from the copy, 5.1 s copying the cut out of the cloud's arrays), and the copy
// would add 4.5 GB to the 10 GB such a cloud takes.
constexpr std::size_t kMaxCurveOrderedPoints = std::size_t{32} << 20;

CurveOrderedCloud curve_ordered_if_small(const CloudBakeSource& source, Progress* progress) {
    return source.cloud->size() <= kMaxCurveOrderedPoints
               ? curve_ordered_cloud(*source.cloud, source.geometry, source.hierarchy, progress)
               : CurveOrderedCloud{};
}

} // namespace

CloudBakeSource prepare_cloud_bake(std::shared_ptr<const PointCloud> cloud,
                                   const BakeSettings& settings,
                                   const LocalGeometryOptions& geometry_options, Progress* progress,
                                   const std::string& cache_dir) {
    if (!cloud || cloud->size() == 0) {
        throw InputError("bake: the point cloud is empty");
    }
    CloudBakeSource source;
    source.cloud = std::move(cloud);
    source.settings = settings;
    source.geometry_options = geometry_options;
    const auto start = std::chrono::steady_clock::now();
    std::string entry;
    PreparedCloudKey key;
    if (!cache_dir.empty()) {
        key = prepared_cloud_key(*source.cloud, geometry_options, settings.lod_texels > 0.0f);
        entry = prepared_cloud_entry_path(key, cache_dir);
        source.cache_entry = entry;
        source.key = key;
        if (std::optional<PreparedCloud> cached = read_prepared_cloud(entry, key)) {
            source.geometry = std::move(cached->geometry);
            source.hierarchy = std::move(cached->hierarchy);
            source.normals_seconds = seconds_since(start);
            source.from_cache = true;
            const auto copy_start = std::chrono::steady_clock::now();
            source.curve = curve_ordered_if_small(source, progress);
            source.hierarchy_seconds = seconds_since(copy_start);
            return source;
        }
    }
    source.geometry = estimate_local_geometry(*source.cloud, geometry_options, progress);
    source.normals_seconds = seconds_since(start);
    const auto hierarchy_start = std::chrono::steady_clock::now();
    source.hierarchy = hierarchy_for_bakes(*source.cloud, source.geometry, settings, progress);
    source.curve = curve_ordered_if_small(source, progress);
    source.hierarchy_seconds = seconds_since(hierarchy_start);
    if (!entry.empty()) {
        (void)try_write_prepared_cloud(entry, key, source.geometry, source.hierarchy);
    }
    return source;
}

ProbeMap bake_probe(const CloudBakeSource& source, const glm::dvec3& centre, Progress* progress) {
    if (!source.curve.empty()) {
        return bake_probe_from_curve_ordered(source.curve, source.hierarchy, centre,
                                             source.settings, progress);
    }
    return bake_probe_from_hierarchy(*source.cloud, source.geometry, source.hierarchy, centre,
                                     source.settings, progress);
}

ProbeSetManifest cloud_bake_manifest(const PointCloud& cloud, const ProbePlacement& placement,
                                     const BakeSettings& settings,
                                     const LocalGeometryOptions& geometry_options,
                                     const json& sources) {
    ProbeSetManifest manifest;
    manifest.world_offset = cloud.world_offset;
    manifest.placement = placement;
    manifest.bake = splat_settings_json(settings);
    manifest.bake.update(json{{"source", "point cloud"},
                              {"resolution", settings.resolution},
                              {"normal_neighbours", geometry_options.normal_neighbours},
                              {"spacing_neighbours", geometry_options.spacing_neighbours},
                              {"points", cloud.size()}});
    manifest.sources = sources;
    return manifest;
}

namespace {

// Bakes the probes `indices` of `placement` one at a time with bake(position), each written
// atomically into `staging`.
template <class Bake>
std::vector<StagedProbe> stage_probes(const ProbePlacement& placement,
                                      const std::vector<std::size_t>& indices,
                                      const std::string& staging, Progress* progress, Bake&& bake) {
    for (const std::size_t i : indices) {
        if (i >= placement.positions.size()) {
            throw InputError("bake: probe " + std::to_string(i) + " does not exist (the set has " +
                             std::to_string(placement.positions.size()) + ")");
        }
    }
    // One probe's scratch arrays serve the next (bake_scratch.hpp).
    const BakeScratchScope scratch;
    OverlappedProbeWrites writes(staging);
    for (const std::size_t i : indices) {
        if (progress != nullptr) {
            progress->throw_if_cancelled();
        }
        writes.write(i, bake(placement.positions[i]));
    }
    return writes.finish();
}

} // namespace

std::vector<StagedProbe> bake_staged_probes(const CloudBakeSource& source,
                                            const ProbePlacement& placement,
                                            const std::vector<std::size_t>& indices,
                                            const std::string& staging, Progress* progress) {
    return stage_probes(placement, indices, staging, progress, [&](const glm::dvec3& centre) {
        return bake_probe(source, centre, progress);
    });
}

std::vector<StagedProbe> bake_staged_probes(const SpatialCloud& cloud, const BakeSettings& settings,
                                            const ProbePlacement& placement,
                                            const std::vector<std::size_t>& indices,
                                            const std::string& staging, Progress* progress) {
    return stage_probes(placement, indices, staging, progress, [&](const glm::dvec3& centre) {
        return bake_probe_from_spatial_cloud(cloud, centre, settings, progress);
    });
}

std::optional<SpatialCloudEntry> write_spatial_cloud_of(const CloudBakeSource& source,
                                                        const std::string& cache_dir,
                                                        Progress* progress) {
    if (cache_dir.empty() || !(source.settings.lod_texels > 0.0f) ||
        source.hierarchy.levels.empty()) {
        return std::nullopt;
    }
    // The preparation's key where it had a cache folder (with lod_texels > 0, as here).
    const PreparedCloudKey key =
        source.key ? *source.key : prepared_cloud_key(*source.cloud, source.geometry_options, true);
    SpatialCloudEntry entry{spatial_cloud_entry_path(key, cache_dir), prepared_cloud_key_hex(key)};
    try {
        const SpatialCloud existing(entry.path, entry.key_hex);
        return entry;
    } catch (const IoError&) {
        // Missing or not usable: written (again) below.
    }
    if (!source.curve.empty()) {
        write_spatial_cloud(entry.path, key, source.curve, source.hierarchy, progress);
    } else {
        write_spatial_cloud(entry.path, key, *source.cloud, source.geometry, source.hierarchy,
                            progress);
    }
    entry.written = true;
    return entry;
}

BakeSummary bake_probe_set_from_cloud(const PointCloud& cloud, const ProbePlacement& placement,
                                      const BakeSettings& settings,
                                      const LocalGeometryOptions& geometry_options,
                                      const std::string& folder, const json& sources,
                                      Progress* progress, const std::string& cache_dir) {
    if (placement.positions.empty()) {
        throw InputError("bake: no probe positions given");
    }
    if (cloud.size() == 0) {
        throw InputError("bake: the point cloud is empty");
    }
    // The caller keeps the cloud alive for the call: a pointer that owns nothing.
    const std::shared_ptr<const PointCloud> borrowed(std::shared_ptr<const PointCloud>{}, &cloud);
    const CloudBakeSource source =
        prepare_cloud_bake(borrowed, settings, geometry_options, progress, cache_dir);
    BakeSummary summary = write_probe_set(
        folder, cloud_bake_manifest(cloud, placement, settings, geometry_options, sources),
        [&](std::size_t i) { return bake_probe(source, placement.positions[i], progress); },
        progress);
    summary.normals_seconds = source.normals_seconds;
    summary.hierarchy_seconds = source.hierarchy_seconds;
    summary.prepared_from_cache = source.from_cache;
    return summary;
}

} // namespace lfprobe
