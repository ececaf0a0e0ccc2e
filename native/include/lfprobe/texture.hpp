// A base-colour texture of a mesh material: decoded with stb_image from PNG or JPG, its 8-bit
// sRGB values decoded to linear float once on load, so that sampling (bilinear, repeat wrap)
// averages linear values as a renderer would.
#pragma once

#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

namespace lfprobe {

// The largest texture accepted: input_limits.hpp (8192 × 8192 pixels by default, 805 MB as
// linear floats).

struct Texture {
    std::string path;
    int width = 0;
    int height = 0;
    std::vector<float> rgb; // linear, 3 per texel, row 0 = the TOP row of the image file

    // Throws IoError when the file is missing, InputError when stb cannot decode it.
    [[nodiscard]] static Texture load(const std::string& path);
    // From float pixels as an image editor holds them (`channels` 3 or 4 per pixel, alpha
    // ignored): `srgb` values are sRGB-encoded and decoded here, else linear; `bottom_up` means
    // row 0 is the bottom row (Blender's Image.pixels). Throws InputError on bad sizes or
    // non-finite values.
    [[nodiscard]] static Texture from_pixels(std::string name, int width, int height,
                                             const float* pixels, int channels, bool srgb,
                                             bool bottom_up);

    // Linear colour at OBJ texture coordinates uv: u right, v UP (so v = 0 is the bottom row
    // of the image file), texel centres at ((x + 0.5) / w, 1 - (y + 0.5) / h); bilinear with
    // repeat wrap in both directions.
    [[nodiscard]] glm::vec3 sample(const glm::vec2& uv) const;
    // The same, filtered over a footprint `footprint_texels` texels of this image wide, as
    // texture LOD does: trilinear between the two mip levels around log2 of the footprint. At
    // most one texel (or without mips) it is sample(uv) exactly.
    [[nodiscard]] glm::vec3 sample(const glm::vec2& uv, double footprint_texels) const;
    // The linear colour of texel (x, y), y = 0 the top row of the file.
    [[nodiscard]] glm::vec3 texel(int x, int y) const;

    // Box-filtered halvings of the image down to 1×1 (odd sizes round up, the last texel
    // averaged with the wrapped first, as the sampler wraps); load and from_pixels build them.
    struct Level {
        int width = 0;
        int height = 0;
        std::vector<float> rgb;
    };
    std::vector<Level> mips; // mips[0] is the first halving
    void build_mips();
};

} // namespace lfprobe
