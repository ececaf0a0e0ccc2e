// Filling a hole on a silhouette from the surface behind it, shared by a probe's hole fill
// (hole_fill.cpp: texels of an octahedral map) and a view's (unknown_fill.cpp: pixels).
// Internal to the core.
#pragma once

#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "grid_neighbours.hpp"

namespace lfprobe {

// Where the depths on a hole's border spread over more than this fraction of the nearest, the
// hole lies on a silhouette: a near and a far surface meet around it.
inline constexpr float kSilhouetteSpread = 0.05f;

// fill_hole_in_layers' tag for a cell outside the hole being filled (and the layer scratch's
// value on entry and on return).
inline constexpr std::int32_t kOutsideHole = std::numeric_limits<std::int32_t>::max();

// Fills the cells of `hole` (8-connected, in a w×h grid) from the cells around it that
// `is_source(u)` accepts, layer by layer inward (onion peeling): layer 1 is the hole's cells
// next to a source, layer k + 1 the cells next to layer k not filled yet. `average(t, known)`
// makes cell t's value from its neighbours for which `known(u)` holds (a source, or a cell of an
// earlier layer: every cell of a layer has one); the whole layer is made before
// `write(t, value, layer)` sets any of it, so a cell never reads another of its own layer and
// the result does not depend on the cells' order. `layer_of` is scratch of the grid's size,
// kOutsideHole everywhere on entry and on return.
template <class Index, class IsSource, class Average, class Write>
void fill_hole_in_layers(const std::vector<Index>& hole, int w, int h,
                         std::vector<std::int32_t>& layer_of, IsSource&& is_source,
                         Average&& average, Write&& write) {
    constexpr std::int32_t kWaiting = kOutsideHole - 1; // in the hole, not reached yet
    constexpr std::int32_t kQueued = kOutsideHole - 2;  // in the next layer
    for (const Index t : hole) {
        layer_of[t] = kWaiting;
    }
    std::int32_t layer = 1;
    const auto known = [&](Index u) { return layer_of[u] < layer || is_source(u); };
    std::vector<Index> frontier;
    for (const Index t : hole) {
        bool next_to_known = false;
        for_each_neighbour(t, w, h, [&](Index u) { next_to_known |= known(u); });
        if (next_to_known) {
            frontier.push_back(t);
        }
    }
    using Value = decltype(average(hole.front(), known));
    std::vector<std::pair<Index, Value>> values;
    std::vector<Index> next;
    for (; !frontier.empty(); ++layer) {
        values.clear();
        for (const Index t : frontier) {
            values.emplace_back(t, average(t, known));
        }
        for (const auto& [t, value] : values) {
            write(t, value, layer);
            layer_of[t] = layer;
        }
        next.clear();
        for (const auto& [t, value] : values) {
            for_each_neighbour(t, w, h, [&](Index u) {
                if (layer_of[u] == kWaiting) {
                    layer_of[u] = kQueued;
                    next.push_back(u);
                }
            });
        }
        frontier.swap(next);
    }
    for (const Index t : hole) {
        layer_of[t] = kOutsideHole; // every cell was reached: the hole is connected
    }
}

} // namespace lfprobe
