// Writing a probe set without ever leaving a half-written one (docs/DESIGN.md §3): the probes
// go into the staging folder `DIR.partial` beside `DIR`, each file written atomically, and the
// manifest is written last, when every probe is there; then the complete set is swapped in.
// The steps are separate so that the probes may be baked by other processes, on other machines
// (a Dask cluster, core/cluster_bake.py), between opening and finishing the staging folder.
#pragma once

#include <cstddef>
#include <exception>
#include <optional>
#include <string>
#include <vector>

#include <tbb/task_group.h>

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

// A set's probes written into `staging` while the next one bakes: write(index, map) hands a
// baked probe over and returns once the probe before it is written, so at most one write runs
// beside the caller's next bake. The write's serial parts (the file, the known space's sort) then
// use a core the bake leaves idle: a 2048² probe from the lab room's 0.1° scans spends 0.8 s of
// its 4.4 s writing. The writes run as tasks of the caller's TBB arena, so a bake limited to
// one thread writes on that one thread, after its bake. finish() waits for the last write and
// returns every staged probe in the order given; a write's error is rethrown by the call after
// it. The destructor waits for a write still running (a bake that threw or was cancelled).
class OverlappedProbeWrites {
public:
    explicit OverlappedProbeWrites(std::string staging) : staging_(std::move(staging)) {}
    ~OverlappedProbeWrites();
    OverlappedProbeWrites(const OverlappedProbeWrites&) = delete;
    OverlappedProbeWrites& operator=(const OverlappedProbeWrites&) = delete;

    void write(std::size_t index, ProbeMap map);
    [[nodiscard]] std::vector<StagedProbe> finish();
    // Seconds spent in the writes themselves (overlapping the bakes).
    [[nodiscard]] double write_seconds() const { return write_seconds_; }

private:
    void wait_for_pending();

    std::string staging_;
    tbb::task_group writes_;
    std::optional<ProbeMap> pending_map_; // the map being written, until its write is collected
    StagedProbe pending_;
    std::exception_ptr error_;
    double write_seconds_ = 0.0;
    std::vector<StagedProbe> staged_;
};

// Finishes a staged bake: `manifest` must list one record per placement position, in order,
// each of whose files is in the staging folder. Removes temporaries that killed writers left,
// writes the manifest there and swaps the set in where `folder` was (the earlier set moves to
// `folder`.previous, then goes). InputError naming the first missing probe otherwise; the
// staging folder is left as it was.
void finish_probe_set_staging(const std::string& folder, const ProbeSetManifest& manifest);

// The probe count, mean coverage and byte figures of `summary` from the probes a bake staged.
void add_staged_figures(BakeSummary& summary, const std::vector<StagedProbe>& staged);

} // namespace lfprobe
