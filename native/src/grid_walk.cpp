#include "lfprobe/grid_walk.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace lfprobe {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

} // namespace

GridCell grid_cell_containing(const ProbeGrid& grid, const glm::dvec3& point) {
    GridCell cell{};
    for (int a = 0; a < 3; ++a) {
        const auto ua = static_cast<std::size_t>(a);
        if (grid.counts[ua] < 2) {
            continue; // one layer: cell 0
        }
        const double f = std::floor((point[a] - grid.origin[a]) / grid.spacing[a]);
        cell[ua] = static_cast<int>(
            std::isfinite(f) ? std::clamp(f, 0.0, static_cast<double>(grid.counts[ua] - 2)) : 0.0);
    }
    return cell;
}

std::size_t grid_cell_corners(const ProbeGrid& grid, const GridCell& cell,
                              std::array<std::size_t, 8>& corners) {
    const auto extent = [&](std::size_t a) { return grid.counts[a] > 1 ? 1 : 0; };
    std::size_t count = 0;
    for (int dz = 0; dz <= extent(2); ++dz) {
        for (int dy = 0; dy <= extent(1); ++dy) {
            for (int dx = 0; dx <= extent(0); ++dx) {
                corners[count++] = static_cast<std::size_t>(cell[0] + dx) +
                                   static_cast<std::size_t>(grid.counts[0]) *
                                       (static_cast<std::size_t>(cell[1] + dy) +
                                        static_cast<std::size_t>(grid.counts[1]) *
                                            static_cast<std::size_t>(cell[2] + dz));
            }
        }
    }
    return count;
}

GridWalk::GridWalk(const ProbeGrid& grid, const Ray& ray) : grid_(grid), ray_(ray) {
    for (int a = 0; a < 3; ++a) {
        if (!std::isfinite(ray.origin[a]) || !std::isfinite(ray.direction[a])) {
            done_ = true; // no cell to walk: the caller's fallback reports the ray
            return;
        }
    }
    double t_enter = ray.t_min;
    double t_exit = ray.t_max;
    for (int a = 0; a < 3; ++a) {
        const auto ua = static_cast<std::size_t>(a);
        bounded_[ua] = grid.counts[ua] > 1;
        cells_[ua] = bounded_[ua] ? grid.counts[ua] - 1 : 1;
        if (!bounded_[ua]) {
            continue;
        }
        clip_to_slab(ray, a, grid.origin[a],
                     grid.origin[a] + grid.spacing[a] * static_cast<double>(grid.counts[ua] - 1),
                     t_enter, t_exit);
    }
    meets_ = t_enter <= t_exit;
    done_ = !meets_;
    if (!meets_) {
        return;
    }
    // The cell where the ray is inside the box, clamped at the faces.
    cell_ = grid_cell_containing(grid, ray.at(t_enter));
    for (int a = 0; a < 3; ++a) {
        if (bounded_[static_cast<std::size_t>(a)]) {
            step_[static_cast<std::size_t>(a)] =
                ray.direction[a] > 0.0 ? 1 : (ray.direction[a] < 0.0 ? -1 : 0);
        }
    }
    t_exit_ = t_exit;
    cell_enter_ = t_enter;
    max_cells_ = cells_[0] + cells_[1] + cells_[2] + 3;
}

double GridWalk::boundary_t(int axis) const {
    const auto ua = static_cast<std::size_t>(axis);
    if (!bounded_[ua] || step_[ua] == 0) {
        return kInfinity;
    }
    const int face = cell_[ua] + (step_[ua] > 0 ? 1 : 0);
    return (grid_.origin[axis] + grid_.spacing[axis] * static_cast<double>(face) -
            ray_.origin[axis]) /
           ray_.direction[axis];
}

std::optional<GridCellSpan> GridWalk::next() {
    if (done_) {
        return std::nullopt;
    }
    if (visited_ > 0) {
        // Step out of the cell handed out last, through the faces it left by.
        if (cell_leave_ >= t_exit_) {
            done_ = true;
            return std::nullopt;
        }
        bool left_grid = false;
        for (std::size_t a = 0; a < 3; ++a) {
            if (next_[a] <= cell_leave_) {
                cell_[a] += step_[a];
                left_grid = left_grid || cell_[a] < 0 || cell_[a] >= cells_[a];
            }
        }
        if (left_grid) {
            done_ = true;
            return std::nullopt;
        }
        cell_enter_ = cell_leave_;
    }
    if (visited_ >= max_cells_) {
        done_ = true;
        return std::nullopt;
    }
    next_ = {boundary_t(0), boundary_t(1), boundary_t(2)};
    cell_leave_ = std::min({next_[0], next_[1], next_[2], t_exit_});
    GridCellSpan span{cell_, cell_enter_, cell_leave_, visited_ == 0};
    ++visited_;
    return span;
}

} // namespace lfprobe
