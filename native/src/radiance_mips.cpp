#include "lfprobe/radiance_mips.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "lfprobe/octahedral.hpp"

namespace lfprobe {

RadianceMips::RadianceMips(const ProbeMap& map) {
    // Level 0 as colour and weight: a texel counts where it holds a surface (finite distance).
    Level below;
    below.n = map.resolution;
    below.colour_weight.resize(map.texel_count());
    for (std::size_t i = 0; i < map.texel_count(); ++i) {
        const bool surface = std::isfinite(map.distance_at(i));
        below.colour_weight[i] = surface ? glm::vec4(map.radiance_at(i), 1.0f) : glm::vec4(0.0f);
    }
    while (below.n > 1) {
        Level level;
        level.n = (below.n + 1) / 2;
        level.colour_weight.assign(static_cast<std::size_t>(level.n) * level.n, glm::vec4(0.0f));
        for (int y = 0; y < level.n; ++y) {
            for (int x = 0; x < level.n; ++x) {
                // Summed as differences from the first child with a surface, so that a surface
                // of one colour keeps exactly that colour at every level.
                glm::vec3 base{0.0f};
                glm::vec3 sum{0.0f};
                float weight = 0.0f;
                for (int j = 0; j < 2; ++j) {
                    for (int i = 0; i < 2; ++i) {
                        // An odd side's last texel has one child along that axis.
                        const int cx = std::min(2 * x + i, below.n - 1);
                        const int cy = std::min(2 * y + j, below.n - 1);
                        const glm::vec4& c =
                            below.colour_weight[oct::texel_index({cx, cy}, below.n)];
                        if (!(c.w > 0.0f)) {
                            continue;
                        }
                        if (!(weight > 0.0f)) {
                            base = glm::vec3(c);
                        }
                        sum += c.w * (glm::vec3(c) - base);
                        weight += c.w;
                    }
                }
                level.colour_weight[oct::texel_index({x, y}, level.n)] =
                    weight > 0.0f ? glm::vec4(base + sum / weight, weight / 4.0f) : glm::vec4(0.0f);
            }
        }
        levels_.push_back(level);
        below = std::move(level);
    }
}

glm::vec3 RadianceMips::bilinear(int level, const glm::vec2& uv, bool& found) const {
    const Level& l = levels_.at(static_cast<std::size_t>(level - 1));
    const float fx = uv.x * static_cast<float>(l.n) - 0.5f;
    const float fy = uv.y * static_cast<float>(l.n) - 0.5f;
    const float x0 = std::floor(fx);
    const float y0 = std::floor(fy);
    const std::array<float, 2> wx{1.0f - (fx - x0), fx - x0};
    const std::array<float, 2> wy{1.0f - (fy - y0), fy - y0};
    // Differences from the first texel with a surface, as the level was built.
    glm::vec3 base{0.0f};
    glm::vec3 sum{0.0f};
    float weight = 0.0f;
    for (int j = 0; j < 2; ++j) {
        for (int i = 0; i < 2; ++i) {
            const oct::Texel t =
                oct::wrap_texel(static_cast<int>(x0) + i, static_cast<int>(y0) + j, l.n);
            const glm::vec4& c = l.colour_weight[oct::texel_index(t, l.n)];
            const float w = wx[static_cast<std::size_t>(i)] * wy[static_cast<std::size_t>(j)] * c.w;
            if (!(w > 0.0f)) {
                continue;
            }
            if (!(weight > 0.0f)) {
                base = glm::vec3(c);
            }
            sum += w * (glm::vec3(c) - base);
            weight += w;
        }
    }
    found = weight > 0.0f;
    return found ? base + sum / weight : glm::vec3(0.0f);
}

std::size_t RadianceMips::memory_bytes() const {
    std::size_t bytes = 0;
    for (const Level& l : levels_) {
        bytes += l.colour_weight.size() * sizeof(glm::vec4);
    }
    return bytes;
}

} // namespace lfprobe
