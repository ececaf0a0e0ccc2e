// Writing a probe set without ever leaving a half-written one (docs/DESIGN.md §3): the probes
// go into the staging folder `DIR.partial` beside `DIR`, each file written atomically, and the
// manifest is written last, when every probe is there; then the complete set is swapped in.
// The steps are separate so that the probes may be baked by other processes, on other machines
// (a Dask cluster, core/cluster_bake.py), between opening and finishing the staging folder.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "lfprobe/probe_map.hpp"
#include "lfprobe/probe_set.hpp"

namespace lfprobe {

// `folder`.partial (a trailing separator of `folder` ignored).
[[nodiscard]] std::string probe_set_staging_path(const std::string& folder);

// Empties and creates the staging folder of `folder` and returns its path. InputError when
// `folder` holds anything but an earlier set's files (a bake replaces the folder as a whole).
std::string open_probe_set_staging(const std::string& folder);

// Removes the staging folder of `folder` and everything in it (a cancelled or failed bake).
void discard_probe_set_staging(const std::string& folder);

// A probe written into a staging folder: its manifest record and its file's size.
struct StagedProbe {
    std::size_t index = 0;
    ProbeRecord record;
    std::size_t bytes_on_disk = 0;
};

// Writes probe `index` (`map`) into `staging` under probe_file_name(index), atomically.
// IoError when `staging` is gone: removing the staging folder is how a bake is called off.
[[nodiscard]] StagedProbe write_staged_probe(const std::string& staging, std::size_t index,
                                             const ProbeMap& map);

// Finishes a staged bake: `manifest` must list one record per placement position, in order,
// each of whose files is in the staging folder. Removes temporaries that killed writers left,
// writes the manifest there and swaps the set in where `folder` was (the earlier set moves to
// `folder`.previous, then goes). InputError naming the first missing probe otherwise; the
// staging folder is left as it was.
void finish_probe_set_staging(const std::string& folder, const ProbeSetManifest& manifest);

// The probe count, mean coverage and byte figures of `summary` from the probes a bake staged.
void add_staged_figures(BakeSummary& summary, const std::vector<StagedProbe>& staged);

} // namespace lfprobe
