// Rendered images (probe traces, splats) in memory and as OpenEXR files (docs/DESIGN.md §3 "Images
// out"): R, G, B, A (linear colour and coverage), Z (distance along the ray, +inf for nothing),
// N.X, N.Y, N.Z (normal), and for analysis "status.X" (0 MISS, 1 HIT, 2 UNKNOWN), "probe.X" (the
// probe that answered, -1 none), "steps.X" (texels visited) and, for ground truth, "object.X":
// passes Blender's multilayer reader takes. Files written before named these "status", "probe",
// "steps", "object"; the reader takes either. Every channel is float32 in the file so that
// analysis reads exact values. Pixel (x, y) is column x of scanline y, y = 0 the top row.
#pragma once

#include <string>

#include "lfprobe/rendered_image.hpp"

namespace lfprobe {

struct ImageMetadata;

// Writes `image` through a temporary file and a rename (an interrupted write leaves no partial
// image). `metadata` (JSON text) goes into the header as the string attribute "lfprobe/render".
// Throws IoError.
void write_rendered_exr(const std::string& path, const RenderedImage& image,
                        const std::string& metadata = "");
// The same with the one metadata layout every renderer writes (image_metadata.hpp).
void write_rendered_exr(const std::string& path, const RenderedImage& image,
                        const ImageMetadata& metadata);

// Reads an image written by write_rendered_exr (with either naming of the analysis channels).
// Throws IoError when the file cannot be read, InputError when a channel is missing.
[[nodiscard]] RenderedImage read_rendered_exr(const std::string& path,
                                              std::string* metadata = nullptr);

} // namespace lfprobe
