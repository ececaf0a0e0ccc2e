#include "lfprobe/probe_placement.hpp"

#include <string>

#include "lfprobe/error.hpp"

namespace lfprobe {

ProbeGrid ProbeGrid::spanning(const glm::dvec3& min_corner, const glm::dvec3& max_corner,
                              const std::array<int, 3>& counts) {
    ProbeGrid grid;
    grid.counts = counts;
    for (int a = 0; a < 3; ++a) {
        if (counts[static_cast<std::size_t>(a)] < 1) {
            throw InputError("probe grid: counts must be at least 1 per axis, got " +
                             std::to_string(counts[static_cast<std::size_t>(a)]));
        }
        if (!(max_corner[a] >= min_corner[a])) {
            throw InputError("probe grid: the maximum corner must not be below the minimum");
        }
        const int c = counts[static_cast<std::size_t>(a)];
        if (c == 1) {
            grid.origin[a] = 0.5 * (min_corner[a] + max_corner[a]);
            grid.spacing[a] = max_corner[a] - min_corner[a];
        } else {
            grid.origin[a] = min_corner[a];
            grid.spacing[a] = (max_corner[a] - min_corner[a]) / static_cast<double>(c - 1);
        }
    }
    return grid;
}

std::size_t ProbeGrid::probe_count() const {
    return static_cast<std::size_t>(counts[0]) * static_cast<std::size_t>(counts[1]) *
           static_cast<std::size_t>(counts[2]);
}

glm::dvec3 ProbeGrid::position(int x, int y, int z) const {
    return origin + spacing * glm::dvec3(x, y, z);
}

std::vector<glm::dvec3> ProbeGrid::positions() const {
    std::vector<glm::dvec3> result;
    result.reserve(probe_count());
    for (int z = 0; z < counts[2]; ++z) {
        for (int y = 0; y < counts[1]; ++y) {
            for (int x = 0; x < counts[0]; ++x) {
                result.push_back(position(x, y, z));
            }
        }
    }
    return result;
}

ProbePlacement ProbePlacement::from_positions(std::vector<glm::dvec3> positions) {
    ProbePlacement p;
    p.is_grid = false;
    p.positions = std::move(positions);
    return p;
}

ProbePlacement ProbePlacement::from_grid(const ProbeGrid& grid) {
    ProbePlacement p;
    p.is_grid = true;
    p.grid = grid;
    p.positions = grid.positions();
    return p;
}

} // namespace lfprobe
