// The octahedral map of docs/DESIGN.md §3, the one mapping between directions and texels that every
// part of lfprobe uses. Z is the fold axis; the upper hemisphere fills the inner diamond, the
// lower hemisphere the four outer triangles. Texel (x, y) is pixel column x, scanline y.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "lfprobe/error.hpp"

namespace lfprobe::oct {

// The angular size of a texel of an N×N map is about sqrt(4π)/N radians (4π sr over N²
// texels): this constant over N.
inline constexpr double kTexelAngleTimesN = 3.5449077018110318;

// s(a) of docs/DESIGN.md: -0.0 maps to +1 (copysign and signbit would give -1).
[[nodiscard]] constexpr float sign_not_zero(float a) {
    return a >= 0.0f ? 1.0f : -1.0f;
}

// Direction (any length > 0, finite) to map coordinates uv in [0, 1]².
// Precondition: finite and not the zero vector; encode_checked tests it.
[[nodiscard]] inline glm::vec2 encode(const glm::vec3& d) {
    const float l1 = std::abs(d.x) + std::abs(d.y) + std::abs(d.z);
    glm::vec2 p{d.x / l1, d.y / l1};
    if (d.z < 0.0f) {
        p = glm::vec2{(1.0f - std::abs(p.y)) * sign_not_zero(p.x),
                      (1.0f - std::abs(p.x)) * sign_not_zero(p.y)};
    }
    return p * 0.5f + 0.5f;
}

// Map coordinates uv (any real numbers; meaningful in [0, 1]²) to a unit direction.
[[nodiscard]] inline glm::vec3 decode(const glm::vec2& uv) {
    const glm::vec2 p = uv * 2.0f - 1.0f;
    glm::vec3 d{p.x, p.y, 1.0f - std::abs(p.x) - std::abs(p.y)};
    if (d.z < 0.0f) {
        d.x = (1.0f - std::abs(p.y)) * sign_not_zero(p.x);
        d.y = (1.0f - std::abs(p.x)) * sign_not_zero(p.y);
    }
    return glm::normalize(d);
}

// True when encode() may be called on d.
[[nodiscard]] inline bool is_valid_direction(const glm::vec3& d) {
    return std::isfinite(d.x) && std::isfinite(d.y) && std::isfinite(d.z) &&
           (d.x != 0.0f || d.y != 0.0f || d.z != 0.0f);
}

// encode() that rejects NaN, infinite and zero directions with an InputError.
[[nodiscard]] inline glm::vec2 encode_checked(const glm::vec3& d) {
    if (!is_valid_direction(d)) {
        throw InputError("octahedral encode: expected a finite non-zero direction, got (" +
                         std::to_string(d.x) + ", " + std::to_string(d.y) + ", " +
                         std::to_string(d.z) + ")");
    }
    return encode(d);
}

struct Texel {
    int x = 0;
    int y = 0;
    friend bool operator==(const Texel&, const Texel&) = default;
};

// The texel of an N×N map that holds uv: [x/N, (x+1)/N) × [y/N, (y+1)/N), clamped to
// [0, N-1] so that u or v = 1 lands on the last texel.
[[nodiscard]] inline Texel texel_of_uv(const glm::vec2& uv, int n) {
    const float fn = static_cast<float>(n);
    // Truncation, not floor: they differ only below 0, which the clamp sends to texel 0 either
    // way, and floor is a call or a long sequence on baseline x86-64 (the lookup's hot path).
    const int x = static_cast<int>(uv.x * fn);
    const int y = static_cast<int>(uv.y * fn);
    return Texel{std::clamp(x, 0, n - 1), std::clamp(y, 0, n - 1)};
}

[[nodiscard]] inline Texel texel_of_direction(const glm::vec3& d, int n) {
    return texel_of_uv(encode(d), n);
}

// uv of a texel's centre.
[[nodiscard]] inline glm::vec2 texel_center_uv(Texel t, int n) {
    const float fn = static_cast<float>(n);
    return glm::vec2{(static_cast<float>(t.x) + 0.5f) / fn, (static_cast<float>(t.y) + 0.5f) / fn};
}

// The direction a texel stands for: the decode of its centre.
[[nodiscard]] inline glm::vec3 texel_direction(Texel t, int n) {
    return decode(texel_center_uv(t, n));
}

// The texel that continues the map across its outer edge: the octahedral map's border is
// mirrored (texel (x, -1) is texel (N-1-x, 0)), so neighbourhoods may step over it. Any offset
// of less than N texels outside the map is folded back inside.
[[nodiscard]] inline Texel wrap_texel(int x, int y, int n) {
    // Folds coordinate `a` back over the edge it crossed; the other coordinate `b` mirrors.
    const auto fold = [n](int& a, int& b) {
        if (a < 0 || a >= n) {
            a = a < 0 ? -a - 1 : 2 * n - 1 - a;
            b = n - 1 - b;
        }
    };
    fold(x, y);
    fold(y, x);
    return Texel{std::clamp(x, 0, n - 1), std::clamp(y, 0, n - 1)};
}

[[nodiscard]] inline std::size_t texel_index(Texel t, int n) {
    return static_cast<std::size_t>(t.y) * static_cast<std::size_t>(n) +
           static_cast<std::size_t>(t.x);
}

} // namespace lfprobe::oct
