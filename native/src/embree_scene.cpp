#include "lfprobe/embree_scene.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <embree3/rtcore.h>
#include <glm/geometric.hpp>

#include "lfprobe/error.hpp"

namespace lfprobe {

namespace {

// Errors reported by Embree's callback are turned into exceptions after the failing call.
void error_callback(void* user, RTCError code, const char* message) {
    auto* last = static_cast<std::string*>(user);
    *last = "Embree error " + std::to_string(static_cast<int>(code)) + ": " +
            (message != nullptr ? message : "");
}

} // namespace

struct EmbreeScene::Impl {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    std::string last_error;
    std::vector<std::vector<std::uint32_t>> triangle_of; // per geometry: primID → triangle
    // Per triangle, what every hit on it computed again: its unit plane normal (double, from
    // the float vertices) and its texture's texels per metre (Mesh::texture_density). The
    // square roots and divisions were a fifth of a mesh bake.
    std::vector<glm::dvec3> unit_normal;
    std::vector<double> texture_density;

    void check(const char* what) {
        const RTCError e = rtcGetDeviceError(device);
        if (e != RTC_ERROR_NONE) {
            throw std::runtime_error(
                std::string(what) + ": " +
                (last_error.empty() ? "Embree device error " + std::to_string(static_cast<int>(e))
                                    : last_error));
        }
    }
    ~Impl() {
        if (scene != nullptr) {
            rtcReleaseScene(scene);
        }
        if (device != nullptr) {
            rtcReleaseDevice(device);
        }
    }
};

EmbreeScene::EmbreeScene(const Mesh& mesh) : mesh_(&mesh), impl_(std::make_unique<Impl>()) {
    impl_->device = rtcNewDevice(nullptr);
    if (impl_->device == nullptr) {
        throw std::runtime_error("Embree: cannot create a device (error " +
                                 std::to_string(static_cast<int>(rtcGetDeviceError(nullptr))) +
                                 ")");
    }
    rtcSetDeviceErrorFunction(impl_->device, error_callback, &impl_->last_error);
    impl_->scene = rtcNewScene(impl_->device);
    rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);
    impl_->check("Embree scene");

    impl_->unit_normal.resize(mesh.triangles.size());
    impl_->texture_density.resize(mesh.triangles.size());
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
        const glm::dvec3 p0(mesh.vertices[mesh.triangles[i][0]]);
        const glm::dvec3 p1(mesh.vertices[mesh.triangles[i][1]]);
        const glm::dvec3 p2(mesh.vertices[mesh.triangles[i][2]]);
        const glm::dvec3 n = glm::cross(p1 - p0, p2 - p0);
        const double len = glm::length(n);
        impl_->unit_normal[i] = len > 0.0 ? n / len : glm::dvec3(0.0, 0.0, 1.0);
        impl_->texture_density[i] = mesh.texture_density(i);
    }
    std::vector<std::vector<std::uint32_t>> by_object(
        std::max<std::size_t>(1, mesh.object_names.size()));
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
        by_object[mesh.object[i]].push_back(static_cast<std::uint32_t>(i));
    }
    for (const auto& tris : by_object) {
        if (tris.empty()) {
            continue;
        }
        RTCGeometry geom = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
        // Three unshared vertices per triangle: the object's triangles are a subset of the
        // mesh, and copying them keeps Embree's barycentrics in the mesh's corner order.
        auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0,
                                                               RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                               3 * tris.size()));
        auto* ib = static_cast<std::uint32_t*>(
            rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                    3 * sizeof(std::uint32_t), tris.size()));
        impl_->check("Embree geometry buffers");
        for (std::size_t j = 0; j < tris.size(); ++j) {
            for (std::size_t k = 0; k < 3; ++k) {
                const glm::vec3& p = mesh.vertices[mesh.triangles[tris[j]][k]];
                vb[9 * j + 3 * k] = p.x;
                vb[9 * j + 3 * k + 1] = p.y;
                vb[9 * j + 3 * k + 2] = p.z;
                ib[3 * j + k] = static_cast<std::uint32_t>(3 * j + k);
            }
        }
        rtcCommitGeometry(geom);
        const unsigned id = rtcAttachGeometry(impl_->scene, geom);
        rtcReleaseGeometry(geom);
        impl_->check("Embree geometry");
        if (id >= impl_->triangle_of.size()) {
            impl_->triangle_of.resize(id + 1);
        }
        impl_->triangle_of[id] = tris;
    }
    rtcCommitScene(impl_->scene);
    impl_->check("Embree scene build");
}

EmbreeScene::~EmbreeScene() = default;

namespace {

RTCRayHit make_ray(const Ray& ray) {
    RTCRayHit rh{};
    rh.ray.org_x = static_cast<float>(ray.origin.x);
    rh.ray.org_y = static_cast<float>(ray.origin.y);
    rh.ray.org_z = static_cast<float>(ray.origin.z);
    rh.ray.dir_x = static_cast<float>(ray.direction.x);
    rh.ray.dir_y = static_cast<float>(ray.direction.y);
    rh.ray.dir_z = static_cast<float>(ray.direction.z);
    rh.ray.tnear = static_cast<float>(ray.t_min);
    rh.ray.tfar = std::isfinite(ray.t_max) ? static_cast<float>(ray.t_max)
                                           : std::numeric_limits<float>::infinity();
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.time = 0.0f;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    return rh;
}

// Traces `ray` into `rh`; whether it met a triangle.
bool cast(RTCScene scene, const Ray& ray, RTCRayHit& rh) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    rh = make_ray(ray);
    rtcIntersect1(scene, &context, &rh);
    return rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
}

} // namespace

bool EmbreeScene::intersect_fast(const Ray& ray, float& t, std::uint32_t& triangle) const {
    RTCRayHit rh;
    if (!cast(impl_->scene, ray, rh)) {
        return false;
    }
    t = rh.ray.tfar;
    triangle = impl_->triangle_of[rh.hit.geomID][rh.hit.primID];
    return true;
}

namespace {

// Sets the lanes of `packet` to rays[first, first + Width) and `valid` to which of them lie
// below `count`; unused lanes repeat the first ray, masked off.
template <class Packet, std::size_t Width>
void load_packet(Packet& packet, std::array<int, Width>& valid, const Ray* rays, std::size_t first,
                 std::size_t count) {
    for (std::size_t k = 0; k < Width; ++k) {
        const std::size_t i = first + k;
        valid[k] = i < count ? -1 : 0;
        const RTCRayHit one = make_ray(rays[i < count ? i : first]);
        packet.ray.org_x[k] = one.ray.org_x;
        packet.ray.org_y[k] = one.ray.org_y;
        packet.ray.org_z[k] = one.ray.org_z;
        packet.ray.dir_x[k] = one.ray.dir_x;
        packet.ray.dir_y[k] = one.ray.dir_y;
        packet.ray.dir_z[k] = one.ray.dir_z;
        packet.ray.tnear[k] = one.ray.tnear;
        packet.ray.tfar[k] = one.ray.tfar;
        packet.ray.mask[k] = one.ray.mask;
        packet.ray.time[k] = 0.0f;
        packet.ray.flags[k] = 0;
        packet.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
        packet.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
}

// rtcIntersect4/8/16 over rays[0, count) in packets of `Packet`'s width, unused lanes of the
// last packet masked off. Flagged coherent, as a renderer flags camera rays: Embree then
// traverses each packet together (the demo's four views at 640×400 on 2 threads: 12.5-21.2 M
// rays/s unflagged, 30.7-50.9 M flagged, against 11.5-16.0 M single rays).
template <class Packet, int Width, class Intersect>
std::uint64_t count_packet_hits(RTCScene scene, const Ray* rays, std::size_t count,
                                Intersect&& intersect) {
    std::uint64_t hits = 0;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    alignas(64) Packet packet;
    alignas(64) std::array<int, Width> valid;
    for (std::size_t first = 0; first < count; first += Width) {
        load_packet(packet, valid, rays, first, count);
        intersect(valid.data(), scene, &context, &packet);
        for (int k = 0; k < Width; ++k) {
            hits += valid[static_cast<std::size_t>(k)] != 0 &&
                            packet.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID
                        ? 1
                        : 0;
        }
    }
    return hits;
}

} // namespace

void EmbreeScene::check_packet(int packet) {
    if (packet != 1 && packet != 4 && packet != 8 && packet != 16) {
        throw InputError("Embree: a packet is 1, 4, 8 or 16 rays, got " + std::to_string(packet));
    }
}

std::uint64_t EmbreeScene::count_hits(const Ray* rays, std::size_t count, int packet) const {
    check_packet(packet);
    switch (packet) {
    case 1: {
        std::uint64_t hits = 0;
        float t = 0.0f;
        std::uint32_t triangle = 0;
        for (std::size_t i = 0; i < count; ++i) {
            hits += intersect_fast(rays[i], t, triangle) ? 1 : 0;
        }
        return hits;
    }
    case 4:
        return count_packet_hits<RTCRayHit4, 4>(impl_->scene, rays, count, rtcIntersect4);
    case 8:
        return count_packet_hits<RTCRayHit8, 8>(impl_->scene, rays, count, rtcIntersect8);
    case 16:
        return count_packet_hits<RTCRayHit16, 16>(impl_->scene, rays, count, rtcIntersect16);
    default:
        break;
    }
    return 0; // unreachable: check_packet took every other width
}

glm::vec3 EmbreeScene::facing(const glm::vec3& n, const glm::dvec3& direction) {
    const double d = static_cast<double>(n.x) * direction.x +
                     static_cast<double>(n.y) * direction.y +
                     static_cast<double>(n.z) * direction.z;
    return d > 0.0 ? -n : n;
}

MeshHit EmbreeScene::intersect(const Ray& ray) const {
    return intersect(ray, 0.0);
}

MeshHit EmbreeScene::intersect(const Ray& ray, double spread) const {
    RTCRayHit rh;
    if (!cast(impl_->scene, ray, rh)) {
        return {};
    }
    MeshHit out;
    describe_hit(ray, impl_->triangle_of[rh.hit.geomID][rh.hit.primID], rh.ray.tfar, rh.hit.u,
                 rh.hit.v, spread, out);
    return out;
}

void EmbreeScene::intersect_packet(const Ray* rays, std::size_t count, double spread,
                                   MeshHit* hits) const {
    if (count > kPacket) {
        throw InputError("Embree: a packet holds at most 16 rays, got " + std::to_string(count));
    }
    if (count == 0) {
        return;
    }
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    // Coherent: Embree then traverses the packet together instead of ray by ray (a mesh
    // bake's 4×4 strata a texel: 6.0-6.5 -> 4.2-4.9 s a 2048² probe).
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    alignas(64) RTCRayHit16 packet;
    alignas(64) std::array<int, kPacket> valid{};
    load_packet(packet, valid, rays, 0, count);
    rtcIntersect16(valid.data(), impl_->scene, &context, &packet);
    // Each hit written in place: a MeshHit built on the stack and copied over stalled on its
    // partly overlapping stores (a tenth of a mesh bake).
    for (std::size_t k = 0; k < count; ++k) {
        const unsigned geometry = packet.hit.geomID[k];
        if (geometry == RTC_INVALID_GEOMETRY_ID) {
            hits[k].hit = false;
            continue;
        }
        describe_hit(rays[k], impl_->triangle_of[geometry][packet.hit.primID[k]],
                     packet.ray.tfar[k], packet.hit.u[k], packet.hit.v[k], spread, hits[k]);
    }
}

void EmbreeScene::describe_hit(const Ray& ray, std::uint32_t tri, float tfar, float u, float v,
                               double spread, MeshHit& out) const {
    const Mesh& m = *mesh_;
    out.hit = true;
    out.triangle = tri;
    out.u = u;
    out.v = v;
    out.object = static_cast<std::int32_t>(m.object[tri]);
    const glm::dvec3 p0(m.vertices[m.triangles[tri][0]]);
    const glm::dvec3& unit = impl_->unit_normal[tri];
    out.geometric_normal = glm::vec3(unit);
    // The plane intersection in double; Embree's float t stays when the ray grazes the plane.
    const double denom = glm::dot(unit, ray.direction);
    out.t = static_cast<double>(tfar);
    if (std::abs(denom) > 1e-6) {
        const double t_plane = glm::dot(unit, p0 - ray.origin) / denom;
        if (std::abs(t_plane - out.t) <= 1e-3 * std::max(1.0, out.t)) {
            out.t = t_plane;
        }
    }
    const float w = 1.0f - out.u - out.v;
    out.shading_normal = out.geometric_normal;
    if (m.has_normals()) {
        const glm::vec3 s = w * m.corner_normals[3 * tri] + out.u * m.corner_normals[3 * tri + 1] +
                            out.v * m.corner_normals[3 * tri + 2];
        const float sl = glm::length(s);
        if (sl > 0.0f && std::isfinite(sl)) {
            out.shading_normal = s / sl;
        }
    }
    out.uv = m.has_uvs() ? w * m.corner_uvs[3 * tri] + out.u * m.corner_uvs[3 * tri + 1] +
                               out.v * m.corner_uvs[3 * tri + 2]
                         : glm::vec2(0.0f);
    double footprint = 0.0;
    if (spread > 0.0) {
        constexpr double kMinCos = 1.0 / 16.0;
        const double cos_incidence = std::max(std::abs(denom), kMinCos);
        footprint = out.t * spread / std::sqrt(cos_incidence);
    }
    out.base_color = m.base_color_over_texels(
        tri, out.u, out.v, footprint > 0.0 ? footprint * impl_->texture_density[tri] : 0.0);
}

} // namespace lfprobe
