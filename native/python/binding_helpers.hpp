// Small pieces that several bindings files share.
#pragma once

#include <optional>
#include <string>
#include <utility>

#include <vector>

#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>
#include <pybind11/pybind11.h>
#include <tbb/task_arena.h>

#include "lfprobe/camera.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/json_input.hpp"
#include "lfprobe/probe_bake.hpp"
#include "lfprobe/probe_map.hpp"
#include "lfprobe/probe_placement.hpp"
#include "lfprobe/probe_set.hpp"
#include "lfprobe/probe_storage.hpp"
#include "lfprobe/throughput.hpp"

namespace lfprobe::python {

// Runs `work` on `threads` cores (all when 0): outputs do not depend on it, times do.
template <class F>
auto on_threads(int threads, F&& work) {
    if (threads <= 0) {
        return work();
    }
    tbb::task_arena arena(threads);
    return arena.execute(std::forward<F>(work));
}

// A camera from a JSON file path, or from the JSON text itself (starts with '{').
inline Camera camera_from(const std::string& camera) {
    const auto first = camera.find_first_not_of(" \t\r\n");
    if (first != std::string::npos && camera[first] == '{') {
        try {
            return Camera::from_json(parse_json(camera, "camera JSON"), "camera JSON");
        } catch (const nlohmann::json::exception& e) {
            throw InputError(std::string("camera JSON: ") + e.what());
        }
    }
    return read_camera_json(camera);
}

// The bake settings a binding takes by name in an options dict: BakeSettings' fields, each
// under its own name (kBakeSettingNames lists them for messages). False for any other key.
inline constexpr const char* kBakeSettingNames =
    "resolution, splat_scale, splat_plane_reach, splat_core_scale, hole_fill_texels, "
    "max_splat_radius_texels, lod_texels, splat_edge_margin, face_the_probe";
inline bool set_bake_setting(BakeSettings& s, const std::string& key, pybind11::handle value) {
    if (key == "resolution") {
        s.resolution = value.cast<int>();
    } else if (key == "splat_scale") {
        s.splat_scale = value.cast<float>();
    } else if (key == "splat_plane_reach") {
        s.splat_plane_reach = value.cast<float>();
    } else if (key == "splat_core_scale") {
        s.splat_core_scale = value.cast<float>();
    } else if (key == "hole_fill_texels") {
        s.hole_fill_texels = value.cast<int>();
    } else if (key == "max_splat_radius_texels") {
        s.max_splat_radius_texels = value.cast<int>();
    } else if (key == "lod_texels") {
        s.lod_texels = value.cast<float>();
    } else if (key == "lod_colour_tolerance") {
        s.lod_colour_tolerance = value.cast<float>();
    } else if (key == "splat_edge_margin") {
        s.splat_edge_margin = value.cast<float>();
    } else if (key == "face_the_probe") {
        s.face_the_probe = value.cast<bool>();
    } else {
        return false;
    }
    return true;
}

// Three numbers from Python as a point; `what` names the argument in the error.
inline glm::dvec3 dvec3_from(const std::vector<double>& v, const char* what) {
    if (v.size() != 3) {
        throw InputError(std::string(what) + ": expected three numbers (x, y, z)");
    }
    return {v[0], v[1], v[2]};
}

inline pybind11::dict coverage_dict(const ProbeCoverage& c) {
    pybind11::dict d;
    d["surface"] = c.surface;
    d["inferred"] = c.inferred;
    d["empty"] = c.empty;
    d["unknown"] = c.unknown;
    return d;
}

// Probes at `positions`, or on a grid from grid_min to grid_max with `counts`, as Python
// passes them (world coordinates); `world_offset` is subtracted to give the local frame.
inline ProbePlacement placement_from(const std::vector<std::vector<double>>& positions,
                                     const std::optional<std::vector<double>>& grid_min,
                                     const std::optional<std::vector<double>>& grid_max,
                                     const std::optional<std::vector<int>>& counts,
                                     const glm::dvec3& world_offset) {
    if (grid_min || grid_max || counts) {
        if (!(grid_min && grid_max && counts) || counts->size() != 3) {
            throw InputError("bake: a grid needs grid_min, grid_max and three counts");
        }
        if (!positions.empty()) {
            throw InputError("bake: give probe positions or a grid, not both");
        }
        return ProbePlacement::from_grid(
            ProbeGrid::spanning(dvec3_from(*grid_min, "grid_min") - world_offset,
                                dvec3_from(*grid_max, "grid_max") - world_offset,
                                {(*counts)[0], (*counts)[1], (*counts)[2]}));
    }
    std::vector<glm::dvec3> local;
    for (const auto& p : positions) {
        local.push_back(dvec3_from(p, "probe position") - world_offset);
    }
    return ProbePlacement::from_positions(std::move(local));
}

// The manifest's "sources" from the JSON text Python passes.
inline nlohmann::json sources_from(const std::string& sources_json) {
    try {
        return parse_json(sources_json, "sources");
    } catch (const nlohmann::json::exception& e) {
        throw InputError(std::string("bake: sources_json is not valid JSON (") + e.what() + ")");
    }
}

// A storage from Python: None (none chosen), "full", "compact" (with `step` metres, the
// default step when 0) or a dict as the manifest writes it.
inline std::optional<ProbeStorage> storage_from(const pybind11::object& storage,
                                                double step = 0.0) {
    if (storage.is_none()) {
        return std::nullopt;
    }
    if (pybind11::isinstance<pybind11::str>(storage)) {
        return ProbeStorage::from_name(storage.cast<std::string>(), step);
    }
    if (pybind11::isinstance<pybind11::dict>(storage)) {
        const std::string text =
            pybind11::module_::import("json").attr("dumps")(storage).cast<std::string>();
        return ProbeStorage::from_json(parse_json(text, "storage"), "storage");
    }
    throw InputError("storage: expected None, \"full\", \"compact\" or a dict");
}

// The manifest's "storage" object as a dict, with the bytes a texel it gives.
inline pybind11::dict storage_dict(const ProbeStorage& storage) {
    nlohmann::json j = storage.to_json();
    j["bytes_per_texel"] = storage.bytes_per_texel();
    return pybind11::module_::import("json").attr("loads")(j.dump());
}

inline pybind11::dict throughput_dict(const ThroughputResult& r) {
    pybind11::dict d;
    d["rays"] = r.rays;
    d["hits"] = r.hits;
    d["seconds"] = r.seconds;
    d["rays_per_second"] = r.rays_per_second;
    d["repeats"] = r.repeats;
    return d;
}

// A bake's summary as a dict; normals_seconds only for bakes that estimate normals.
inline pybind11::dict bake_summary_dict(const BakeSummary& s, bool with_normals) {
    pybind11::dict d;
    d["folder"] = s.folder;
    d["probe_count"] = s.probe_count;
    if (with_normals) {
        d["normals_seconds"] = s.normals_seconds;
        d["hierarchy_seconds"] = s.hierarchy_seconds;
        d["prepared_from_cache"] = s.prepared_from_cache;
    }
    d["bake_seconds"] = s.bake_seconds;
    d["write_seconds"] = s.write_seconds;
    d["mean_coverage"] = coverage_dict(s.mean_coverage);
    d["bytes_in_memory_per_probe"] = s.bytes_in_memory_per_probe;
    d["bytes_on_disk"] = s.bytes_on_disk;
    return d;
}

} // namespace lfprobe::python
