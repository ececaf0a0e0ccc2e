#include "lfprobe/input_limits.hpp"

#include <array>
#include <charconv>
#include <cstdlib>
#include <cstring>

#include "lfprobe/error.hpp"

namespace lfprobe {

namespace {

struct LimitDefinition {
    const char* variable;
    std::int64_t default_value;
};

constexpr std::array<LimitDefinition, 5> kLimits{{
    {"LFPROBE_MAX_CAMERA_PIXELS", 8192LL * 8192LL},
    {"LFPROBE_MAX_TEXTURE_PIXELS", 8192LL * 8192LL},
    {"LFPROBE_MAX_IMAGE_PIXELS", 8192LL * 8192LL},
    {"LFPROBE_MAX_MTL_BYTES", std::int64_t{64} << 20},
    {"LFPROBE_MAX_OBJ_BYTES", std::int64_t{8} << 30},
}};

const LimitDefinition& definition(InputLimit which) {
    return kLimits.at(static_cast<std::size_t>(which));
}

} // namespace

std::int64_t input_limit(InputLimit which) {
    const LimitDefinition& limit = definition(which);
    const char* text = std::getenv(limit.variable);
    if (text == nullptr || *text == '\0') {
        return limit.default_value;
    }
    std::int64_t value = 0;
    const char* end = text + std::strlen(text);
    const auto [stop, error] = std::from_chars(text, end, value);
    if (error != std::errc() || stop != end || value < 1 || value > (std::int64_t{1} << 62)) {
        throw InputError(std::string("environment variable ") + limit.variable + "=" + text +
                         ": expected a whole number from 1 to 2^62");
    }
    return value;
}

const char* input_limit_variable(InputLimit which) {
    return definition(which).variable;
}

std::string input_limit_hint(InputLimit which) {
    return "at most " + std::to_string(input_limit(which)) + "; set " +
           input_limit_variable(which) + " to change it";
}

} // namespace lfprobe
