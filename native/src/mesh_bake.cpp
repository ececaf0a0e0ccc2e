#include "lfprobe/mesh_bake.hpp"

#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lfprobe/error.hpp"
#include "lfprobe/octahedral.hpp"
#include "lfprobe/probe_exr.hpp"
#include "lfprobe/probe_set.hpp"

namespace lfprobe {

namespace {

void check_settings(const MeshBakeSettings& s) {
    if (s.resolution < 1 || s.resolution > 16384) {
        throw InputError("mesh bake: resolution must be in [1, 16384], got " +
                         std::to_string(s.resolution));
    }
    if (s.supersample < 1 || s.supersample > 16) {
        throw InputError("mesh bake: supersample must be in [1, 16], got " +
                         std::to_string(s.supersample));
    }
}

} // namespace

ProbeMap bake_probe_from_mesh(const EmbreeScene& scene, const glm::dvec3& position,
                              const MeshBakeSettings& settings, Progress* progress) {
    check_settings(settings);
    const int n = settings.resolution;
    const int ss = settings.supersample;
    ProbeMap map(n, position);
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
                const MeshHit centre = scene.intersect(ray);
                if (!centre.hit) {
                    map.set_empty(i);
                    continue;
                }
                glm::vec3 colour = centre.base_color;
                if (ss > 1) {
                    glm::vec3 sum{0.0f};
                    int hits = 0;
                    for (int sy = 0; sy < ss; ++sy) {
                        for (int sx = 0; sx < ss; ++sx) {
                            const glm::vec2 uv{
                                (static_cast<float>(x) +
                                 (static_cast<float>(sx) + 0.5f) / static_cast<float>(ss)) /
                                    static_cast<float>(n),
                                (static_cast<float>(y) +
                                 (static_cast<float>(sy) + 0.5f) / static_cast<float>(ss)) /
                                    static_cast<float>(n)};
                            Ray sub = ray;
                            sub.direction = glm::dvec3(oct::decode(uv));
                            const MeshHit h = scene.intersect(sub);
                            if (h.hit) {
                                sum += h.base_color;
                                ++hits;
                            }
                        }
                    }
                    // The centre ray hit, so at least one sample did (odd ss) or nearly so;
                    // keep the centre colour when every sample slipped past an edge.
                    if (hits > 0) {
                        colour = sum / static_cast<float>(hits);
                    }
                }
                const glm::vec3 normal = EmbreeScene::facing(centre.shading_normal, ray.direction);
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
    manifest.bake = nlohmann::json{{"source", "mesh"},
                                   {"mesh", scene.mesh().path},
                                   {"triangles", scene.mesh().triangle_count()},
                                   {"resolution", settings.resolution},
                                   {"supersample", settings.supersample},
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
