#include "lfprobe/min_distance_pyramid.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>

#include <tbb/parallel_for.h>

#include "lfprobe/error.hpp"

namespace lfprobe {

namespace {

MinDistanceLevel halve(const std::vector<float>& below, int below_n) {
    MinDistanceLevel level;
    level.resolution = (below_n + 1) / 2;
    const auto n = static_cast<std::size_t>(level.resolution);
    const auto bn = static_cast<std::size_t>(below_n);
    level.min_distance.assign(n * n, 0.0f);
    tbb::parallel_for(std::size_t{0}, n, [&](std::size_t y) {
        for (std::size_t x = 0; x < n; ++x) {
            float m = std::numeric_limits<float>::infinity();
            for (std::size_t dy = 0; dy < 2; ++dy) {
                const std::size_t fy = std::min(2 * y + dy, bn - 1);
                for (std::size_t dx = 0; dx < 2; ++dx) {
                    const std::size_t fx = std::min(2 * x + dx, bn - 1);
                    m = std::min(m, min_distance_bound(below[fy * bn + fx]));
                }
            }
            level.min_distance[y * n + x] = m;
        }
    });
    return level;
}

} // namespace

MinDistancePyramid::MinDistancePyramid(const std::vector<float>& fine, int n, int coarsest) {
    if (n <= 0 || fine.size() != static_cast<std::size_t>(n) * static_cast<std::size_t>(n)) {
        throw InputError("min-distance pyramid: expected " + std::to_string(n) +
                         "² distances, got " + std::to_string(fine.size()));
    }
    coarsest = std::max(coarsest, 1);
    const std::vector<float>* below = &fine;
    int below_n = n;
    while (below_n > coarsest) {
        levels_.push_back(halve(*below, below_n));
        below = &levels_.back().min_distance;
        below_n = levels_.back().resolution;
    }
}

void MinDistancePyramid::quantise(double step) {
    if (!(step > 0.0) || !std::isfinite(step)) {
        throw InputError("min-distance pyramid: the quantisation step must be positive");
    }
    for (MinDistanceLevel& level : levels_) {
        if (!level.min_code.empty()) {
            throw InputError("min-distance pyramid: the levels are quantised already");
        }
        std::vector<std::uint16_t> codes(level.min_distance.size());
        for (std::size_t i = 0; i < codes.size(); ++i) {
            const float d = level.min_distance[i];
            if (std::isinf(d)) {
                codes[i] = 0xFFFF;
                continue;
            }
            double code = std::clamp(std::floor(static_cast<double>(d) / step), 0.0, 65534.0);
            // Down, also where the decode's own rounding would land above d.
            while (code > 0.0 && static_cast<float>(code * step) > d) {
                code -= 1.0;
            }
            codes[i] = static_cast<std::uint16_t>(code);
        }
        level.min_code = std::move(codes);
        level.step = step;
        std::vector<float>().swap(level.min_distance);
    }
}

std::size_t MinDistancePyramid::memory_bytes() const {
    std::size_t bytes = 0;
    for (const auto& level : levels_) {
        bytes += level.min_distance.size() * sizeof(float) +
                 level.min_code.size() * sizeof(std::uint16_t);
    }
    return bytes;
}

} // namespace lfprobe
