#include "lfprobe/mesh_reader.hpp"

#include <algorithm>
#include <charconv>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string_view>

#include <fast_float/fast_float.h>

#include "lfprobe/error.hpp"
#include "lfprobe/input_limits.hpp"
#include "text_words.hpp"

namespace lfprobe {

namespace fs = std::filesystem;

namespace {

// Whitespace-separated tokens of one line, without the trailing comment.
std::vector<std::string_view> split_tokens(std::string_view line) {
    return split_words(line.substr(0, line.find('#')));
}

std::optional<double> parse_double(std::string_view s) {
    if (!s.empty() && s.front() == '+') {
        s.remove_prefix(1); // fast_float rejects a leading '+', some exporters write one
    }
    double value = 0.0;
    const auto r = fast_float::from_chars(s.data(), s.data() + s.size(), value);
    if (r.ec != std::errc() || r.ptr != s.data() + s.size()) {
        return std::nullopt;
    }
    return value;
}

std::optional<long long> parse_int(std::string_view s) {
    if (!s.empty() && s.front() == '+') {
        s.remove_prefix(1);
    }
    long long value = 0;
    const auto r = std::from_chars(s.data(), s.data() + s.size(), value);
    if (r.ec != std::errc() || r.ptr != s.data() + s.size()) {
        return std::nullopt;
    }
    return value;
}

// Reads a whole text file that must be a regular file (a FIFO would block, /dev/zero never
// end) of at most `max_bytes`.
// A material library is a few kilobytes; an OBJ of tens of millions of triangles is a few GB.
std::string read_text(const std::string& path, const char* what, InputLimit limit) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) {
        throw MissingFileError(
            path + ": cannot open " + what +
            (std::filesystem::exists(path, ec) ? " (not a regular file)" : " (no such file)"));
    }
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    if (!ec && size > static_cast<std::uintmax_t>(input_limit(limit))) {
        throw InputError(path + ": the " + what + " is " + std::to_string(size) + " bytes; " +
                         input_limit_hint(limit) + " bytes");
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        throw IoError(path + ": cannot open " + what);
    }
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

// Calls f(line_number, tokens) for every non-empty line.
template <class F>
void for_each_line(const std::string& text, F&& f) {
    std::size_t start = 0;
    std::uint64_t line_number = 0;
    while (start <= text.size()) {
        std::size_t end = text.find('\n', start);
        if (end == std::string::npos) {
            end = text.size();
        }
        ++line_number;
        std::string_view line(text.data() + start, end - start);
        const auto tokens = split_tokens(line);
        if (!tokens.empty()) {
            f(line_number, tokens);
        }
        start = end + 1;
    }
}

FileLocation at_line(const std::string& path, std::uint64_t line) {
    return FileLocation{path, line, 0, true};
}

glm::dvec3 read_dvec3(const std::vector<std::string_view>& tokens, std::size_t first,
                      const FileLocation& where, const char* what) {
    glm::dvec3 v{0.0};
    for (int k = 0; k < 3; ++k) {
        const std::size_t i = first + static_cast<std::size_t>(k);
        const auto value = i < tokens.size() ? parse_double(tokens[i]) : std::nullopt;
        if (!value) {
            throw input_error_at(where, std::string("expected ") + what);
        }
        v[k] = *value;
    }
    return v;
}

glm::vec3 read_vec3(const std::vector<std::string_view>& tokens, std::size_t first,
                    const FileLocation& where, const char* what) {
    return glm::vec3(read_dvec3(tokens, first, where, what));
}

// Materials of an MTL file, by name; texture paths are relative to the MTL's folder.
void read_mtl(const std::string& path, std::vector<Material>& materials,
              std::map<std::string, std::uint32_t>& by_name,
              std::map<std::string, std::shared_ptr<const Texture>>& textures) {
    const std::string text =
        read_text(path, "material library (mtllib)", InputLimit::MaterialLibraryBytes);
    const fs::path folder = fs::path(path).parent_path();
    Material* current = nullptr;
    for_each_line(text, [&](std::uint64_t line, const std::vector<std::string_view>& t) {
        const FileLocation where = at_line(path, line);
        if (t[0] == "newmtl") {
            if (t.size() < 2) {
                throw input_error_at(where, "expected a material name after newmtl");
            }
            const std::string name(t[1]);
            auto found = by_name.find(name);
            if (found == by_name.end()) {
                found = by_name.emplace(name, static_cast<std::uint32_t>(materials.size())).first;
                materials.push_back(Material{name, glm::vec3(0.8f), nullptr});
            }
            current = &materials[found->second];
        } else if (t[0] == "Kd") {
            if (current == nullptr) {
                throw input_error_at(where, "expected newmtl before Kd");
            }
            // "Kd r" alone means grey r.
            if (t.size() == 2) {
                const auto g = parse_double(t[1]);
                if (!g) {
                    throw input_error_at(where, "expected Kd r g b");
                }
                current->base_color = glm::vec3(static_cast<float>(*g));
            } else {
                current->base_color = read_vec3(t, 1, where, "Kd r g b");
            }
        } else if (t[0] == "map_Kd") {
            if (current == nullptr) {
                throw input_error_at(where, "expected newmtl before map_Kd");
            }
            if (t.size() < 2) {
                throw input_error_at(where, "expected a texture file after map_Kd");
            }
            // Options (-s, -o, ...) come first; the file name is the last token.
            const std::string file = (folder / std::string(t.back())).string();
            auto found = textures.find(file);
            if (found == textures.end()) {
                std::shared_ptr<const Texture> tex;
                try {
                    tex = std::make_shared<const Texture>(Texture::load(file));
                } catch (const MissingFileError& e) {
                    throw MissingFileError(path + ":" + std::to_string(line) +
                                           ": map_Kd: " + e.what());
                } catch (const IoError& e) {
                    throw IoError(path + ":" + std::to_string(line) + ": map_Kd: " + e.what());
                }
                found = textures.emplace(file, std::move(tex)).first;
            }
            current->texture = found->second;
        }
    });
}

// One corner of an OBJ face: "v", "v/vt", "v//vn" or "v/vt/vn", 1-based or negative.
struct ObjCorner {
    std::int64_t v = -1;
    std::int64_t vt = -1;
    std::int64_t vn = -1;
};

std::int64_t resolve_index(std::string_view token, std::size_t count, const FileLocation& where,
                           const char* what) {
    const auto value = parse_int(token);
    if (!value || *value == 0) {
        throw input_error_at(where, std::string("expected a non-zero ") + what + " index, got '" +
                                        std::string(token) + "'");
    }
    const long long n = static_cast<long long>(count);
    const long long index = *value > 0 ? *value - 1 : n + *value;
    if (index < 0 || index >= n) {
        throw input_error_at(where, std::string("expected a ") + what + " index within the " +
                                        std::to_string(count) + " defined so far, got " +
                                        std::string(token));
    }
    return index;
}

} // namespace

Mesh read_obj(const std::string& path) {
    const std::string text = read_text(path, "OBJ mesh", InputLimit::ObjBytes);
    const fs::path folder = fs::path(path).parent_path();
    Mesh mesh;
    mesh.path = path;
    std::vector<glm::dvec3> world_vertices; // double until the world offset is chosen
    std::vector<glm::vec2> uvs;
    std::vector<glm::vec3> normals;
    std::vector<glm::vec3> vertex_colors;
    bool any_vertex_color = false;
    std::vector<ObjCorner> corners; // 3 per triangle
    std::map<std::string, std::uint32_t> material_by_name;
    std::map<std::string, std::shared_ptr<const Texture>> textures;
    std::map<std::string, std::uint32_t> object_by_name;
    std::optional<std::uint32_t> current_material;
    std::optional<std::uint32_t> current_object;

    // The index of the object or material called `name`, appended to `list` when new.
    const auto index_of = [](std::map<std::string, std::uint32_t>& by_name, auto& list,
                             const std::string& name, auto&& make) {
        const auto [found, added] =
            by_name.try_emplace(name, static_cast<std::uint32_t>(list.size()));
        if (added) {
            list.push_back(make());
        }
        return found->second;
    };
    auto object_id = [&](const std::string& name) {
        return index_of(object_by_name, mesh.object_names, name, [&] { return name; });
    };
    auto material_id = [&](const std::string& name) {
        // Blender's importer also keeps going with a default material for unknown names.
        return index_of(material_by_name, mesh.materials, name, [&] {
            return Material{name, glm::vec3(0.8f), nullptr};
        });
    };

    for_each_line(text, [&](std::uint64_t line, const std::vector<std::string_view>& t) {
        const FileLocation where = at_line(path, line);
        const std::string_view kw = t[0];
        if (kw == "v") {
            world_vertices.push_back(read_dvec3(t, 1, where, "v x y z"));
            if (t.size() >= 7) {
                vertex_colors.push_back(read_vec3(t, 4, where, "v x y z r g b"));
                any_vertex_color = true;
            } else {
                vertex_colors.push_back(glm::vec3(1.0f));
            }
        } else if (kw == "vt") {
            const auto u = t.size() > 1 ? parse_double(t[1]) : std::nullopt;
            const auto v = t.size() > 2 ? parse_double(t[2]) : std::optional<double>(0.0);
            if (!u || !v) {
                throw input_error_at(where, "expected vt u v");
            }
            uvs.emplace_back(static_cast<float>(*u), static_cast<float>(*v));
        } else if (kw == "vn") {
            normals.push_back(read_vec3(t, 1, where, "vn x y z"));
        } else if (kw == "f") {
            if (t.size() < 4) {
                throw input_error_at(where, "expected a face of at least 3 vertices");
            }
            std::vector<ObjCorner> poly;
            for (std::size_t i = 1; i < t.size(); ++i) {
                const std::string_view c = t[i];
                ObjCorner corner;
                const auto s1 = c.find('/');
                corner.v = resolve_index(c.substr(0, s1), world_vertices.size(), where, "vertex");
                if (s1 != std::string_view::npos) {
                    const std::string_view rest = c.substr(s1 + 1);
                    const auto s2 = rest.find('/');
                    const std::string_view vt = rest.substr(0, s2);
                    if (!vt.empty()) {
                        corner.vt = resolve_index(vt, uvs.size(), where, "texture coordinate");
                    }
                    if (s2 != std::string_view::npos && s2 + 1 < rest.size()) {
                        corner.vn =
                            resolve_index(rest.substr(s2 + 1), normals.size(), where, "normal");
                    }
                }
                poly.push_back(corner);
            }
            if (!current_object) {
                current_object = object_id("default");
            }
            if (!current_material) {
                current_material = material_id("default");
            }
            // Fan triangulation: right for the convex polygons that exporters write.
            for (std::size_t i = 1; i + 1 < poly.size(); ++i) {
                corners.push_back(poly[0]);
                corners.push_back(poly[i]);
                corners.push_back(poly[i + 1]);
                mesh.material.push_back(*current_material);
                mesh.object.push_back(*current_object);
            }
        } else if (kw == "o" || kw == "g") {
            // Each o or g starts an object; the name joins the remaining tokens.
            std::string name;
            for (std::size_t i = 1; i < t.size(); ++i) {
                if (i > 1) {
                    name.push_back(' ');
                }
                name.append(t[i]);
            }
            current_object = object_id(name.empty() ? "default" : name);
        } else if (kw == "usemtl") {
            if (t.size() < 2) {
                throw input_error_at(where, "expected a material name after usemtl");
            }
            current_material = material_id(std::string(t[1]));
        } else if (kw == "mtllib") {
            if (t.size() < 2) {
                throw input_error_at(where, "expected a file name after mtllib");
            }
            for (std::size_t i = 1; i < t.size(); ++i) {
                read_mtl((folder / std::string(t[i])).string(), mesh.materials, material_by_name,
                         textures);
            }
        }
    });

    mesh.set_world_vertices(world_vertices);
    const std::size_t tri_count = corners.size() / 3;
    mesh.triangles.resize(tri_count);
    bool any_uv = false;
    bool any_normal = false;
    for (const ObjCorner& c : corners) {
        any_uv = any_uv || c.vt >= 0;
        any_normal = any_normal || c.vn >= 0;
    }
    for (std::size_t i = 0; i < tri_count; ++i) {
        for (std::size_t k = 0; k < 3; ++k) {
            mesh.triangles[i][k] = static_cast<std::uint32_t>(corners[3 * i + k].v);
        }
    }
    if (any_uv) {
        mesh.corner_uvs.reserve(corners.size());
        for (const ObjCorner& c : corners) {
            mesh.corner_uvs.push_back(c.vt >= 0 ? uvs[static_cast<std::size_t>(c.vt)]
                                                : glm::vec2(0.0f));
        }
    }
    if (any_normal) {
        mesh.corner_normals.reserve(corners.size());
        for (const ObjCorner& c : corners) {
            // A corner without vn gets a zero normal: the geometric normal is used there.
            mesh.corner_normals.push_back(c.vn >= 0 ? normals[static_cast<std::size_t>(c.vn)]
                                                    : glm::vec3(0.0f));
        }
    }
    if (any_vertex_color) {
        mesh.corner_colors.reserve(corners.size());
        for (const ObjCorner& c : corners) {
            mesh.corner_colors.push_back(vertex_colors[static_cast<std::size_t>(c.v)]);
        }
    }
    if (mesh.materials.empty()) {
        mesh.materials.push_back(Material{"default", glm::vec3(0.8f), nullptr});
    }
    if (mesh.object_names.empty()) {
        mesh.object_names.push_back("default");
    }
    mesh.validate(path);
    // A file that is not an OBJ (garbage, empty, only comments) parses to nothing: refuse it
    // rather than render an empty scene that looks like a valid answer.
    if (mesh.triangles.empty()) {
        throw InputError(path + ": no faces (expected an OBJ with 'f' lines of three or more "
                                "vertices)");
    }
    return mesh;
}

Mesh read_mesh(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (ext == ".obj") {
        return read_obj(path);
    }
    if (ext == ".ply") {
        return read_ply_mesh(path);
    }
    throw InputError(path + ": expected a mesh file ending in .obj or .ply");
}

} // namespace lfprobe
