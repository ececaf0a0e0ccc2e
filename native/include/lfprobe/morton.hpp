// Morton (Z-curve) keys of integer cells: interleaving the bits of x, y and z puts cells that are
// close in space close in key order, and every aligned cube of 2^s cells per axis is one run of
// consecutive keys (its keys share all but the low 3s bits).
#pragma once

#include <cstdint>
#include <vector>

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

// Points sorted along the Morton curve of the cube [origin, origin + cube_size]³ divided into
// 2^21 cells per axis: keys[j] is the key of point order[j], ascending (ties by index).
struct SortedPoints {
    glm::vec3 origin{0.0f};
    float cube_size = 0.0f;
    std::vector<std::uint64_t> keys;
    std::vector<std::uint32_t> order;
    // The edge of a cell of 2^shift base cells per axis.
    [[nodiscard]] float cell_size(int shift) const {
        return cube_size / static_cast<float>(1u << kBitsPerAxis) *
               static_cast<float>(std::uint64_t{1} << shift);
    }
};

// Sorts on all cores; the same positions give the same result for any thread count.
[[nodiscard]] SortedPoints sort_points(const std::vector<glm::vec3>& positions);

// The same, given an order sort_points made of the same positions before (as local geometry
// keeps it): the keys are recomputed, and the sort is skipped when they are ascending.
[[nodiscard]] SortedPoints sort_points(const std::vector<glm::vec3>& positions,
                                       const std::vector<std::uint32_t>& earlier_order);

} // namespace lfprobe::morton
