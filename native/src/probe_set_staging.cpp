#include "lfprobe/probe_set_staging.hpp"

#include <chrono>
#include <filesystem>
#include <system_error>
#include <utility>

#include "lfprobe/error.hpp"
#include "lfprobe/known_space.hpp"
#include "lfprobe/probe_exr.hpp"

#include <tbb/parallel_for.h>

namespace lfprobe {

namespace fs = std::filesystem;

namespace {

// The folder as a path without a trailing separator ("out/set/" names "out/set").
fs::path set_folder_path(const std::string& folder) {
    fs::path p = fs::path(folder).lexically_normal();
    if (!p.has_filename() && p.has_parent_path()) {
        p = p.parent_path();
    }
    return p;
}

fs::path sibling(const fs::path& folder, const std::string& suffix) {
    return folder.parent_path() / (folder.filename().string() + suffix);
}

// A probe set's own files: its manifest, its probes, their known space and their temporaries.
bool is_probe_set_file(const std::string& name) {
    return name.rfind("probe_", 0) == 0 || name.rfind(kManifestName, 0) == 0 ||
           name.rfind(kKnownSpaceName, 0) == 0;
}

// Where probe `index` leaves its own known space in the staging folder, for the finish to merge
// into the set's.
std::string staged_known_space_name(std::size_t index) {
    return probe_file_name(index) + ".known";
}

// A bake replaces `folder` as a whole, so it must hold nothing but an earlier set's files.
void check_replaceable(const fs::path& folder) {
    std::error_code ec;
    if (!fs::exists(folder, ec)) {
        return;
    }
    if (!fs::is_directory(folder, ec)) {
        throw InputError(folder.string() + ": exists and is not a folder; a probe set is a folder");
    }
    for (const auto& entry : fs::directory_iterator(folder, ec)) {
        const std::string name = entry.path().filename().string();
        if (!entry.is_regular_file(ec) || !is_probe_set_file(name)) {
            throw InputError(folder.string() + ": holds \"" + name +
                             "\", which is not a probe set's file; bake into an empty folder or "
                             "over an earlier probe set");
        }
    }
}

// Puts the complete set in `staging` where `target` is: the earlier set moves aside first and
// goes only once the new one is in place.
void swap_in(const fs::path& staging, const fs::path& target) {
    std::error_code ec;
    const fs::path previous = sibling(target, ".previous");
    fs::remove_all(previous, ec);
    const bool had_one = fs::exists(target, ec);
    if (had_one) {
        fs::rename(target, previous, ec);
        if (ec) {
            throw IoError(target.string() + ": cannot move the earlier probe set aside (" +
                          ec.message() + ")");
        }
    }
    fs::rename(staging, target, ec);
    if (ec) {
        if (had_one) {
            std::error_code back;
            fs::rename(previous, target, back);
        }
        throw IoError(target.string() + ": cannot put the new probe set in place (" + ec.message() +
                      ")");
    }
    fs::remove_all(previous, ec);
}

// What writers that died left in `staging`: anything but the probes `manifest` lists (their
// temporaries, PROBE.tmp.PID.N, and probes of no position, which no bake of it writes).
void remove_strays(const fs::path& staging, const ProbeSetManifest& manifest) {
    std::error_code ec;
    std::vector<fs::path> strays;
    for (const auto& entry : fs::directory_iterator(staging, ec)) {
        const std::string name = entry.path().filename().string();
        bool listed = !manifest.known_space_file.empty() && name == manifest.known_space_file;
        for (const ProbeRecord& record : manifest.probes) {
            listed = listed || record.file == name;
        }
        if (!listed) {
            strays.push_back(entry.path());
        }
    }
    for (const fs::path& stray : strays) {
        fs::remove_all(stray, ec);
    }
}

} // namespace

std::string probe_set_staging_path(const std::string& folder) {
    return sibling(set_folder_path(folder), ".partial").string();
}

std::string open_probe_set_staging(const std::string& folder) {
    check_replaceable(set_folder_path(folder));
    const fs::path staging = probe_set_staging_path(folder);
    std::error_code ec;
    fs::remove_all(staging, ec); // what a killed bake left
    fs::create_directories(staging, ec);
    if (ec) {
        throw IoError(staging.string() + ": cannot create the probe set's staging folder (" +
                      ec.message() + ")");
    }
    return staging.string();
}

void discard_probe_set_staging(const std::string& folder) {
    std::error_code ec;
    fs::remove_all(probe_set_staging_path(folder), ec);
}

StagedProbe write_staged_probe(const std::string& staging, std::size_t index, const ProbeMap& map) {
    std::error_code ec;
    if (!fs::is_directory(staging, ec)) {
        throw IoError(staging + ": the probe set's staging folder is gone (the bake was called "
                                "off)");
    }
    const std::string file = probe_file_name(index);
    const std::string path = (fs::path(staging) / file).string();
    write_probe_exr(path, map);
    KnownSpace known;
    known.add_probe(map, index);
    known.write((fs::path(staging) / staged_known_space_name(index)).string());
    StagedProbe staged;
    staged.index = index;
    // The map's own position: a planned probe may have been moved off its grid point.
    staged.record =
        ProbeRecord{file, map.position, map.resolution, coverage_of(map), map.memory_bytes()};
    staged.bytes_on_disk = static_cast<std::size_t>(fs::file_size(path, ec));
    return staged;
}

OverlappedProbeWrites::~OverlappedProbeWrites() {
    try {
        writes_.wait();
    } catch (...) {
        // Already on the way out of a failed bake: its own error is the one to report.
    }
}

void OverlappedProbeWrites::wait_for_pending() {
    writes_.wait();
    if (error_) {
        std::rethrow_exception(std::exchange(error_, nullptr));
    }
    if (pending_map_) {
        staged_.push_back(pending_);
        pending_map_.reset();
    }
}

void OverlappedProbeWrites::write(std::size_t index, ProbeMap map) {
    wait_for_pending();
    pending_map_.emplace(std::move(map));
    writes_.run([this, index] {
        try {
            const auto start = std::chrono::steady_clock::now();
            pending_ = write_staged_probe(staging_, index, *pending_map_);
            write_seconds_ +=
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        } catch (...) {
            error_ = std::current_exception();
        }
    });
}

std::vector<StagedProbe> OverlappedProbeWrites::finish() {
    wait_for_pending();
    return std::move(staged_);
}

void finish_probe_set_staging(const std::string& folder, const ProbeSetManifest& listed) {
    ProbeSetManifest manifest = listed;
    const fs::path target = set_folder_path(folder);
    const fs::path staging = probe_set_staging_path(folder);
    const std::size_t count = manifest.placement.positions.size();
    if (manifest.probes.size() != count) {
        throw InputError(folder + ": the manifest lists " + std::to_string(manifest.probes.size()) +
                         " probes for " + std::to_string(count) + " positions");
    }
    std::error_code ec;
    for (std::size_t i = 0; i < count; ++i) {
        const std::string& file = manifest.probes[i].file;
        if (file != probe_file_name(i) || !fs::is_regular_file(staging / file, ec)) {
            throw InputError(staging.string() + ": probe " + std::to_string(i) + " (" +
                             probe_file_name(i) + ") is not there; the set is not complete");
        }
    }
    check_replaceable(target);
    // The probes' known spaces, merged into the set's; a set some of whose probes were staged
    // without one (by an older writer) gets none, and traces ask every probe as before.
    manifest.known_space_file.clear();
    bool every_probe = true;
    for (std::size_t i = 0; i < count && every_probe; ++i) {
        every_probe = fs::is_regular_file(staging / staged_known_space_name(i), ec);
    }
    if (every_probe) {
        std::vector<KnownSpace> parts(count);
        tbb::parallel_for(std::size_t{0}, count, [&](std::size_t i) {
            parts[i] = KnownSpace::read((staging / staged_known_space_name(i)).string());
        });
        for (std::size_t width = 1; width < count; width *= 2) {
            tbb::parallel_for(std::size_t{0}, count, 2 * width, [&](std::size_t i) {
                if (i + width < count) {
                    parts[i].merge(parts[i + width]);
                    parts[i + width] = KnownSpace();
                }
            });
        }
        parts.front().write((staging / kKnownSpaceName).string());
        manifest.known_space_file = kKnownSpaceName;
    }
    remove_strays(staging, manifest);
    write_manifest(staging.string(), manifest);
    swap_in(staging, target);
}

void add_staged_figures(BakeSummary& summary, const std::vector<StagedProbe>& staged) {
    summary.probe_count = staged.size();
    ProbeCoverage mean;
    for (const StagedProbe& probe : staged) {
        mean.surface += probe.record.coverage.surface;
        mean.inferred += probe.record.coverage.inferred;
        mean.empty += probe.record.coverage.empty;
        mean.unknown += probe.record.coverage.unknown;
        summary.bytes_in_memory_per_probe = probe.record.memory_bytes;
        summary.bytes_on_disk += probe.bytes_on_disk;
    }
    if (!staged.empty()) {
        const double count = static_cast<double>(staged.size());
        mean.surface /= count;
        mean.inferred /= count;
        mean.empty /= count;
        mean.unknown /= count;
    }
    summary.mean_coverage = mean;
}

} // namespace lfprobe
