// The header of a PLY file: format, elements and their properties, and the scanner position
// that some writers leave in a comment.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "lfprobe/mapped_file.hpp"

namespace lfprobe::detail {

enum class PlyFormat { Ascii, BinaryLittleEndian, BinaryBigEndian };

enum class PlyType : std::uint8_t { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

[[nodiscard]] std::size_t ply_type_size(PlyType type);
[[nodiscard]] bool ply_type_is_float(PlyType type);
[[nodiscard]] const char* ply_type_name(PlyType type);

struct PlyProperty {
    std::string name;
    PlyType type = PlyType::Float32; // the value type (of each item, for a list)
    bool is_list = false;
    PlyType count_type = PlyType::UInt8; // lists only
};

struct PlyElement {
    std::string name;
    std::uint64_t count = 0;
    std::vector<PlyProperty> properties;
    std::uint64_t header_line = 0; // where the element was declared

    [[nodiscard]] bool has_lists() const;
    // Bytes per item in a binary file; only meaningful without lists.
    [[nodiscard]] std::size_t fixed_stride() const;
};

struct PlyHeader {
    PlyFormat format = PlyFormat::Ascii;
    std::vector<PlyElement> elements;
    std::size_t data_offset = 0;  // first byte after the end_header line
    std::uint64_t line_count = 0; // lines up to and including end_header
    // From "comment scanner X Y Z" or PCL's "sensor origin at (X,Y,Z)".
    glm::dvec3 scanner{0.0};
    bool has_scanner = false;
};

// Parses the header; throws InputError with the line for a missing magic, an unknown format
// or type, a malformed line, or a header that never ends.
[[nodiscard]] PlyHeader parse_ply_header(const MappedFile& file);

} // namespace lfprobe::detail
