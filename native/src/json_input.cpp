#include "lfprobe/json_input.hpp"

#include <filesystem>
#include <fstream>

#include "lfprobe/error.hpp"

namespace lfprobe {

namespace {

nlohmann::json::parser_callback_t depth_limit(const std::string& where) {
    return [where](int depth, nlohmann::json::parse_event_t, nlohmann::json&) {
        if (depth > kMaxJsonDepth) {
            throw InputError(where + ": JSON nested deeper than " + std::to_string(kMaxJsonDepth) +
                             " levels");
        }
        return true;
    };
}

} // namespace

nlohmann::json parse_json(std::istream& text, const std::string& where) {
    return nlohmann::json::parse(text, depth_limit(where));
}

nlohmann::json parse_json(const std::string& text, const std::string& where) {
    return nlohmann::json::parse(text, depth_limit(where));
}

nlohmann::json read_json_file(const std::string& path, const std::string& what,
                              const std::string& missing_hint) {
    std::error_code error;
    if (!std::filesystem::is_regular_file(path, error)) {
        const bool exists = std::filesystem::exists(path, error);
        throw MissingFileError(path + ": no " + what + " here (" +
                               (exists                 ? "not a regular file"
                                : missing_hint.empty() ? "no such file"
                                                       : missing_hint) +
                               ")");
    }
    std::ifstream in(path);
    if (!in) {
        throw IoError(path + ": cannot read the " + what);
    }
    try {
        return parse_json(in, path);
    } catch (const nlohmann::json::exception& e) {
        throw InputError(path + ": the " + what + " is not valid JSON (" + e.what() + ")");
    }
}

} // namespace lfprobe
