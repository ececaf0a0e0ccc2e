#include "lfprobe/probe_resolution.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lfprobe/error.hpp"
#include "lfprobe/octahedral.hpp"

namespace lfprobe {

namespace {

constexpr double kSqrtFourPi = oct::kTexelAngleTimesN;
constexpr std::uint64_t kNoNearestPoint = std::numeric_limits<std::uint64_t>::max();

double quantile_of(std::vector<double>& values, double q) {
    const auto k = static_cast<std::size_t>(
        std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1) + 0.5);
    std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
    return values[k];
}

} // namespace

const std::vector<int>& resolution_steps() {
    static const std::vector<int> steps{16,  24,  32,   48,   64,   96,   128,  192,  256, 384,
                                        512, 768, 1024, 1536, 2048, 3072, 4096, 6144, 8192};
    return steps;
}

ResolutionChoice choose_resolution(const PointCloud& cloud, const LocalGeometry& geometry,
                                   const glm::dvec3& centre, const ResolutionSettings& settings) {
    if (settings.min_resolution < 1 || settings.max_resolution < settings.min_resolution ||
        settings.survey_resolution < 8 || !(settings.quantile >= 0.0 && settings.quantile <= 1.0) ||
        !(settings.footprint >= 0.0) ||
        !(settings.samples_per_spacing > 0.0 && std::isfinite(settings.samples_per_spacing))) {
        throw InputError("choose resolution: expected 1 <= min <= max resolution, a survey map of "
                         "at least 8², a quantile in [0, 1], a footprint >= 0 and samples per "
                         "spacing > 0");
    }
    if (geometry.spacing.size() != cloud.size()) {
        throw InputError("choose resolution: the local geometry does not belong to the cloud");
    }
    const int n = settings.survey_resolution;
    // Front-most point per survey texel: distance bits (positive floats order as integers)
    // above the point index, combined with an atomic minimum.
    std::vector<std::atomic<std::uint64_t>> front(static_cast<std::size_t>(n) *
                                                  static_cast<std::size_t>(n));
    for (auto& f : front) {
        f.store(kNoNearestPoint, std::memory_order_relaxed);
    }
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, cloud.size(), 65536),
        [&](const tbb::blocked_range<std::size_t>& block) {
            for (std::size_t i = block.begin(); i != block.end(); ++i) {
                const glm::dvec3 v = glm::dvec3(cloud.positions[i]) - centre;
                const double r = glm::length(v);
                if (!(r > 1e-4) || !std::isfinite(r)) {
                    continue;
                }
                const oct::Texel t = oct::texel_of_direction(glm::vec3(v / r), n);
                const std::uint64_t key =
                    (static_cast<std::uint64_t>(std::bit_cast<std::uint32_t>(static_cast<float>(r)))
                     << 32) |
                    static_cast<std::uint64_t>(i);
                auto& slot = front[oct::texel_index(t, n)];
                std::uint64_t seen = slot.load(std::memory_order_relaxed);
                while (key < seen &&
                       !slot.compare_exchange_weak(seen, key, std::memory_order_relaxed)) {
                }
            }
        });
    std::vector<double> supported;
    std::vector<double> distances;
    std::vector<double> spacings;
    for (const auto& f : front) {
        const std::uint64_t key = f.load(std::memory_order_relaxed);
        if (key == kNoNearestPoint) {
            continue;
        }
        const auto index = static_cast<std::size_t>(key & 0xffffffffu);
        const double r =
            static_cast<double>(std::bit_cast<float>(static_cast<std::uint32_t>(key >> 32)));
        const double s = static_cast<double>(geometry.spacing[index]);
        if (!(s > 0.0)) {
            continue;
        }
        supported.push_back(kSqrtFourPi * r / s);
        distances.push_back(r);
        spacings.push_back(s);
    }
    if (supported.empty()) {
        throw InputError("choose resolution: the probe sees no point of the cloud");
    }
    ResolutionChoice choice;
    choice.directions = supported.size();
    choice.data_resolution = quantile_of(supported, settings.quantile);
    choice.median_distance = quantile_of(distances, 0.5);
    choice.median_spacing = quantile_of(spacings, 0.5);
    double wanted = settings.samples_per_spacing * choice.data_resolution;
    if (settings.footprint > 0.0) {
        choice.footprint_resolution = kSqrtFourPi * choice.median_distance / settings.footprint;
        wanted = std::min(wanted, choice.footprint_resolution);
    }
    int chosen = settings.min_resolution;
    double best = std::numeric_limits<double>::infinity();
    for (const int step : resolution_steps()) {
        const double off = std::abs(std::log(static_cast<double>(step) / wanted));
        if (step >= settings.min_resolution && off < best) {
            best = off;
            chosen = step;
        }
    }
    choice.resolution = std::clamp(chosen, settings.min_resolution, settings.max_resolution);
    return choice;
}

} // namespace lfprobe
