// Pieces shared by the scan readers (text and PLY): column names, number parsing, chunking a
// mapped file at line boundaries, lazy line numbers and colour decoding.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <thread>
#include <vector>

#include <fast_float/fast_float.h>
#include <glm/vec3.hpp>

#include "lfprobe/color.hpp"
#include "lfprobe/enum_names.hpp"

namespace lfprobe::detail {

// What a column (text) or vertex property (PLY) holds.
enum class Channel : std::uint8_t {
    Ignore,
    X,
    Y,
    Z,
    Intensity,
    Red,
    Green,
    Blue,
    NormalX,
    NormalY,
    NormalZ
};
inline constexpr std::size_t channel_count = 11;

[[nodiscard]] inline char ascii_lower(char c) {
    return c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : c;
}

[[nodiscard]] inline bool equals_ignoring_case(std::string_view a, std::string_view b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
               return ascii_lower(x) == ascii_lower(y);
           });
}

// Every name a column header or PLY property may give a channel, case-insensitive; the first
// row for a channel is the name messages use.
inline constexpr auto channel_names = std::to_array<EnumName<Channel>>({
    {Channel::X, "x"},
    {Channel::Y, "y"},
    {Channel::Z, "z"},
    {Channel::Intensity, "intensity"},
    {Channel::Red, "red"},
    {Channel::Green, "green"},
    {Channel::Blue, "blue"},
    {Channel::NormalX, "nx"},
    {Channel::NormalY, "ny"},
    {Channel::NormalZ, "nz"},
    {Channel::Intensity, "i"},
    {Channel::Intensity, "reflectance"},
    {Channel::Intensity, "scalar_intensity"},
    {Channel::Intensity, "scalar_reflectance"},
    {Channel::Intensity, "intensities"},
    {Channel::Intensity, "remission"},
    {Channel::Red, "r"},
    {Channel::Green, "g"},
    {Channel::Blue, "b"},
    {Channel::Red, "diffuse_red"},
    {Channel::Green, "diffuse_green"},
    {Channel::Blue, "diffuse_blue"},
    // CloudCompare names float colours Rf Gf Bf.
    {Channel::Red, "rf"},
    {Channel::Green, "gf"},
    {Channel::Blue, "bf"},
    {Channel::NormalX, "normal_x"},
    {Channel::NormalY, "normal_y"},
    {Channel::NormalZ, "normal_z"},
    {Channel::NormalX, "normalx"},
    {Channel::NormalY, "normaly"},
    {Channel::NormalZ, "normalz"},
    {Channel::Ignore, "_"},
});

// The channel a column header or PLY property name stands for; nullopt for names no reader
// knows.
[[nodiscard]] inline std::optional<Channel> channel_from_name(std::string_view name) {
    const auto row =
        std::find_if(channel_names.begin(), channel_names.end(), [&](const EnumName<Channel>& r) {
            return equals_ignoring_case(r.name, name);
        });
    return row == channel_names.end() ? std::nullopt : std::optional<Channel>(row->value);
}

[[nodiscard]] inline const char* channel_name(Channel channel) {
    return channel == Channel::Ignore ? "ignored" : name_of(channel_names, channel);
}

// Where each channel sits among the columns (or properties), -1 when absent.
struct ChannelLayout {
    std::array<int, channel_count> index_of{};
    bool has_colour = false;
    bool has_normal = false;
    bool has_intensity = false;

    [[nodiscard]] int index(Channel channel) const {
        return index_of[static_cast<std::size_t>(channel)];
    }
};

// Builds the layout of `channels`; returns an explanation instead when a channel appears
// twice, x/y/z is missing, or colours/normals are incomplete.
[[nodiscard]] inline std::string make_channel_layout(const std::vector<Channel>& channels,
                                                     ChannelLayout& layout) {
    layout = ChannelLayout{};
    layout.index_of.fill(-1);
    for (std::size_t column = 0; column < channels.size(); ++column) {
        const Channel channel = channels[column];
        if (channel == Channel::Ignore) {
            continue;
        }
        int& slot = layout.index_of[static_cast<std::size_t>(channel)];
        if (slot >= 0) {
            return std::string("'") + channel_name(channel) + "' appears twice";
        }
        slot = static_cast<int>(column);
    }
    for (Channel channel : {Channel::X, Channel::Y, Channel::Z}) {
        if (layout.index(channel) < 0) {
            return std::string("no '") + channel_name(channel) + "' column";
        }
    }
    const int colours = (layout.index(Channel::Red) >= 0) + (layout.index(Channel::Green) >= 0) +
                        (layout.index(Channel::Blue) >= 0);
    if (colours != 0 && colours != 3) {
        return "colour needs all three of red, green and blue";
    }
    const int normals = (layout.index(Channel::NormalX) >= 0) +
                        (layout.index(Channel::NormalY) >= 0) +
                        (layout.index(Channel::NormalZ) >= 0);
    if (normals != 0 && normals != 3) {
        return "normals need all three of nx, ny and nz";
    }
    layout.has_colour = colours == 3;
    layout.has_normal = normals == 3;
    layout.has_intensity = layout.index(Channel::Intensity) >= 0;
    return {};
}

// Column separators of the text formats: any run of spaces, tabs and commas; a CR before the
// LF is treated as one more separator so that CRLF files need no special path.
[[nodiscard]] inline bool is_separator(char c) {
    return c == ' ' || c == '\t' || c == ',' || c == '\r';
}

// How far a parse may read. `Bounded`: up to `last`, compared at every byte. `Newline`: the
// caller knows that the byte before `last` is a newline (a chunk of whole lines), which ends
// every run of digits, blanks and separators, so the loops need not compare with `last`. Those
// comparisons (and a digit counter) were a fifth of a text scan's parse: 1,063 instructions a
// line of "x y z r g b" before, 843 after, 18 % less time.
enum class RangeEnd { Bounded, Newline };

// Appends the decimal digits from `p` to `digits` (wrapping past 19 digits: callers turn such
// numbers away by their length); returns the first byte that is not a digit.
template <RangeEnd kEnd>
[[nodiscard]] inline const char* append_digits(const char* p, const char* last,
                                               std::uint64_t& digits) {
    while (kEnd == RangeEnd::Newline || p < last) {
        const unsigned digit = static_cast<unsigned>(static_cast<unsigned char>(*p)) - '0';
        if (digit >= 10u) {
            break;
        }
        digits = digits * 10 + digit;
        ++p;
    }
    return p;
}

// The plain decimals scanners write ([-]digits[.digits], no exponent), parsed the fast way
// (Clinger's): the digits as an integer m and the decimals k; where m < 2^53 and k <= 22 both
// are exact doubles and m / 10^k is one correctly rounded division, so the value is the
// correctly rounded one, bit for bit what fast_float returns. Half the parse time of a scan
// went to fast_float's general path. Returns the number's end, or nullptr for anything else
// (an exponent, 20 digits or more, no digit before or after the point): fast_float parses those.
template <RangeEnd kEnd = RangeEnd::Bounded>
[[nodiscard]] inline const char* parse_plain_decimal(const char* first, const char* last,
                                                     double& value) {
    static constexpr std::array<double, 20> kPowersOfTen{1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,
                                                         1e7,  1e8,  1e9,  1e10, 1e11, 1e12, 1e13,
                                                         1e14, 1e15, 1e16, 1e17, 1e18, 1e19};
    constexpr bool kNewline = kEnd == RangeEnd::Newline;
    const char* p = first;
    const bool negative = (kNewline || p < last) && *p == '-';
    p += negative ? 1 : 0;
    std::uint64_t digits = 0;
    const char* const integer = p;
    p = append_digits<kEnd>(p, last, digits);
    std::ptrdiff_t count = p - integer;
    if (count == 0) {
        return nullptr;
    }
    std::ptrdiff_t decimals = 0;
    if ((kNewline || p < last) && *p == '.') {
        const char* const fraction = ++p;
        p = append_digits<kEnd>(p, last, digits);
        decimals = p - fraction;
        if (decimals == 0) {
            return nullptr;
        }
        count += decimals;
    }
    // At most 19 digits: m < 10^19 did not wrap, and k <= 19.
    constexpr std::uint64_t kExactInteger = std::uint64_t{1} << 53;
    if (count > 19 || digits > kExactInteger ||
        ((kNewline || p < last) && (*p == 'e' || *p == 'E'))) {
        return nullptr;
    }
    const double magnitude = decimals == 0 ? static_cast<double>(digits)
                                           : static_cast<double>(digits) /
                                                 kPowersOfTen[static_cast<std::size_t>(decimals)];
    value = negative ? -magnitude : magnitude;
    return p;
}

// Parses a double at [first, last). fast_float rejects a leading '+', which some exporters
// write, so it is skipped here. Returns the end of the number, or nullptr when there is none.
// Overflowing values come back as infinities: callers check finiteness. `kEnd` as for
// parse_plain_decimal.
template <RangeEnd kEnd = RangeEnd::Bounded>
[[nodiscard]] inline const char* parse_double(const char* first, const char* last, double& value) {
    const char* start = first;
    if (start < last && *start == '+' && start + 1 < last && *(start + 1) != '-' &&
        *(start + 1) != '+') {
        ++start;
    }
    if (const char* end = parse_plain_decimal<kEnd>(start, last, value)) {
        return end;
    }
    const fast_float::from_chars_result result = fast_float::from_chars(start, last, value);
    if (result.ec == std::errc::invalid_argument || result.ptr == start) {
        return nullptr;
    }
    if (result.ec == std::errc::result_out_of_range && !std::isfinite(value)) {
        value = HUGE_VAL;
    }
    return result.ptr;
}

// 1-based number of the line holding byte `offset`; only called on the error path.
[[nodiscard]] inline std::uint64_t line_number_at(const char* data, std::size_t offset) {
    return 1 + static_cast<std::uint64_t>(std::count(data, data + offset, '\n'));
}

// Bytes quoted in a message, with anything unprintable (binary junk) shown as '?'.
[[nodiscard]] inline std::string printable(std::string_view text) {
    std::string out(text);
    for (char& c : out) {
        if (c < ' ' || c > '~') {
            c = '?';
        }
    }
    return out;
}

// The whitespace- or separator-delimited token starting at `first`, for quoting in errors.
[[nodiscard]] inline std::string token_at(const char* first, const char* last) {
    const char* end = first;
    while (end < last && *end != '\n' && !is_separator(*end) && end - first < 64) {
        ++end;
    }
    return printable(std::string_view(first, static_cast<std::size_t>(end - first)));
}

// Bytes per parallel work item: small enough to spread a few MB over every core, large
// enough (at most 4 MB) that scheduling costs nothing next to parsing.
[[nodiscard]] inline std::size_t parse_chunk_bytes(std::size_t total_bytes) {
    const std::size_t threads = std::max(1u, std::thread::hardware_concurrency());
    const std::size_t per_core = total_bytes / (4 * threads);
    return std::clamp<std::size_t>(per_core, std::size_t{256} << 10, std::size_t{4} << 20);
}

struct ByteRange {
    std::size_t begin = 0;
    std::size_t end = 0;
};

// Splits [begin, end) into ranges of about `chunk_bytes` that start at line starts.
[[nodiscard]] inline std::vector<ByteRange>
split_at_lines(const char* data, std::size_t begin, std::size_t end, std::size_t chunk_bytes) {
    std::vector<ByteRange> ranges;
    std::size_t start = begin;
    while (start < end) {
        std::size_t stop = end;
        if (end - start > chunk_bytes) {
            const char* cut = data + start + chunk_bytes;
            const void* newline = std::memchr(cut, '\n', end - (start + chunk_bytes));
            stop = newline == nullptr
                       ? end
                       : static_cast<std::size_t>(static_cast<const char*>(newline) - data) + 1;
        }
        ranges.push_back({start, stop});
        start = stop;
    }
    return ranges;
}

// A problem found by a worker: kept, not thrown, so that the earliest one in the file is
// reported whatever the thread timing.
struct ParseFailure {
    bool failed = false;
    std::size_t byte_offset = 0;
    std::string message;

    void set(std::size_t offset, std::string what) {
        if (!failed || offset < byte_offset) {
            failed = true;
            byte_offset = offset;
            message = std::move(what);
        }
    }
};

// Decodes colours stored as raw sRGB values in place. Files write 0-255 integers or 0-1
// floats; which one is told by the largest value in the file (`max_value`).
inline void decode_srgb_in_place(glm::vec3* colours, std::size_t count, double max_value) {
    if (max_value <= 1.0) {
        for (std::size_t i = 0; i < count; ++i) {
            for (int c = 0; c < 3; ++c) {
                colours[i][c] = srgb_to_linear(colours[i][c]);
            }
        }
        return;
    }
    const std::array<float, 256>& table = srgb8_to_linear_table();
    for (std::size_t i = 0; i < count; ++i) {
        for (int c = 0; c < 3; ++c) {
            const float value = colours[i][c];
            const auto whole = static_cast<std::size_t>(value);
            colours[i][c] =
                static_cast<float>(whole) == value ? table[whole] : srgb_to_linear(value / 255.0f);
        }
    }
}

// A unit normal, or zero when the file says zero (no normal known for that point).
[[nodiscard]] inline glm::vec3 unit_normal(double x, double y, double z) {
    const double length = std::sqrt(x * x + y * y + z * z);
    if (!(length > 0.0)) {
        return glm::vec3(0.0f);
    }
    return glm::vec3(static_cast<float>(x / length), static_cast<float>(y / length),
                     static_cast<float>(z / length));
}

} // namespace lfprobe::detail
