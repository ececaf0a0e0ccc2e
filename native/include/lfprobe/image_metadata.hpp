// What a rendered EXR records about how it was made: one layout for every renderer and every
// caller (the CLI, the Blender add-on, the report), stored as JSON in the header attribute
// "lfprobe/render" (image_exr.hpp). It holds JSON values, so this header includes the whole of
// nlohmann/json; only the code that writes or reads images includes it.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace lfprobe {

struct ImageMetadata {
    std::string renderer; // "lfprobe probe trace", "lfprobe point splats", "embree ground truth"
    // What was rendered, as the renderer names it: e.g. {"probes": folder, "storage": ...,
    // "memory_bytes": ...} or {"ground_truth": mesh path}. Its keys go to the top level.
    nlohmann::json source = nlohmann::json::object();
    nlohmann::json camera;   // Camera::to_json
    nlohmann::json settings; // the renderer's settings
    nlohmann::json stats;    // its counts and the time it took

    // {"renderer", source's keys, "camera", "settings", "stats"} as JSON text.
    [[nodiscard]] std::string dump() const;
};

} // namespace lfprobe
