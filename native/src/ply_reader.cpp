// PLY data: the elements before "vertex" are skipped, the vertices read (binary in parallel
// chunks, byte-swapped where the file's byte order differs from the machine's), and whatever
// follows (faces) is ignored.
#include "ply_reader.hpp"

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include <tbb/parallel_for.h>

#include "lfprobe/error.hpp"
#include "ply_header.hpp"
#include "ply_vertices.hpp"

namespace lfprobe::detail {

namespace {

template <class Unsigned>
[[nodiscard]] Unsigned load_bits(const char* bytes, bool swap) {
    Unsigned bits;
    std::memcpy(&bits, bytes, sizeof(bits));
    if (!swap) {
        return bits;
    }
    if constexpr (sizeof(Unsigned) == 2) {
        return __builtin_bswap16(bits);
    } else if constexpr (sizeof(Unsigned) == 4) {
        return __builtin_bswap32(bits);
    } else {
        return __builtin_bswap64(bits);
    }
}

[[nodiscard]] double load_value(const char* bytes, PlyType type, bool swap) {
    switch (type) {
    case PlyType::Int8:
        return static_cast<double>(static_cast<std::int8_t>(*bytes));
    case PlyType::UInt8:
        return static_cast<double>(static_cast<std::uint8_t>(*bytes));
    case PlyType::Int16:
        return static_cast<double>(
            std::bit_cast<std::int16_t>(load_bits<std::uint16_t>(bytes, swap)));
    case PlyType::UInt16:
        return static_cast<double>(load_bits<std::uint16_t>(bytes, swap));
    case PlyType::Int32:
        return static_cast<double>(
            std::bit_cast<std::int32_t>(load_bits<std::uint32_t>(bytes, swap)));
    case PlyType::UInt32:
        return static_cast<double>(load_bits<std::uint32_t>(bytes, swap));
    case PlyType::Float32:
        return static_cast<double>(std::bit_cast<float>(load_bits<std::uint32_t>(bytes, swap)));
    case PlyType::Float64:
        return std::bit_cast<double>(load_bits<std::uint64_t>(bytes, swap));
    }
    return 0.0;
}

// "N bytes", or a note that the product does not even fit 64 bits.
[[nodiscard]] std::string byte_product_text(std::uint64_t count, std::uint64_t size) {
    std::uint64_t product = 0;
    if (__builtin_mul_overflow(count, size, &product)) {
        return "more than 2^64 bytes";
    }
    return std::to_string(product) + " bytes";
}

class PlyReader {
public:
    PlyReader(const MappedFile& file, Progress* progress)
        : file_(file), progress_(progress), header_(parse_ply_header(file)),
          swap_(header_.format != PlyFormat::Ascii &&
                (header_.format == PlyFormat::BinaryBigEndian) !=
                    (std::endian::native == std::endian::big)) {}

    [[nodiscard]] ScanFile read() {
        if (progress_ != nullptr) {
            progress_->begin_stage("parsing " + file_.path(), file_.size());
        }
        std::size_t vertex_element = header_.elements.size();
        for (std::size_t e = 0; e < header_.elements.size(); ++e) {
            if (header_.elements[e].name == "vertex") {
                vertex_element = e;
                break;
            }
        }
        if (vertex_element == header_.elements.size()) {
            throw at_line(header_.line_count, "the header declares no 'vertex' element: expected "
                                              "'element vertex COUNT' with x, y, z properties");
        }
        const PlyElement& vertex = header_.elements[vertex_element];
        const VertexLayout layout = make_vertex_layout(vertex, file_.path());
        if (vertex.count == 0) {
            throw at_line(vertex.header_line,
                          "the header declares 0 vertices: expected at least one point");
        }
        const bool vertex_is_last = vertex_element + 1 == header_.elements.size();

        ScanFile scan;
        scan.path = file_.path();
        scan.scanner = header_.scanner;
        scan.has_scanner = header_.has_scanner;
        if (header_.format == PlyFormat::Ascii) {
            read_ascii(vertex_element, layout, vertex_is_last, scan);
        } else if (layout.has_lists) {
            read_binary_serial(skip_binary_elements(vertex_element), vertex, layout, vertex_is_last,
                               scan);
        } else {
            read_binary_parallel(skip_binary_elements(vertex_element), vertex, layout,
                                 vertex_is_last, scan);
        }
        report(file_.size() - reported_bytes_); // what follows the vertices is not read
        return scan;
    }

private:
    void report(std::size_t bytes) {
        if (progress_ != nullptr) {
            progress_->advance(bytes);
        }
        reported_bytes_ += bytes;
    }

    [[nodiscard]] InputError at_line(std::uint64_t line, const std::string& what) const {
        return input_error_at({file_.path(), line, 0, true}, what);
    }
    [[nodiscard]] InputError at_byte(std::size_t offset, const std::string& what) const {
        return input_error_at({file_.path(), 0, offset, false}, what);
    }

    // The bytes of one item (of any element) starting at `offset`, walking its lists; throws
    // when the item runs past the end of the file.
    [[nodiscard]] std::size_t binary_item_size(const PlyElement& element, std::size_t offset,
                                               std::uint64_t item) const {
        std::size_t size = 0;
        const std::size_t file_size = file_.size();
        auto need = [&](std::size_t bytes) {
            if (bytes > file_size - offset || size > file_size - offset - bytes) {
                throw at_byte(offset, element.name + " " + std::to_string(item) +
                                          " (counting from 0) runs past the end of the file (" +
                                          std::to_string(file_size) +
                                          " bytes): the header declares more data than the "
                                          "file holds");
            }
        };
        for (const PlyProperty& property : element.properties) {
            if (!property.is_list) {
                need(ply_type_size(property.type));
                size += ply_type_size(property.type);
                continue;
            }
            const std::size_t count_size = ply_type_size(property.count_type);
            need(count_size);
            const double count =
                load_value(file_.data() + offset + size, property.count_type, swap_);
            if (count < 0.0) {
                throw at_byte(offset + size, element.name + " " + std::to_string(item) +
                                                 " has a negative list length for '" +
                                                 property.name + "'");
            }
            // NaN, or more items than any file holds: refused before the cast to size_t, which
            // is undefined for them. A length short of that is checked against the file below.
            if (!(count <= 1.0e15)) {
                throw at_byte(offset + size, element.name + " " + std::to_string(item) +
                                                 " has a list length of " + std::to_string(count) +
                                                 " for '" + property.name + "'");
            }
            size += count_size;
            const std::size_t list_bytes =
                static_cast<std::size_t>(count) * ply_type_size(property.type);
            need(list_bytes);
            size += list_bytes;
        }
        return size;
    }

    // Byte offset of the vertex data, past every element declared before it.
    [[nodiscard]] std::size_t skip_binary_elements(std::size_t vertex_element) const {
        std::size_t offset = header_.data_offset;
        for (std::size_t e = 0; e < vertex_element; ++e) {
            const PlyElement& element = header_.elements[e];
            if (element.has_lists()) {
                for (std::uint64_t item = 0; item < element.count; ++item) {
                    offset += binary_item_size(element, offset, item);
                }
                continue;
            }
            const std::size_t stride = element.fixed_stride();
            const std::size_t available = file_.size() - offset;
            if (stride != 0 && element.count > available / stride) {
                throw at_byte(offset, "header declares " + std::to_string(element.count) + " " +
                                          element.name + " elements of " + std::to_string(stride) +
                                          " bytes each (" +
                                          byte_product_text(element.count, stride) +
                                          ") after byte offset " + std::to_string(offset) +
                                          ", but the file has only " + std::to_string(available) +
                                          " bytes there");
            }
            offset += static_cast<std::size_t>(element.count) * stride;
        }
        return offset;
    }

    void gather(const char* bytes, const VertexLayout& layout, ChannelValues& values) const {
        for (const VertexProperty& property : layout.properties) {
            if (property.channel != Channel::Ignore) {
                values[static_cast<std::size_t>(property.channel)] =
                    load_value(bytes + property.offset, property.type, swap_);
            }
        }
    }

    void check_trailing_bytes(std::size_t data_end, const PlyElement& vertex,
                              std::size_t vertex_offset, bool vertex_is_last) const {
        // More data than declared is only fine when other elements (faces) follow.
        if (vertex_is_last && data_end != file_.size()) {
            throw at_byte(data_end,
                          "header declares " + std::to_string(vertex.count) +
                              " vertices after byte offset " + std::to_string(vertex_offset) +
                              " that end here, but the file has " +
                              std::to_string(file_.size() - data_end) +
                              " more bytes and no element follows: the header does not match "
                              "the data");
        }
    }

    void read_binary_parallel(std::size_t vertex_offset, const PlyElement& vertex,
                              const VertexLayout& layout, bool vertex_is_last, ScanFile& scan) {
        const std::size_t stride = layout.stride;
        const std::size_t available = file_.size() - vertex_offset;
        if (vertex.count > available / stride) {
            throw at_byte(vertex_offset,
                          "header declares " + std::to_string(vertex.count) + " vertices of " +
                              std::to_string(stride) + " bytes each (" +
                              byte_product_text(vertex.count, stride) + ") after byte offset " +
                              std::to_string(vertex_offset) + ", but the file has only " +
                              std::to_string(available) + " bytes there");
        }
        const auto count = static_cast<std::size_t>(vertex.count);
        check_trailing_bytes(vertex_offset + count * stride, vertex, vertex_offset, vertex_is_last);
        report(vertex_offset);

        VertexStore store(scan, layout, count);
        const char* const base = file_.data() + vertex_offset;
        ChannelValues first{};
        gather(base, layout, first);
        store.set_origin_from(first);

        const std::size_t chunk_vertices =
            std::max<std::size_t>(1, parse_chunk_bytes(count * stride) / stride);
        const std::size_t chunk_count = (count + chunk_vertices - 1) / chunk_vertices;
        std::vector<ParseFailure> failures(chunk_count);
        std::vector<double> max_colours(chunk_count, 0.0);
        tbb::parallel_for(std::size_t{0}, chunk_count, [&](std::size_t chunk) {
            if (progress_ != nullptr) {
                progress_->throw_if_cancelled();
            }
            const std::size_t begin = chunk * chunk_vertices;
            const std::size_t end = std::min(count, begin + chunk_vertices);
            ChannelValues values{};
            for (std::size_t i = begin; i < end; ++i) {
                gather(base + i * stride, layout, values);
                std::string problem = store.store(i, values, max_colours[chunk]);
                if (!problem.empty()) {
                    failures[chunk].set(vertex_offset + i * stride, std::move(problem));
                    return;
                }
            }
            if (progress_ != nullptr) {
                progress_->advance((end - begin) * stride);
            }
        });
        reported_bytes_ += count * stride;
        for (const ParseFailure& failure : failures) {
            if (failure.failed) {
                throw at_byte(failure.byte_offset, failure.message);
            }
        }
        store.finish(*std::max_element(max_colours.begin(), max_colours.end()));
    }

    // Vertices with list properties have no fixed size: walk them one after the other.
    void read_binary_serial(std::size_t vertex_offset, const PlyElement& vertex,
                            const VertexLayout& layout, bool vertex_is_last, ScanFile& scan) {
        // Each vertex takes at least its scalar bytes and list counts: bound the allocation
        // by what the file can hold, whatever the header claims.
        std::size_t minimum_bytes = 0;
        for (const VertexProperty& property : layout.properties) {
            minimum_bytes += ply_type_size(property.is_list ? property.count_type : property.type);
        }
        const std::size_t capacity = static_cast<std::size_t>(std::min<std::uint64_t>(
            vertex.count, (file_.size() - vertex_offset) / minimum_bytes + 1));
        VertexStore store(scan, layout, capacity);

        std::size_t offset = vertex_offset;
        double max_colour = 0.0;
        ChannelValues values{};
        for (std::uint64_t i = 0; i < vertex.count; ++i) {
            const std::size_t size = binary_item_size(vertex, offset, i);
            if (i >= capacity) {
                throw at_byte(offset, "the header declares " + std::to_string(vertex.count) +
                                          " vertices, more than the file can hold");
            }
            std::size_t field = offset;
            for (const VertexProperty& property : layout.properties) {
                if (property.is_list) {
                    const double length =
                        load_value(file_.data() + field, property.count_type, swap_);
                    if (!(length >= 0.0 && length <= 1.0e15)) {
                        throw at_byte(field, "vertex " + std::to_string(i) +
                                                 " has a list length of " + std::to_string(length));
                    }
                    field += ply_type_size(property.count_type) +
                             static_cast<std::size_t>(length) * ply_type_size(property.type);
                    continue;
                }
                if (property.channel != Channel::Ignore) {
                    values[static_cast<std::size_t>(property.channel)] =
                        load_value(file_.data() + field, property.type, swap_);
                }
                field += ply_type_size(property.type);
            }
            if (i == 0) {
                store.set_origin_from(values);
            }
            const std::string problem =
                store.store(static_cast<std::size_t>(i), values, max_colour);
            if (!problem.empty()) {
                throw at_byte(offset, problem);
            }
            offset += size;
            if (progress_ != nullptr && (i & 0xffff) == 0xffff) {
                progress_->throw_if_cancelled();
                report(offset - reported_bytes_);
            }
        }
        check_trailing_bytes(offset, vertex, vertex_offset, vertex_is_last);
        store.finish(max_colour);
    }

    void read_ascii(std::size_t vertex_element, const VertexLayout& layout, bool vertex_is_last,
                    ScanFile& scan);

    const MappedFile& file_;
    Progress* progress_;
    PlyHeader header_;
    bool swap_;
    std::size_t reported_bytes_ = 0;
};

// Ascii data: one element item per line, values separated by blanks.
class AsciiLines {
public:
    AsciiLines(const MappedFile& file, std::size_t offset, std::uint64_t lines_before)
        : begin_(file.data() + offset), end_(file.data() + file.size()),
          line_number_(lines_before) {}

    // The next line that is not blank, or false at the end of the data.
    [[nodiscard]] bool next(const char*& first, const char*& last) {
        while (begin_ < end_) {
            ++line_number_;
            const void* newline =
                std::memchr(begin_, '\n', static_cast<std::size_t>(end_ - begin_));
            first = begin_;
            last = newline == nullptr ? end_ : static_cast<const char*>(newline);
            begin_ = newline == nullptr ? end_ : last + 1;
            for (const char* p = first; p < last; ++p) {
                if (*p != ' ' && *p != '\t' && *p != '\r') {
                    return true;
                }
            }
        }
        return false;
    }
    [[nodiscard]] std::uint64_t line_number() const { return line_number_; }
    [[nodiscard]] std::size_t consumed(const char* data) const {
        return static_cast<std::size_t>(begin_ - data);
    }

private:
    const char* begin_;
    const char* end_;
    std::uint64_t line_number_;
};

[[nodiscard]] bool is_blank(char c) {
    return c == ' ' || c == '\t' || c == '\r';
}

[[nodiscard]] std::size_t count_words(const char* first, const char* last) {
    std::size_t words = 0;
    bool in_word = false;
    for (const char* p = first; p < last; ++p) {
        const bool blank = is_blank(*p);
        words += !blank && !in_word;
        in_word = !blank;
    }
    return words;
}

void PlyReader::read_ascii(std::size_t vertex_element, const VertexLayout& layout,
                           bool vertex_is_last, ScanFile& scan) {
    AsciiLines lines(file_, header_.data_offset, header_.line_count);
    const char* first = nullptr;
    const char* last = nullptr;
    for (std::size_t e = 0; e < vertex_element; ++e) {
        const PlyElement& element = header_.elements[e];
        for (std::uint64_t item = 0; item < element.count; ++item) {
            if (!lines.next(first, last)) {
                throw at_line(lines.line_number(),
                              "the header declares " + std::to_string(element.count) + " '" +
                                  element.name + "' elements, but the data ends after " +
                                  std::to_string(item));
            }
        }
    }

    const PlyElement& vertex = header_.elements[vertex_element];
    // A vertex line holds at least one character and one separator per scalar: bound the
    // allocation by what the file can hold, whatever the header claims.
    const std::size_t remaining = file_.size() - lines.consumed(file_.data());
    const std::size_t capacity = static_cast<std::size_t>(
        std::min<std::uint64_t>(vertex.count, remaining / (2 * layout.scalar_count - 1) + 1));
    VertexStore store(scan, layout, capacity);
    const std::string expected_values =
        layout.has_lists ? "values for " + std::to_string(layout.properties.size()) +
                               " properties (lists with their lengths)"
                         : std::to_string(layout.properties.size()) + " values";

    double max_colour = 0.0;
    ChannelValues values{};
    for (std::uint64_t i = 0; i < vertex.count; ++i) {
        if (!lines.next(first, last) || i >= capacity) {
            throw at_line(lines.line_number(),
                          "the header declares " + std::to_string(vertex.count) +
                              " vertices, but the data ends after " + std::to_string(i) +
                              ": expected one line per vertex");
        }
        const std::uint64_t line = lines.line_number();
        auto wrong_count = [&] {
            return at_line(line, "vertex " + std::to_string(i) + " (counting from 0): expected " +
                                     expected_values + ", found " +
                                     std::to_string(count_words(first, last)));
        };
        const char* p = first;
        // The next value on the line; throws when the line has too few or a non-number.
        auto next_value = [&](const std::string& property_name) {
            while (p < last && is_blank(*p)) {
                ++p;
            }
            if (p == last) {
                throw wrong_count();
            }
            double value = 0.0;
            const char* after = parse_double(p, last, value);
            if (after == nullptr || (after < last && !is_blank(*after))) {
                throw at_line(line, "vertex " + std::to_string(i) +
                                        " (counting from 0): "
                                        "non-numeric value '" +
                                        token_at(p, last) + "' for property '" + property_name +
                                        "': expected a number");
            }
            p = after;
            return value;
        };
        for (std::size_t k = 0; k < layout.properties.size(); ++k) {
            const VertexProperty& property = layout.properties[k];
            const std::string& name = vertex.properties[k].name;
            const double value = next_value(name);
            if (!property.is_list) {
                if (property.channel != Channel::Ignore) {
                    values[static_cast<std::size_t>(property.channel)] = value;
                }
                continue;
            }
            if (!(value >= 0.0 && value == std::floor(value))) {
                throw at_line(line, "vertex " + std::to_string(i) +
                                        " (counting from 0): the "
                                        "list length of '" +
                                        name +
                                        "' is not a whole number: expected a length, then the "
                                        "list's values");
            }
            for (double item = 0.0; item < value; item += 1.0) {
                (void)next_value(name);
            }
        }
        while (p < last && is_blank(*p)) {
            ++p;
        }
        if (p != last) {
            throw wrong_count();
        }
        if (i == 0) {
            store.set_origin_from(values);
        }
        const std::string problem = store.store(static_cast<std::size_t>(i), values, max_colour);
        if (!problem.empty()) {
            throw at_line(line, problem);
        }
        if (progress_ != nullptr && (i & 0xffff) == 0xffff) {
            progress_->throw_if_cancelled();
            report(lines.consumed(file_.data()) - reported_bytes_);
        }
    }
    if (vertex_is_last && lines.next(first, last)) {
        throw at_line(lines.line_number(),
                      "data after the last vertex: the header declares " +
                          std::to_string(vertex.count) +
                          " vertices and no element follows, but the file holds more lines");
    }
    store.finish(max_colour);
}

} // namespace

ScanFile read_ply_scan(const MappedFile& file, Progress* progress) {
    return PlyReader(file, progress).read();
}

} // namespace lfprobe::detail
