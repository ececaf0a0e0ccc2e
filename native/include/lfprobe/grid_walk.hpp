// Walking a ray through the cells of a probe grid (docs/DESIGN.md §4 "Many probes"): the cells it
// passes, in order, with the ray interval inside each, as a 3D DDA. A cell is the box between
// 2×2×2 neighbouring probes; an axis with one probe has a single unbounded cell. The trace asks
// each cell's corner probes, nearest first; blending asks the corners of the cell a point lies
// in.
#pragma once

#include <array>
#include <cstddef>
#include <optional>

#include "lfprobe/probe_placement.hpp"
#include "lfprobe/ray.hpp"

namespace lfprobe {

// Cell (x, y, z) spans probes x..x+1, y..y+1, z..z+1 (x only, on an axis with one probe).
using GridCell = std::array<int, 3>;

// The cell holding `point`, clamped to the grid at its faces (a point outside, or NaN, goes to
// the nearest cell; NaN to cell 0).
[[nodiscard]] GridCell grid_cell_containing(const ProbeGrid& grid, const glm::dvec3& point);

// The probe indices at the corners of `cell`, x fastest, then y, then z (8, or 4, 2, 1 where
// axes hold one probe); returns how many.
std::size_t grid_cell_corners(const ProbeGrid& grid, const GridCell& cell,
                              std::array<std::size_t, 8>& corners);

// One step of the walk: the cell and the part of the ray inside it.
struct GridCellSpan {
    GridCell cell{};
    double t_enter = 0.0;
    double t_leave = 0.0;
    bool first = false; // the cell where the ray enters the grid
};

// The cells `ray` passes between its t_min and t_max, in order:
//     GridWalk walk(grid, ray);
//     while (const auto span = walk.next()) { ... }
// A ray that misses the grid's box yields nothing (meets_grid() is false).
class GridWalk {
public:
    GridWalk(const ProbeGrid& grid, const Ray& ray);

    [[nodiscard]] bool meets_grid() const { return meets_; }
    [[nodiscard]] std::optional<GridCellSpan> next();

private:
    [[nodiscard]] double boundary_t(int axis) const;

    const ProbeGrid& grid_;
    const Ray& ray_;
    std::array<int, 3> cells_{}; // cells per axis
    std::array<bool, 3> bounded_{};
    std::array<int, 3> step_{};
    std::array<double, 3> next_{}; // where the ray crosses the current cell's far face per axis
    GridCell cell_{};
    double t_exit_ = 0.0;
    double cell_enter_ = 0.0;
    double cell_leave_ = 0.0;
    int visited_ = 0;
    int max_cells_ = 0;
    bool meets_ = false;
    bool done_ = false;
};

} // namespace lfprobe
