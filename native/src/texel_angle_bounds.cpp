#include "texel_angle_bounds.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <map>
#include <memory>
#include <mutex>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

namespace lfprobe {

namespace {

// The angle between two unit vectors `chord` apart, taken a tenth low: the rule that a texel k
// steps away lies (k - 0.5) bounds away holds only roughly where the grid shears near the map's
// folds, and this keeps a 2048² map's searches as wide as the rounded arccosine used to make
// them (about a fifth low there). +inf stays +inf.
float angle_of_chord(float chord) {
    if (!(chord < std::numeric_limits<float>::infinity())) {
        return chord;
    }
    constexpr double kMargin = 0.9;
    return static_cast<float>(kMargin * 2.0 *
                              std::asin(std::min(1.0, 0.5 * static_cast<double>(chord))));
}

} // namespace

TexelAngleBounds::TexelAngleBounds(int n) : blocks_((n + kBlock - 1) / kBlock) {
    const auto blocks = static_cast<std::size_t>(blocks_);
    std::vector<float> own(blocks * blocks, std::numeric_limits<float>::infinity());
    // Per block, the shortest chord between the unit directions of two neighbouring texels
    // (right or below), and its angle once: 2 asin(chord / 2) grows with the chord. The chord
    // keeps its precision where the arccosine of a float dot product does not: at 4096² the
    // corners' neighbours lie 2.5e-4 rad apart, a dot product of 1 - 3e-8 that rounds to 1; the
    // angle came out 0, the bound fell back to 1e-6 rad and a splat there searched 129 × 129
    // texels (a 4096² probe baked in 42 s instead of 6.4). Each row's directions are decoded
    // once and serve as the row below of the row above.
    tbb::parallel_for(0, blocks_, [&](int by) {
        const int y_end = std::min(n, (by + 1) * kBlock);
        std::vector<float> shortest(blocks, std::numeric_limits<float>::infinity());
        std::vector<glm::vec3> row(static_cast<std::size_t>(n));
        std::vector<glm::vec3> below(static_cast<std::size_t>(n));
        const auto decode_row = [n](int y, std::vector<glm::vec3>& out) {
            for (int x = 0; x < n; ++x) {
                out[static_cast<std::size_t>(x)] = oct::texel_direction({x, y}, n);
            }
        };
        decode_row(by * kBlock, row);
        for (int y = by * kBlock; y < y_end; ++y) {
            if (y + 1 < n) {
                decode_row(y + 1, below);
            }
            for (int x = 0; x < n; ++x) {
                const auto i = static_cast<std::size_t>(x);
                float chord = std::numeric_limits<float>::infinity();
                if (x + 1 < n) {
                    chord = std::min(chord, glm::length(row[i + 1] - row[i]));
                }
                if (y + 1 < n) {
                    chord = std::min(chord, glm::length(below[i] - row[i]));
                }
                float& slot = shortest[static_cast<std::size_t>(x / kBlock)];
                slot = std::min(slot, chord);
            }
            std::swap(row, below);
        }
        for (std::size_t bx = 0; bx < blocks; ++bx) {
            own[static_cast<std::size_t>(by) * blocks + bx] = angle_of_chord(shortest[bx]);
        }
    });
    global_ = *std::min_element(own.begin(), own.end());
    if (!(global_ > 0.0f)) {
        global_ = 1e-6f;
    }
    // Each block's bound covers the blocks around it too (the map wraps at its edges).
    around_.assign(own.size(), global_);
    for (int by = 0; by < blocks_; ++by) {
        for (int bx = 0; bx < blocks_; ++bx) {
            float smallest = std::numeric_limits<float>::infinity();
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                    const auto y = static_cast<std::size_t>((by + dy + blocks_) % blocks_);
                    const auto x = static_cast<std::size_t>((bx + dx + blocks_) % blocks_);
                    smallest = std::min(smallest, own[y * blocks + x]);
                }
            }
            around_[static_cast<std::size_t>(by) * blocks + static_cast<std::size_t>(bx)] =
                std::max(smallest, global_);
        }
    }
}

int TexelAngleBounds::search_radius(oct::Texel home, float alpha, int max_radius) const {
    const int r = static_cast<int>(std::ceil(alpha / around(home) + 0.5f));
    if (r <= kBlock) {
        return std::min(max_radius, r);
    }
    return std::min(max_radius, static_cast<int>(std::ceil(alpha / global_ + 0.5f)));
}

const TexelAngleBounds& TexelAngleBounds::of(int n) {
    static std::mutex mutex;
    static std::map<int, std::unique_ptr<TexelAngleBounds>> cache;
    const std::lock_guard lock(mutex);
    std::unique_ptr<TexelAngleBounds>& slot = cache[n];
    if (!slot) {
        slot = std::make_unique<TexelAngleBounds>(n);
    }
    return *slot;
}

} // namespace lfprobe
