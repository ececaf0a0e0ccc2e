// JSON read from files and from callers (manifests, cameras, sources, storage): parsed with a
// bound on nesting, so that a hostile file cannot make the recursive copies and destructors of
// the JSON tree run out of stack. Nothing lfprobe writes nests deeper than a few levels.
#pragma once

#include <istream>
#include <string>

#include <nlohmann/json.hpp>

namespace lfprobe {

inline constexpr int kMaxJsonDepth = 64;

// Parses `text` (a string or a stream); nlohmann::json::exception for invalid JSON, InputError
// naming `where` for nesting deeper than kMaxJsonDepth.
[[nodiscard]] nlohmann::json parse_json(std::istream& text, const std::string& where);
[[nodiscard]] nlohmann::json parse_json(const std::string& text, const std::string& where);

} // namespace lfprobe
