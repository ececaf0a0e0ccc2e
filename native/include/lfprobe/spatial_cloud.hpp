// A prepared cloud laid out to be read in parts: what a probe's bake reads of every point
// (position, colour, normal, spacing, orientation, edge) stored in the point hierarchy's Morton
// order, then the hierarchy's levels, each array on pages of its own in one file. A process maps
// the file and bakes from it (core/cluster_bake.py's workers): a probe's cut reads the
// full-density points near the probe and the coarse cells' surfels elsewhere, so the pages a
// task touches follow where its probes are, not the cloud's size, and a cloud larger than a
// worker's memory still bakes (the mapping's pages are the file's, which the system can drop).
//
// The file is named by the prepared-cloud key (prepared_cloud_cache.hpp) and written to a
// temporary and renamed. Its header and section table carry a checksum; the sections do not
// (checking them would read them all): what a cut reads is checked as it is read instead, the
// hierarchy's runs against their arrays and every gathered value for being finite, so a damaged
// file gives IoError, never a read out of bounds.
#pragma once

#include <cstddef>
#include <optional>
#include <string>

#include <glm/vec3.hpp>

#include "lfprobe/curve_ordered_cloud.hpp"
#include "lfprobe/local_geometry.hpp"
#include "lfprobe/mapped_file.hpp"
#include "lfprobe/point_cloud.hpp"
#include "lfprobe/point_hierarchy.hpp"
#include "lfprobe/prepared_cloud_cache.hpp"
#include "lfprobe/probe_bake.hpp"
#include "lfprobe/progress.hpp"

namespace lfprobe {

// The spatial cloud of `key` in `cache_dir`: spatial-<key>.lfpspatial.
[[nodiscard]] std::string spatial_cloud_entry_path(const PreparedCloudKey& key,
                                                   const std::string& cache_dir);

// Writes the spatial cloud of `cloud` with its `geometry` and `hierarchy` (which must have
// levels: a cloud without one bakes from every point, which this file does not serve) to
// `path` atomically, creating its folder. Cancellable; IoError when it cannot be written.
void write_spatial_cloud(const std::string& path, const PreparedCloudKey& key,
                         const PointCloud& cloud, const LocalGeometry& geometry,
                         const PointHierarchy& hierarchy, Progress* progress = nullptr);
// The same file from the cloud's points already copied into curve order (from `hierarchy`):
// read front to back instead of gathered again.
void write_spatial_cloud(const std::string& path, const PreparedCloudKey& key,
                         const CurveOrderedCloud& curve, const PointHierarchy& hierarchy,
                         Progress* progress = nullptr);

class SpatialCloud {
public:
    // Maps `path` without reading its sections. IoError when it is not a spatial cloud of
    // `key_hex` (prepared_cloud_key_hex): another format or version, another key, a damaged
    // header or section table, sections that do not fit the file.
    SpatialCloud(const std::string& path, const std::string& key_hex);

    [[nodiscard]] std::size_t point_count() const { return hierarchy_.point_count; }
    [[nodiscard]] std::size_t file_bytes() const { return file_.size(); }
    [[nodiscard]] const std::string& path() const { return file_.path(); }
    [[nodiscard]] const PointHierarchyView& hierarchy() const { return hierarchy_; }
    // The file's bytes this process has touched so far (MappedFile::resident_bytes).
    [[nodiscard]] std::optional<std::size_t> resident_bytes() const {
        return file_.resident_bytes();
    }

    // The cut's points (cut.points: positions along the curve, as cut_for_probe gives them
    // over hierarchy()) copied out of the file into `points` and `geometry`, cut.points then
    // numbering them 0 … m-1. Checks every value read, and the cut's surfels.
    void gather(HierarchyCut& cut, PointCloud& points, LocalGeometry& geometry) const;

private:
    struct Section {
        std::size_t offset = 0;
        std::size_t count = 0;
    };
    template <class T>
    T read(const Section& section, std::size_t i) const;

    MappedFile file_;
    PointHierarchyView hierarchy_;
    Section positions_, colours_, normals_, spacing_, oriented_, edges_;
};

// Bakes the probe at `centre` from `cloud`: the same probe bake_probe_from_hierarchy bakes from
// the cloud, geometry and hierarchy the file was written from, bit for bit. settings.lod_texels
// must be above 0 (a spatial cloud serves cuts).
[[nodiscard]] ProbeMap bake_probe_from_spatial_cloud(const SpatialCloud& cloud,
                                                     const glm::dvec3& centre,
                                                     const BakeSettings& settings,
                                                     Progress* progress = nullptr);

} // namespace lfprobe
