// A probe set on disk (docs/DESIGN.md §3): a folder with manifest.json and one EXR per probe.
// The manifest holds the format version, the world offset, the placement (positions, or grid
// origin/spacing/counts), per-probe resolution and coverage, the bake settings and the
// sources with their hashes. It is written last, so a folder without it is no probe set.
#pragma once

#include <functional>
#include <string>
#include <vector>

// The whole of nlohmann/json, not json_fwd.hpp: the manifest holds JSON values.
#include <nlohmann/json.hpp>

#include "lfprobe/probe_bake.hpp"
#include "lfprobe/probe_map.hpp"
#include "lfprobe/probe_placement.hpp"
#include "lfprobe/probe_storage.hpp"
#include "lfprobe/progress.hpp"

namespace lfprobe {

inline constexpr int kProbeSetFormatVersion = 1;
inline constexpr const char* kManifestName = "manifest.json";

struct ProbeRecord {
    std::string file; // relative to the set's folder
    glm::dvec3 position{0.0};
    int resolution = 0;
    ProbeCoverage coverage;
    std::size_t memory_bytes = 0;
};

// A probe's entry in the manifest's "probes" list.
[[nodiscard]] nlohmann::json probe_record_json(const ProbeRecord& record);

struct ProbeSetManifest {
    int format_version = kProbeSetFormatVersion;
    glm::dvec3 world_offset{0.0};
    ProbePlacement placement;
    std::vector<ProbeRecord> probes;
    nlohmann::json bake;    // settings the probes were baked with
    nlohmann::json sources; // array: path, hash, points, scanner, ...
    // How a field loads the probes by default (the files stay full precision): chosen from the
    // data at bake time, or set later with set_probe_set_storage.
    ProbeStorage storage;
    // Where the probes know something about space (known_space.hpp), a file in the set's
    // folder; empty for sets baked before bakes wrote it ("known_space" in the JSON, absent
    // then).
    std::string known_space_file;

    [[nodiscard]] nlohmann::json to_json() const;
    [[nodiscard]] static ProbeSetManifest from_json(const nlohmann::json& j,
                                                    const std::string& where);
};

[[nodiscard]] std::string probe_file_name(std::size_t index);

[[nodiscard]] ProbeSetManifest read_manifest(const std::string& folder);
void write_manifest(const std::string& folder, const ProbeSetManifest& manifest);

// `manifest` with its probes held as `storage`: the storage and every probe's memory figure.
void use_storage(ProbeSetManifest& manifest, const ProbeStorage& storage);

// Sets the in-memory storage a set's probes load with (the files are not touched) and the
// per-probe memory figures of its manifest; the manifest is rewritten atomically.
ProbeSetManifest set_probe_set_storage(const std::string& folder, const ProbeStorage& storage);

// Reads probe `index` of the set in `folder`.
[[nodiscard]] ProbeMap read_probe(const std::string& folder, const ProbeSetManifest& manifest,
                                  std::size_t index);

struct BakeSummary {
    std::string folder;
    std::size_t probe_count = 0;
    double normals_seconds = 0.0;
    double hierarchy_seconds = 0.0; // building the point hierarchy, once per bake
    // Normals, spacing and hierarchy read from the prepared-cloud cache (normals_seconds is
    // then the read, hierarchy_seconds 0).
    bool prepared_from_cache = false;
    double bake_seconds = 0.0;  // all probes, splatting and hole filling
    double write_seconds = 0.0; // EXR encoding and writing (beside the next probe's bake)
    ProbeCoverage mean_coverage;
    std::size_t bytes_in_memory_per_probe = 0;
    std::size_t bytes_on_disk = 0;
};

// The write path every bake shares: bakes probe i with `bake_one(i)` and writes it, one probe at
// a time, then `manifest` (with the probe records added), all into the staging folder
// `folder`.partial beside `folder`, and swaps the complete set in (an earlier set moves to
// `folder`.previous, then goes). A cancelled or failed bake removes the staging folder and
// leaves an earlier set in `folder` exactly as it was. InputError when `folder` holds anything
// but an earlier set's files. Fills the bake, write, coverage and byte figures of the returned
// summary.
[[nodiscard]] BakeSummary write_probe_set(const std::string& folder, ProbeSetManifest manifest,
                                          const std::function<ProbeMap(std::size_t)>& bake_one,
                                          Progress* progress = nullptr);

// The splat settings of a cloud bake as its manifest records them under "bake": one list for
// every kind of cloud bake, so that a new setting is recorded by all of them.
[[nodiscard]] nlohmann::json splat_settings_json(const BakeSettings& settings);

} // namespace lfprobe
