// A binary cache of parsed scan files, so that a cloud of tens of millions of points is
// parsed once. Entries are keyed by the file's absolute path, size, modification time and
// the read options; a stale or corrupt entry is ignored and rewritten. Entries are written to
// a temporary name and renamed, so an interrupted write never leaves a partial entry.
#pragma once

#include <string>
#include <vector>

#include "lfprobe/scan_reader.hpp"

namespace lfprobe {

// Reads `path` through the cache in `cache_dir` (created when missing). An empty cache_dir
// disables caching. `hit` (when given) says whether the cache answered.
[[nodiscard]] ScanFile read_scan_file_cached(const std::string& path,
                                             const ScanReadOptions& options,
                                             const std::string& cache_dir,
                                             Progress* progress = nullptr, bool* hit = nullptr);

// The cache entry that `path` is read from (or written to) in `cache_dir`; empty where the
// cache does not apply (no cache_dir, or a file that cannot be stamped).
[[nodiscard]] std::string scan_cache_entry_path(const std::string& path,
                                                const ScanReadOptions& options,
                                                const std::string& cache_dir);

// The scan loading every caller runs: reads each of `paths` (through the cache in `cache_dir`;
// empty: no cache) and merges them into one cloud. InputError when `paths` is empty.
[[nodiscard]] PointCloud load_scans(const std::vector<std::string>& paths,
                                    const ScanReadOptions& read_options,
                                    const MergeOptions& merge_options, const std::string& cache_dir,
                                    Progress* progress = nullptr);

} // namespace lfprobe
