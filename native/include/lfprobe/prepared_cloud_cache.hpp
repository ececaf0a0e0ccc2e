// A cache of what a cloud bake prepares before its first probe (prepare_cloud_bake): the
// points' local geometry (normals, spacing, edges, Morton order) and the point hierarchy. On a
// real scan they take most of a bake's time (21.6 M points: 18 s of normals and 3 s of
// hierarchy against 6 s for a 2048² probe), and they depend only on the cloud and a few
// options, not on where the probes are: a rebake after moving a grid, another resolution, or a
// cluster's workers (core/cluster_bake.py) read them instead of computing them again.
//
// An entry is named by a hash of everything that shapes it: the cloud's arrays (positions,
// colours, normals, intensities, scan indices), its scans' scanner positions, the geometry
// options and whether a hierarchy is built, and the format version. It is written to a
// temporary and renamed, so a cancelled or failed preparation leaves no entry; one that does
// not match its name, fails its checksum or does not hold a consistent hierarchy is ignored
// and computed again.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include "lfprobe/local_geometry.hpp"
#include "lfprobe/point_cloud.hpp"
#include "lfprobe/point_hierarchy.hpp"
#include "lfprobe/progress.hpp"

namespace lfprobe {

struct PreparedCloud {
    LocalGeometry geometry;
    PointHierarchy hierarchy;
};

// What names and checks an entry: a 128-bit hash of the inputs listed above.
struct PreparedCloudKey {
    std::array<std::uint64_t, 2> hash{};
    std::uint64_t point_count = 0;
    friend bool operator==(const PreparedCloudKey&, const PreparedCloudKey&) = default;
};

[[nodiscard]] PreparedCloudKey prepared_cloud_key(const PointCloud& cloud,
                                                  const LocalGeometryOptions& options,
                                                  bool with_hierarchy);

// The key as 32 hex digits, as entries are named.
[[nodiscard]] std::string prepared_cloud_key_hex(const PreparedCloudKey& key);

// The entry for `key` in `cache_dir` ("" when cache_dir is empty).
[[nodiscard]] std::string prepared_cloud_entry_path(const PreparedCloudKey& key,
                                                    const std::string& cache_dir);

// The entry's contents, or none when it is missing, unreadable, of another key or damaged.
[[nodiscard]] std::optional<PreparedCloud> read_prepared_cloud(const std::string& entry,
                                                               const PreparedCloudKey& key);

// Writes the entry atomically (creating `cache_dir`'s folder); throws IoError.
void write_prepared_cloud(const std::string& entry, const PreparedCloudKey& key,
                          const LocalGeometry& geometry, const PointHierarchy& hierarchy);

// The same where a cache that cannot be written (a full disk, a read-only folder) only means
// the next run computes again: false instead of an error.
bool try_write_prepared_cloud(const std::string& entry, const PreparedCloudKey& key,
                              const LocalGeometry& geometry, const PointHierarchy& hierarchy);

// The cloud's local geometry with the default options, for what needs the geometry without a
// bake (splats, the Poisson peer's normals): read from a bake's entry in `cache_dir` (it holds
// the point hierarchy too) or from a geometry-only entry, else estimated and written as a
// geometry-only entry, so that several such uses of one cloud estimate it once. An empty
// cache_dir estimates and caches nothing.
[[nodiscard]] LocalGeometry cached_local_geometry(const PointCloud& cloud,
                                                  const std::string& cache_dir,
                                                  Progress* progress = nullptr);

} // namespace lfprobe
