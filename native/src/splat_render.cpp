#include "lfprobe/splat_render.hpp"

#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lfprobe/error.hpp"
#include "lfprobe/image_exr.hpp"
#include "lfprobe/image_metadata.hpp"
#include "lfprobe/prepared_cloud_cache.hpp"
#include "lfprobe/probe_trace.hpp"

namespace lfprobe {

namespace {

constexpr std::uint64_t kEmptyPixel = std::numeric_limits<std::uint64_t>::max();

// Positive floats order like their bit patterns: (distance, index) in one integer.
std::uint64_t depth_key(float distance, std::uint32_t index) {
    return (static_cast<std::uint64_t>(std::bit_cast<std::uint32_t>(distance)) << 32) | index;
}

void atomic_min(std::atomic<std::uint64_t>& slot, std::uint64_t key) {
    std::uint64_t current = slot.load(std::memory_order_relaxed);
    while (key < current && !slot.compare_exchange_weak(current, key, std::memory_order_relaxed)) {
    }
}

} // namespace

nlohmann::json SplatStats::to_json() const {
    return nlohmann::json{{"points", points},       {"drawn", drawn},
                          {"fragments", fragments}, {"covered", covered},
                          {"seconds", seconds},     {"points_per_second", points_per_second()}};
}

RenderedImage render_splats(const PointCloud& cloud, const LocalGeometry* geometry,
                            const Camera& camera, const SplatSettings& settings, Progress* progress,
                            SplatStats* stats) {
    const std::size_t count = cloud.size();
    if (count >= std::numeric_limits<std::uint32_t>::max()) {
        throw InputError("splat render: at most 2^32 - 1 points, got " + std::to_string(count));
    }
    const bool use_spacing =
        settings.fixed_radius <= 0.0 && geometry != nullptr && geometry->spacing.size() == count;
    if (geometry != nullptr && !geometry->spacing.empty() && geometry->spacing.size() != count) {
        throw InputError("splat render: the local geometry is for another cloud (" +
                         std::to_string(geometry->spacing.size()) + " points, cloud has " +
                         std::to_string(count) + ")");
    }
    const auto start = std::chrono::steady_clock::now();
    const int w = camera.width;
    const int h = camera.height;
    const std::size_t pixels = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
    // Zero-initialised by value; set to "empty" below.
    const auto zbuffer = std::make_unique<std::atomic<std::uint64_t>[]>(pixels);
    const auto coverage = std::make_unique<std::atomic<std::uint32_t>[]>(pixels);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pixels, 1 << 16),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i < r.end(); ++i) {
                              zbuffer[i].store(kEmptyPixel, std::memory_order_relaxed);
                              coverage[i].store(0, std::memory_order_relaxed);
                          }
                      });
    if (progress != nullptr) {
        progress->begin_stage("splatting", count);
    }
    const glm::dmat3 to_camera = camera.world_to_camera_rotation();
    // The camera in the cloud's frame, in double: points stay small numbers.
    const glm::dvec3 eye = camera.position() - cloud.world_offset;
    const double max_radius = static_cast<double>(settings.max_radius_pixels);
    std::atomic<std::uint64_t> drawn{0};
    std::atomic<std::uint64_t> fragments{0};
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, count, 4096),
        [&](const tbb::blocked_range<std::size_t>& r) {
            if (progress != nullptr) {
                progress->throw_if_cancelled();
            }
            std::uint64_t local_drawn = 0;
            std::uint64_t local_fragments = 0;
            for (std::size_t i = r.begin(); i < r.end(); ++i) {
                const glm::dvec3 p = to_camera * (glm::dvec3(cloud.positions[i]) - eye);
                glm::dvec2 xy;
                double distance = 0.0;
                if (!camera.project_camera_space(p, xy, distance)) {
                    continue;
                }
                double radius_world = settings.fixed_radius;
                if (use_spacing) {
                    radius_world =
                        settings.radius_scale * static_cast<double>(geometry->spacing[i]);
                }
                const glm::dvec2 scale = camera.pixels_per_unit_at(p);
                const double rx = std::min(radius_world * scale.x, max_radius);
                const double ry = std::min(radius_world * scale.y, max_radius);
                const int x0 = std::max(static_cast<int>(std::floor(xy.x - rx)), 0);
                const int x1 = std::min(static_cast<int>(std::floor(xy.x + rx)), w - 1);
                const int y0 = std::max(static_cast<int>(std::floor(xy.y - ry)), 0);
                const int y1 = std::min(static_cast<int>(std::floor(xy.y + ry)), h - 1);
                if (x0 > x1 || y0 > y1) {
                    continue;
                }
                ++local_drawn;
                const std::uint64_t key =
                    depth_key(static_cast<float>(distance), static_cast<std::uint32_t>(i));
                for (int y = y0; y <= y1; ++y) {
                    for (int x = x0; x <= x1; ++x) {
                        const std::size_t pixel =
                            static_cast<std::size_t>(y) * static_cast<std::size_t>(w) +
                            static_cast<std::size_t>(x);
                        atomic_min(zbuffer[pixel], key);
                        coverage[pixel].fetch_add(1, std::memory_order_relaxed);
                        ++local_fragments;
                    }
                }
            }
            drawn.fetch_add(local_drawn, std::memory_order_relaxed);
            fragments.fetch_add(local_fragments, std::memory_order_relaxed);
            if (progress != nullptr) {
                progress->advance(r.size());
            }
        });

    RenderedImage image(w, h);
    const bool file_normals = cloud.has_normals();
    const bool geometry_normals = geometry != nullptr && geometry->normals.size() == count;
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, pixels, 1 << 14),
        [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) {
                const std::uint64_t key = zbuffer[i].load(std::memory_order_relaxed);
                image.steps[i] = coverage[i].load(std::memory_order_relaxed);
                if (key == kEmptyPixel) {
                    continue;
                }
                const std::size_t point = static_cast<std::size_t>(key & 0xffffffffu);
                const glm::vec3 rgb = cloud.has_colors() ? cloud.colors[point] : glm::vec3(1.0f);
                glm::vec3 n(0.0f);
                if (file_normals) {
                    n = cloud.normals[point];
                } else if (geometry_normals) {
                    n = geometry->normals[point];
                    // A normal of unknown sign faces the camera that sees it.
                    const bool oriented =
                        geometry->oriented.size() == count && geometry->oriented[point] != 0;
                    const glm::dvec3 view = glm::dvec3(cloud.positions[point]) - eye;
                    if (!oriented && glm::dot(glm::dvec3(n), view) > 0.0) {
                        n = -n;
                    }
                }
                image.rgba[4 * i] = rgb.x;
                image.rgba[4 * i + 1] = rgb.y;
                image.rgba[4 * i + 2] = rgb.z;
                image.rgba[4 * i + 3] = 1.0f;
                image.depth[i] = std::bit_cast<float>(static_cast<std::uint32_t>(key >> 32));
                image.normal[3 * i] = n.x;
                image.normal[3 * i + 1] = n.y;
                image.normal[3 * i + 2] = n.z;
                image.status[i] = static_cast<std::uint8_t>(TraceStatus::Hit);
            }
        });
    if (stats != nullptr) {
        stats->points = count;
        stats->drawn = drawn.load();
        stats->fragments = fragments.load();
        stats->covered = 0;
        for (const std::uint8_t s : image.status) {
            stats->covered += s == static_cast<std::uint8_t>(TraceStatus::Hit) ? 1 : 0;
        }
        stats->seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    return image;
}

nlohmann::json splat_settings_json(const SplatSettings& settings) {
    return nlohmann::json{{"radius_scale", settings.radius_scale},
                          {"fixed_radius", settings.fixed_radius},
                          {"max_radius_pixels", settings.max_radius_pixels}};
}

SplatStats splat_cloud_to_exr(const PointCloud& cloud, const Camera& camera,
                              const SplatSettings& settings, const std::string& output_path,
                              Progress* progress, double* geometry_seconds,
                              const std::string& cache_dir) {
    std::optional<LocalGeometry> geometry;
    if (settings.fixed_radius <= 0.0) {
        const auto start = std::chrono::steady_clock::now();
        geometry = cached_local_geometry(cloud, cache_dir, progress);
        if (geometry_seconds != nullptr) {
            *geometry_seconds =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        }
    } else if (geometry_seconds != nullptr) {
        *geometry_seconds = 0.0;
    }
    SplatStats stats;
    const RenderedImage image =
        render_splats(cloud, geometry ? &*geometry : nullptr, camera, settings, progress, &stats);
    ImageMetadata metadata;
    metadata.renderer = "lfprobe point splats";
    metadata.camera = camera.to_json();
    metadata.settings = splat_settings_json(settings);
    metadata.stats = stats.to_json();
    write_rendered_exr(output_path, image, metadata);
    return stats;
}

} // namespace lfprobe
