#include "lfprobe/mesh.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "lfprobe/error.hpp"
#include "lfprobe/world_offset.hpp"

namespace lfprobe {

namespace {

// How many of the texture's texels a metre of triangle `tri` spans: the square root of its
// texel area over its surface area (an isotropic measure, as one mip level is).
double texels_per_metre(const Mesh& mesh, std::size_t tri, const Texture& texture) {
    const glm::dvec3 p0(mesh.vertices[mesh.triangles[tri][0]]);
    const glm::dvec3 p1(mesh.vertices[mesh.triangles[tri][1]]);
    const glm::dvec3 p2(mesh.vertices[mesh.triangles[tri][2]]);
    const double area = glm::length(glm::cross(p1 - p0, p2 - p0));
    const glm::dvec2 t0(mesh.corner_uvs[3 * tri]);
    const glm::dvec2 t1(mesh.corner_uvs[3 * tri + 1]);
    const glm::dvec2 t2(mesh.corner_uvs[3 * tri + 2]);
    const glm::dvec2 a = t1 - t0;
    const glm::dvec2 b = t2 - t0;
    const double uv_area = std::abs(a.x * b.y - a.y * b.x) * texture.width * texture.height;
    if (!(area > 0.0) || !(uv_area > 0.0) || !std::isfinite(uv_area / area)) {
        return 0.0;
    }
    return std::sqrt(uv_area / area);
}

} // namespace

MeshBounds Mesh::bounds() const {
    if (triangles.empty()) {
        return {};
    }
    MeshBounds b{glm::vec3(std::numeric_limits<float>::max()),
                 glm::vec3(std::numeric_limits<float>::lowest())};
    for (const auto& t : triangles) {
        for (const std::uint32_t i : t) {
            b.min = glm::min(b.min, vertices[i]);
            b.max = glm::max(b.max, vertices[i]);
        }
    }
    return b;
}

glm::vec3 Mesh::base_color(std::size_t tri, float u, float v) const {
    return base_color(tri, u, v, 0.0);
}

glm::vec3 Mesh::base_color(std::size_t tri, float u, float v, double footprint) const {
    return base_color_over_texels(tri, u, v,
                                  footprint > 0.0 ? footprint * texture_density(tri) : 0.0);
}

double Mesh::texture_density(std::size_t tri) const {
    const Material& m = materials[material[tri]];
    return m.texture && has_uvs() ? texels_per_metre(*this, tri, *m.texture) : 0.0;
}

glm::vec3 Mesh::base_color_over_texels(std::size_t tri, float u, float v,
                                       double footprint_texels) const {
    const float w = 1.0f - u - v;
    const Material& m = materials[material[tri]];
    glm::vec3 c = m.base_color;
    if (m.texture && has_uvs()) {
        const glm::vec2 uv =
            w * corner_uvs[3 * tri] + u * corner_uvs[3 * tri + 1] + v * corner_uvs[3 * tri + 2];
        // At most one texel (or none given) it is the bilinear sample itself.
        c *= m.texture->sample(uv, footprint_texels);
    }
    if (has_colors()) {
        c *= w * corner_colors[3 * tri] + u * corner_colors[3 * tri + 1] +
             v * corner_colors[3 * tri + 2];
    }
    return c;
}

void Mesh::set_world_vertices(const std::vector<glm::dvec3>& world) {
    glm::dvec3 lo(std::numeric_limits<double>::infinity());
    glm::dvec3 hi(-std::numeric_limits<double>::infinity());
    for (const glm::dvec3& p : world) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    world_offset = world_offset_for_bounds(lo, hi);
    vertices.resize(world.size());
    for (std::size_t i = 0; i < world.size(); ++i) {
        vertices[i] = glm::vec3(world[i] - world_offset);
    }
}

void Mesh::validate(const std::string& where) const {
    const std::size_t n = triangles.size();
    for (std::size_t i = 0; i < vertices.size(); ++i) {
        const glm::vec3& p = vertices[i];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
            throw InputError(where + ": vertex " + std::to_string(i) +
                             " is not finite (expected real coordinates)");
        }
    }
    if (material.size() != n || object.size() != n) {
        throw InputError(where + ": expected one material and one object id per triangle");
    }
    if ((!corner_uvs.empty() && corner_uvs.size() != 3 * n) ||
        (!corner_colors.empty() && corner_colors.size() != 3 * n) ||
        (!corner_normals.empty() && corner_normals.size() != 3 * n)) {
        throw InputError(where + ": expected per-corner attributes for every triangle corner");
    }
    for (const auto& t : triangles) {
        for (const std::uint32_t i : t) {
            if (i >= vertices.size()) {
                throw InputError(where + ": triangle index " + std::to_string(i) +
                                 " is out of range (" + std::to_string(vertices.size()) +
                                 " vertices)");
            }
        }
    }
    for (std::size_t i = 0; i < n; ++i) {
        if (material[i] >= materials.size() || object[i] >= object_names.size()) {
            throw InputError(where + ": triangle " + std::to_string(i) +
                             " names a material or object that does not exist");
        }
    }
}

} // namespace lfprobe
