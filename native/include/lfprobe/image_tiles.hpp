// The image loop every renderer of pixels shares (probe traces, ground truth): square tiles on
// all cores, each the unit of parallel work, of progress and of cancellation. Every pixel is
// computed on its own from the same inputs, so an image does not depend on the thread count.
#pragma once

#include <chrono>
#include <cstddef>

#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include "lfprobe/progress.hpp"

namespace lfprobe {

// Rows r.rows() and columns r.cols() of one tile.
using ImageTile = tbb::blocked_range2d<int>;

// Runs body(tile) over every tile of `tile_size` × `tile_size` pixels of a width × height image.
// Cancellation is checked before each tile (throws Cancelled); progress advances by the tile's
// pixels after it. Returns the loop's wall time in seconds.
template <class Body>
double for_each_image_tile(int width, int height, int tile_size, Progress* progress,
                           const Body& body) {
    const auto start = std::chrono::steady_clock::now();
    const auto tile = static_cast<std::size_t>(tile_size);
    tbb::parallel_for(
        ImageTile(0, height, tile, 0, width, tile),
        [&](const ImageTile& r) {
            if (progress != nullptr) {
                progress->throw_if_cancelled();
            }
            body(r);
            if (progress != nullptr) {
                progress->advance(r.rows().size() * r.cols().size());
            }
        },
        tbb::simple_partitioner());
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

} // namespace lfprobe
