// Rendered images (probe traces, splats) in memory and as OpenEXR files (DESIGN.md §3 "Images
// out"): R, G, B, A (linear colour and coverage), Z (distance along the ray, +inf for nothing),
// N.X, N.Y, N.Z (normal), and for analysis "status" (0 MISS, 1 HIT, 2 UNKNOWN), "probe" (the
// probe that answered, -1 none) and "steps" (texels visited). Every channel is float32 in the
// file so that analysis reads exact values. Pixel (x, y) is column x of scanline y, y = 0 the
// top row.
#pragma once

#include <cstdint>
#include <string>
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
    // Optional: the mesh object seen (ground truth), -1 none. Empty = no "object" channel; the
    // reader fills it only when the file has one.
    std::vector<std::int32_t> object;

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

// Writes `image` through a temporary file and a rename (an interrupted write leaves no partial
// image). `metadata` (e.g. a JSON string: camera, settings, timing) goes into the header as
// the string attribute "lfprobe/render". Throws IoError.
void write_rendered_exr(const std::string& path, const RenderedImage& image,
                        const std::string& metadata = "");

// Reads an image written by write_rendered_exr. Throws IoError when the file cannot be read,
// InputError when a channel is missing.
[[nodiscard]] RenderedImage read_rendered_exr(const std::string& path,
                                              std::string* metadata = nullptr);

} // namespace lfprobe
