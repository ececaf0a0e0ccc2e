#include "lfprobe/unknown_fill.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include <glm/vec3.hpp>

#include "grid_neighbours.hpp"
#include "hole_layers.hpp"
#include "lfprobe/error.hpp"

namespace lfprobe {

namespace {

constexpr std::int32_t kUnreached = std::numeric_limits<std::int32_t>::max();

// One level of the pull pyramid: the coverage-weighted colour sum and the weight of each cell,
// the weight capped at 1 (a cell with a full pixel's worth of HIT colour is known).
struct Level {
    int width = 0;
    int height = 0;
    std::vector<glm::vec3> sum;
    std::vector<float> weight;

    Level(int w, int h)
        : width(w), height(h), sum(static_cast<std::size_t>(w) * static_cast<std::size_t>(h)),
          weight(sum.size(), 0.0f) {}
    [[nodiscard]] std::size_t at(int x, int y) const {
        return static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
               static_cast<std::size_t>(x);
    }
};

Level pull(const Level& fine) {
    Level coarse((fine.width + 1) / 2, (fine.height + 1) / 2);
    for (int y = 0; y < fine.height; ++y) {
        for (int x = 0; x < fine.width; ++x) {
            const std::size_t f = fine.at(x, y);
            const std::size_t c = coarse.at(x / 2, y / 2);
            coarse.sum[c] += fine.sum[f];
            coarse.weight[c] += fine.weight[f];
        }
    }
    for (std::size_t c = 0; c < coarse.weight.size(); ++c) {
        if (coarse.weight[c] > 1.0f) {
            coarse.sum[c] /= coarse.weight[c];
            coarse.weight[c] = 1.0f;
        }
    }
    return coarse;
}

// The fill colour of every cell of `level`: its own mean where its weight is 1, the coarser
// level's fill (bilinear between the four nearest coarse cells) where it is 0, and the blend
// of the two in between.
std::vector<glm::vec3> push(const Level& level, const std::vector<glm::vec3>& coarse_fill,
                            int coarse_width, int coarse_height) {
    std::vector<glm::vec3> fill(level.sum.size());
    const auto coarse_at = [&](int x, int y) {
        x = std::clamp(x, 0, coarse_width - 1);
        y = std::clamp(y, 0, coarse_height - 1);
        return coarse_fill[static_cast<std::size_t>(y) * static_cast<std::size_t>(coarse_width) +
                           static_cast<std::size_t>(x)];
    };
    for (int y = 0; y < level.height; ++y) {
        for (int x = 0; x < level.width; ++x) {
            // This cell's centre in the coarse level's cells.
            const float cx = (static_cast<float>(x) + 0.5f) * 0.5f - 0.5f;
            const float cy = (static_cast<float>(y) + 0.5f) * 0.5f - 0.5f;
            const int x0 = static_cast<int>(std::floor(cx));
            const int y0 = static_cast<int>(std::floor(cy));
            const float fx = cx - static_cast<float>(x0);
            const float fy = cy - static_cast<float>(y0);
            const glm::vec3 up =
                (1.0f - fy) * ((1.0f - fx) * coarse_at(x0, y0) + fx * coarse_at(x0 + 1, y0)) +
                fy * ((1.0f - fx) * coarse_at(x0, y0 + 1) + fx * coarse_at(x0 + 1, y0 + 1));
            const std::size_t i = level.at(x, y);
            const float w = level.weight[i];
            fill[i] = w > 0.0f ? level.sum[i] + (1.0f - w) * up : up;
        }
    }
    return fill;
}

// Chessboard steps from a pixel with a HIT, through hole pixels only (kUnreached where no HIT
// is reachable), and the 8-connected region of every hole pixel (-1 elsewhere).
struct HoleRegions {
    std::vector<std::int32_t> depth;
    std::vector<std::int32_t> region;
    std::vector<std::int32_t> region_depth; // the deepest pixel of each region
};

HoleRegions hole_regions(const std::vector<std::uint8_t>& hole, const std::vector<float>& coverage,
                         int w, int h) {
    HoleRegions r;
    const std::size_t count = hole.size();
    r.depth.assign(count, kUnreached);
    r.region.assign(count, -1);
    std::vector<std::size_t> frontier;
    for (std::size_t i = 0; i < count; ++i) {
        if (!hole[i]) {
            continue;
        }
        bool beside_hit = false;
        for_each_neighbour(i, w, h, [&](std::size_t u) { beside_hit |= coverage[u] > 0.0f; });
        if (beside_hit) {
            r.depth[i] = 1;
            frontier.push_back(i);
        }
    }
    std::vector<std::size_t> next;
    for (std::int32_t d = 2; !frontier.empty(); ++d) {
        next.clear();
        for (const std::size_t i : frontier) {
            for_each_neighbour(i, w, h, [&](std::size_t u) {
                if (hole[u] && r.depth[u] == kUnreached) {
                    r.depth[u] = d;
                    next.push_back(u);
                }
            });
        }
        frontier.swap(next);
    }
    std::vector<std::size_t> stack;
    for (std::size_t start = 0; start < count; ++start) {
        if (!hole[start] || r.region[start] >= 0) {
            continue;
        }
        const auto id = static_cast<std::int32_t>(r.region_depth.size());
        std::int32_t deepest = 0;
        r.region[start] = id;
        stack.assign(1, start);
        while (!stack.empty()) {
            const std::size_t i = stack.back();
            stack.pop_back();
            deepest = std::max(deepest, r.depth[i]);
            for_each_neighbour(i, w, h, [&](std::size_t u) {
                if (hole[u] && r.region[u] < 0) {
                    r.region[u] = id;
                    stack.push_back(u);
                }
            });
        }
        r.region_depth.push_back(deepest);
    }
    return r;
}

// The fill colours of the holes that lie on a silhouette: a hole whose border holds a near and
// a far surface (depths that differ by over kSilhouetteSpread of the nearest) is what no probe
// saw behind the near one, a disocclusion, and what lies there is the far surface continued.
// Such a hole is filled from its far border alone (the border pixels at least as far as the
// middle of its border's depths), layer by layer inward, a pixel the mean colour of its
// neighbours already known (fill_hole_in_layers), then blended to the harmonic interpolation of
// that border (blend_hole_harmonically), as a probe's hole fill continues the surface behind a
// disocclusion. `far_fill` gets the colour of every pixel of such a hole
// (coverage 1), and `filled` is 1 there; holes deeper than `reach` are left to stay black.
void fill_disocclusions(const HoleRegions& regions, const std::vector<std::uint8_t>& hole,
                        const RenderedImage& image, const std::vector<float>& coverage,
                        std::int32_t reach, std::vector<glm::vec3>& far_fill,
                        std::vector<std::uint8_t>& filled) {
    const int w = image.width;
    const int h = image.height;
    const std::size_t count = hole.size();
    const auto has_depth = [&](std::size_t u) {
        return !hole[u] && coverage[u] > 0.0f && std::isfinite(image.depth[u]) &&
               image.depth[u] > 0.0f;
    };
    // Each hole's pixels and the depths on its border.
    struct Border {
        std::vector<std::size_t> members;
        float nearest = std::numeric_limits<float>::infinity();
        float farthest = 0.0f;
    };
    std::vector<Border> borders(regions.region_depth.size());
    for (std::size_t i = 0; i < count; ++i) {
        if (!hole[i]) {
            continue;
        }
        const auto r = static_cast<std::size_t>(regions.region[i]);
        if (regions.region_depth[r] > reach) {
            continue;
        }
        Border& b = borders[r];
        b.members.push_back(i);
        for_each_neighbour(i, w, h, [&](std::size_t u) {
            if (has_depth(u)) {
                b.nearest = std::min(b.nearest, image.depth[u]);
                b.farthest = std::max(b.farthest, image.depth[u]);
            }
        });
    }
    std::vector<std::int32_t> layer_of(count, kOutsideHole);
    for (const Border& b : borders) {
        if (b.members.empty() || !(b.farthest - b.nearest > kSilhouetteSpread * b.nearest)) {
            continue;
        }
        const float split = 0.5f * (b.nearest + b.farthest);
        const auto behind = [&](std::size_t u) { return has_depth(u) && image.depth[u] >= split; };
        std::int32_t layers = 0;
        fill_hole_in_layers(
            b.members, w, h, layer_of, behind,
            [&](std::size_t i, auto&& known) {
                // The far border's colours (premultiplied by their coverage) and the earlier
                // layers' (coverage 1).
                glm::vec3 sum(0.0f);
                float weight = 0.0f;
                for_each_neighbour(i, w, h, [&](std::size_t u) {
                    if (!known(u)) {
                        return;
                    }
                    if (hole[u]) {
                        sum += far_fill[u];
                        weight += 1.0f;
                    } else {
                        sum += glm::vec3(image.rgba[4 * u], image.rgba[4 * u + 1],
                                         image.rgba[4 * u + 2]);
                        weight += std::min(coverage[u], 1.0f);
                    }
                });
                return sum / weight;
            },
            [&](std::size_t i, const glm::vec3& colour, std::int32_t layer) {
                far_fill[i] = colour;
                filled[i] = 1;
                layers = std::max(layers, layer);
            });
        // Then the harmonic blend of the far border, as a probe's disocclusions are given.
        std::vector<glm::vec3> colour(b.members.size());
        std::transform(b.members.begin(), b.members.end(), colour.begin(),
                       [&](std::size_t i) { return far_fill[i]; });
        blend_hole_harmonically(
            b.members, w, h, colour, layers, [&](std::size_t u, glm::vec3& sum, float& weight) {
                if (behind(u)) {
                    sum +=
                        glm::vec3(image.rgba[4 * u], image.rgba[4 * u + 1], image.rgba[4 * u + 2]);
                    weight += std::min(coverage[u], 1.0f);
                }
            });
        for (std::size_t m = 0; m < b.members.size(); ++m) {
            far_fill[b.members[m]] = colour[m];
        }
    }
}

} // namespace

int default_hole_fill_pixels(int width, int height) {
    return std::max(2, static_cast<int>(std::lround(0.05 * std::max(width, height))));
}

UnknownFillStats fill_unknown_pixels(RenderedImage& image, std::span<const float> unknown_share,
                                     int max_width) {
    UnknownFillStats stats;
    const std::size_t count = image.pixel_count();
    if (unknown_share.size() != count) {
        throw InputError("fill_unknown_pixels: " + std::to_string(unknown_share.size()) +
                         " unknown shares for an image of " + std::to_string(count) + " pixels");
    }
    if (max_width < 0) {
        throw InputError("hole fill: the widest hole to fill must be 0 pixels (off) or more, got " +
                         std::to_string(max_width));
    }
    if (max_width == 0 || count == 0 ||
        std::none_of(unknown_share.begin(), unknown_share.end(),
                     [](float u) { return u > 0.0f; })) {
        return stats;
    }
    const int w = image.width;
    const int h = image.height;
    std::vector<float> coverage(count);
    std::vector<std::uint8_t> hole(count, 0);
    Level base(w, h);
    for (std::size_t i = 0; i < count; ++i) {
        coverage[i] = image.rgba[4 * i + 3];
        // The colour is premultiplied by coverage: the sum a pyramid of coverage weights needs.
        base.sum[i] = glm::vec3(image.rgba[4 * i], image.rgba[4 * i + 1], image.rgba[4 * i + 2]);
        base.weight[i] = std::min(coverage[i], 1.0f);
        hole[i] = coverage[i] <= 0.0f && unknown_share[i] > 0.0f ? 1 : 0;
    }
    const HoleRegions regions = hole_regions(hole, coverage, w, h);
    const std::int32_t reach = (max_width + 1) / 2;
    // Holes on a silhouette, filled from the surface behind instead of the pull-push below.
    std::vector<glm::vec3> far_fill(count, glm::vec3(0.0f));
    std::vector<std::uint8_t> far_filled(count, 0);
    if (image.depth.size() == count) {
        fill_disocclusions(regions, hole, image, coverage, reach, far_fill, far_filled);
    }

    std::vector<Level> levels;
    levels.push_back(std::move(base));
    while (levels.back().width > 1 || levels.back().height > 1) {
        levels.push_back(pull(levels.back()));
    }
    const Level& top = levels.back();
    std::vector<glm::vec3> fill(1, top.weight[0] > 0.0f ? top.sum[0] / top.weight[0]
                                                        : glm::vec3(0.0f));
    for (std::size_t l = levels.size() - 1; l-- > 0;) {
        fill = push(levels[l], fill, levels[l + 1].width, levels[l + 1].height);
    }

    for (std::size_t i = 0; i < count; ++i) {
        const float u = unknown_share[i];
        if (u <= 0.0f) {
            continue;
        }
        if (hole[i]) {
            const std::int32_t region = regions.region[i];
            if (regions.region_depth[static_cast<std::size_t>(region)] > reach) {
                ++stats.pixels_left;
                continue;
            }
            ++stats.pixels_filled;
        }
        const glm::vec3& colour = far_filled[i] ? far_fill[i] : fill[i];
        for (int c = 0; c < 3; ++c) {
            image.rgba[4 * i + static_cast<std::size_t>(c)] += u * colour[c];
        }
        image.rgba[4 * i + 3] = std::min(1.0f, coverage[i] + u);
    }
    return stats;
}

} // namespace lfprobe
