// PLY vertex properties: names to channels, and values to positions, colours and normals.
#include "ply_vertices.hpp"

#include <cmath>
#include <cstdio>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lfprobe/color.hpp"
#include "lfprobe/error.hpp"

namespace lfprobe::detail {

namespace {

[[nodiscard]] ColourEncoding encoding_of(PlyType type) {
    switch (type) {
    case PlyType::UInt8:
        return ColourEncoding::Byte;
    case PlyType::UInt16:
        return ColourEncoding::Word;
    case PlyType::Float32:
    case PlyType::Float64:
        return ColourEncoding::Float;
    default:
        return ColourEncoding::Integer;
    }
}

[[nodiscard]] std::string number_text(double value) {
    std::array<char, 32> buffer{};
    std::snprintf(buffer.data(), buffer.size(), "%.17g", value);
    return buffer.data();
}

// An 8-bit sRGB value, whole (the table) or not (the formula).
[[nodiscard]] float decode_srgb255(double value) {
    const auto whole = static_cast<std::size_t>(value);
    if (static_cast<double>(whole) == value) {
        return srgb8_to_linear_table()[whole];
    }
    return srgb_to_linear(static_cast<float>(value / 255.0));
}

} // namespace

VertexLayout make_vertex_layout(const PlyElement& vertex, const std::string& path) {
    VertexLayout layout;
    std::vector<Channel> channels;
    std::size_t offset = 0;
    for (const PlyProperty& property : vertex.properties) {
        VertexProperty entry;
        entry.type = property.type;
        entry.is_list = property.is_list;
        entry.count_type = property.count_type;
        entry.offset = offset;
        if (!property.is_list) {
            entry.channel = channel_from_name(property.name).value_or(Channel::Ignore);
            // A second property of the same meaning (say "r" beside "red") is ignored.
            for (const Channel earlier : channels) {
                if (earlier == entry.channel) {
                    entry.channel = Channel::Ignore;
                }
            }
            offset += ply_type_size(property.type);
            ++layout.scalar_count;
        } else {
            layout.has_lists = true;
        }
        channels.push_back(entry.channel);
        layout.properties.push_back(entry);
    }
    layout.stride = offset;
    if (const std::string problem = make_channel_layout(channels, layout.channels);
        !problem.empty()) {
        throw input_error_at({path, vertex.header_line, 0, true},
                             "the vertex element is not usable: " + problem +
                                 " (expected scalar properties x, y, z, optionally red green "
                                 "blue, nx ny nz, intensity)");
    }
    if (layout.channels.has_colour) {
        for (std::size_t c = 0; c < 3; ++c) {
            const auto column = static_cast<std::size_t>(layout.channels.index(
                static_cast<Channel>(static_cast<int>(Channel::Red) + static_cast<int>(c))));
            layout.colour_encoding[c] = encoding_of(layout.properties[column].type);
            layout.has_float_colour =
                layout.has_float_colour || layout.colour_encoding[c] == ColourEncoding::Float;
        }
    }
    return layout;
}

VertexStore::VertexStore(ScanFile& scan, const VertexLayout& layout, std::size_t capacity)
    : scan_(scan), layout_(layout) {
    scan_.positions.resize(capacity);
    if (layout_.channels.has_colour) {
        scan_.colors.resize(capacity);
    }
    if (layout_.channels.has_normal) {
        scan_.normals.resize(capacity);
    }
    if (layout_.channels.has_intensity) {
        scan_.intensities.resize(capacity);
    }
}

void VertexStore::set_origin_from(const ChannelValues& first) {
    scan_.origin = glm::dvec3(std::round(first[static_cast<std::size_t>(Channel::X)]),
                              std::round(first[static_cast<std::size_t>(Channel::Y)]),
                              std::round(first[static_cast<std::size_t>(Channel::Z)]));
}

std::string VertexStore::store(std::size_t index, const ChannelValues& values,
                               double& max_float_colour) const {
    auto value_of = [&](Channel channel) { return values[static_cast<std::size_t>(channel)]; };
    // Checking the float32 result catches NaN, infinities and points too far from the origin.
    const glm::vec3 position(static_cast<float>(value_of(Channel::X) - scan_.origin.x),
                             static_cast<float>(value_of(Channel::Y) - scan_.origin.y),
                             static_cast<float>(value_of(Channel::Z) - scan_.origin.z));
    for (int axis = 0; axis < 3; ++axis) {
        if (!std::isfinite(position[axis])) {
            const Channel channel = static_cast<Channel>(static_cast<int>(Channel::X) + axis);
            const std::string coordinate =
                std::string(channel_name(channel)) + " = " + number_text(value_of(channel));
            return "vertex " + std::to_string(index) + " (counting from 0) has " +
                   (std::isfinite(value_of(channel))
                        ? "a coordinate too far from the first vertex for float32: " + coordinate
                        : "a NaN or infinite coordinate: " + coordinate +
                              ": expected finite coordinates");
        }
    }
    scan_.positions[index] = position;

    if (layout_.channels.has_colour) {
        glm::vec3 colour;
        for (int c = 0; c < 3; ++c) {
            const Channel channel = static_cast<Channel>(static_cast<int>(Channel::Red) + c);
            const double value = value_of(channel);
            const ColourEncoding encoding = layout_.colour_encoding[static_cast<std::size_t>(c)];
            const double limit = encoding == ColourEncoding::Word ? 65535.0 : 255.0;
            if (!(value >= 0.0 && value <= limit)) {
                return "vertex " + std::to_string(index) + " (counting from 0) has a bad " +
                       channel_name(channel) + " value " + number_text(value) + ": expected " +
                       (encoding == ColourEncoding::Word    ? "0-65535"
                        : encoding == ColourEncoding::Float ? "0-1 (or 0-255)"
                                                            : "0-255");
            }
            switch (encoding) {
            case ColourEncoding::Byte:
            case ColourEncoding::Integer:
                colour[c] = decode_srgb255(value);
                break;
            case ColourEncoding::Word:
                colour[c] = srgb_to_linear(static_cast<float>(value / 65535.0));
                break;
            case ColourEncoding::Float:
                max_float_colour = std::max(max_float_colour, value);
                colour[c] = static_cast<float>(value);
                break;
            }
        }
        scan_.colors[index] = colour;
    }
    if (layout_.channels.has_intensity) {
        const auto intensity = static_cast<float>(value_of(Channel::Intensity));
        if (!std::isfinite(intensity)) {
            return "vertex " + std::to_string(index) + " (counting from 0) has intensity " +
                   number_text(value_of(Channel::Intensity)) + ": expected a finite number";
        }
        scan_.intensities[index] = intensity;
    }
    if (layout_.channels.has_normal) {
        const double nx = value_of(Channel::NormalX);
        const double ny = value_of(Channel::NormalY);
        const double nz = value_of(Channel::NormalZ);
        if (!std::isfinite(nx) || !std::isfinite(ny) || !std::isfinite(nz)) {
            return "vertex " + std::to_string(index) + " (counting from 0) has a NaN or " +
                   "infinite normal: expected finite nx, ny, nz";
        }
        scan_.normals[index] = unit_normal(nx, ny, nz);
    }
    return {};
}

void VertexStore::finish(double max_float_colour) const {
    if (!layout_.has_float_colour) {
        return;
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, scan_.colors.size(), 1 << 16),
                      [&](const tbb::blocked_range<std::size_t>& block) {
                          for (std::size_t i = block.begin(); i != block.end(); ++i) {
                              for (std::size_t c = 0; c < 3; ++c) {
                                  if (layout_.colour_encoding[c] != ColourEncoding::Float) {
                                      continue;
                                  }
                                  float& value = scan_.colors[i][static_cast<int>(c)];
                                  value = max_float_colour <= 1.0
                                              ? srgb_to_linear(value)
                                              : decode_srgb255(static_cast<double>(value));
                              }
                          }
                      });
}

} // namespace lfprobe::detail
