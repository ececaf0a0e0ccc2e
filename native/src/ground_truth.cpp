#include "lfprobe/ground_truth.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lfprobe/error.hpp"
#include "lfprobe/image_exr.hpp"
#include "lfprobe/image_metadata.hpp"
#include "lfprobe/image_tiles.hpp"
#include "lfprobe/probe_trace.hpp"

namespace lfprobe {

nlohmann::json GroundTruthStats::to_json() const {
    return nlohmann::json{{"rays", rays},
                          {"hits", hits},
                          {"pixels", pixels},
                          {"seconds", seconds},
                          {"rays_per_second", rays_per_second()}};
}

namespace {

// The width per metre along the ray of one of a pixel's n×n samples: the angle between the
// pixel's centre ray and the rays a stratum to the side and a stratum down (their geometric
// mean), which holds for panoramas as for pinhole cameras.
double sample_spread(const CameraRays& rays, int x, int y, int n) {
    const double step = 1.0 / n;
    const glm::dvec3 centre = rays.local_pixel_ray(x, y, glm::dvec3(0.0)).direction;
    const glm::dvec3 across =
        rays.local_pixel_ray(x, y, glm::dvec3(0.0), 0.5 + step, 0.5).direction;
    const glm::dvec3 down = rays.local_pixel_ray(x, y, glm::dvec3(0.0), 0.5, 0.5 + step).direction;
    const double a = glm::length(across - centre);
    const double b = glm::length(down - centre);
    const double spread = std::sqrt(a * b);
    return std::isfinite(spread) ? spread : 0.0;
}

} // namespace

RenderedImage render_ground_truth(const EmbreeScene& scene, const Camera& camera,
                                  const GroundTruthSettings& settings, Progress* progress,
                                  GroundTruthStats* stats) {
    if (settings.tile_size < 1) {
        throw InputError("ground truth: tile_size must be at least 1");
    }
    const int n = samples_per_axis(settings.samples_per_pixel, "ground truth");
    RenderedImage image(camera.width, camera.height);
    image.object.assign(image.pixel_count(), -1);
    if (progress != nullptr) {
        progress->begin_stage("ground truth", image.pixel_count());
    }
    const glm::dvec3 offset = scene.mesh().world_offset;
    const float inv_samples = 1.0f / static_cast<float>(n * n);
    std::atomic<std::uint64_t> rays{0};
    const CameraRays camera_rays(camera);
    camera_rays.require_finite_rays();
    const double seconds = for_each_image_tile(
        camera.width, camera.height, settings.tile_size, progress, [&](const ImageTile& r) {
            std::uint64_t tile_rays = 0;
            constexpr int kPacket = static_cast<int>(EmbreeScene::kPacket);
            std::array<Ray, EmbreeScene::kPacket> strata_rays;
            std::array<MeshHit, EmbreeScene::kPacket> strata_hits;
            for (int y = r.rows().begin(); y < r.rows().end(); ++y) {
                for (int x = r.cols().begin(); x < r.cols().end(); ++x) {
                    const std::size_t i = image.index(x, y);
                    const Ray centre_ray = camera_rays.local_pixel_ray(x, y, offset);
                    const double spread =
                        settings.filter_textures ? sample_spread(camera_rays, x, y, n) : 0.0;
                    const MeshHit centre = scene.intersect(centre_ray, n == 1 ? spread : 0.0);
                    ++tile_rays;
                    glm::vec3 colour{0.0f};
                    float coverage = 0.0f;
                    if (n == 1) {
                        if (centre.hit) {
                            colour = centre.base_color;
                            coverage = 1.0f;
                        }
                    } else {
                        // Summed in a fixed order: the same floats for any thread count.
                        // The strata row by row, up to a packet at a time: they lie within
                        // the pixel (EmbreeScene::intersect_coherent).
                        const int strata = n * n;
                        for (int first = 0; first < strata; first += kPacket) {
                            const int count = std::min(kPacket, strata - first);
                            for (int k = 0; k < count; ++k) {
                                const int s = first + k;
                                strata_rays[static_cast<std::size_t>(k)] =
                                    camera_rays.local_pixel_ray(x, y, offset,
                                                                stratum_centre(s % n, n),
                                                                stratum_centre(s / n, n));
                            }
                            scene.intersect_coherent(strata_rays.data(),
                                                     static_cast<std::size_t>(count), spread,
                                                     strata_hits.data());
                            tile_rays += static_cast<std::uint64_t>(count);
                            for (int k = 0; k < count; ++k) {
                                const MeshHit& h = strata_hits[static_cast<std::size_t>(k)];
                                if (h.hit) {
                                    colour += h.base_color;
                                    coverage += 1.0f;
                                }
                            }
                        }
                        colour *= inv_samples;
                        coverage *= inv_samples;
                    }
                    image.rgba[4 * i] = colour.x;
                    image.rgba[4 * i + 1] = colour.y;
                    image.rgba[4 * i + 2] = colour.z;
                    image.rgba[4 * i + 3] = coverage;
                    if (centre.hit) {
                        const glm::vec3 nrm =
                            EmbreeScene::facing(centre.shading_normal, centre_ray.direction);
                        image.depth[i] = static_cast<float>(centre.t);
                        image.normal[3 * i] = nrm.x;
                        image.normal[3 * i + 1] = nrm.y;
                        image.normal[3 * i + 2] = nrm.z;
                        image.status[i] = static_cast<std::uint8_t>(TraceStatus::Hit);
                        image.object[i] = centre.object;
                    }
                }
            }
            rays.fetch_add(tile_rays, std::memory_order_relaxed);
        });
    if (stats != nullptr) {
        *stats = GroundTruthStats{};
        stats->rays = rays.load();
        stats->pixels = image.pixel_count();
        stats->seconds = seconds;
        for (const std::uint8_t s : image.status) {
            stats->hits += s == static_cast<std::uint8_t>(TraceStatus::Hit) ? 1 : 0;
        }
    }
    return image;
}

ThroughputResult embree_throughput(const EmbreeScene& scene, const Camera& camera, int repeats,
                                   int packet) {
    EmbreeScene::check_packet(packet); // before the rays are made and the clock runs
    return measure_batch_throughput(
        camera, scene.mesh().world_offset, repeats, "embree",
        [&](const Ray* rays, std::size_t count) { return scene.count_hits(rays, count, packet); });
}

GroundTruthStats ground_truth_to_exr(const EmbreeScene& scene, const std::string& mesh_path,
                                     const Camera& camera, const GroundTruthSettings& settings,
                                     const std::string& output_path, Progress* progress) {
    GroundTruthStats stats;
    const RenderedImage image = render_ground_truth(scene, camera, settings, progress, &stats);
    ImageMetadata metadata;
    metadata.renderer = "embree ground truth";
    // "samples_per_pixel" at the top level too, where the first images recorded it.
    metadata.source = nlohmann::json{{"ground_truth", mesh_path},
                                     {"samples_per_pixel", settings.samples_per_pixel}};
    metadata.camera = camera.to_json();
    metadata.settings =
        nlohmann::json{{"samples_per_pixel", settings.samples_per_pixel},
                       {"tile_size", settings.tile_size},
                       {"texture_filter", settings.filter_textures ? "footprint" : "point"}};
    metadata.stats = stats.to_json();
    write_rendered_exr(output_path, image, metadata);
    return stats;
}

} // namespace lfprobe
