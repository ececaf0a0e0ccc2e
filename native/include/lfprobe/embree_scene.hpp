// A Mesh in Embree 3 for closest-hit queries: the reference geometry of ground truth renders,
// mesh bakes and simulated scans (docs/DESIGN.md §4). One triangle geometry per mesh object, built
// with RTC_SCENE_FLAG_ROBUST so that rays along shared edges do not slip through.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "lfprobe/mesh.hpp"
#include "lfprobe/ray.hpp"

namespace lfprobe {

struct MeshHit {
    bool hit = false;
    // Distance along the (unit) ray direction: Embree finds the triangle, then t is recomputed
    // in double against the triangle's plane, so that depths are exact to double rounding
    // rather than to Embree's float ray.
    double t = 0.0;
    glm::vec3 geometric_normal{0.0f}; // unit, right-handed winding (v1-v0)×(v2-v0), not flipped
    glm::vec3 shading_normal{0.0f};   // unit, interpolated vn when the mesh has them, else
                                      // the geometric normal
    std::uint32_t triangle = 0;
    float u = 0.0f; // barycentrics: p = (1-u-v)·v0 + u·v1 + v·v2
    float v = 0.0f;
    glm::vec2 uv{0.0f};
    glm::vec3 base_color{0.0f}; // linear: texture × material × vertex colour
    std::int32_t object = -1;
};

class EmbreeScene {
public:
    // Builds the scene (the mesh is copied into Embree's buffers; `mesh` must outlive the
    // scene for colours and normals). Throws std::runtime_error on an Embree device error.
    explicit EmbreeScene(const Mesh& mesh);
    ~EmbreeScene();
    EmbreeScene(const EmbreeScene&) = delete;
    EmbreeScene& operator=(const EmbreeScene&) = delete;

    [[nodiscard]] const Mesh& mesh() const { return *mesh_; }

    // The closest hit in [ray.t_min, ray.t_max] of a ray in the mesh's local frame, with all
    // the attributes filled. Thread-safe.
    [[nodiscard]] MeshHit intersect(const Ray& ray) const;
    // The same, its base colour's texture filtered over the ray's footprint (texture LOD):
    // `spread` is the footprint's width per metre along the ray (the angle between a sample's
    // ray and its neighbour's), widened on a slanted surface by 1/sqrt(cos) (the footprint's
    // area, its stretch capped at 16 as anisotropic filtering caps it). 0: intersect(ray).
    [[nodiscard]] MeshHit intersect(const Ray& ray, double spread) const;
    // intersect(rays[k], spread) for k in [0, count), count at most kPacket, traced together
    // in one of Embree's 16-ray packets (rtcIntersect16), flagged coherent (for rays that are:
    // intersect_coherent). A ray through a triangle's edge may take the other triangle than
    // intersect takes, or miss where intersect hits. Every hit's attributes are computed as
    // intersect computes them from Embree's answer; a miss sets only `hit` (false), the other
    // fields keep what they held. Thread-safe.
    static constexpr std::size_t kPacket = 16;
    void intersect_packet(const Ray* rays, std::size_t count, double spread, MeshHit* hits) const;
    // The same for rays that lie close together (a texel's or a pixel's strata), count at most
    // kPacket: in a packet from kCoherentPacketFrom rays, else one by one, whichever is faster
    // (a packet costs about what 5-6 single rays do, however few of its rays are live; a
    // 2048² mesh bake of the lab room on 2 threads, packets against single rays: 2×2 strata a
    // texel 2.7-2.9 s against 2.5 s, 3×3 3.5 against 4.6 s, 4×4 4.2-4.9 against 7.7 s).
    // A packet's miss is traced again as a single ray: the packet's traversal leaves cracks
    // along shared edges that a single ray's does not (15 of a 0.1° station's 5.4 M rays
    // escaped the closed lab room through them), and a miss is rare where it matters.
    static constexpr std::size_t kCoherentPacketFrom = 6;
    void intersect_coherent(const Ray* rays, std::size_t count, double spread,
                            MeshHit* hits) const {
        if (count >= kCoherentPacketFrom) {
            intersect_packet(rays, count, spread, hits);
            for (std::size_t k = 0; k < count; ++k) {
                if (!hits[k].hit) {
                    hits[k] = intersect(rays[k], spread);
                }
            }
            return;
        }
        for (std::size_t k = 0; k < count; ++k) {
            hits[k] = intersect(rays[k], spread);
        }
    }
    // Only whether and where: t (Embree's float) and the triangle; for throughput figures.
    [[nodiscard]] bool intersect_fast(const Ray& ray, float& t, std::uint32_t& triangle) const;

    // How many of rays[0, count) hit, traced in Embree's ray packets of `packet` rays (4, 8 or
    // 16: rtcIntersect4/8/16, the API for coherent rays such as a camera's) or one at a time
    // (1: rtcIntersect1). InputError for another packet size.
    [[nodiscard]] std::uint64_t count_hits(const Ray* rays, std::size_t count, int packet) const;
    // InputError unless `packet` is one of the widths count_hits takes.
    static void check_packet(int packet);

    // Normal `n` turned to face a viewer looking along `direction`.
    [[nodiscard]] static glm::vec3 facing(const glm::vec3& n, const glm::dvec3& direction);

private:
    // `out` filled with a hit's attributes from Embree's answer for `ray`: triangle `tri`,
    // distance `tfar`, barycentrics (u, v).
    void describe_hit(const Ray& ray, std::uint32_t tri, float tfar, float u, float v,
                      double spread, MeshHit& out) const;
    struct Impl;
    const Mesh* mesh_;
    std::unique_ptr<Impl> impl_;
};

} // namespace lfprobe
