// PLY header parsing: line by line up to end_header, LF or CRLF.
#include "ply_header.hpp"
#include "text_words.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <optional>
#include <string_view>

#include "lfprobe/enum_names.hpp"
#include "lfprobe/error.hpp"
#include "scan_parsing.hpp"

namespace lfprobe::detail {

namespace {

// The PLY specification's names first (written in messages), then the sized aliases.
constexpr auto type_names = std::to_array<EnumName<PlyType>>({
    {PlyType::Int8, "char"},
    {PlyType::UInt8, "uchar"},
    {PlyType::Int16, "short"},
    {PlyType::UInt16, "ushort"},
    {PlyType::Int32, "int"},
    {PlyType::UInt32, "uint"},
    {PlyType::Float32, "float"},
    {PlyType::Float64, "double"},
    {PlyType::Int8, "int8"},
    {PlyType::UInt8, "uint8"},
    {PlyType::Int16, "int16"},
    {PlyType::UInt16, "uint16"},
    {PlyType::Int32, "int32"},
    {PlyType::UInt32, "uint32"},
    {PlyType::Float32, "float32"},
    {PlyType::Float64, "float64"},
});

[[nodiscard]] std::optional<PlyType> type_from_name(std::string_view name) {
    return value_named(type_names, name);
}

[[nodiscard]] std::optional<double> finite_number(std::string_view text) {
    double value = 0.0;
    const char* end = parse_double(text.data(), text.data() + text.size(), value);
    if (end != text.data() + text.size() || !std::isfinite(value)) {
        return std::nullopt;
    }
    return value;
}

// "comment scanner X Y Z", or PCL's "... sensor origin at (X,Y,Z) ...".
void read_scanner_comment(std::string_view line, const std::vector<std::string_view>& words,
                          PlyHeader& header) {
    if (words.size() == 5 && equals_ignoring_case(words[1], "scanner")) {
        const std::optional<double> x = finite_number(words[2]);
        const std::optional<double> y = finite_number(words[3]);
        const std::optional<double> z = finite_number(words[4]);
        if (x && y && z) {
            header.scanner = glm::dvec3(*x, *y, *z);
            header.has_scanner = true;
        }
        return;
    }
    std::string lowered(line);
    for (char& c : lowered) {
        c = ascii_lower(c);
    }
    const std::size_t phrase = lowered.find("sensor origin at");
    if (phrase == std::string::npos) {
        return;
    }
    const std::size_t open = lowered.find('(', phrase);
    const std::size_t close = lowered.find(')', open == std::string::npos ? phrase : open);
    if (open == std::string::npos || close == std::string::npos) {
        return;
    }
    std::string_view inside = line.substr(open + 1, close - open - 1);
    std::array<double, 3> coordinates{};
    std::size_t found = 0;
    while (!inside.empty() && found <= 3) {
        const std::size_t comma = inside.find(',');
        std::string_view part = inside.substr(0, comma);
        while (!part.empty() && (part.front() == ' ' || part.front() == '\t')) {
            part.remove_prefix(1);
        }
        while (!part.empty() && (part.back() == ' ' || part.back() == '\t')) {
            part.remove_suffix(1);
        }
        const std::optional<double> value = finite_number(part);
        if (!value || found == 3) {
            return;
        }
        coordinates[found++] = *value;
        inside = comma == std::string_view::npos ? std::string_view{} : inside.substr(comma + 1);
    }
    if (found == 3) {
        header.scanner = glm::dvec3(coordinates[0], coordinates[1], coordinates[2]);
        header.has_scanner = true;
    }
}

} // namespace

std::size_t ply_type_size(PlyType type) {
    switch (type) {
    case PlyType::Int8:
    case PlyType::UInt8:
        return 1;
    case PlyType::Int16:
    case PlyType::UInt16:
        return 2;
    case PlyType::Int32:
    case PlyType::UInt32:
    case PlyType::Float32:
        return 4;
    case PlyType::Float64:
        return 8;
    }
    return 0;
}

bool ply_type_is_float(PlyType type) {
    return type == PlyType::Float32 || type == PlyType::Float64;
}

const char* ply_type_name(PlyType type) {
    return name_of(type_names, type);
}

bool PlyElement::has_lists() const {
    for (const PlyProperty& property : properties) {
        if (property.is_list) {
            return true;
        }
    }
    return false;
}

std::size_t PlyElement::fixed_stride() const {
    std::size_t stride = 0;
    for (const PlyProperty& property : properties) {
        stride += ply_type_size(property.type);
    }
    return stride;
}

PlyHeader parse_ply_header(const MappedFile& file) {
    const std::string_view text = file.view();
    std::uint64_t line_number = 0;
    auto fail = [&](const std::string& what) -> InputError {
        return input_error_at({file.path(), std::max<std::uint64_t>(line_number, 1), 0, true},
                              what);
    };

    PlyHeader header;
    bool has_format = false;
    std::size_t position = 0;
    while (position < text.size()) {
        ++line_number;
        const std::size_t newline = text.find('\n', position);
        const std::size_t line_end = newline == std::string_view::npos ? text.size() : newline;
        const std::string_view line = text.substr(position, line_end - position);
        position = newline == std::string_view::npos ? text.size() : newline + 1;
        const std::vector<std::string_view> words = split_words(line);

        if (line_number == 1) {
            if (words.size() != 1 || words[0] != "ply") {
                throw fail("expected the magic line 'ply' that starts every PLY file");
            }
            continue;
        }
        if (words.empty()) {
            continue;
        }
        const std::string_view keyword = words[0];
        if (keyword == "comment" || keyword == "obj_info") {
            read_scanner_comment(line, words, header);
        } else if (keyword == "format") {
            if (words.size() < 2) {
                throw fail("the format line names no format: expected ascii, "
                           "binary_little_endian or binary_big_endian");
            }
            if (words[1] == "ascii") {
                header.format = PlyFormat::Ascii;
            } else if (words[1] == "binary_little_endian") {
                header.format = PlyFormat::BinaryLittleEndian;
            } else if (words[1] == "binary_big_endian") {
                header.format = PlyFormat::BinaryBigEndian;
            } else {
                throw fail("unknown format '" + std::string(words[1]) +
                           "': expected ascii, binary_little_endian or binary_big_endian");
            }
            has_format = true;
        } else if (keyword == "element") {
            std::uint64_t count = 0;
            const std::string_view count_text = words.size() == 3 ? words[2] : std::string_view{};
            const auto [end, error] =
                std::from_chars(count_text.data(), count_text.data() + count_text.size(), count);
            if (words.size() != 3 || error != std::errc() ||
                end != count_text.data() + count_text.size()) {
                throw fail("expected 'element NAME COUNT' with a whole-number count, found '" +
                           std::string(line) + "'");
            }
            header.elements.push_back({std::string(words[1]), count, {}, line_number});
        } else if (keyword == "property") {
            if (header.elements.empty()) {
                throw fail("a property before any element: expected 'element NAME COUNT' first");
            }
            PlyProperty property;
            std::size_t type_word = 1;
            if (words.size() >= 2 && words[1] == "list") {
                if (words.size() != 5) {
                    throw fail("expected 'property list COUNT_TYPE ITEM_TYPE NAME', found '" +
                               std::string(line) + "'");
                }
                const std::optional<PlyType> count_type = type_from_name(words[2]);
                if (!count_type) {
                    throw fail("unknown property type '" + std::string(words[2]) +
                               "': expected char, uchar, short, ushort, int, uint, float, "
                               "double or their sized names (int8 ... float64)");
                }
                if (ply_type_is_float(*count_type)) {
                    throw fail("list count type '" + std::string(words[2]) +
                               "' is a float type: expected an integer type");
                }
                property.is_list = true;
                property.count_type = *count_type;
                type_word = 3;
            } else if (words.size() != 3) {
                throw fail("expected 'property TYPE NAME', found '" + std::string(line) + "'");
            }
            const std::optional<PlyType> type = type_from_name(words[type_word]);
            if (!type) {
                throw fail("unknown property type '" + std::string(words[type_word]) +
                           "': expected char, uchar, short, ushort, int, uint, float, double "
                           "or their sized names (int8 ... float64)");
            }
            property.type = *type;
            property.name = std::string(words[type_word + 1]);
            header.elements.back().properties.push_back(std::move(property));
        } else if (keyword == "end_header") {
            if (!has_format) {
                throw fail("end_header before any format line: expected 'format ascii 1.0', "
                           "'format binary_little_endian 1.0' or 'format binary_big_endian 1.0'");
            }
            header.data_offset = position;
            header.line_count = line_number;
            return header;
        } else {
            throw fail("expected 'end_header' or a header line (format, comment, obj_info, "
                       "element, property), found '" +
                       printable(line.substr(0, 64)) + "'");
        }
    }
    if (line_number == 0) {
        throw fail("empty file: expected the magic line 'ply' that starts every PLY file");
    }
    throw fail("the header has no end_header line: expected the header to end with "
               "'end_header' before the end of the file");
}

} // namespace lfprobe::detail
