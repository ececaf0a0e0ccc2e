// The 8 neighbours of a cell of a row-major w×h grid (a probe map's texels, an image's pixels):
// the hole fills of probes (hole_fill.cpp) and of rendered views (unknown_fill.cpp) both walk
// their holes this way. Internal to the core.
#pragma once

namespace lfprobe {

// Calls visit(u) for each of cell i's neighbours inside the grid, the row above first, each
// row left to right. Index is the caller's cell index type.
template <class Index, class Visit>
void for_each_neighbour(Index i, int w, int h, Visit&& visit) {
    const int x = static_cast<int>(i % static_cast<Index>(w));
    const int y = static_cast<int>(i / static_cast<Index>(w));
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            const int ux = x + dx;
            const int uy = y + dy;
            if ((dx != 0 || dy != 0) && ux >= 0 && uy >= 0 && ux < w && uy < h) {
                visit(static_cast<Index>(uy) * static_cast<Index>(w) + static_cast<Index>(ux));
            }
        }
    }
}

} // namespace lfprobe
