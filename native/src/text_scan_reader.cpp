// The text scan formats. The prefix up to the first point (header lines, the .pts count) is
// read serially: it fixes the column layout and the file's origin. The rest is cut into chunks
// at line boundaries that are parsed in parallel, each into its own arrays, and concatenated.
#include "text_scan_reader.hpp"

#include <charconv>
#include <cmath>
#include <optional>
#include <string_view>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lfprobe/error.hpp"
#include "scan_parsing.hpp"

namespace lfprobe::detail {

namespace {

enum class TextDialect { Xyz, Pts };

// Everything the serial pass learns before the first point line.
struct TextPrefix {
    std::size_t data_begin = 0; // byte offset of the first point line
    std::size_t first_line_bytes = 0;
    std::vector<Channel> channels; // one per column
    ChannelLayout layout;
    glm::dvec3 origin{0.0};
    glm::dvec3 scanner{0.0};
    bool has_scanner = false;
    std::uint64_t declared_points = 0; // .pts counts seen before the first point
    std::uint64_t first_count_line = 0;
};

// One chunk's share of the points, colours still raw sRGB values.
struct ChunkPoints {
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> colours;
    std::vector<glm::vec3> normals;
    std::vector<float> intensities;
    double max_colour = 0.0;
    bool colours_decoded = false; // linear already (decode_srgb_in_place)
    std::uint64_t declared_points = 0;
    ParseFailure failure;
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
            prefix.first_line_bytes = next - position;
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

// Parses the point lines of [range.begin, range.end) into `out`. Stops at the first problem,
// which it records with its byte offset rather than throwing.
void parse_chunk(const char* data, ByteRange range, const TextPrefix& prefix, TextDialect dialect,
                 ChunkPoints& out) {
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

    const std::size_t expected_points =
        (range.end - range.begin) / std::max<std::size_t>(prefix.first_line_bytes, 8) + 16;
    out.positions.reserve(expected_points + expected_points / 8);
    if (layout.has_colour) {
        out.colours.reserve(out.positions.capacity());
    }
    if (layout.has_normal) {
        out.normals.reserve(out.positions.capacity());
    }
    if (layout.has_intensity) {
        out.intensities.reserve(out.positions.capacity());
    }

    std::vector<double> values(column_count);
    std::vector<const char*> starts(column_count);
    const char* const end = data + range.end;
    const char* p = data + range.begin;
    auto fail = [&](const char* where, std::string what) {
        out.failure.set(static_cast<std::size_t>(where - data), std::move(what));
    };

    while (p < end) {
        const char* const line_start = p;
        while (p < end && (*p == ' ' || *p == '\t')) {
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
            while (p < end && is_separator(*p)) {
                ++p;
            }
            if (p == end || *p == '\n') {
                break;
            }
            double value = 0.0;
            const char* after = parse_double(p, end, value);
            if (after == nullptr || (after < end && *after != '\n' && !is_separator(*after))) {
                fail(p, "non-numeric field " + in_quotes(token_at(p, end)) + " in " +
                            column_label(column, prefix.channels) + ": expected a number");
                return;
            }
            if (column < column_count) {
                values[column] = value;
                starts[column] = p;
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
                const std::string token = token_at(starts[0], end);
                const auto [count_end, error] =
                    std::from_chars(token.data(), token.data() + token.size(), count);
                if (error == std::errc() && count_end == token.data() + token.size()) {
                    out.declared_points += count;
                    continue;
                }
                fail(line_start, "expected a point count (a single whole number) or " +
                                     std::to_string(column_count) + " columns, found " +
                                     in_quotes(token));
                return;
            }
            fail(line_start, "expected " + std::to_string(column_count) + " columns, found " +
                                 std::to_string(column));
            return;
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
            const std::string where =
                in_quotes(token_at(starts[bad], end)) + " in " + column_label(bad, prefix.channels);
            fail(line_start,
                 std::isfinite(values[bad])
                     ? "coordinate " + where + " is too far from the file's first point for float32"
                     : "NaN or infinite coordinate " + where + ": expected a finite number");
            return;
        }
        out.positions.push_back(position);

        if (layout.has_colour) {
            glm::vec3 colour;
            for (int c = 0; c < 3; ++c) {
                const auto col =
                    static_cast<std::size_t>(colour_columns[static_cast<std::size_t>(c)]);
                const double value = values[col];
                if (!(value >= 0.0 && value <= 255.0)) {
                    fail(line_start, "bad colour value " + in_quotes(token_at(starts[col], end)) +
                                         " in " + column_label(col, prefix.channels) +
                                         ": expected integers 0-255 or floats 0-1");
                    return;
                }
                out.max_colour = std::max(out.max_colour, value);
                colour[c] = static_cast<float>(value);
            }
            out.colours.push_back(colour);
        }
        if (layout.has_intensity) {
            const auto col = static_cast<std::size_t>(intensity_column);
            const auto intensity = static_cast<float>(values[col]);
            if (!std::isfinite(intensity)) {
                fail(line_start, "non-finite value " + in_quotes(token_at(starts[col], end)) +
                                     " in " + column_label(col, prefix.channels) +
                                     ": expected a finite number");
                return;
            }
            out.intensities.push_back(intensity);
        }
        if (layout.has_normal) {
            std::array<double, 3> normal{};
            for (std::size_t c = 0; c < 3; ++c) {
                const auto col = static_cast<std::size_t>(normal_columns[c]);
                normal[c] = values[col];
                if (!std::isfinite(normal[c])) {
                    fail(line_start, "non-finite value " + in_quotes(token_at(starts[col], end)) +
                                         " in " + column_label(col, prefix.channels) +
                                         ": expected a finite number");
                    return;
                }
            }
            out.normals.push_back(unit_normal(normal[0], normal[1], normal[2]));
        }
    }
}

template <class T>
void concatenate(std::vector<ChunkPoints>& chunks, std::vector<T> ChunkPoints::*member,
                 const std::vector<std::size_t>& offsets, std::vector<T>& out) {
    out.resize(offsets.back());
    tbb::parallel_for(std::size_t{0}, chunks.size(), [&](std::size_t i) {
        std::vector<T>& part = chunks[i].*member;
        std::copy(part.begin(), part.end(), out.begin() + static_cast<std::ptrdiff_t>(offsets[i]));
        std::vector<T>().swap(part);
    });
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
    std::vector<ChunkPoints> chunks(ranges.size());
    tbb::parallel_for(std::size_t{0}, ranges.size(), [&](std::size_t i) {
        if (progress != nullptr) {
            progress->throw_if_cancelled();
        }
        ChunkPoints& chunk = chunks[i];
        parse_chunk(file.data(), ranges[i], prefix, dialect, chunk);
        // A value above 1 makes the whole file's colours 0-255 integers: decoded now, while
        // they are in cache; the rest once the file's largest value is known.
        if (chunk.max_colour > 1.0 && !chunk.failure.failed) {
            decode_srgb_in_place(chunk.colours.data(), chunk.colours.size(), chunk.max_colour);
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

    std::vector<std::size_t> offsets{0};
    std::uint64_t declared_points = prefix.declared_points;
    double max_colour = 0.0;
    for (const ChunkPoints& chunk : chunks) {
        offsets.push_back(offsets.back() + chunk.positions.size());
        declared_points += chunk.declared_points;
        max_colour = std::max(max_colour, chunk.max_colour);
    }
    if (dialect == TextDialect::Pts && declared_points != offsets.back()) {
        throw input_error_at({path, prefix.first_count_line, 0, true},
                             "the point count lines declare " + std::to_string(declared_points) +
                                 " points, but the file holds " + std::to_string(offsets.back()));
    }

    ScanFile scan;
    scan.path = path;
    scan.origin = prefix.origin;
    scan.scanner = prefix.scanner;
    scan.has_scanner = prefix.has_scanner;
    concatenate(chunks, &ChunkPoints::positions, offsets, scan.positions);
    if (prefix.layout.has_colour) {
        tbb::parallel_for(std::size_t{0}, chunks.size(), [&](std::size_t i) {
            ChunkPoints& chunk = chunks[i];
            if (!chunk.colours_decoded) {
                decode_srgb_in_place(chunk.colours.data(), chunk.colours.size(), max_colour);
            }
        });
        concatenate(chunks, &ChunkPoints::colours, offsets, scan.colors);
    }
    if (prefix.layout.has_normal) {
        concatenate(chunks, &ChunkPoints::normals, offsets, scan.normals);
    }
    if (prefix.layout.has_intensity) {
        concatenate(chunks, &ChunkPoints::intensities, offsets, scan.intensities);
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
