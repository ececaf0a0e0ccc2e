// Hole filling for baked probes: small connected holes are filled from a pull pyramid of the
// measured texels and marked inferred; large holes stay unknown (docs/DESIGN.md §4).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <glm/geometric.hpp>

#include "lfprobe/probe_bake.hpp"

namespace lfprobe {

namespace {

// Where the spread of distances among the texels a fill draws from exceeds this fraction of
// the nearest one, the hole sits on a silhouette: the nearest surface fills it, so a far
// surface never shows through a near one.
constexpr float kSilhouetteSpread = 0.05f;

struct PullLevel {
    int n = 0;
    std::vector<float> weight;
    std::vector<glm::vec3> sum_rgb;
    std::vector<glm::vec3> sum_normal;
    std::vector<double> sum_distance;
    std::vector<float> min_distance;
    std::vector<float> max_distance;
    std::vector<glm::vec3> min_rgb;
    std::vector<glm::vec3> min_normal;

    void resize(int size) {
        n = size;
        const std::size_t count = static_cast<std::size_t>(size) * static_cast<std::size_t>(size);
        weight.assign(count, 0.0f);
        sum_rgb.assign(count, glm::vec3(0.0f));
        sum_normal.assign(count, glm::vec3(0.0f));
        sum_distance.assign(count, 0.0);
        min_distance.assign(count, std::numeric_limits<float>::infinity());
        max_distance.assign(count, 0.0f);
        min_rgb.assign(count, glm::vec3(0.0f));
        min_normal.assign(count, glm::vec3(0.0f));
    }
};

// Connected (4-neighbour) components of unknown texels whose bounding box fits in
// `max_extent` × `max_extent`; returns a mask of the texels to fill.
std::vector<std::uint8_t> small_hole_mask(const ProbeMap& map, int max_extent) {
    const int n = map.resolution;
    const std::size_t count = map.texel_count();
    std::vector<std::uint8_t> fill(count, 0);
    std::vector<std::uint8_t> seen(count, 0);
    std::vector<std::uint32_t> stack;
    std::vector<std::uint32_t> component;
    for (std::size_t start = 0; start < count; ++start) {
        if (seen[start] || map.state(start) != TexelState::Unknown) {
            continue;
        }
        int min_x = n, min_y = n, max_x = -1, max_y = -1;
        bool too_big = false;
        component.clear();
        stack.assign(1, static_cast<std::uint32_t>(start));
        seen[start] = 1;
        while (!stack.empty()) {
            const std::uint32_t t = stack.back();
            stack.pop_back();
            const int x = static_cast<int>(t % static_cast<std::uint32_t>(n));
            const int y = static_cast<int>(t / static_cast<std::uint32_t>(n));
            min_x = std::min(min_x, x);
            max_x = std::max(max_x, x);
            min_y = std::min(min_y, y);
            max_y = std::max(max_y, y);
            too_big = too_big || max_x - min_x >= max_extent || max_y - min_y >= max_extent;
            if (!too_big) {
                component.push_back(t);
            }
            const int nx[4] = {x - 1, x + 1, x, x};
            const int ny[4] = {y, y, y - 1, y + 1};
            for (int k = 0; k < 4; ++k) {
                if (nx[k] < 0 || ny[k] < 0 || nx[k] >= n || ny[k] >= n) {
                    continue;
                }
                const std::size_t u =
                    static_cast<std::size_t>(ny[k]) * static_cast<std::size_t>(n) +
                    static_cast<std::size_t>(nx[k]);
                if (!seen[u] && map.state(u) == TexelState::Unknown) {
                    seen[u] = 1;
                    stack.push_back(static_cast<std::uint32_t>(u));
                }
            }
        }
        if (!too_big) {
            for (const std::uint32_t t : component) {
                fill[t] = 1;
            }
        }
    }
    return fill;
}

} // namespace

void fill_small_holes(ProbeMap& map, int hole_fill_texels) {
    if (hole_fill_texels <= 0) {
        return;
    }
    const int n = map.resolution;
    const std::vector<std::uint8_t> fill = small_hole_mask(map, hole_fill_texels);
    if (std::find(fill.begin(), fill.end(), 1) == fill.end()) {
        return;
    }
    // Pull: level l texel (x, y) gathers the measured texels of level 0 in its 2^l block.
    std::vector<PullLevel> levels;
    PullLevel base;
    base.resize(n);
    for (std::size_t i = 0; i < map.texel_count(); ++i) {
        const TexelState s = map.state(i);
        if (s != TexelState::Surface) {
            continue;
        }
        const float d = map.distance[i];
        base.weight[i] = 1.0f;
        base.sum_rgb[i] = map.radiance_at(i);
        base.sum_normal[i] = map.normal_at(i);
        base.sum_distance[i] = d;
        base.min_distance[i] = d;
        base.max_distance[i] = d;
        base.min_rgb[i] = map.radiance_at(i);
        base.min_normal[i] = map.normal_at(i);
    }
    levels.push_back(std::move(base));
    while (levels.back().n > 1) {
        const PullLevel& below = levels.back();
        PullLevel up;
        up.resize((below.n + 1) / 2);
        const auto bn = static_cast<std::size_t>(below.n);
        for (std::size_t y = 0; y < static_cast<std::size_t>(up.n); ++y) {
            for (std::size_t x = 0; x < static_cast<std::size_t>(up.n); ++x) {
                const std::size_t o = y * static_cast<std::size_t>(up.n) + x;
                for (std::size_t dy = 0; dy < 2; ++dy) {
                    for (std::size_t dx = 0; dx < 2; ++dx) {
                        const std::size_t bx = 2 * x + dx;
                        const std::size_t by = 2 * y + dy;
                        if (bx >= bn || by >= bn) {
                            continue;
                        }
                        const std::size_t b = by * bn + bx;
                        if (below.weight[b] <= 0.0f) {
                            continue;
                        }
                        up.weight[o] += below.weight[b];
                        up.sum_rgb[o] += below.sum_rgb[b];
                        up.sum_normal[o] += below.sum_normal[b];
                        up.sum_distance[o] += below.sum_distance[b];
                        up.max_distance[o] = std::max(up.max_distance[o], below.max_distance[b]);
                        if (below.min_distance[b] < up.min_distance[o]) {
                            up.min_distance[o] = below.min_distance[b];
                            up.min_rgb[o] = below.min_rgb[b];
                            up.min_normal[o] = below.min_normal[b];
                        }
                    }
                }
            }
        }
        levels.push_back(std::move(up));
        // A hole of K texels is bridged once blocks are 2K wide; no need to go further.
        if ((1 << (levels.size() - 1)) >= 4 * hole_fill_texels) {
            break;
        }
    }
    // Push: each texel of a small hole takes the smallest enclosing block with support.
    for (std::size_t i = 0; i < map.texel_count(); ++i) {
        if (!fill[i]) {
            continue;
        }
        const std::size_t x = i % static_cast<std::size_t>(n);
        const std::size_t y = i / static_cast<std::size_t>(n);
        for (std::size_t l = 1; l < levels.size(); ++l) {
            const PullLevel& level = levels[l];
            const std::size_t o = (y >> l) * static_cast<std::size_t>(level.n) + (x >> l);
            if (level.weight[o] <= 0.0f) {
                continue;
            }
            const float confidence = std::ldexp(1.0f, -static_cast<int>(l));
            const float near = level.min_distance[o];
            if (level.max_distance[o] - near > kSilhouetteSpread * near) {
                map.set_surface(i, near, level.min_rgb[o], level.min_normal[o], confidence);
            } else {
                const float w = level.weight[o];
                glm::vec3 normal = level.sum_normal[o];
                const float len = glm::length(normal);
                normal = len > 0.0f ? normal / len : level.min_normal[o];
                map.set_surface(i, static_cast<float>(level.sum_distance[o] / w),
                                level.sum_rgb[o] / w, normal, confidence);
            }
            break;
        }
    }
}

} // namespace lfprobe
