// Primary-ray throughput measured one way for every tracer (docs/DESIGN.md §6): the camera's
// pixel-centre rays made once beforehand, then only the traces timed, fastest of `repeats`, on
// the calling task arena's threads. Ray generation and writing pixels are not in the figure.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lfprobe/camera.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/ray.hpp"

namespace lfprobe {

struct ThroughputResult {
    std::uint64_t rays = 0;
    std::uint64_t hits = 0;
    double seconds = 0.0;
    double rays_per_second = 0.0;
    int repeats = 0;
};

// The camera's pixel-centre rays, row by row, in the local frame of `world_offset`.
[[nodiscard]] inline std::vector<Ray> camera_local_rays(const Camera& camera,
                                                        const glm::dvec3& world_offset) {
    std::vector<Ray> rays(static_cast<std::size_t>(camera.width) *
                          static_cast<std::size_t>(camera.height));
    const CameraRays camera_rays(camera);
    camera_rays.require_finite_rays();
    for (int y = 0; y < camera.height; ++y) {
        for (int x = 0; x < camera.width; ++x) {
            rays[static_cast<std::size_t>(y) * static_cast<std::size_t>(camera.width) +
                 static_cast<std::size_t>(x)] = camera_rays.local_pixel_ray(x, y, world_offset);
        }
    }
    return rays;
}

// Times `count_hits(const Ray* rays, std::size_t count) -> hits among them` over `rays`,
// handed out in runs of up to 1024 consecutive rays (a tracer may work on several rays at
// once). `who` names the tracer in errors.
template <class CountHits>
[[nodiscard]] ThroughputResult measure_rays_throughput(const std::vector<Ray>& rays, int repeats,
                                                       const std::string& who,
                                                       CountHits&& count_hits) {
    if (repeats < 1) {
        throw InputError(who + " throughput: repeats must be at least 1");
    }
    ThroughputResult result;
    result.rays = rays.size();
    result.repeats = repeats;
    result.seconds = std::numeric_limits<double>::infinity();
    for (int rep = 0; rep < repeats; ++rep) {
        std::atomic<std::uint64_t> hits{0};
        const auto start = std::chrono::steady_clock::now();
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), 1024),
                          [&](const tbb::blocked_range<std::size_t>& r) {
                              const std::uint64_t local =
                                  count_hits(rays.data() + r.begin(), r.size());
                              hits.fetch_add(local, std::memory_order_relaxed);
                          });
        const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        result.seconds = std::min(result.seconds, seconds);
        result.hits = hits.load();
    }
    result.rays_per_second =
        result.seconds > 0.0 ? static_cast<double>(result.rays) / result.seconds : 0.0;
    return result;
}

// measure_rays_throughput over the camera's pixel-centre rays in the local frame of
// `world_offset`.
template <class CountHits>
[[nodiscard]] ThroughputResult
measure_batch_throughput(const Camera& camera, const glm::dvec3& world_offset, int repeats,
                         const std::string& who, CountHits&& count_hits) {
    if (repeats < 1) {
        throw InputError(who + " throughput: repeats must be at least 1");
    }
    return measure_rays_throughput(camera_local_rays(camera, world_offset), repeats, who,
                                   std::forward<CountHits>(count_hits));
}

} // namespace lfprobe
