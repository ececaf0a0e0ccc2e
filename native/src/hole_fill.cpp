// Hole filling for baked probes: narrow connected holes are filled and marked inferred, large
// holes stay unknown (docs/DESIGN.md §4). A hole where the scans could not see behind a near
// surface (a disocclusion) continues the surface behind; any other hole is filled from a pull
// pyramid of the measured texels around it.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include "grid_neighbours.hpp"
#include "hole_layers.hpp"
#include "lfprobe/probe_bake.hpp"

namespace lfprobe {

namespace {

// Where the spread of distances among the texels a fill draws from exceeds kSilhouetteSpread
// (hole_layers.hpp) of the nearest one, the hole sits on a silhouette. A pull-push fill then
// takes the nearest surface, so a far surface never shows through a near one; a disocclusion
// takes the far one.
// A hole on a silhouette whose border is at least this much the far surface is a
// disocclusion, filled from behind (classify_hole_border).
constexpr float kMinFarBorder = 0.25f;
// Below this |cos| between a texel's ray and a neighbour's surface plane the plane is too
// grazing to continue, and the neighbour's own distance is used.
constexpr float kMinPlaneCosine = 0.05f;

// One level of the pull pyramid. Its arrays are left unset when made and each texel is set
// (clear) by the task that fills its row: set on one thread, a 1024² level's 75 MB took longer
// than the whole fill of a 2048² probe's holes.
struct PullLevel {
    int n = 0;
    std::unique_ptr<float[]> weight;
    std::unique_ptr<glm::vec3[]> sum_rgb;
    std::unique_ptr<glm::vec3[]> sum_normal;
    std::unique_ptr<double[]> sum_distance;
    std::unique_ptr<float[]> min_distance;
    std::unique_ptr<float[]> max_distance;
    std::unique_ptr<glm::vec3[]> min_rgb;
    std::unique_ptr<glm::vec3[]> min_normal;

    void allocate(int size) {
        n = size;
        const std::size_t count = static_cast<std::size_t>(size) * static_cast<std::size_t>(size);
        weight = std::make_unique_for_overwrite<float[]>(count);
        sum_rgb = std::make_unique_for_overwrite<glm::vec3[]>(count);
        sum_normal = std::make_unique_for_overwrite<glm::vec3[]>(count);
        sum_distance = std::make_unique_for_overwrite<double[]>(count);
        min_distance = std::make_unique_for_overwrite<float[]>(count);
        max_distance = std::make_unique_for_overwrite<float[]>(count);
        min_rgb = std::make_unique_for_overwrite<glm::vec3[]>(count);
        min_normal = std::make_unique_for_overwrite<glm::vec3[]>(count);
    }
    void clear(std::size_t o) {
        weight[o] = 0.0f;
        sum_rgb[o] = glm::vec3(0.0f);
        sum_normal[o] = glm::vec3(0.0f);
        sum_distance[o] = 0.0;
        min_distance[o] = std::numeric_limits<float>::infinity();
        max_distance[o] = 0.0f;
        min_rgb[o] = glm::vec3(0.0f);
        min_normal[o] = glm::vec3(0.0f);
    }
};

// Connected (8-neighbour) components of unknown texels that are at most `max_width` texels
// across: no texel of one lies more than ceil(max_width / 2) steps (8-neighbour) from the
// measured surface around it. Width, not the bounding box: a long thin crack (the strip under a
// shelf's lip that no scanner saw) is as fillable as a short one. Each is its texels in the
// order they were found, and its depth: the most steps any of them lies from the surface.
struct SmallHole {
    std::vector<std::uint32_t> texels;
    std::int32_t depth = 0;
};

std::vector<SmallHole> small_holes(const ProbeMap& map, int max_width) {
    const int n = map.resolution;
    const std::size_t count = map.texel_count();
    const int max_depth = (max_width + 1) / 2;
    std::vector<SmallHole> holes;
    std::vector<std::uint8_t> seen(count, 0);
    std::vector<std::int32_t> depth(count, 0);
    std::vector<std::uint32_t> stack;
    std::vector<std::uint32_t> component;
    std::vector<std::uint32_t> frontier;
    std::vector<std::uint32_t> next;
    for (std::size_t start = 0; start < count; ++start) {
        if (seen[start] || map.state(start) != TexelState::Unknown) {
            continue;
        }
        component.clear();
        stack.assign(1, static_cast<std::uint32_t>(start));
        seen[start] = 1;
        while (!stack.empty()) {
            const std::uint32_t t = stack.back();
            stack.pop_back();
            component.push_back(t);
            for_each_neighbour(t, n, n, [&](std::uint32_t u) {
                if (!seen[u] && map.state(u) == TexelState::Unknown) {
                    seen[u] = 1;
                    stack.push_back(u);
                }
            });
        }
        // Steps from the measured surface, breadth first, given up past max_depth.
        frontier.clear();
        for (const std::uint32_t t : component) {
            bool on_border = false;
            for_each_neighbour(t, n, n, [&](std::uint32_t u) {
                on_border = on_border || map.state(u) == TexelState::Surface;
            });
            depth[t] = on_border ? 1 : 0;
            if (on_border) {
                frontier.push_back(t);
            }
        }
        std::size_t reached = frontier.size();
        std::int32_t deepest = 1;
        for (int d = 2; d <= max_depth && !frontier.empty(); ++d) {
            next.clear();
            for (const std::uint32_t t : frontier) {
                for_each_neighbour(t, n, n, [&](std::uint32_t u) {
                    if (depth[u] == 0 && map.state(u) == TexelState::Unknown) {
                        depth[u] = d;
                        next.push_back(u);
                    }
                });
            }
            reached += next.size();
            deepest = next.empty() ? deepest : d;
            frontier.swap(next);
        }
        for (const std::uint32_t t : component) {
            depth[t] = 0;
        }
        if (reached == component.size()) {
            holes.push_back({component, deepest});
        }
    }
    return holes;
}

// The measured surface a disocclusion hole shows, when it is one: the distance beyond which
// its border's texels count as the background. A hole whose border holds a near and a far
// surface (a spread over kSilhouetteSpread) and whose far part is at least kMinFarBorder of
// the border lies where the scans could not see behind the near surface (a scanner's shadow,
// seen from elsewhere): what is there is the far surface, continued. A hole bordered mostly by
// the near surface is a gap in that surface (a thin object's missing points), or lies beside
// it (within_near_surface tells which).
struct HoleBorder {
    enum Kind { kPlain, kNearSurface, kDisocclusion } kind = kPlain; // plain: on no silhouette
    float split = 0.0f; // on a silhouette: the distance between its near and far surfaces
};

HoleBorder classify_hole_border(const ProbeMap& map, const std::vector<std::uint32_t>& hole,
                                std::vector<std::uint8_t>& in_border) {
    const int n = map.resolution;
    std::vector<std::uint32_t> border;
    for (const std::uint32_t t : hole) {
        for_each_neighbour(t, n, n, [&](std::uint32_t u) {
            if (!in_border[u] && map.state(u) == TexelState::Surface) {
                in_border[u] = 1;
                border.push_back(u);
            }
        });
    }
    float near = std::numeric_limits<float>::infinity();
    float far = 0.0f;
    for (const std::uint32_t u : border) {
        in_border[u] = 0;
        near = std::min(near, map.distance[u]);
        far = std::max(far, map.distance[u]);
    }
    if (border.empty() || !(far - near > kSilhouetteSpread * near)) {
        return {};
    }
    const float split = 0.5f * (near + far);
    const auto far_count = static_cast<std::size_t>(std::count_if(
        border.begin(), border.end(), [&](std::uint32_t u) { return map.distance[u] >= split; }));
    return {static_cast<float>(far_count) >= kMinFarBorder * static_cast<float>(border.size())
                ? HoleBorder::kDisocclusion
                : HoleBorder::kNearSurface,
            split};
}

// Whether a hole on a silhouette that its border calls a gap in the near surface lies within
// one near surface: at least half its texels meet, both ways along a row or a column, texels
// nearer than `split` whose distances agree within kSilhouetteSpread (the surface continues
// across the hole). A blind's slats around the gap between them do; a strip under a desk's
// front edge seen from above does not (the desk on one side, the floor under it on the other:
// the desk's front face and what lies under it, which no scan saw). Such a strip stays
// unknown, for the other probes and the render's hole fill: the near surface's colour there
// was most of the error of the probes' guesses. `in_hole` is scratch, all 0 on entry and on
// return.
bool within_near_surface(const ProbeMap& map, const std::vector<std::uint32_t>& hole, float split,
                         std::vector<std::uint8_t>& in_hole) {
    const int n = map.resolution;
    for (const std::uint32_t t : hole) {
        in_hole[t] = 1;
    }
    // The distance of the first texel past the hole from (x, y) in steps of (dx, dy) where it
    // is a measured surface nearer than the split; +inf otherwise.
    const auto near_beyond = [&](int x, int y, int dx, int dy) {
        constexpr float none = std::numeric_limits<float>::infinity();
        for (;;) {
            x += dx;
            y += dy;
            if (x < 0 || y < 0 || x >= n || y >= n) {
                return none;
            }
            const std::size_t u = oct::texel_index({x, y}, n);
            if (in_hole[u] == 0) {
                return map.state(u) == TexelState::Surface && map.distance[u] < split
                           ? map.distance[u]
                           : none;
            }
        }
    };
    const auto one_surface = [](float a, float b) {
        return std::isfinite(a) && std::isfinite(b) &&
               std::abs(a - b) <= kSilhouetteSpread * std::min(a, b);
    };
    std::size_t within = 0;
    for (const std::uint32_t t : hole) {
        const int x = static_cast<int>(t % static_cast<std::uint32_t>(n));
        const int y = static_cast<int>(t / static_cast<std::uint32_t>(n));
        if (one_surface(near_beyond(x, y, 1, 0), near_beyond(x, y, -1, 0)) ||
            one_surface(near_beyond(x, y, 0, 1), near_beyond(x, y, 0, -1))) {
            ++within;
        }
    }
    for (const std::uint32_t t : hole) {
        in_hole[t] = 0;
    }
    return 2 * within >= hole.size();
}

// Whether texel u is a disocclusion's background border: a measured surface at least as far as
// the split between its near and far surfaces.
bool is_background(const ProbeMap& map, std::uint32_t u, float split) {
    return map.state(u) == TexelState::Surface && map.distance[u] >= split;
}

// Fills a disocclusion hole from its background side only, layer by layer inward (onion
// peeling): a texel takes the mean colour and normal of its neighbours already known (the
// background border, then earlier layers), and the distance where its ray meets their
// surface planes, so a plane behind the near surface continues under it. Layer k is inferred
// with confidence 2^-(1 + floor(log2 k)): as the pull-push's level, halving as the fill
// reaches twice as far. Reads only texels of earlier layers, so the order is fixed. Returns the
// number of layers (about half the hole's width).
std::int32_t fill_from_background(ProbeMap& map, const std::vector<std::uint32_t>& hole,
                                  float split, std::vector<std::int32_t>& layer_of) {
    const int n = map.resolution;
    std::int32_t layers = 0;
    struct Fill {
        float distance;
        glm::vec3 rgb;
        glm::vec3 normal;
    };
    const auto direction_of = [n](std::uint32_t t) {
        return oct::texel_direction({static_cast<int>(t % static_cast<std::uint32_t>(n)),
                                     static_cast<int>(t / static_cast<std::uint32_t>(n))},
                                    n);
    };
    fill_hole_in_layers(
        hole, n, n, layer_of, [&](std::uint32_t u) { return is_background(map, u, split); },
        [&](std::uint32_t t, auto&& known) {
            const glm::vec3 dir = direction_of(t);
            Fill f{0.0f, glm::vec3(0.0f), glm::vec3(0.0f)};
            int from = 0;
            for_each_neighbour(t, n, n, [&](std::uint32_t u) {
                if (!known(u)) {
                    return;
                }
                const float d = map.distance[u];
                const glm::vec3 normal = map.normal_at(u);
                const float cos_plane = glm::dot(normal, dir);
                float s = d;
                if (std::abs(cos_plane) >= kMinPlaneCosine) {
                    const float on_plane = glm::dot(normal, d * direction_of(u)) / cos_plane;
                    if (on_plane > 0.5f * d && on_plane < 2.0f * d) {
                        s = on_plane;
                    }
                }
                f.distance += s;
                f.rgb += map.radiance_at(u);
                f.normal += normal;
                ++from;
            });
            const float len = glm::length(f.normal);
            f.distance /= static_cast<float>(from);
            f.rgb /= static_cast<float>(from);
            f.normal = len > 0.0f ? f.normal / len : glm::vec3(0.0f);
            return f;
        },
        [&](std::uint32_t t, const Fill& f, std::int32_t layer) {
            const float confidence =
                std::ldexp(1.0f, -static_cast<int>(std::bit_width(static_cast<unsigned>(layer))));
            map.set_surface(t, f.distance, f.rgb, f.normal, confidence);
            layers = std::max(layers, layer);
        });
    return layers;
}

// Gives a filled hole the harmonic blend of the colours of the texels around it that
// `is_source` accepts (blend_hole_harmonically). Writes only the hole's colours and reads only
// it and its border, so holes can be blended at once.
template <class IsSource>
void blend_colours_with(ProbeMap& map, const std::vector<std::uint32_t>& hole, std::int32_t layers,
                        IsSource&& is_source) {
    std::vector<glm::vec3> colour(hole.size());
    std::transform(hole.begin(), hole.end(), colour.begin(),
                   [&](std::uint32_t t) { return map.radiance_at(t); });
    blend_hole_harmonically(hole, map.resolution, map.resolution, colour, layers,
                            [&](std::uint32_t u, glm::vec3& sum, float& weight) {
                                if (is_source(u)) {
                                    sum += map.radiance_at(u);
                                    weight += 1.0f;
                                }
                            });
    for (std::size_t i = 0; i < hole.size(); ++i) {
        for (int a = 0; a < 3; ++a) {
            map.rgba[4 * hole[i] + static_cast<std::size_t>(a)] = Imath::half(colour[i][a]);
        }
    }
}

// A disocclusion's, from its background border.
void blend_colours_from_background(ProbeMap& map, const std::vector<std::uint32_t>& hole,
                                   float split, std::int32_t layers) {
    blend_colours_with(map, hole, layers,
                       [&](std::uint32_t u) { return is_background(map, u, split); });
}

// The pull-push fill (the holes that are not disocclusions): a pull pyramid of the measured
// texels; each texel to fill takes the smallest enclosing block with support, its mean, or
// its nearest surface where the block spans a silhouette.
void pull_push(ProbeMap& map, const std::vector<std::uint8_t>& fill, int hole_fill_texels) {
    const int n = map.resolution;
    // Pull: level l texel (x, y) gathers the measured texels of level 0 in its 2^l block.
    // levels[l - 1] is level l; level 0 is the map itself, read in place (a copy of it would be
    // the pyramid's largest level, and the push never reads it). Every level's texel adds its
    // four below in one fixed order, so each level is built a row per task.
    std::vector<PullLevel> levels;
    auto pull = [&](int below_n, PullLevel& up, auto&& add_below) {
        up.allocate((below_n + 1) / 2);
        const auto bn = static_cast<std::size_t>(below_n);
        tbb::parallel_for(0, up.n, [&](int row) {
            const auto y = static_cast<std::size_t>(row);
            for (std::size_t x = 0; x < static_cast<std::size_t>(up.n); ++x) {
                const std::size_t o = y * static_cast<std::size_t>(up.n) + x;
                up.clear(o);
                for (std::size_t dy = 0; dy < 2; ++dy) {
                    for (std::size_t dx = 0; dx < 2; ++dx) {
                        const std::size_t bx = 2 * x + dx;
                        const std::size_t by = 2 * y + dy;
                        if (bx < bn && by < bn) {
                            add_below(up, o, by * bn + bx);
                        }
                    }
                }
            }
        });
    };
    {
        PullLevel first;
        pull(n, first, [&](PullLevel& up, std::size_t o, std::size_t b) {
            if (map.state(b) != TexelState::Surface) {
                return;
            }
            const float d = map.distance[b];
            up.weight[o] += 1.0f;
            up.sum_rgb[o] += map.radiance_at(b);
            up.sum_normal[o] += map.normal_at(b);
            up.sum_distance[o] += d;
            up.max_distance[o] = std::max(up.max_distance[o], d);
            if (d < up.min_distance[o]) {
                up.min_distance[o] = d;
                up.min_rgb[o] = map.radiance_at(b);
                up.min_normal[o] = map.normal_at(b);
            }
        });
        levels.push_back(std::move(first));
    }
    // A hole of K texels is bridged once blocks are 2K wide; no need to go further.
    while (levels.back().n > 1 && (1 << levels.size()) < 4 * hole_fill_texels) {
        const PullLevel& below = levels.back();
        PullLevel up;
        pull(below.n, up, [&](PullLevel& level, std::size_t o, std::size_t b) {
            if (below.weight[b] <= 0.0f) {
                return;
            }
            level.weight[o] += below.weight[b];
            level.sum_rgb[o] += below.sum_rgb[b];
            level.sum_normal[o] += below.sum_normal[b];
            level.sum_distance[o] += below.sum_distance[b];
            level.max_distance[o] = std::max(level.max_distance[o], below.max_distance[b]);
            if (below.min_distance[b] < level.min_distance[o]) {
                level.min_distance[o] = below.min_distance[b];
                level.min_rgb[o] = below.min_rgb[b];
                level.min_normal[o] = below.min_normal[b];
            }
        });
        levels.push_back(std::move(up));
    }
    // Push: each texel of a small hole takes the smallest enclosing block with support.
    tbb::parallel_for(std::size_t{0}, map.texel_count(), [&](std::size_t i) {
        if (!fill[i]) {
            return;
        }
        const std::size_t x = i % static_cast<std::size_t>(n);
        const std::size_t y = i / static_cast<std::size_t>(n);
        for (std::size_t l = 1; l <= levels.size(); ++l) {
            const PullLevel& level = levels[l - 1];
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
    });
}

} // namespace

namespace {

// A texel is seen through a nearer surface where that surface lies nearer than its own
// distance divided by this: well apart from the depth steps within one surface.
constexpr float kSieveDepthRatio = 1.25f;
// A gap's rim joins its hole at distances within this fraction of its neighbour's in the hole.
constexpr float kSieveRimSpread = 0.1f;

} // namespace

int sieve_gap_reach(int resolution) {
    return std::max(1, resolution / 256);
}

std::size_t open_gaps_in_nearer_surfaces(ProbeMap& map, int reach) {
    const int n = map.resolution;
    if (reach <= 0 || n <= 0) {
        return 0;
    }
    const std::size_t count = map.texel_count();
    // Measured distances (+inf elsewhere), read while the flags are written: the test sees the
    // map as the splats left it.
    std::vector<float> measured(count);
    tbb::parallel_for(std::size_t{0}, count, [&](std::size_t t) {
        measured[t] = map.state(t) == TexelState::Surface ? map.distance_at(t)
                                                          : std::numeric_limits<float>::infinity();
    });
    constexpr int kDirections[8][2] = {{1, 0}, {-1, 0}, {0, 1},  {0, -1},
                                       {1, 1}, {1, -1}, {-1, 1}, {-1, -1}};
    const auto index = [n](int x, int y) {
        return static_cast<std::size_t>(y) * static_cast<std::size_t>(n) +
               static_cast<std::size_t>(x);
    };
    // In how many of the 8 directions a nearer surface lies within the reach, stopping once
    // more than `stop` are open. Beyond the map's edge counts as open: the octahedral fold's far
    // side is not a step away in texels.
    const auto closed_directions = [&](int x, int y, int stop) {
        const float nearer_than = measured[index(x, y)] / kSieveDepthRatio;
        int closed = 0;
        int open = 0;
        for (const auto& d : kDirections) {
            bool found = false;
            for (int k = 1; k <= reach && !found; ++k) {
                const int ux = x + k * d[0];
                const int uy = y + k * d[1];
                if (ux < 0 || uy < 0 || ux >= n || uy >= n) {
                    break;
                }
                found = measured[index(ux, uy)] < nearer_than;
            }
            closed += found ? 1 : 0;
            open += found ? 0 : 1;
            if (open > stop) {
                break;
            }
        }
        return closed;
    };
    // Seeds: texels closed in every direction. Most texels stop at their first open direction.
    std::vector<std::uint8_t> seen_through(count, 0);
    tbb::parallel_for(0, n, [&](int y) {
        for (int x = 0; x < n; ++x) {
            if (std::isfinite(measured[index(x, y)]) && closed_directions(x, y, 0) == 8) {
                seen_through[index(x, y)] = 1;
            }
        }
    });
    // A gap wider than the reach across one way leaves its rim open that way: the rim joins
    // its seed where it is closed in all but two directions at about the seed's distance, so
    // that the hole is the whole gap. A hole with the far surface left in its border would be
    // filled as a disocclusion, from behind. A slit (open both ways along it) has no seed.
    std::vector<std::uint32_t> queue;
    for (std::size_t t = 0; t < count; ++t) {
        if (seen_through[t] != 0) {
            queue.push_back(static_cast<std::uint32_t>(t));
        }
    }
    for (std::size_t q = 0; q < queue.size(); ++q) {
        const std::uint32_t t = queue[q];
        const float depth = measured[t];
        for_each_neighbour(t, n, n, [&](std::uint32_t u) {
            if (seen_through[u] != 0 ||
                !(std::abs(measured[u] - depth) <= kSieveRimSpread * depth)) {
                return;
            }
            const int ux = static_cast<int>(u % static_cast<std::uint32_t>(n));
            const int uy = static_cast<int>(u / static_cast<std::uint32_t>(n));
            if (closed_directions(ux, uy, 2) >= 6) {
                seen_through[u] = 1;
                queue.push_back(u);
            }
        });
    }
    for (const std::uint32_t t : queue) {
        map.set_unknown(t);
    }
    return queue.size();
}

void fill_small_holes(ProbeMap& map, int hole_fill_texels) {
    if (hole_fill_texels <= 0) {
        return;
    }
    const std::vector<SmallHole> holes = small_holes(map, hole_fill_texels);
    if (holes.empty()) {
        return;
    }
    // Disocclusions are filled from behind (fill_from_background), the other holes by the
    // pull-push below, both from the measured texels only: a fill writes inferred texels,
    // which neither reads. `nearer_than` is, per hole that the pull-push fills, the distance
    // below which its border's texels are its own surface: all of them for a hole on no
    // silhouette, the near surface's for a gap in one.
    std::vector<std::uint8_t> fill(map.texel_count(), 0);
    std::vector<std::pair<std::size_t, float>> disocclusions;
    std::vector<std::pair<std::size_t, float>> pulled;
    {
        std::vector<std::uint8_t> in_border(map.texel_count(), 0);
        std::vector<std::uint8_t> in_hole(map.texel_count(), 0);
        for (std::size_t h = 0; h < holes.size(); ++h) {
            const HoleBorder border = classify_hole_border(map, holes[h].texels, in_border);
            if (border.kind == HoleBorder::kDisocclusion) {
                disocclusions.emplace_back(h, border.split);
            } else if (border.kind == HoleBorder::kNearSurface &&
                       !within_near_surface(map, holes[h].texels, border.split, in_hole)) {
                continue; // beside a near edge, not within the near surface: stays unknown
            } else {
                for (const std::uint32_t t : holes[h].texels) {
                    fill[t] = 1;
                }
                pulled.emplace_back(h, border.kind == HoleBorder::kNearSurface
                                           ? border.split
                                           : std::numeric_limits<float>::infinity());
            }
        }
    }
    if (!pulled.empty()) {
        pull_push(map, fill, hole_fill_texels);
    }
    std::vector<std::int32_t> layers(disocclusions.size());
    if (!disocclusions.empty()) {
        std::vector<std::int32_t> layer_of(map.texel_count(), kOutsideHole);
        for (std::size_t d = 0; d < disocclusions.size(); ++d) {
            const auto& [h, split] = disocclusions[d];
            layers[d] = fill_from_background(map, holes[h].texels, split, layer_of);
        }
    }
    // Then each hole's colours, the harmonic blend of the measured texels of its own surface
    // around it: a disocclusion's of the surface behind it (eye at the demo's grid probe 25.53
    // -> 26.63 dB), a pull-push hole's of its border, or of the near surface's part of it for
    // a gap in a near surface. A pull-push texel takes the mean of the smallest block around it
    // with support, a step where the block changes; the blend gained the demo grid's eyes up to
    // 0.14 dB (between probes at the grid probe 31.88 -> 32.02 dB), none lost. Each blend
    // writes only its hole and reads only measured texels, so all run at once.
    tbb::parallel_for(std::size_t{0}, pulled.size() + disocclusions.size(), [&](std::size_t i) {
        if (i < pulled.size()) {
            // Named copies, not a structured binding: C++20 lets a lambda capture one, but
            // Clang 14 (the fuzz build) does not yet.
            const std::size_t h = pulled[i].first;
            const float nearer_than = pulled[i].second;
            blend_colours_with(map, holes[h].texels, holes[h].depth, [&](std::uint32_t u) {
                return map.state(u) == TexelState::Surface && map.distance[u] < nearer_than;
            });
        } else {
            const std::size_t d = i - pulled.size();
            const auto& [h, split] = disocclusions[d];
            blend_colours_from_background(map, holes[h].texels, split, layers[d]);
        }
    });
}

} // namespace lfprobe
