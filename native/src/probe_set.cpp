#include "lfprobe/probe_set.hpp"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "lfprobe/error.hpp"
#include "lfprobe/json_input.hpp"
#include "lfprobe/probe_exr.hpp"

namespace lfprobe {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

json vec_json(const glm::dvec3& v) {
    return json::array({v.x, v.y, v.z});
}

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

// Temporary files (NAME.tmp.PID.N) of a bake that was killed before it could rename them.
double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

} // namespace

std::string probe_file_name(std::size_t index) {
    char name[32];
    std::snprintf(name, sizeof name, "probe_%05zu.exr", index);
    return name;
}

json ProbeSetManifest::to_json() const {
    json j;
    j["format"] = "lfprobe-probe-set";
    j["format_version"] = format_version;
    j["world_offset"] = vec_json(world_offset);
    j["frame"] = "probe positions are local: world = world_offset + position";
    if (placement.is_grid) {
        j["layout"] = "grid";
        j["grid"] = json{{"origin", vec_json(placement.grid.origin)},
                         {"spacing", vec_json(placement.grid.spacing)},
                         {"counts", placement.grid.counts}};
    } else {
        j["layout"] = "positions";
    }
    json list = json::array();
    for (const ProbeRecord& p : probes) {
        list.push_back(json{{"file", p.file},
                            {"position", vec_json(p.position)},
                            {"resolution", p.resolution},
                            {"coverage", coverage_json(p.coverage)},
                            {"memory_bytes", p.memory_bytes}});
    }
    j["probes"] = list;
    j["bake"] = bake;
    j["sources"] = sources.is_null() ? json::array() : sources;
    j["storage"] = storage.to_json();
    j["channels"] = json{{"R,G,B", "linear radiance, half"},
                         {"A", "confidence: 1 measured, (0,1) inferred, 0 unknown or empty"},
                         {"Z", "radial distance in metres, float32; NaN unknown, +inf empty"},
                         {"N.X,N.Y,N.Z", "world-space unit surface normal, half"}};
    return j;
}

ProbeSetManifest ProbeSetManifest::from_json(const json& j, const std::string& where) {
    if (!j.is_object() || j.value("format", "") != "lfprobe-probe-set") {
        throw InputError(where + ": not an lfprobe probe set manifest (expected \"format\": "
                                 "\"lfprobe-probe-set\")");
    }
    ProbeSetManifest m;
    m.format_version = j.value("format_version", 0);
    if (m.format_version != kProbeSetFormatVersion) {
        throw InputError(where + ": format_version " + std::to_string(m.format_version) +
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
        r.memory_bytes = p.value("memory_bytes", std::size_t{0});
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
    return m;
}

ProbeSetManifest read_manifest(const std::string& folder) {
    const std::string path = (fs::path(folder) / kManifestName).string();
    std::error_code missing;
    if (!fs::is_regular_file(path, missing)) {
        throw MissingFileError(path + ": no probe set manifest here (was the bake finished?)");
    }
    std::ifstream in(path);
    if (!in) {
        throw IoError(path + ": cannot read the probe set manifest");
    }
    json j;
    try {
        j = parse_json(in, path);
    } catch (const json::exception& e) {
        throw InputError(path + ": invalid JSON (" + e.what() + ")");
    }
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

namespace {

BakeSummary write_probe_files(const std::string& folder, ProbeSetManifest manifest,
                              const std::function<ProbeMap(std::size_t)>& bake_one,
                              Progress* progress);

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

// A probe set's own files: its manifest, its probes and their temporaries.
bool is_probe_set_file(const std::string& name) {
    return name.rfind("probe_", 0) == 0 || name.rfind(kManifestName, 0) == 0;
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

} // namespace

BakeSummary write_probe_set(const std::string& folder, ProbeSetManifest manifest,
                            const std::function<ProbeMap(std::size_t)>& bake_one,
                            Progress* progress) {
    const std::vector<glm::dvec3>& positions = manifest.placement.positions;
    if (positions.empty()) {
        throw InputError("bake: no probe positions given");
    }
    // The set is written into a staging folder beside `folder` and swapped in when complete:
    // an interrupted bake (cancel, a kill, a full disk) leaves the previous set as it was.
    const fs::path target = set_folder_path(folder);
    check_replaceable(target);
    const fs::path staging = sibling(target, ".partial");
    std::error_code ec;
    fs::remove_all(staging, ec); // what a killed bake left
    fs::create_directories(staging, ec);
    if (ec) {
        throw IoError(staging.string() + ": cannot create the probe set's staging folder (" +
                      ec.message() + ")");
    }
    try {
        BakeSummary summary =
            write_probe_files(staging.string(), std::move(manifest), bake_one, progress);
        swap_in(staging, target);
        summary.folder = folder;
        return summary;
    } catch (...) {
        fs::remove_all(staging, ec);
        throw;
    }
}

namespace {

BakeSummary write_probe_files(const std::string& folder, ProbeSetManifest manifest,
                              const std::function<ProbeMap(std::size_t)>& bake_one,
                              Progress* progress) {
    const std::vector<glm::dvec3>& positions = manifest.placement.positions;
    BakeSummary summary;
    summary.folder = folder;
    manifest.probes.clear();
    for (std::size_t i = 0; i < positions.size(); ++i) {
        if (progress != nullptr) {
            progress->throw_if_cancelled();
        }
        auto start = std::chrono::steady_clock::now();
        ProbeMap map = bake_one(i);
        summary.bake_seconds += seconds_since(start);
        start = std::chrono::steady_clock::now();
        if (progress != nullptr) {
            progress->begin_stage("writing probe " + std::to_string(i + 1) + " of " +
                                      std::to_string(positions.size()),
                                  1);
        }
        const std::string file = probe_file_name(i);
        const std::string path = (fs::path(folder) / file).string();
        write_probe_exr(path, map);
        summary.write_seconds += seconds_since(start);
        // The map's own position: a planned probe may have been moved off its grid point.
        ProbeRecord record{file, map.position, map.resolution, coverage_of(map),
                           map.memory_bytes()};
        summary.mean_coverage.surface += record.coverage.surface;
        summary.mean_coverage.inferred += record.coverage.inferred;
        summary.mean_coverage.empty += record.coverage.empty;
        summary.mean_coverage.unknown += record.coverage.unknown;
        summary.bytes_in_memory_per_probe = map.memory_bytes();
        summary.bytes_on_disk += static_cast<std::size_t>(fs::file_size(path));
        manifest.probes.push_back(std::move(record));
    }
    write_manifest(folder, manifest);
    const double count = static_cast<double>(manifest.probes.size());
    summary.probe_count = manifest.probes.size();
    summary.mean_coverage.surface /= count;
    summary.mean_coverage.inferred /= count;
    summary.mean_coverage.empty /= count;
    summary.mean_coverage.unknown /= count;
    return summary;
}

} // namespace

json splat_settings_json(const BakeSettings& settings) {
    return json{{"splat_scale", settings.splat_scale},
                {"splat_plane_reach", settings.splat_plane_reach},
                {"max_splat_radius_texels", settings.max_splat_radius_texels},
                {"hole_fill_texels", settings.hole_fill_texels},
                {"min_distance", settings.min_distance},
                {"lod_texels", settings.lod_texels}};
}

BakeSummary bake_probe_set_from_cloud(const PointCloud& cloud, const ProbePlacement& placement,
                                      const BakeSettings& settings,
                                      const LocalGeometryOptions& geometry_options,
                                      const std::string& folder, const json& sources,
                                      Progress* progress) {
    if (placement.positions.empty()) {
        throw InputError("bake: no probe positions given");
    }
    if (cloud.size() == 0) {
        throw InputError("bake: the point cloud is empty");
    }
    const auto start = std::chrono::steady_clock::now();
    const LocalGeometry geometry = estimate_local_geometry(cloud, geometry_options, progress);
    const double normals_seconds = seconds_since(start);
    const auto hierarchy_start = std::chrono::steady_clock::now();
    const PointHierarchy hierarchy = hierarchy_for_bakes(cloud, geometry, settings, progress);
    const double hierarchy_seconds = seconds_since(hierarchy_start);

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
    BakeSummary summary = write_probe_set(
        folder, std::move(manifest),
        [&](std::size_t i) {
            return bake_probe_from_hierarchy(cloud, geometry, hierarchy, placement.positions[i],
                                             settings, progress);
        },
        progress);
    summary.normals_seconds = normals_seconds;
    summary.hierarchy_seconds = hierarchy_seconds;
    return summary;
}

} // namespace lfprobe
