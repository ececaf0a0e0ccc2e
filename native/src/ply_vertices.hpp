// What the PLY readers (binary and ascii) share: the meaning of each vertex property and the
// conversion of one vertex's values into the ScanFile's arrays.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "lfprobe/scan_reader.hpp"
#include "ply_header.hpp"
#include "scan_parsing.hpp"

namespace lfprobe::detail {

// How a colour property encodes sRGB: by its type, except that float colours follow the text
// formats' rule (0-1 unless some value in the file exceeds 1, then 0-255).
enum class ColourEncoding : std::uint8_t { Byte, Word, Integer, Float };

struct VertexProperty {
    Channel channel = Channel::Ignore;
    PlyType type = PlyType::Float32;
    bool is_list = false;
    PlyType count_type = PlyType::UInt8;
    std::size_t offset = 0; // within a binary vertex without lists
};

struct VertexLayout {
    std::vector<VertexProperty> properties;
    ChannelLayout channels;
    std::array<ColourEncoding, 3> colour_encoding{};
    bool has_float_colour = false;
    bool has_lists = false;
    std::size_t stride = 0;       // binary bytes per vertex without lists
    std::size_t scalar_count = 0; // properties that are not lists
};

// The meaning of the vertex element's properties; throws InputError at the element's header
// line when x, y or z is missing or colours/normals are incomplete.
[[nodiscard]] VertexLayout make_vertex_layout(const PlyElement& vertex, const std::string& path);

// One vertex's values, indexed by Channel.
using ChannelValues = std::array<double, channel_count>;

// Writes vertices into arrays sized for every vertex, from any thread (distinct indices).
class VertexStore {
public:
    VertexStore(ScanFile& scan, const VertexLayout& layout, std::size_t capacity);

    // Stores vertex `index`; returns an explanation instead when a value is unusable. Float
    // colours are kept raw and their maximum tracked in `max_float_colour`.
    [[nodiscard]] std::string store(std::size_t index, const ChannelValues& values,
                                    double& max_float_colour) const;

    // Sets the origin from the first vertex (whole units); call before any store().
    void set_origin_from(const ChannelValues& first);

    // Decodes the raw float colours once the maximum over the file is known.
    void finish(double max_float_colour) const;

private:
    ScanFile& scan_;
    const VertexLayout& layout_;
};

} // namespace lfprobe::detail
