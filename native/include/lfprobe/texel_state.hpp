// The three states a probe texel can be in (docs/DESIGN.md §3), and how a distance encodes them.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

namespace lfprobe {

enum class TexelState : std::uint8_t {
    Unknown = 0,  // no data (scanner shadow, unfilled hole): never a HIT, never a MISS across it
    Empty = 1,    // nothing in that direction: distance +inf
    Surface = 2,  // measured surface: finite distance
    Inferred = 3, // surface filled in from measured neighbours: finite distance, confidence < 1
};

// In the distance channel unknown is NaN and empty is +inf, so a distance alone tells the
// state apart from a surface; the confidence (alpha) separates measured from inferred.
inline constexpr float kUnknownDistance = std::numeric_limits<float>::quiet_NaN();
inline constexpr float kEmptyDistance = std::numeric_limits<float>::infinity();

[[nodiscard]] inline TexelState texel_state(float distance, float confidence) {
    if (std::isnan(distance)) {
        return TexelState::Unknown;
    }
    if (std::isinf(distance)) {
        return TexelState::Empty;
    }
    return confidence >= 1.0f ? TexelState::Surface : TexelState::Inferred;
}

} // namespace lfprobe
