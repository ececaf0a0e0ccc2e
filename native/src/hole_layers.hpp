// Filling a hole on a silhouette from the surface behind it, shared by a probe's hole fill
// (hole_fill.cpp: texels of an octahedral map) and a view's (unknown_fill.cpp: pixels).
// Internal to the core.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <utility>
#include <vector>

#include <glm/common.hpp>
#include <glm/vec3.hpp>

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

// Makes the colours of a hole filled by fill_hole_in_layers the harmonic blend of its border's:
// each cell the weighted mean of its 8 neighbours (the discrete Laplace equation), solved by
// successive over-relaxation from `colour`, the layers' colours in the order of `hole`.
// `border(u, sum, weight)` adds a neighbour u outside the hole that the blend draws from (the
// surface behind) to sum (its colour times its weight) and weight; a neighbour it adds nothing
// for (the near surface) is left out. The layers carry the nearest border cell's colour
// straight in, so a skirting board's brown grew up a white wall in a streak; nothing saw what
// lies in the hole, and the smooth blend of everything around it is the guess with the least
// squared error. A linear ramp of colour along the border is continued exactly. `layers` (the
// layers' count, about half the hole's width) sets the over-relaxation. Sweeps the cells in
// index order, so the result does not depend on threads; reads only the hole and its border.
template <class Index, class Border>
void blend_hole_harmonically(const std::vector<Index>& hole, int w, int h,
                             std::vector<glm::vec3>& colour, std::int32_t layers, Border&& border) {
    const std::size_t count = hole.size();
    std::vector<std::size_t> order(count);
    for (std::size_t i = 0; i < count; ++i) {
        order[i] = i;
    }
    std::sort(order.begin(), order.end(),
              [&](std::size_t a, std::size_t b) { return hole[a] < hole[b]; });
    std::vector<Index> sorted(count);
    std::vector<glm::vec3> value(count);
    for (std::size_t i = 0; i < count; ++i) {
        sorted[i] = hole[order[i]];
        value[i] = colour[order[i]];
    }
    // Per cell: its border neighbours' weighted colours, the reciprocal of all its neighbours'
    // weight, and its neighbours in the hole (each weighs 1).
    struct Stencil {
        glm::vec3 fixed_sum{0.0f};
        float reciprocal = 0.0f;
        std::uint32_t inside = 0;
        std::array<std::uint32_t, 8> in_hole{};
    };
    std::vector<Stencil> stencils(count);
    for (std::size_t i = 0; i < count; ++i) {
        Stencil& s = stencils[i];
        float weight = 0.0f;
        for_each_neighbour(sorted[i], w, h, [&](Index u) {
            const auto at = std::lower_bound(sorted.begin(), sorted.end(), u);
            if (at != sorted.end() && *at == u) {
                s.in_hole[s.inside++] = static_cast<std::uint32_t>(at - sorted.begin());
                weight += 1.0f;
            } else {
                border(u, s.fixed_sum, weight);
            }
        });
        s.reciprocal = weight > 0.0f ? 1.0f / weight : 0.0f; // a lone cell keeps its colour
    }
    // The over-relaxation that converges fastest on a strip 2 × layers wide; the sweeps stop
    // when no colour moves by more than kSettled (a tenth of a half float's step at 1), or after
    // kMaxSweeps. Most holes settle in 20 to 150 sweeps; a long strip reached by the surface
    // behind at its ends only would take about its length (804 sweeps for a strip of 32,302
    // texels, the largest of a demo probe's holes), and stops part way from the layers' colours
    // to the blend: the demo's views came out the same to 0.01 dB with and without the cap.
    const double width = 2.0 * static_cast<double>(std::max(layers, 1)) + 1.0;
    const auto omega = static_cast<float>(2.0 / (1.0 + std::sin(std::numbers::pi / width)));
    constexpr float kSettled = 1e-4f;
    constexpr int kMaxSweeps = 256;
    for (int sweep = 0; sweep < kMaxSweeps; ++sweep) {
        glm::vec3 moved(0.0f);
        for (std::size_t i = 0; i < count; ++i) {
            const Stencil& s = stencils[i];
            if (s.reciprocal == 0.0f) {
                continue;
            }
            glm::vec3 sum = s.fixed_sum;
            for (std::uint32_t k = 0; k < s.inside; ++k) {
                sum += value[s.in_hole[k]];
            }
            const glm::vec3 step = omega * (sum * s.reciprocal - value[i]);
            value[i] += step;
            moved = glm::max(moved, glm::abs(step));
        }
        if (std::max({moved.x, moved.y, moved.z}) < kSettled) {
            break;
        }
    }
    for (std::size_t i = 0; i < count; ++i) {
        colour[order[i]] = glm::max(value[i], glm::vec3(0.0f));
    }
}

} // namespace lfprobe
