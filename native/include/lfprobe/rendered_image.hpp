// A rendered image in memory (probe traces, splats, ground truth; docs/DESIGN.md §3 "Rendered
// images"): linear colour and coverage, distance along the ray, normal, and for analysis the trace
// status, the probe that answered and the texels visited. Pixel (x, y) is column x of row y, y = 0
// the top row.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace lfprobe {

struct RenderedImage {
    int width = 0;
    int height = 0;
    std::vector<float> rgba;          // 4 per pixel
    std::vector<float> depth;         // Z
    std::vector<float> normal;        // 3 per pixel
    std::vector<std::uint8_t> status; // TraceStatus values
    std::vector<std::int32_t> probe;  // -1 where no probe answered
    std::vector<std::uint32_t> steps; // texels visited (splats: points covering the pixel)
    // Optional: the mesh object seen (ground truth), -1 none. Empty = no "object.X" channel; the
    // reader fills it only when the file has one.
    std::vector<std::int32_t> object;
    // Optional: probe traces, 1 where the pixel's centre sample HIT a hole-filled texel (a
    // surface no scan saw there, guessed from around it: TexelState::Inferred), else 0. Empty
    // = no "guessed.X" channel. Compact storage keeps no confidence: all 0 there.
    std::vector<std::uint8_t> guessed;

    RenderedImage() = default;
    // Every pixel a MISS: colour and coverage 0, Z +inf, normal 0, probe -1, steps 0.
    RenderedImage(int w, int h);

    [[nodiscard]] std::size_t pixel_count() const {
        return static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    }
    [[nodiscard]] std::size_t index(int x, int y) const {
        return static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
               static_cast<std::size_t>(x);
    }
};

} // namespace lfprobe
