// The text scan formats. The prefix up to the first point (header lines, the .pts count) is
// read serially: it fixes the column layout and the file's origin. The rest is cut into chunks
// at line boundaries whose lines are counted, then parsed in parallel, each into its own slice
// of the file's arrays.
#include "text_scan_reader.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstring>
#include <optional>
#include <string_view>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include "lfprobe/error.hpp"
#include "lfprobe/huge_pages.hpp"
#include "scan_parsing.hpp"

namespace lfprobe::detail {

namespace {

enum class TextDialect { Xyz, Pts };

// Everything the serial pass learns before the first point line.
struct TextPrefix {
    std::size_t data_begin = 0;    // byte offset of the first point line
    std::vector<Channel> channels; // one per column
    ChannelLayout layout;
    glm::dvec3 origin{0.0};
    glm::dvec3 scanner{0.0};
    bool has_scanner = false;
    std::uint64_t declared_points = 0; // .pts counts seen before the first point
    std::uint64_t first_count_line = 0;
};

// One chunk's share of the points: its slice of the file's arrays, which it fills in place
// (a copy from per-chunk arrays into the file's cost a tenth of the parse, most of it in the
// page faults of memory written twice). Colours stay raw sRGB values until decoded.
struct ChunkPoints {
    std::size_t first = 0;    // index of the chunk's first point in the file's arrays
    std::size_t capacity = 0; // the chunk's lines: it cannot hold more points
    std::size_t count = 0;    // the points it parsed
    double max_colour = 0.0;
    bool colours_decoded = false; // linear already (decode_srgb_in_place)
    std::uint64_t declared_points = 0;
    ParseFailure failure;
};

// The file's arrays, sized for every line to be a point; null where the file has no such
// channel.
struct PointArrays {
    glm::vec3* positions = nullptr;
    glm::vec3* colours = nullptr;
    glm::vec3* normals = nullptr;
    float* intensities = nullptr;
};

[[nodiscard]] std::string in_quotes(std::string_view text) {
    std::string out;
    out.reserve(text.size() + 2);
    out.push_back('\'');
    out.append(printable(text.substr(0, 64)));
    out.push_back('\'');
    return out;
}

[[nodiscard]] std::string column_label(std::size_t column, const std::vector<Channel>& channels) {
    std::string label = "column " + std::to_string(column + 1);
    if (column < channels.size() && channels[column] != Channel::Ignore) {
        label += std::string(" (") + channel_name(channels[column]) + ")";
    }
    return label;
}

// The text after a comment marker ('#', '//', '%' or ';' after optional blanks), or nullopt
// when the line is not a comment.
[[nodiscard]] std::optional<std::string_view> comment_body(std::string_view line) {
    std::size_t i = 0;
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) {
        ++i;
    }
    if (i < line.size() && (line[i] == '#' || line[i] == '%' || line[i] == ';')) {
        return line.substr(i + 1);
    }
    if (i + 1 < line.size() && line[i] == '/' && line[i + 1] == '/') {
        return line.substr(i + 2);
    }
    return std::nullopt;
}

[[nodiscard]] std::vector<std::string_view> split_fields(std::string_view line) {
    std::vector<std::string_view> fields;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && is_separator(line[i])) {
            ++i;
        }
        const std::size_t start = i;
        while (i < line.size() && !is_separator(line[i])) {
            ++i;
        }
        if (i > start) {
            fields.push_back(line.substr(start, i - start));
        }
    }
    return fields;
}

[[nodiscard]] std::optional<double> number_from(std::string_view field) {
    double value = 0.0;
    const char* end = parse_double(field.data(), field.data() + field.size(), value);
    if (end != field.data() + field.size()) {
        return std::nullopt;
    }
    return value;
}

[[nodiscard]] std::optional<std::uint64_t> count_from(std::string_view field) {
    std::uint64_t value = 0;
    const auto [end, error] = std::from_chars(field.data(), field.data() + field.size(), value);
    if (error != std::errc() || end != field.data() + field.size()) {
        return std::nullopt;
    }
    return value;
}

// Column names of a header line, or nullopt when the line does not name x, y and z.
// Unknown names become ignored columns.
[[nodiscard]] std::optional<std::vector<Channel>>
channels_from_header(const std::vector<std::string_view>& fields) {
    std::vector<Channel> channels;
    bool x = false;
    bool y = false;
    bool z = false;
    for (std::string_view field : fields) {
        const Channel channel = channel_from_name(field).value_or(Channel::Ignore);
        x = x || channel == Channel::X;
        y = y || channel == Channel::Y;
        z = z || channel == Channel::Z;
        channels.push_back(channel);
    }
    if (!(x && y && z)) {
        return std::nullopt;
    }
    return channels;
}

// The layout that the column count implies when nothing names the columns.
[[nodiscard]] std::optional<std::vector<Channel>> channels_from_count(std::size_t count,
                                                                      TextDialect dialect) {
    using C = Channel;
    switch (count) {
    case 3:
        return std::vector<C>{C::X, C::Y, C::Z};
    case 4:
        return std::vector<C>{C::X, C::Y, C::Z, C::Intensity};
    case 6:
        return std::vector<C>{C::X, C::Y, C::Z, C::Red, C::Green, C::Blue};
    case 7:
        return std::vector<C>{C::X, C::Y, C::Z, C::Intensity, C::Red, C::Green, C::Blue};
    case 9:
        if (dialect == TextDialect::Xyz) {
            return std::vector<C>{C::X,    C::Y,       C::Z,       C::Red,    C::Green,
                                  C::Blue, C::NormalX, C::NormalY, C::NormalZ};
        }
        break;
    case 10:
        if (dialect == TextDialect::Xyz) {
            return std::vector<C>{C::X,     C::Y,    C::Z,       C::Intensity, C::Red,
                                  C::Green, C::Blue, C::NormalX, C::NormalY,   C::NormalZ};
        }
        break;
    default:
        break;
    }
    return std::nullopt;
}

[[nodiscard]] std::string accepted_counts(TextDialect dialect) {
    std::string text = "3 (x y z), 4 (x y z i), 6 (x y z r g b), 7 (x y z i r g b)";
    if (dialect == TextDialect::Xyz) {
        text += ", 9 (x y z r g b nx ny nz), 10 (x y z i r g b nx ny nz)";
    }
    return text;
}

// Reads ScanReadOptions::columns.
[[nodiscard]] std::vector<Channel> channels_from_option(const std::string& path,
                                                        const std::string& columns) {
    std::vector<Channel> channels;
    for (std::string_view name : split_fields(columns)) {
        const std::optional<Channel> channel = channel_from_name(name);
        if (!channel) {
            throw InputError(path + ": options.columns names an unknown column " + in_quotes(name) +
                             ": expected x y z r g b i nx ny nz, or _ for a column to ignore");
        }
        channels.push_back(*channel);
    }
    ChannelLayout layout;
    if (const std::string problem = make_channel_layout(channels, layout); !problem.empty()) {
        throw InputError(path + ": options.columns '" + columns + "' is not usable: " + problem);
    }
    return channels;
}

class PrefixReader {
public:
    PrefixReader(const MappedFile& file, const std::string& columns, TextDialect dialect)
        : file_(file), columns_(columns), dialect_(dialect) {}

    [[nodiscard]] TextPrefix read() {
        TextPrefix prefix;
        const std::string_view text = file_.view();
        // Windows tools often start UTF-8 text with a byte order mark; it is not data.
        std::size_t position = text.starts_with("\xEF\xBB\xBF") ? 3 : 0;
        std::uint64_t line_number = 0;
        bool seen_count = false;
        while (position < text.size()) {
            ++line_number;
            const std::size_t newline = text.find('\n', position);
            const std::size_t line_end = newline == std::string_view::npos ? text.size() : newline;
            const std::size_t next = newline == std::string_view::npos ? text.size() : newline + 1;
            const std::string_view line = text.substr(position, line_end - position);

            if (const std::optional<std::string_view> body = comment_body(line)) {
                read_comment(split_fields(*body), line_number, prefix);
                position = next;
                continue;
            }
            const std::vector<std::string_view> fields = split_fields(line);
            if (fields.empty()) {
                position = next;
                continue;
            }
            if (!number_from(fields[0])) {
                if (seen_count) {
                    fail(line_number, "non-numeric field " + in_quotes(fields[0]) +
                                          " in column 1: expected a number");
                }
                // A header line before the data: it may name the columns.
                if (std::optional<std::vector<Channel>> named = channels_from_header(fields)) {
                    header_channels_ = std::move(named);
                    header_line_ = line_number;
                }
                position = next;
                continue;
            }
            if (dialect_ == TextDialect::Pts) {
                if (fields.size() == 1) {
                    const std::optional<std::uint64_t> count = count_from(fields[0]);
                    if (!count) {
                        fail(line_number, "expected a point count (a single whole number), found " +
                                              in_quotes(fields[0]));
                    }
                    if (!seen_count) {
                        prefix.first_count_line = line_number;
                    }
                    prefix.declared_points += *count;
                    seen_count = true;
                    position = next;
                    continue;
                }
                if (!seen_count) {
                    fail(line_number, "expected the point count (a single whole number) on the "
                                      "first data line of a .pts file, found " +
                                          std::to_string(fields.size()) + " fields");
                }
            }
            read_first_point(fields, line_number, prefix);
            prefix.data_begin = position;
            return prefix;
        }

        const std::uint64_t last_line = std::max<std::uint64_t>(line_number, 1);
        if (dialect_ == TextDialect::Pts && seen_count) {
            if (prefix.declared_points == 0) {
                fail(prefix.first_count_line, "the file declares 0 points and holds none: "
                                              "expected at least one point");
            }
            fail(prefix.first_count_line, "the point count line declares " +
                                              std::to_string(prefix.declared_points) +
                                              " points, but the file holds 0");
        }
        fail(last_line, std::string("no data lines: expected lines of ") +
                            (dialect_ == TextDialect::Pts ? "a point count, then points of " : "") +
                            accepted_counts(dialect_) + " numbers");
    }

private:
    [[noreturn]] void fail(std::uint64_t line, const std::string& what) const {
        throw input_error_at({file_.path(), line, 0, true}, what);
    }

    void read_comment(const std::vector<std::string_view>& fields, std::uint64_t line_number,
                      TextPrefix& prefix) {
        if (fields.size() == 4 && equals_ignoring_case(fields[0], "scanner")) {
            const std::optional<double> x = number_from(fields[1]);
            const std::optional<double> y = number_from(fields[2]);
            const std::optional<double> z = number_from(fields[3]);
            if (x && y && z && std::isfinite(*x) && std::isfinite(*y) && std::isfinite(*z)) {
                prefix.scanner = glm::dvec3(*x, *y, *z);
                prefix.has_scanner = true;
            }
            return;
        }
        // CloudCompare writes "//X,Y,Z,R,G,B"; others "# x y z". A prose comment that merely
        // mentions x, y and z must not become a column map, hence: first name x.
        if (!fields.empty() && channel_from_name(fields[0]) == Channel::X) {
            if (std::optional<std::vector<Channel>> named = channels_from_header(fields)) {
                header_channels_ = std::move(named);
                header_line_ = line_number;
            }
        }
    }

    void read_first_point(const std::vector<std::string_view>& fields, std::uint64_t line_number,
                          TextPrefix& prefix) {
        std::vector<double> values;
        for (std::size_t column = 0; column < fields.size(); ++column) {
            const std::optional<double> value = number_from(fields[column]);
            if (!value) {
                fail(line_number, "non-numeric field " + in_quotes(fields[column]) + " in column " +
                                      std::to_string(column + 1) + ": expected a number");
            }
            values.push_back(*value);
        }

        if (!columns_.empty()) {
            prefix.channels = channels_from_option(file_.path(), columns_);
            if (prefix.channels.size() != fields.size()) {
                fail(line_number,
                     "options.columns names " + std::to_string(prefix.channels.size()) +
                         " columns, but this line has " + std::to_string(fields.size()));
            }
        } else if (header_channels_) {
            prefix.channels = *header_channels_;
            if (prefix.channels.size() != fields.size()) {
                fail(line_number, "the header on line " + std::to_string(header_line_) + " names " +
                                      std::to_string(prefix.channels.size()) +
                                      " columns, but this line has " +
                                      std::to_string(fields.size()));
            }
        } else if (std::optional<std::vector<Channel>> guessed =
                       channels_from_count(fields.size(), dialect_)) {
            prefix.channels = std::move(*guessed);
        } else {
            fail(line_number, "cannot tell what " + std::to_string(fields.size()) +
                                  " columns hold: expected " + accepted_counts(dialect_) +
                                  " columns, a header line naming them, or options.columns");
        }
        if (const std::string problem = make_channel_layout(prefix.channels, prefix.layout);
            !problem.empty()) {
            fail(header_line_, "the header line's column names are not usable: " + problem);
        }

        glm::dvec3 first{0.0};
        for (int axis = 0; axis < 3; ++axis) {
            const auto column = static_cast<std::size_t>(
                prefix.layout.index(static_cast<Channel>(static_cast<int>(Channel::X) + axis)));
            if (!std::isfinite(values[column])) {
                fail(line_number, "NaN or infinite coordinate " + in_quotes(fields[column]) +
                                      " in " + column_label(column, prefix.channels) +
                                      ": expected a finite number");
            }
            first[axis] = values[column];
        }
        // Whole units keep the origin exact and readable; the remainder fits float32 well.
        prefix.origin = glm::dvec3(std::round(first.x), std::round(first.y), std::round(first.z));
    }

    const MappedFile& file_;
    const std::string& columns_;
    TextDialect dialect_;
    std::optional<std::vector<Channel>> header_channels_;
    std::uint64_t header_line_ = 0;
};

// Where column `column` of the point line at `line` starts: the columns of a line that parsed
// are runs of non-separators. Only for messages, so the parse need not keep every start.
[[nodiscard]] const char* column_start(const char* line, const char* end, std::size_t column) {
    const char* p = line;
    for (std::size_t i = 0;; ++i) {
        while (p < end && is_separator(*p)) {
            ++p;
        }
        if (i == column || p == end || *p == '\n') {
            return p;
        }
        while (p < end && *p != '\n' && !is_separator(*p)) {
            ++p;
        }
    }
}

// Parses the point lines of [range.begin, range.end) into the chunk's slice of `arrays`. Stops
// at the first problem, which it records with its byte offset rather than throwing. `kEnd`:
// RangeEnd::Newline where the range ends with a newline (every chunk but a last one whose file
// does not), which ends every run the loops scan.
template <RangeEnd kEnd>
void parse_chunk(const char* data, ByteRange range, const TextPrefix& prefix, TextDialect dialect,
                 const PointArrays& arrays, ChunkPoints& out) {
    constexpr bool kNewline = kEnd == RangeEnd::Newline;
    const std::size_t column_count = prefix.channels.size();
    const ChannelLayout& layout = prefix.layout;
    const auto ix = static_cast<std::size_t>(layout.index(Channel::X));
    const auto iy = static_cast<std::size_t>(layout.index(Channel::Y));
    const auto iz = static_cast<std::size_t>(layout.index(Channel::Z));
    const std::array<int, 3> colour_columns{
        layout.index(Channel::Red), layout.index(Channel::Green), layout.index(Channel::Blue)};
    const std::array<int, 3> normal_columns{layout.index(Channel::NormalX),
                                            layout.index(Channel::NormalY),
                                            layout.index(Channel::NormalZ)};
    const int intensity_column = layout.index(Channel::Intensity);

    // A line's values on the stack for the usual column counts.
    constexpr std::size_t kStackColumns = 16;
    std::array<double, kStackColumns> stack_values{};
    std::vector<double> heap_values(column_count > kStackColumns ? column_count : 0);
    double* const values = column_count > kStackColumns ? heap_values.data() : stack_values.data();
    const char* const end = data + range.end;
    const char* p = data + range.begin;
    std::size_t index = out.first;
    const std::size_t limit = out.first + out.capacity;
    double max_colour = 0.0;
    auto fail = [&](const char* where, std::string what) {
        out.failure.set(static_cast<std::size_t>(where - data), std::move(what));
    };
    auto quoted_column = [&](const char* line, std::size_t column) {
        return in_quotes(token_at(column_start(line, end, column), end)) + " in " +
               column_label(column, prefix.channels);
    };

    while (p < end) {
        const char* const line_start = p;
        while ((kNewline || p < end) && (*p == ' ' || *p == '\t')) {
            ++p;
        }
        if (p < end &&
            (*p == '#' || *p == '%' || *p == ';' || (*p == '/' && p + 1 < end && p[1] == '/'))) {
            const void* newline = std::memchr(p, '\n', static_cast<std::size_t>(end - p));
            p = newline == nullptr ? end : static_cast<const char*>(newline) + 1;
            continue;
        }

        std::size_t column = 0;
        while (true) {
            while ((kNewline || p < end) && is_separator(*p)) {
                ++p;
            }
            if ((!kNewline && p == end) || *p == '\n') {
                break;
            }
            double value = 0.0;
            const char* after = parse_double<kEnd>(p, end, value);
            if (after == nullptr ||
                ((kNewline || after < end) && *after != '\n' && !is_separator(*after))) {
                fail(p, "non-numeric field " + in_quotes(token_at(p, end)) + " in " +
                            column_label(column, prefix.channels) + ": expected a number");
                out.count = index - out.first;
                return;
            }
            if (column < column_count) {
                values[column] = value;
            }
            ++column;
            p = after;
        }
        if (p < end) {
            ++p; // the newline
        }
        if (column == 0) {
            continue; // blank line
        }
        if (column != column_count) {
            if (dialect == TextDialect::Pts && column == 1) {
                // Leica PTS: a count line starts another block of points.
                std::uint64_t count = 0;
                const std::string token = token_at(column_start(line_start, end, 0), end);
                const auto [count_end, error] =
                    std::from_chars(token.data(), token.data() + token.size(), count);
                if (error == std::errc() && count_end == token.data() + token.size()) {
                    out.declared_points += count;
                    continue;
                }
                fail(line_start, "expected a point count (a single whole number) or " +
                                     std::to_string(column_count) + " columns, found " +
                                     in_quotes(token));
                break;
            }
            fail(line_start, "expected " + std::to_string(column_count) + " columns, found " +
                                 std::to_string(column));
            break;
        }
        if (index == limit) { // cannot happen: the chunk's lines were counted
            fail(line_start, "more points than lines in a chunk (a bug in the reader)");
            break;
        }

        // Checking the float32 result catches NaN, infinities, doubles that overflowed and
        // coordinates too far from the origin for float, all at once.
        const glm::vec3 position(static_cast<float>(values[ix] - prefix.origin.x),
                                 static_cast<float>(values[iy] - prefix.origin.y),
                                 static_cast<float>(values[iz] - prefix.origin.z));
        if (!std::isfinite(position.x) || !std::isfinite(position.y) ||
            !std::isfinite(position.z)) {
            const std::size_t bad = !std::isfinite(position.x)   ? ix
                                    : !std::isfinite(position.y) ? iy
                                                                 : iz;
            const std::string where = quoted_column(line_start, bad);
            fail(line_start,
                 std::isfinite(values[bad])
                     ? "coordinate " + where + " is too far from the file's first point for float32"
                     : "NaN or infinite coordinate " + where + ": expected a finite number");
            break;
        }
        arrays.positions[index] = position;

        if (arrays.colours != nullptr) {
            glm::vec3 colour;
            bool in_range = true;
            for (int c = 0; c < 3; ++c) {
                const double value = values[colour_columns[static_cast<std::size_t>(c)]];
                in_range = in_range && value >= 0.0 && value <= 255.0;
                max_colour = std::max(max_colour, value);
                colour[c] = static_cast<float>(value);
            }
            if (!in_range) {
                for (int c = 0; c < 3; ++c) {
                    const auto col =
                        static_cast<std::size_t>(colour_columns[static_cast<std::size_t>(c)]);
                    if (!(values[col] >= 0.0 && values[col] <= 255.0)) {
                        fail(line_start, "bad colour value " + quoted_column(line_start, col) +
                                             ": expected integers 0-255 or floats 0-1");
                        break;
                    }
                }
                break;
            }
            arrays.colours[index] = colour;
        }
        if (arrays.intensities != nullptr) {
            const auto col = static_cast<std::size_t>(intensity_column);
            const auto intensity = static_cast<float>(values[col]);
            if (!std::isfinite(intensity)) {
                fail(line_start, "non-finite value " + quoted_column(line_start, col) +
                                     ": expected a finite number");
                break;
            }
            arrays.intensities[index] = intensity;
        }
        if (arrays.normals != nullptr) {
            std::array<double, 3> normal{};
            bool finite = true;
            for (std::size_t c = 0; c < 3; ++c) {
                const auto col = static_cast<std::size_t>(normal_columns[c]);
                normal[c] = values[col];
                if (!std::isfinite(normal[c])) {
                    fail(line_start, "non-finite value " + quoted_column(line_start, col) +
                                         ": expected a finite number");
                    finite = false;
                    break;
                }
            }
            if (!finite) {
                break;
            }
            arrays.normals[index] = unit_normal(normal[0], normal[1], normal[2]);
        }
        ++index;
    }
    out.count = index - out.first;
    out.max_colour = max_colour;
}

// The newlines in [first, last). SSE2 (every x86-64 has it): sixteen bytes compared at once,
// the matches summed in byte counters that are widened before they can overflow; elsewhere
// eight bytes at a time in a 64-bit word. Either runs at memory speed, where a byte loop took
// a tenth of a parse.
[[nodiscard]] std::size_t count_newlines(const char* first, const char* last) {
    std::size_t count = 0;
#if defined(__SSE2__)
    const __m128i newline = _mm_set1_epi8('\n');
    while (last - first >= 16) {
        // At most 255 blocks of 16 bytes before the byte counters are summed.
        const std::ptrdiff_t blocks = std::min<std::ptrdiff_t>((last - first) / 16, 255);
        __m128i counters = _mm_setzero_si128();
        for (std::ptrdiff_t b = 0; b < blocks; ++b, first += 16) {
            const __m128i bytes = _mm_loadu_si128(reinterpret_cast<const __m128i*>(first));
            // A match is 0xFF, minus one: subtracting adds one to the byte's counter.
            counters = _mm_sub_epi8(counters, _mm_cmpeq_epi8(bytes, newline));
        }
        const __m128i sums = _mm_sad_epu8(counters, _mm_setzero_si128());
        count += static_cast<std::size_t>(_mm_cvtsi128_si64(sums)) +
                 static_cast<std::size_t>(_mm_cvtsi128_si64(_mm_unpackhi_epi64(sums, sums)));
    }
#else
    constexpr std::uint64_t kNewlines = 0x0A0A0A0A0A0A0A0Aull;
    constexpr std::uint64_t kLow7 = 0x7F7F7F7F7F7F7F7Full;
    constexpr std::uint64_t kHigh = 0x8080808080808080ull;
    for (; last - first >= 8; first += 8) {
        std::uint64_t word = 0;
        std::memcpy(&word, first, sizeof(word));
        const std::uint64_t x = word ^ kNewlines;
        const std::uint64_t nonzero = ((x & kLow7) + kLow7) | x;
        // One bit per newline byte, moved to the byte's bottom and summed by a multiply.
        const std::uint64_t ones = (~nonzero & kHigh) >> 7;
        count += static_cast<std::size_t>((ones * 0x0101010101010101ull) >> 56);
    }
#endif
    return count + static_cast<std::size_t>(std::count(first, last, '\n'));
}

// Moves each chunk's points down to follow the previous chunk's, where lines that held no
// point (comments, blank lines, .pts count lines) left gaps, and trims the array to the points.
template <class T>
void close_gaps(std::vector<T>& values, const std::vector<ChunkPoints>& chunks) {
    std::size_t next = 0;
    for (const ChunkPoints& chunk : chunks) {
        if (chunk.first != next) {
            const auto from = values.begin() + static_cast<std::ptrdiff_t>(chunk.first);
            std::copy(from, from + static_cast<std::ptrdiff_t>(chunk.count),
                      values.begin() + static_cast<std::ptrdiff_t>(next));
        }
        next += chunk.count;
    }
    values.resize(next);
}

[[nodiscard]] ScanFile read_text_scan(const MappedFile& file, const std::string& columns,
                                      Progress* progress, TextDialect dialect) {
    const std::string& path = file.path();
    if (progress != nullptr) {
        progress->begin_stage("parsing " + path, file.size());
    }
    const TextPrefix prefix = PrefixReader(file, columns, dialect).read();
    if (progress != nullptr) {
        progress->advance(prefix.data_begin);
        progress->throw_if_cancelled();
    }

    const std::vector<ByteRange> ranges =
        split_at_lines(file.data(), prefix.data_begin, file.size(),
                       parse_chunk_bytes(file.size() - prefix.data_begin));
    // Every line may be a point: each chunk's lines, counted first, give it its slice of the
    // file's arrays (a pass at memory speed, which also maps the file's pages in).
    std::vector<ChunkPoints> chunks(ranges.size());
    tbb::parallel_for(std::size_t{0}, ranges.size(), [&](std::size_t i) {
        const char* first = file.data() + ranges[i].begin;
        const char* last = file.data() + ranges[i].end;
        chunks[i].capacity =
            count_newlines(first, last) + (last > first && last[-1] != '\n' ? 1 : 0);
    });
    std::size_t lines = 0;
    for (ChunkPoints& chunk : chunks) {
        chunk.first = lines;
        lines += chunk.capacity;
    }

    ScanFile scan;
    scan.path = path;
    scan.origin = prefix.origin;
    scan.scanner = prefix.scanner;
    scan.has_scanner = prefix.has_scanner;
    // Sized side by side: each array's pages are zeroed as it is sized, one thread an array.
    tbb::parallel_invoke([&] { resize_in_huge_pages(scan.positions, lines); },
                         [&] {
                             if (prefix.layout.has_colour) {
                                 resize_in_huge_pages(scan.colors, lines);
                             }
                         },
                         [&] {
                             if (prefix.layout.has_normal) {
                                 resize_in_huge_pages(scan.normals, lines);
                             }
                             if (prefix.layout.has_intensity) {
                                 resize_in_huge_pages(scan.intensities, lines);
                             }
                         });
    PointArrays arrays;
    arrays.positions = scan.positions.data();
    if (prefix.layout.has_colour) {
        arrays.colours = scan.colors.data();
    }
    if (prefix.layout.has_normal) {
        arrays.normals = scan.normals.data();
    }
    if (prefix.layout.has_intensity) {
        arrays.intensities = scan.intensities.data();
    }

    tbb::parallel_for(std::size_t{0}, ranges.size(), [&](std::size_t i) {
        if (progress != nullptr) {
            progress->throw_if_cancelled();
        }
        ChunkPoints& chunk = chunks[i];
        const ByteRange range = ranges[i];
        if (file.data()[range.end - 1] == '\n') {
            parse_chunk<RangeEnd::Newline>(file.data(), range, prefix, dialect, arrays, chunk);
        } else {
            parse_chunk<RangeEnd::Bounded>(file.data(), range, prefix, dialect, arrays, chunk);
        }
        // A value above 1 makes the whole file's colours 0-255 integers: decoded now, while
        // they are in cache; the rest once the file's largest value is known.
        if (arrays.colours != nullptr && chunk.max_colour > 1.0 && !chunk.failure.failed) {
            decode_srgb_in_place(arrays.colours + chunk.first, chunk.count, chunk.max_colour);
            chunk.colours_decoded = true;
        }
        if (progress != nullptr) {
            progress->advance(ranges[i].end - ranges[i].begin);
        }
    });

    ParseFailure failure;
    for (const ChunkPoints& chunk : chunks) {
        if (chunk.failure.failed) {
            failure.set(chunk.failure.byte_offset, chunk.failure.message);
        }
    }
    if (failure.failed) {
        throw input_error_at(
            {path, line_number_at(file.data(), failure.byte_offset), failure.byte_offset, true},
            failure.message);
    }

    std::size_t points = 0;
    std::uint64_t declared_points = prefix.declared_points;
    double max_colour = 0.0;
    for (const ChunkPoints& chunk : chunks) {
        points += chunk.count;
        declared_points += chunk.declared_points;
        max_colour = std::max(max_colour, chunk.max_colour);
    }
    if (dialect == TextDialect::Pts && declared_points != points) {
        throw input_error_at({path, prefix.first_count_line, 0, true},
                             "the point count lines declare " + std::to_string(declared_points) +
                                 " points, but the file holds " + std::to_string(points));
    }

    if (arrays.colours != nullptr) {
        tbb::parallel_for(std::size_t{0}, chunks.size(), [&](std::size_t i) {
            const ChunkPoints& chunk = chunks[i];
            if (!chunk.colours_decoded) {
                decode_srgb_in_place(arrays.colours + chunk.first, chunk.count, max_colour);
            }
        });
    }
    if (points != lines) {
        close_gaps(scan.positions, chunks);
        if (arrays.colours != nullptr) {
            close_gaps(scan.colors, chunks);
        }
        if (arrays.normals != nullptr) {
            close_gaps(scan.normals, chunks);
        }
        if (arrays.intensities != nullptr) {
            close_gaps(scan.intensities, chunks);
        }
    }
    return scan;
}

} // namespace

ScanFile read_xyz_scan(const MappedFile& file, const std::string& columns, Progress* progress) {
    return read_text_scan(file, columns, progress, TextDialect::Xyz);
}

ScanFile read_pts_scan(const MappedFile& file, const std::string& columns, Progress* progress) {
    return read_text_scan(file, columns, progress, TextDialect::Pts);
}

} // namespace lfprobe::detail
