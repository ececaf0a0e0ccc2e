// Small pieces that several bindings files share.
#pragma once

#include <string>
#include <utility>

#include <vector>

#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>
#include <pybind11/pybind11.h>
#include <tbb/task_arena.h>

#include "lfprobe/camera.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/probe_map.hpp"

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
            return Camera::from_json(nlohmann::json::parse(camera), "camera JSON");
        } catch (const nlohmann::json::exception& e) {
            throw InputError(std::string("camera JSON: ") + e.what());
        }
    }
    return read_camera_json(camera);
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

} // namespace lfprobe::python
