// The coarse levels of a probe (docs/DESIGN.md §4): each coarse texel holds the minimum radial
// distance of the fine texels it covers, a conservative bound that lets a trace skip texels
// whose every surface lies beyond the ray. Empty texels (+inf) do not lower the bound; unknown
// texels (NaN) lower it to 0, so a coarse texel over unknown data is never skipped and the
// fine trace meets the unknown texel itself (never a MISS across unknown).
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

namespace lfprobe {

struct MinDistanceLevel {
    int resolution = 0;
    std::vector<float> min_distance; // resolution² values, row-major (scanline y, column x)
    // Quantised (MinDistancePyramid::quantise): 16-bit multiples of `step`, rounded down so the
    // bound stays a bound; 65535 is +inf. min_distance is then empty.
    std::vector<std::uint16_t> min_code;
    double step = 0.0;

    [[nodiscard]] float value(std::size_t i) const {
        if (min_code.empty()) {
            return min_distance[i];
        }
        const std::uint16_t c = min_code[i];
        return c == 0xFFFF ? std::numeric_limits<float>::infinity()
                           : static_cast<float>(static_cast<double>(c) * step);
    }
};

class MinDistancePyramid {
public:
    MinDistancePyramid() = default;
    // Builds levels of ceil(n/2), ceil(n/4), ... texels per side down to `coarsest` (at least
    // 1). Coarse texel (x, y) of a level covers texels (2x..2x+1, 2y..2y+1) of the level below,
    // clamped to its edge. `fine` holds n² distances.
    MinDistancePyramid(const std::vector<float>& fine, int n, int coarsest = 1);

    // Holds every level as 16-bit multiples of `step` metres, each rounded down (a surface
    // beyond 65534 steps is bounded by the last code): half the memory, and a skip stays
    // conservative. For probes whose distances are stored in the same steps (compact storage).
    void quantise(double step);

    // Level 0 is the first coarse level (half the fine resolution).
    [[nodiscard]] const std::vector<MinDistanceLevel>& levels() const { return levels_; }
    [[nodiscard]] std::size_t memory_bytes() const;

private:
    std::vector<MinDistanceLevel> levels_;
};

// The conservative value a fine texel contributes to a minimum.
[[nodiscard]] inline float min_distance_bound(float distance) {
    return distance != distance ? 0.0f : distance; // NaN (unknown) bounds nothing: 0
}

} // namespace lfprobe
