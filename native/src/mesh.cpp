#include "lfprobe/mesh.hpp"

#include <algorithm>
#include <limits>

#include <glm/common.hpp>

#include "lfprobe/error.hpp"

namespace lfprobe {

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
    const float w = 1.0f - u - v;
    const Material& m = materials[material[tri]];
    glm::vec3 c = m.base_color;
    if (m.texture && has_uvs()) {
        const glm::vec2 uv =
            w * corner_uvs[3 * tri] + u * corner_uvs[3 * tri + 1] + v * corner_uvs[3 * tri + 2];
        c *= m.texture->sample(uv);
    }
    if (has_colors()) {
        c *= w * corner_colors[3 * tri] + u * corner_colors[3 * tri + 1] +
             v * corner_colors[3 * tri + 2];
    }
    return c;
}

void Mesh::validate(const std::string& where) const {
    const std::size_t n = triangles.size();
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
