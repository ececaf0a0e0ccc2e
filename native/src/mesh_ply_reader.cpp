// PLY meshes: a generic property reader (ascii and both binary byte orders) that keeps the
// vertex attributes and face lists a mesh needs and skips every other element and property.
#include <bit>
#include <cstring>
#include <limits>
#include <optional>

#include <fast_float/fast_float.h>

#include "lfprobe/color.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/mapped_file.hpp"
#include "lfprobe/mesh_reader.hpp"
#include "ply_header.hpp"

namespace lfprobe {

namespace {

using detail::PlyFormat;
using detail::PlyHeader;
using detail::PlyProperty;
using detail::PlyType;

// Reads one value after another from the data section, in whichever encoding the file uses.
class PlyValueReader {
public:
    PlyValueReader(const MappedFile& file, const PlyHeader& header)
        : file_(file), format_(header.format), pos_(header.data_offset),
          line_(header.line_count + 1) {}

    double read(PlyType type) {
        if (format_ == PlyFormat::Ascii) {
            return read_ascii();
        }
        const std::size_t size = detail::ply_type_size(type);
        if (pos_ + size > file_.size()) {
            throw input_error_at(FileLocation{file_.path(), 0, pos_, false},
                                 "expected more binary data (the file ends early)");
        }
        unsigned char bytes[8];
        std::memcpy(bytes, file_.data() + pos_, size);
        pos_ += size;
        const bool file_little = format_ == PlyFormat::BinaryLittleEndian;
        if (file_little != (std::endian::native == std::endian::little)) {
            for (std::size_t i = 0; i < size / 2; ++i) {
                std::swap(bytes[i], bytes[size - 1 - i]);
            }
        }
        switch (type) {
        case PlyType::Int8:
            return static_cast<double>(static_cast<std::int8_t>(bytes[0]));
        case PlyType::UInt8:
            return static_cast<double>(bytes[0]);
        case PlyType::Int16:
            return from_bytes<std::int16_t>(bytes);
        case PlyType::UInt16:
            return from_bytes<std::uint16_t>(bytes);
        case PlyType::Int32:
            return from_bytes<std::int32_t>(bytes);
        case PlyType::UInt32:
            return from_bytes<std::uint32_t>(bytes);
        case PlyType::Float32:
            return from_bytes<float>(bytes);
        case PlyType::Float64:
            return from_bytes<double>(bytes);
        }
        return 0.0;
    }

    // Ascii: every element item is one line; the next item starts on the next line.
    void end_item() {
        if (format_ != PlyFormat::Ascii) {
            return;
        }
        skip_blanks();
        if (pos_ < file_.size() && file_.data()[pos_] == '\r') {
            ++pos_;
        }
        if (pos_ < file_.size() && file_.data()[pos_] == '\n') {
            ++pos_;
            ++line_;
        } else if (pos_ < file_.size()) {
            throw input_error_at(where(), "expected the end of the line (more values than the "
                                          "header declares)");
        }
    }

    // Items of an element without properties: no bytes each in a binary file, an empty line
    // each in an ASCII one, where the file must hold them. Skipped at once, never walked item
    // by item: a header may declare 4e14 of them.
    void skip_items_without_properties(std::uint64_t count) {
        if (format_ != PlyFormat::Ascii) {
            return;
        }
        for (std::uint64_t item = 0; item < count; ++item) {
            if (pos_ >= file_.size()) {
                throw input_error_at(where(), "expected " + std::to_string(count) +
                                                  " empty lines of an element without "
                                                  "properties, found " +
                                                  std::to_string(item));
            }
            end_item(); // consumes a line or refuses what is not one
        }
    }

    [[nodiscard]] FileLocation where() const {
        return format_ == PlyFormat::Ascii ? FileLocation{file_.path(), line_, 0, true}
                                           : FileLocation{file_.path(), 0, pos_, false};
    }

private:
    template <class T>
    static double from_bytes(const unsigned char* bytes) {
        T v;
        std::memcpy(&v, bytes, sizeof v);
        return static_cast<double>(v);
    }

    void skip_blanks() {
        while (pos_ < file_.size() && (file_.data()[pos_] == ' ' || file_.data()[pos_] == '\t')) {
            ++pos_;
        }
    }

    double read_ascii() {
        skip_blanks();
        const char* first = file_.data() + pos_;
        const char* last = file_.data() + file_.size();
        const char* end = first;
        while (end < last && *end != ' ' && *end != '\t' && *end != '\r' && *end != '\n') {
            ++end;
        }
        double value = 0.0;
        const char* start = (first < end && *first == '+') ? first + 1 : first;
        const auto r = fast_float::from_chars(start, end, value);
        if (first == end || r.ec != std::errc() || r.ptr != end) {
            throw input_error_at(where(),
                                 "expected a number, got '" + std::string(first, end) + "'");
        }
        pos_ += static_cast<std::size_t>(end - first);
        return value;
    }

    const MappedFile& file_;
    PlyFormat format_;
    std::size_t pos_;
    std::uint64_t line_;
};

int find_property(const detail::PlyElement& e, std::initializer_list<const char*> names) {
    for (const char* name : names) {
        for (std::size_t i = 0; i < e.properties.size(); ++i) {
            if (e.properties[i].name == name && !e.properties[i].is_list) {
                return static_cast<int>(i);
            }
        }
    }
    return -1;
}

[[nodiscard]] Mesh read_ply_mesh_from(const MappedFile& file) {
    const std::string& path = file.path();
    const PlyHeader header = detail::parse_ply_header(file);
    Mesh mesh;
    mesh.path = path;
    PlyValueReader reader(file, header);
    std::vector<glm::dvec3> world_vertices; // double until the world offset is chosen
    std::vector<glm::vec3> colors;
    std::vector<glm::vec2> uvs;
    bool has_vertex_element = false;
    for (const detail::PlyElement& e : header.elements) {
        std::vector<double> values(e.properties.size(), 0.0);
        const bool is_vertex = e.name == "vertex";
        const bool is_face = e.name == "face";
        const int ix = find_property(e, {"x"});
        const int iy = find_property(e, {"y"});
        const int iz = find_property(e, {"z"});
        const int ir = find_property(e, {"red", "r"});
        const int ig = find_property(e, {"green", "g"});
        const int ib = find_property(e, {"blue", "b"});
        const int iu = find_property(e, {"s", "u", "texture_u", "texture_s"});
        const int iv = find_property(e, {"t", "v", "texture_v", "texture_t"});
        int list_index = -1;
        for (std::size_t i = 0; i < e.properties.size(); ++i) {
            if (e.properties[i].is_list && (e.properties[i].name == "vertex_indices" ||
                                            e.properties[i].name == "vertex_index")) {
                list_index = static_cast<int>(i);
            }
        }
        if (is_vertex) {
            has_vertex_element = true;
            if (ix < 0 || iy < 0 || iz < 0) {
                throw input_error_at(FileLocation{path, e.header_line, 0, true},
                                     "expected vertex properties x, y and z");
            }
        }
        if (is_face && list_index < 0) {
            throw input_error_at(FileLocation{path, e.header_line, 0, true},
                                 "expected a face list property vertex_indices");
        }
        if (e.properties.empty()) {
            reader.skip_items_without_properties(e.count);
            continue;
        }
        const bool has_color = ir >= 0 && ig >= 0 && ib >= 0;
        const bool has_uv = iu >= 0 && iv >= 0;
        std::vector<std::int64_t> face;
        for (std::uint64_t item = 0; item < e.count; ++item) {
            face.clear();
            for (std::size_t p = 0; p < e.properties.size(); ++p) {
                const PlyProperty& prop = e.properties[p];
                if (!prop.is_list) {
                    values[p] = reader.read(prop.type);
                    continue;
                }
                const double count = reader.read(prop.count_type);
                // Negated so that NaN is refused too: a cast of NaN to int is undefined.
                if (!(count >= 0.0 && count <= 1.0e6)) {
                    throw input_error_at(reader.where(),
                                         "expected a list length, got " + std::to_string(count));
                }
                for (int k = 0; k < static_cast<int>(count); ++k) {
                    const double v = reader.read(prop.type);
                    if (static_cast<int>(p) == list_index) {
                        // Read as a double whatever the file's type: checked before the cast,
                        // which is undefined for NaN or a value an int64 cannot hold (1.8e19
                        // in a damaged file).
                        if (!(v >= 0.0 && v < 4294967296.0)) {
                            throw input_error_at(reader.where(),
                                                 "expected a vertex index from 0 to 2^32 - 1, "
                                                 "got " +
                                                     std::to_string(v));
                        }
                        face.push_back(static_cast<std::int64_t>(v));
                    }
                }
            }
            const FileLocation where = reader.where();
            reader.end_item();
            if (is_vertex) {
                world_vertices.emplace_back(values[static_cast<std::size_t>(ix)],
                                            values[static_cast<std::size_t>(iy)],
                                            values[static_cast<std::size_t>(iz)]);
                if (has_color) {
                    glm::vec3 c{static_cast<float>(values[static_cast<std::size_t>(ir)]),
                                static_cast<float>(values[static_cast<std::size_t>(ig)]),
                                static_cast<float>(values[static_cast<std::size_t>(ib)])};
                    // Integer colours are 8-bit sRGB; float colours are taken as linear.
                    if (!detail::ply_type_is_float(
                            e.properties[static_cast<std::size_t>(ir)].type)) {
                        c = glm::vec3(srgb_to_linear(c.x / 255.0f), srgb_to_linear(c.y / 255.0f),
                                      srgb_to_linear(c.z / 255.0f));
                    }
                    colors.push_back(c);
                }
                if (has_uv) {
                    uvs.emplace_back(values[static_cast<std::size_t>(iu)],
                                     values[static_cast<std::size_t>(iv)]);
                }
            } else if (is_face) {
                if (!has_vertex_element) {
                    throw input_error_at(where, "expected the vertex element before faces");
                }
                if (face.size() < 3) {
                    throw input_error_at(where, "expected a face of at least 3 vertices");
                }
                for (const std::int64_t index : face) {
                    if (index < 0 || static_cast<std::size_t>(index) >= world_vertices.size()) {
                        throw input_error_at(where, "expected vertex indices below " +
                                                        std::to_string(world_vertices.size()) +
                                                        ", got " + std::to_string(index));
                    }
                }
                for (std::size_t k = 1; k + 1 < face.size(); ++k) {
                    mesh.triangles.push_back({static_cast<std::uint32_t>(face[0]),
                                              static_cast<std::uint32_t>(face[k]),
                                              static_cast<std::uint32_t>(face[k + 1])});
                }
            }
        }
    }
    mesh.set_world_vertices(world_vertices);
    for (const auto& t : mesh.triangles) {
        for (const std::uint32_t i : t) {
            if (!colors.empty()) {
                mesh.corner_colors.push_back(colors[i]);
            }
            if (!uvs.empty()) {
                mesh.corner_uvs.push_back(uvs[i]);
            }
        }
    }
    // Vertex colours are the whole base colour of a PLY mesh, so the material is white.
    mesh.materials.push_back(Material{"default", glm::vec3(colors.empty() ? 0.8f : 1.0f), nullptr});
    mesh.object_names.push_back("default");
    mesh.material.assign(mesh.triangles.size(), 0);
    mesh.object.assign(mesh.triangles.size(), 0);
    mesh.validate(path);
    if (mesh.triangles.empty()) {
        throw InputError(path + ": no faces (expected an element face with vertex_indices; a "
                                "point cloud is a scan, not a mesh)");
    }
    return mesh;
}

} // namespace

Mesh read_ply_mesh(const std::string& path) {
    return read_ply_mesh_from(MappedFile(path));
}

Mesh read_ply_mesh_bytes(const std::string& name, std::string_view bytes) {
    return read_ply_mesh_from(MappedFile(name, bytes));
}

} // namespace lfprobe
