// Morton (Z-curve) keys of integer cells: interleaving the bits of x, y and z puts cells that are
// close in space close in key order, and every aligned cube of 2^s cells per axis is one run of
// consecutive keys (its keys share all but the low 3s bits).
#pragma once

#include <cstdint>

#include <glm/vec3.hpp>

namespace lfprobe::morton {

// Cells per axis: 21 bits each, 63 bits a key.
inline constexpr int kBitsPerAxis = 21;

// Spreads the low 21 bits of v so that two zero bits follow each one.
[[nodiscard]] inline std::uint64_t spread_bits(std::uint64_t v) {
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffull;
    v = (v | v << 16) & 0x1f0000ff0000ffull;
    v = (v | v << 8) & 0x100f00f00f00f00full;
    v = (v | v << 4) & 0x10c30c30c30c30c3ull;
    v = (v | v << 2) & 0x1249249249249249ull;
    return v;
}

// The inverse of spread_bits: every third bit, packed.
[[nodiscard]] inline std::uint64_t compact_bits(std::uint64_t v) {
    v &= 0x1249249249249249ull;
    v = (v ^ (v >> 2)) & 0x10c30c30c30c30c3ull;
    v = (v ^ (v >> 4)) & 0x100f00f00f00f00full;
    v = (v ^ (v >> 8)) & 0x1f0000ff0000ffull;
    v = (v ^ (v >> 16)) & 0x1f00000000ffffull;
    v = (v ^ (v >> 32)) & 0x1fffff;
    return v;
}

[[nodiscard]] inline std::uint64_t key(std::uint64_t x, std::uint64_t y, std::uint64_t z) {
    return spread_bits(x) | spread_bits(y) << 1 | spread_bits(z) << 2;
}

// The cell (x, y, z) of a key.
[[nodiscard]] inline glm::u64vec3 cell(std::uint64_t k) {
    return {compact_bits(k), compact_bits(k >> 1), compact_bits(k >> 2)};
}

} // namespace lfprobe::morton
