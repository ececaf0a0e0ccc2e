// Mesh files for ground truth and mesh bakes: Wavefront OBJ (with its MTL: Kd and map_Kd) and
// PLY (ascii and binary). Errors name the file and line and say what was expected.
#pragma once

#include <string>
#include <string_view>

#include "lfprobe/mesh.hpp"

namespace lfprobe {

// OBJ: v, vt, vn, f (polygons fan-triangulated; negative indices count back from the end),
// o and g start objects, usemtl picks a material of the mtllib files (paths relative to the
// OBJ, texture paths relative to the MTL). Unknown statements are ignored.
[[nodiscard]] Mesh read_obj(const std::string& path);

// PLY: element vertex with x y z, optional red green blue (uchar sRGB or float linear),
// s t or u v (texture_u/texture_v too); element face with a vertex_indices (or vertex_index)
// list, fan-triangulated. One object, one material (white, or the vertex colours).
[[nodiscard]] Mesh read_ply_mesh(const std::string& path);
// The same for a PLY's bytes already in memory, `name` standing for the file in errors.
[[nodiscard]] Mesh read_ply_mesh_bytes(const std::string& name, std::string_view bytes);

// By extension: .obj or .ply. Throws InputError for other extensions.
[[nodiscard]] Mesh read_mesh(const std::string& path);

} // namespace lfprobe
