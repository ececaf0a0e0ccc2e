#include "lfprobe/mesh_bake.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

#include <nlohmann/json.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lfprobe/error.hpp"
#include "lfprobe/octahedral.hpp"
#include "lfprobe/probe_exr.hpp"
#include "lfprobe/probe_set.hpp"

namespace lfprobe {

namespace {

void check_settings(const MeshBakeSettings& s) {
    if (s.resolution < 1 || s.resolution > kMaxProbeResolution) {
        throw InputError("mesh bake: resolution must be in [1, " +
                         std::to_string(kMaxProbeResolution) + "], got " +
                         std::to_string(s.resolution));
    }
    if (s.supersample < 1 || s.supersample > 16) {
        throw InputError("mesh bake: supersample must be in [1, 16], got " +
                         std::to_string(s.supersample));
    }
}

// A texel's colour as the mean over an ss×ss stratified grid of rays across it, counting only
// the rays that meet the centre ray's surface (within kSameSurface of its plane, facing the
// same side): the texel's distance and normal are the centre's, so its colour must be that
// surface's, never a mix with what lies behind a silhouette. Summed as differences from the
// centre's colour, so that a surface of one colour stays exactly that colour.
// The ray through the centre of stratum (sx, sy) of an ss×ss grid across texel `texel`.
Ray stratum_ray(const glm::dvec3& position, oct::Texel texel, int n, int ss, int sx, int sy) {
    const glm::vec2 uv{
        (static_cast<float>(texel.x) + (static_cast<float>(sx) + 0.5f) / static_cast<float>(ss)) /
            static_cast<float>(n),
        (static_cast<float>(texel.y) + (static_cast<float>(sy) + 0.5f) / static_cast<float>(ss)) /
            static_cast<float>(n)};
    Ray sub;
    sub.origin = position;
    sub.direction = glm::dvec3(oct::decode(uv));
    return sub;
}

// The share of an empty texel's ss×ss rays that meet nothing either: its coverage.
float empty_coverage(const EmbreeScene& scene, const glm::dvec3& position, oct::Texel texel, int n,
                     int ss) {
    int empty = 0;
    for (int sy = 0; sy < ss; ++sy) {
        for (int sx = 0; sx < ss; ++sx) {
            float t = 0.0f;
            std::uint32_t triangle = 0;
            empty += scene.intersect_fast(stratum_ray(position, texel, n, ss, sx, sy), t, triangle)
                         ? 0
                         : 1;
        }
    }
    return static_cast<float>(empty) / static_cast<float>(ss * ss);
}

struct TexelFootprint {
    glm::vec3 colour;
    float coverage; // the share of the ss×ss rays that met the centre ray's surface
};

TexelFootprint texel_footprint(const EmbreeScene& scene, const glm::dvec3& position,
                               oct::Texel texel, int n, int ss, const MeshHit& centre,
                               const glm::dvec3& normal, double spread) {
    const double distance_scale = centre.t * oct::kTexelAngleTimesN / n; // the texel's footprint
    const double same_surface = 1e-4 + 2.0 * distance_scale;
    const glm::dvec3 centre_point =
        position + centre.t * glm::dvec3(oct::texel_direction(texel, n));
    glm::vec3 sum{0.0f};
    int counted = 0;
    // The strata in rows, traced together (EmbreeScene::intersect_coherent): they leave one
    // point a texel wide.
    constexpr std::size_t kPacket = EmbreeScene::kPacket;
    std::array<Ray, kPacket> rays;
    std::array<MeshHit, kPacket> hits;
    const int strata = ss * ss;
    for (int first = 0; first < strata; first += static_cast<int>(kPacket)) {
        const auto count =
            static_cast<std::size_t>(std::min(strata - first, static_cast<int>(kPacket)));
        for (std::size_t k = 0; k < count; ++k) {
            const int s = first + static_cast<int>(k);
            rays[k] = stratum_ray(position, texel, n, ss, s % ss, s / ss);
        }
        scene.intersect_coherent(rays.data(), count, spread, hits.data());
        for (std::size_t k = 0; k < count; ++k) {
            const MeshHit& h = hits[k];
            if (!h.hit) {
                continue;
            }
            const glm::dvec3 point = position + h.t * rays[k].direction;
            const glm::dvec3 sub_normal(EmbreeScene::facing(h.shading_normal, rays[k].direction));
            if (std::abs(glm::dot(normal, point - centre_point)) > same_surface ||
                glm::dot(sub_normal, normal) <= 0.0) {
                continue;
            }
            sum += h.base_color - centre.base_color;
            ++counted;
        }
    }
    const glm::vec3 colour =
        counted > 0 ? centre.base_color + sum / static_cast<float>(counted) : centre.base_color;
    return {colour, static_cast<float>(counted) / static_cast<float>(ss * ss)};
}

} // namespace

ProbeMap bake_probe_from_mesh(const EmbreeScene& scene, const glm::dvec3& position,
                              const MeshBakeSettings& settings, Progress* progress) {
    check_settings(settings);
    const int n = settings.resolution;
    const int ss = settings.supersample;
    // A ray's footprint: the texel's width over the rays per side (each ray stands for one
    // stratum of its texel).
    const double spread = settings.filter_textures ? oct::kTexelAngleTimesN / n / ss : 0.0;
    ProbeMap map(n, position);
    if (ss > 1) {
        map.coverage.assign(map.texel_count(), Imath::half(1.0f));
    }
    if (progress != nullptr) {
        progress->begin_stage("baking probe from mesh", static_cast<std::uint64_t>(n));
    }
    tbb::parallel_for(tbb::blocked_range<int>(0, n), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y < rows.end(); ++y) {
            if (progress != nullptr) {
                progress->throw_if_cancelled();
            }
            for (int x = 0; x < n; ++x) {
                const oct::Texel texel{x, y};
                const std::size_t i = oct::texel_index(texel, n);
                Ray ray;
                ray.origin = position;
                ray.direction = glm::dvec3(oct::texel_direction(texel, n));
                const MeshHit centre = scene.intersect(ray, spread);
                if (!centre.hit) {
                    map.set_empty(i);
                    if (ss > 1) {
                        map.coverage[i] =
                            Imath::half(empty_coverage(scene, position, texel, n, ss));
                    }
                    continue;
                }
                const glm::vec3 normal = EmbreeScene::facing(centre.shading_normal, ray.direction);
                glm::vec3 colour = centre.base_color;
                if (ss > 1) {
                    const TexelFootprint footprint = texel_footprint(
                        scene, position, texel, n, ss, centre, glm::dvec3(normal), spread);
                    colour = footprint.colour;
                    map.coverage[i] = Imath::half(footprint.coverage);
                }
                map.set_surface(i, static_cast<float>(centre.t), colour, normal, 1.0f);
            }
            if (progress != nullptr) {
                progress->advance(1);
            }
        }
    });
    return map;
}

BakeSummary bake_probe_set_from_mesh(const EmbreeScene& scene, const ProbePlacement& placement,
                                     const MeshBakeSettings& settings, const std::string& folder,
                                     const nlohmann::json& sources, Progress* progress) {
    check_settings(settings);
    if (placement.positions.empty()) {
        throw InputError("mesh bake: no probe positions given");
    }
    if (scene.mesh().triangle_count() == 0) {
        throw InputError("mesh bake: the mesh has no triangles");
    }
    ProbeSetManifest manifest;
    manifest.world_offset = scene.mesh().world_offset;
    manifest.placement = placement;
    manifest.bake =
        nlohmann::json{{"source", "mesh"},
                       {"mesh", scene.mesh().path},
                       {"triangles", scene.mesh().triangle_count()},
                       {"resolution", settings.resolution},
                       {"supersample", settings.supersample},
                       {"texture_filter", settings.filter_textures ? "footprint" : "point"},
                       {"normals", "shading normal if present, else geometric; "
                                   "turned to face the probe"}};
    manifest.sources = sources;
    return write_probe_set(
        folder, std::move(manifest),
        [&](std::size_t i) {
            return bake_probe_from_mesh(scene, placement.positions[i], settings, progress);
        },
        progress);
}

} // namespace lfprobe
