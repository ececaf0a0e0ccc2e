// JSON read from files and from callers (manifests, cameras, sources, storage): parsed with a
// bound on nesting, so that a hostile file cannot make the recursive copies and destructors of
// the JSON tree run out of stack. Nothing lfprobe writes nests deeper than a few levels.
#pragma once

#include <istream>
#include <string>

#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

namespace lfprobe {

inline constexpr int kMaxJsonDepth = 64;

// Parses `text` (a string or a stream); nlohmann::json::exception for invalid JSON, InputError
// naming `where` for nesting deeper than kMaxJsonDepth.
[[nodiscard]] nlohmann::json parse_json(std::istream& text, const std::string& where);
[[nodiscard]] nlohmann::json parse_json(const std::string& text, const std::string& where);

// The JSON document in the file at `path`; `what` names the file in messages ("camera file").
// MissingFileError when `path` is not a regular file (`missing_hint`, when given, says why it
// may be missing), IoError when it cannot be read, InputError for invalid or too deep JSON.
[[nodiscard]] nlohmann::json read_json_file(const std::string& path, const std::string& what,
                                            const std::string& missing_hint = "");

// A point or vector as lfprobe's JSON files hold one: [x, y, z].
[[nodiscard]] inline nlohmann::json json_of(const glm::dvec3& v) {
    return nlohmann::json::array({v.x, v.y, v.z});
}

} // namespace lfprobe
