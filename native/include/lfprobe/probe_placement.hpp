// Where probes go: a list of positions, or the vertices of a uniform grid (any counts, not
// only powers of two). Positions are in the local (offset) frame.
#pragma once

#include <array>
#include <vector>

#include <glm/vec3.hpp>

namespace lfprobe {

struct ProbeGrid {
    glm::dvec3 origin{0.0};  // position of probe (0, 0, 0)
    glm::dvec3 spacing{1.0}; // distance between neighbouring probes per axis
    std::array<int, 3> counts{1, 1, 1};

    // A grid whose corner probes sit on the box corners (one probe at the centre of an axis
    // whose count is 1).
    [[nodiscard]] static ProbeGrid spanning(const glm::dvec3& min_corner,
                                            const glm::dvec3& max_corner,
                                            const std::array<int, 3>& counts);
    [[nodiscard]] std::size_t probe_count() const;
    // Probe index i = x + counts[0] * (y + counts[1] * z).
    [[nodiscard]] glm::dvec3 position(int x, int y, int z) const;
    [[nodiscard]] std::vector<glm::dvec3> positions() const;
};

struct ProbePlacement {
    bool is_grid = false;
    ProbeGrid grid;                    // when is_grid
    std::vector<glm::dvec3> positions; // always filled: the probes in index order

    [[nodiscard]] static ProbePlacement from_positions(std::vector<glm::dvec3> positions);
    [[nodiscard]] static ProbePlacement from_grid(const ProbeGrid& grid);
};

} // namespace lfprobe
