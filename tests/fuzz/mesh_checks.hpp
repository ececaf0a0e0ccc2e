// The promises of a mesh a reader returns: indices inside the vertex list, per-corner and
// per-triangle arrays of the right length, finite vertices, materials and objects that exist.
#pragma once

#include <cmath>

#include "fuzz_support.hpp"
#include "lfprobe/mesh.hpp"

namespace lfprobe::fuzz {

inline void check_mesh(const Mesh& mesh) {
    const std::size_t triangles = mesh.triangles.size();
    expect(!mesh.materials.empty(), "a mesh without materials");
    for (const auto& triangle : mesh.triangles) {
        for (const std::uint32_t index : triangle) {
            expect(index < mesh.vertices.size(), "a triangle index outside the vertex list");
        }
    }
    for (const glm::vec3& v : mesh.vertices) {
        expect(std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z),
               "a vertex is not finite");
    }
    expect(mesh.corner_uvs.empty() || mesh.corner_uvs.size() == 3 * triangles,
           "uv count differs from corners");
    expect(mesh.corner_colors.empty() || mesh.corner_colors.size() == 3 * triangles,
           "colour count differs from corners");
    expect(mesh.corner_normals.empty() || mesh.corner_normals.size() == 3 * triangles,
           "normal count differs from corners");
    expect(mesh.material.size() == triangles, "material count differs from triangles");
    for (const std::uint32_t m : mesh.material) {
        expect(m < mesh.materials.size(), "a triangle names a material that is not there");
    }
    expect(mesh.object.empty() || mesh.object.size() == triangles,
           "object count differs from triangles");
    for (const std::uint32_t o : mesh.object) {
        expect(o < mesh.object_names.size(), "a triangle names an object that is not there");
    }
    // The base colour at a triangle's centre reads the texture: any size, any uv.
    if (triangles != 0) {
        const glm::vec3 colour = mesh.base_color(0, 1.0f / 3.0f, 1.0f / 3.0f);
        (void)colour;
    }
}

} // namespace lfprobe::fuzz
