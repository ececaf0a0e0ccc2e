// sRGB transfer functions (IEC 61966-2-1): scan colours are sRGB, the program is linear.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

namespace lfprobe {

[[nodiscard]] inline float srgb_to_linear(float c) {
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

[[nodiscard]] inline float linear_to_srgb(float c) {
    return c <= 0.0031308f ? c * 12.92f : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

// Decoding table for 8-bit sRGB, built once.
[[nodiscard]] inline const std::array<float, 256>& srgb8_to_linear_table() {
    static const std::array<float, 256> table = [] {
        std::array<float, 256> t{};
        for (int i = 0; i < 256; ++i) {
            t[static_cast<std::size_t>(i)] = srgb_to_linear(static_cast<float>(i) / 255.0f);
        }
        return t;
    }();
    return table;
}

} // namespace lfprobe
