// A probe's radiance prefiltered for lookups whose footprint is wider than a texel (the
// footprint filter of docs/DESIGN.md §5): the texture-LOD answer to aliasing when a pixel sees
// many texels. Level k has ceil(N / 2^k) texels a side; each texel is the mean colour of the
// level-0 texels below it that hold a surface, with the fraction of them that do as its weight,
// so that a lookup averages surfaces, not the unknown or empty directions between them.
#pragma once

#include <cstddef>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "lfprobe/probe_map.hpp"

namespace lfprobe {

class RadianceMips {
public:
    RadianceMips() = default;
    // Levels 1, 2, ... down to 1×1 texel, from the map's radiance (level 0 is the map itself).
    explicit RadianceMips(const ProbeMap& map);

    // Levels held, level 0 not counted.
    [[nodiscard]] int level_count() const { return static_cast<int>(levels_.size()); }
    // The colour at octahedral coordinates `uv` in level `level` (1..level_count()),
    // interpolated bilinearly between the four texels around uv, each weighted by its surface
    // fraction. `found` is false where none of the four holds a surface.
    [[nodiscard]] glm::vec3 bilinear(int level, const glm::vec2& uv, bool& found) const;
    [[nodiscard]] std::size_t memory_bytes() const;

private:
    struct Level {
        int n = 0;
        std::vector<glm::vec4> colour_weight; // mean colour of the surfaces below, fraction
    };
    std::vector<Level> levels_;
};

} // namespace lfprobe
