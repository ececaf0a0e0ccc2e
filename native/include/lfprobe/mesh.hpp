// A triangle mesh scene as the ground truth renderer, the mesh bake and the simulated scanner
// use it (docs/DESIGN.md §4): float positions in a local frame (world = world_offset + position),
// per-corner texture coordinates, colours and normals when the file has them, and per-triangle
// material and object ids. Colours are linear; the quantity rendered is the unlit base colour
// texture × material colour × vertex colour.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "lfprobe/texture.hpp"

namespace lfprobe {

struct Material {
    std::string name;
    glm::vec3 base_color{1.0f};             // linear (MTL Kd is taken as linear, as Blender does)
    std::shared_ptr<const Texture> texture; // base-colour texture (map_Kd), or null
};

struct MeshBounds {
    glm::vec3 min{0.0f};
    glm::vec3 max{0.0f};
};

struct Mesh {
    std::string path;
    glm::dvec3 world_offset{0.0};
    std::vector<glm::vec3> vertices;
    std::vector<std::array<std::uint32_t, 3>> triangles; // indices into vertices
    // Per corner (3 per triangle) when present, else empty.
    std::vector<glm::vec2> corner_uvs;
    std::vector<glm::vec3> corner_colors; // linear
    std::vector<glm::vec3> corner_normals;
    // Per triangle.
    std::vector<std::uint32_t> material; // index into materials
    std::vector<std::uint32_t> object;   // index into object_names
    std::vector<Material> materials;     // never empty once a reader has run
    std::vector<std::string> object_names;

    [[nodiscard]] std::size_t triangle_count() const { return triangles.size(); }
    [[nodiscard]] bool has_uvs() const { return !corner_uvs.empty(); }
    [[nodiscard]] bool has_colors() const { return !corner_colors.empty(); }
    [[nodiscard]] bool has_normals() const { return !corner_normals.empty(); }
    // Bounds of the vertices that triangles use (local frame); zero for an empty mesh.
    [[nodiscard]] MeshBounds bounds() const;
    // Linear base colour of triangle `tri` at barycentrics (u, v) (p = (1-u-v)·v0 + u·v1 +
    // v·v2): texture at the interpolated uv × material colour × interpolated vertex colour.
    [[nodiscard]] glm::vec3 base_color(std::size_t tri, float u, float v) const;
    // The same with the texture filtered over a footprint `footprint` metres wide on the
    // triangle (texture LOD: a ray's sample covers that much surface, so its colour is the
    // texture's mean over it, not one texel's). 0: base_color(tri, u, v) exactly.
    [[nodiscard]] glm::vec3 base_color(std::size_t tri, float u, float v, double footprint) const;
    // How many of its texture's texels a metre spans on triangle `tri` (0 without a texture or
    // on a degenerate triangle): base_color(tri, u, v, footprint) filters its texture over
    // footprint × this many texels.
    [[nodiscard]] double texture_density(std::size_t tri) const;
    // base_color(tri, u, v, footprint) given texture_density(tri) × footprint: for callers that
    // keep each triangle's density.
    [[nodiscard]] glm::vec3 base_color_over_texels(std::size_t tri, float u, float v,
                                                   double footprint_texels) const;
    // Sets `vertices` from world positions read in double: chooses the world offset by the
    // rule scans use (world_offset.hpp) and stores positions relative to it.
    void set_world_vertices(const std::vector<glm::dvec3>& world);
    // Throws InputError when indices or per-triangle arrays are inconsistent or a vertex is not
    // finite.
    void validate(const std::string& where) const;
};

} // namespace lfprobe
