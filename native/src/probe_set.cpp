#include "lfprobe/probe_set.hpp"

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "lfprobe/bake_scratch.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/json_input.hpp"
#include "lfprobe/probe_exr.hpp"
#include "lfprobe/probe_set_staging.hpp"
#include "seconds_since.hpp"

namespace lfprobe {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

glm::dvec3 vec_from(const json& j, const std::string& what, const std::string& where) {
    if (!j.is_array() || j.size() != 3 || !j[0].is_number() || !j[1].is_number() ||
        !j[2].is_number()) {
        throw InputError(where + ": '" + what + "' must be an array of three numbers");
    }
    return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
}

json coverage_json(const ProbeCoverage& c) {
    return json{{"surface", c.surface},
                {"inferred", c.inferred},
                {"empty", c.empty},
                {"unknown", c.unknown}};
}

} // namespace

std::string probe_file_name(std::size_t index) {
    char name[32];
    std::snprintf(name, sizeof name, "probe_%05zu.exr", index);
    return name;
}

json probe_record_json(const ProbeRecord& p) {
    return json{{"file", p.file},
                {"position", json_of(p.position)},
                {"resolution", p.resolution},
                {"coverage", coverage_json(p.coverage)},
                {"memory_bytes", p.memory_bytes}};
}

json ProbeSetManifest::to_json() const {
    json j;
    j["format"] = "lfprobe-probe-set";
    j["format_version"] = format_version;
    j["world_offset"] = json_of(world_offset);
    j["frame"] = "probe positions are local: world = world_offset + position";
    if (placement.is_grid) {
        j["layout"] = "grid";
        j["grid"] = json{{"origin", json_of(placement.grid.origin)},
                         {"spacing", json_of(placement.grid.spacing)},
                         {"counts", placement.grid.counts}};
    } else {
        j["layout"] = "positions";
    }
    json list = json::array();
    for (const ProbeRecord& p : probes) {
        list.push_back(probe_record_json(p));
    }
    j["probes"] = list;
    j["bake"] = bake;
    j["sources"] = sources.is_null() ? json::array() : sources;
    j["storage"] = storage.to_json();
    if (!known_space_file.empty()) {
        j["known_space"] = known_space_file;
    }
    j["channels"] = json{{"R,G,B", "linear radiance, half"},
                         {"A", "confidence: 1 measured, (0,1) inferred, 0 unknown or empty"},
                         {"Z", "radial distance in metres, float32; NaN unknown, +inf empty"},
                         {"N.X,N.Y,N.Z", "world-space unit surface normal, half"}};
    return j;
}

namespace {

// A whole-number field of `j`, or `fallback` where it is absent. Anything else (a fraction,
// 1e300, a string) is refused naming the field: never cast, since a float beyond the integer's
// range is undefined behaviour (found by the manifest fuzz harness).
std::int64_t whole_number_or(const json& j, const char* key, std::int64_t fallback,
                             const std::string& where) {
    const auto found = j.find(key);
    if (found == j.end()) {
        return fallback;
    }
    if (!found->is_number_integer() ||
        (found->is_number_unsigned() &&
         found->get<std::uint64_t>() >
             static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()))) {
        throw InputError(where + ": '" + key + "' must be a whole number, got " + found->dump());
    }
    return found->get<std::int64_t>();
}

} // namespace

ProbeSetManifest ProbeSetManifest::from_json(const json& j, const std::string& where) {
    if (!j.is_object() || j.value("format", "") != "lfprobe-probe-set") {
        throw InputError(where + ": not an lfprobe probe set manifest (expected \"format\": "
                                 "\"lfprobe-probe-set\")");
    }
    ProbeSetManifest m;
    const std::int64_t format_version = whole_number_or(j, "format_version", 0, where);
    if (format_version != kProbeSetFormatVersion) {
        throw InputError(where + ": format_version " + std::to_string(format_version) +
                         " is not supported (expected " + std::to_string(kProbeSetFormatVersion) +
                         ")");
    }
    m.world_offset = vec_from(j.at("world_offset"), "world_offset", where);
    if (!j.contains("probes") || !j["probes"].is_array()) {
        throw InputError(where + ": expected a 'probes' array");
    }
    std::vector<glm::dvec3> positions;
    for (const json& p : j["probes"]) {
        ProbeRecord r;
        r.file = p.at("file").get<std::string>();
        if (r.file.find('/') != std::string::npos || r.file.find("..") != std::string::npos) {
            throw InputError(where + ": probe file '" + r.file + "' must be a plain file name");
        }
        r.position = vec_from(p.at("position"), "position", where);
        const json& resolution = p.at("resolution");
        if (!resolution.is_number_integer() || resolution.get<std::int64_t>() < 1 ||
            resolution.get<std::int64_t>() > kMaxProbeResolution) {
            throw InputError(where + ": probe '" + r.file + "' has resolution " +
                             resolution.dump() + "; expected a whole number from 1 to " +
                             std::to_string(kMaxProbeResolution));
        }
        r.resolution = resolution.get<int>();
        if (p.contains("coverage")) {
            const json& c = p["coverage"];
            r.coverage = ProbeCoverage{c.value("surface", 0.0), c.value("inferred", 0.0),
                                       c.value("empty", 0.0), c.value("unknown", 0.0)};
        }
        const std::int64_t memory_bytes = whole_number_or(p, "memory_bytes", 0, where);
        if (memory_bytes < 0) {
            throw InputError(where + ": probe '" + r.file + "' has a negative memory_bytes");
        }
        r.memory_bytes = static_cast<std::size_t>(memory_bytes);
        positions.push_back(r.position);
        m.probes.push_back(std::move(r));
    }
    if (j.value("layout", "positions") == "grid") {
        const json& g = j.at("grid");
        ProbeGrid grid;
        grid.origin = vec_from(g.at("origin"), "grid.origin", where);
        grid.spacing = vec_from(g.at("spacing"), "grid.spacing", where);
        const json& counts = g.at("counts");
        std::uint64_t product = 1;
        for (std::size_t a = 0; a < 3; ++a) {
            const json& c = counts.at(a);
            if (!c.is_number_integer() || c.get<std::int64_t>() < 1 ||
                c.get<std::int64_t>() > static_cast<std::int64_t>(m.probes.size())) {
                throw InputError(where + ": grid.counts " + counts.dump() + " do not fit the " +
                                 std::to_string(m.probes.size()) + " probes listed");
            }
            grid.counts[a] = c.get<int>();
            product *= static_cast<std::uint64_t>(grid.counts[a]);
        }
        if (product != m.probes.size()) {
            throw InputError(where + ": grid counts give " + std::to_string(product) +
                             " probes but " + std::to_string(m.probes.size()) + " are listed");
        }
        m.placement = ProbePlacement::from_grid(grid);
        if (m.placement.positions.size() != m.probes.size()) {
            throw InputError(where + ": grid counts give " +
                             std::to_string(m.placement.positions.size()) + " probes but " +
                             std::to_string(m.probes.size()) + " are listed");
        }
    } else {
        m.placement = ProbePlacement::from_positions(positions);
    }
    m.bake = j.value("bake", json::object());
    m.sources = j.value("sources", json::array());
    if (j.contains("storage")) {
        m.storage = ProbeStorage::from_json(j["storage"], where);
    }
    if (j.contains("known_space")) {
        if (!j["known_space"].is_string()) {
            throw InputError(where + ": 'known_space' must be a file name, got " +
                             j["known_space"].dump());
        }
        m.known_space_file = j["known_space"].get<std::string>();
        if (m.known_space_file.empty() || m.known_space_file.find('/') != std::string::npos ||
            m.known_space_file.find("..") != std::string::npos) {
            throw InputError(where + ": known-space file '" + m.known_space_file +
                             "' must be a plain file name");
        }
    }
    return m;
}

ProbeSetManifest read_manifest(const std::string& folder) {
    const std::string path = (fs::path(folder) / kManifestName).string();
    const json j = read_json_file(path, "probe set manifest", "was the bake finished?");
    try {
        return ProbeSetManifest::from_json(j, path);
    } catch (const json::exception& e) {
        throw InputError(path + ": " + e.what());
    }
}

void write_manifest(const std::string& folder, const ProbeSetManifest& manifest) {
    write_file_atomically((fs::path(folder) / kManifestName).string(),
                          manifest.to_json().dump(2) + "\n");
}

ProbeMap read_probe(const std::string& folder, const ProbeSetManifest& manifest,
                    std::size_t index) {
    if (index >= manifest.probes.size()) {
        throw InputError(folder + ": probe " + std::to_string(index) +
                         " does not exist (the set has " + std::to_string(manifest.probes.size()) +
                         ")");
    }
    const ProbeRecord& record = manifest.probes[index];
    ProbeMap map = read_probe_exr((fs::path(folder) / record.file).string());
    if (map.resolution != record.resolution) {
        throw InputError(folder + "/" + record.file + ": resolution " +
                         std::to_string(map.resolution) + " does not match the manifest's " +
                         std::to_string(record.resolution));
    }
    map.position = record.position;
    return map;
}

void use_storage(ProbeSetManifest& manifest, const ProbeStorage& storage) {
    manifest.storage = storage;
    for (ProbeRecord& record : manifest.probes) {
        const auto n = static_cast<std::size_t>(record.resolution);
        record.memory_bytes = n * n * storage.bytes_per_texel();
    }
}

ProbeSetManifest set_probe_set_storage(const std::string& folder, const ProbeStorage& storage) {
    ProbeSetManifest manifest = read_manifest(folder);
    use_storage(manifest, storage);
    write_manifest(folder, manifest);
    return manifest;
}

BakeSummary write_probe_set(const std::string& folder, ProbeSetManifest manifest,
                            const std::function<ProbeMap(std::size_t)>& bake_one,
                            Progress* progress) {
    const std::size_t count = manifest.placement.positions.size();
    if (count == 0) {
        throw InputError("bake: no probe positions given");
    }
    const std::string staging = open_probe_set_staging(folder);
    try {
        BakeSummary summary;
        manifest.probes.clear();
        // One probe's scratch arrays serve the next (bake_scratch.hpp).
        const BakeScratchScope scratch;
        OverlappedProbeWrites writes(staging);
        for (std::size_t i = 0; i < count; ++i) {
            if (progress != nullptr) {
                progress->throw_if_cancelled();
            }
            const auto start = std::chrono::steady_clock::now();
            ProbeMap map = bake_one(i);
            summary.bake_seconds += seconds_since(start);
            writes.write(i, std::move(map));
        }
        if (progress != nullptr) {
            progress->begin_stage(
                "writing probe " + std::to_string(count) + " of " + std::to_string(count), 1);
        }
        const std::vector<StagedProbe> staged = writes.finish();
        summary.write_seconds = writes.write_seconds();
        for (const StagedProbe& probe : staged) {
            manifest.probes.push_back(probe.record);
        }
        finish_probe_set_staging(folder, manifest);
        add_staged_figures(summary, staged);
        summary.folder = folder;
        return summary;
    } catch (...) {
        discard_probe_set_staging(folder);
        throw;
    }
}

json splat_settings_json(const BakeSettings& settings) {
    return json{{"splat_scale", settings.splat_scale},
                {"splat_plane_reach", settings.splat_plane_reach},
                {"splat_core_scale", settings.splat_core_scale},
                {"max_splat_radius_texels", settings.max_splat_radius_texels},
                {"hole_fill_texels", settings.hole_fill_texels},
                {"min_distance", settings.min_distance},
                {"lod_texels", settings.lod_texels},
                {"lod_colour_tolerance", settings.lod_colour_tolerance},
                {"splat_edge_margin", settings.splat_edge_margin},
                {"face_the_probe", settings.face_the_probe}};
}

} // namespace lfprobe
