#include "lfprobe/json_input.hpp"

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

} // namespace lfprobe
