#include "lfprobe/texture.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>

#include <stb_image.h>

#include "lfprobe/color.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/input_limits.hpp"

namespace lfprobe {

namespace {

// stb_image trusts a PNG chunk's declared length and grows its buffer to it before reading: a
// 1 KB file declaring a 1.2 GB IDAT chunk makes a 2 GB allocation (found by the OBJ/MTL fuzz
// harness). The chunks are walked here first: each must fit in the file, and there is one IHDR.
void require_png_chunks_within_the_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::array<unsigned char, 8> signature{};
    if (!in.read(reinterpret_cast<char*>(signature.data()), signature.size()) ||
        signature != std::array<unsigned char, 8>{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'}) {
        return; // not a PNG: stb's other readers size their buffers from the checked header
    }
    const std::uintmax_t file_size = std::filesystem::file_size(path);
    std::uintmax_t at = signature.size();
    int headers = 0;
    for (;;) {
        std::array<unsigned char, 8> chunk{};
        if (!in.read(reinterpret_cast<char*>(chunk.data()), chunk.size())) {
            return; // the end, or a truncated chunk header: stb reports what it makes of it
        }
        const std::uintmax_t length = (std::uintmax_t{chunk[0]} << 24) |
                                      (std::uintmax_t{chunk[1]} << 16) |
                                      (std::uintmax_t{chunk[2]} << 8) | chunk[3];
        const std::string type(reinterpret_cast<const char*>(chunk.data()) + 4, 4);
        if (length + 12 > file_size - at) {
            throw InputError(path + ": PNG chunk '" + type + "' at byte " + std::to_string(at) +
                             " declares " + std::to_string(length) +
                             " bytes, more than the file holds (a truncated or damaged PNG)");
        }
        if (type == "IHDR" && ++headers > 1) {
            throw InputError(path + ": a PNG with more than one IHDR chunk (a damaged PNG)");
        }
        if (type == "IEND") {
            return;
        }
        at += length + 12;
        in.seekg(static_cast<std::streamoff>(at));
    }
}

} // namespace

Texture Texture::load(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) {
        throw MissingFileError(path + ": texture file not found");
    }
    if (!std::filesystem::is_regular_file(path, ec)) {
        throw MissingFileError(path + ": cannot open the texture (not a regular file)");
    }
    require_png_chunks_within_the_file(path);
    int w = 0;
    int h = 0;
    int channels = 0;
    // The size from the header before any pixel is decoded: a small PNG can declare 16384²
    // pixels, 3 GB once decoded to linear floats.
    if (stbi_info(path.c_str(), &w, &h, &channels) != 0 &&
        static_cast<long long>(w) * h > input_limit(InputLimit::TexturePixels)) {
        throw InputError(path + ": the texture is " + std::to_string(w) + " × " +
                         std::to_string(h) + " pixels; textures of " +
                         input_limit_hint(InputLimit::TexturePixels) + " (default 8192 × 8192)");
    }
    // Always ask for 3 channels: only the base colour is used, alpha is ignored.
    std::unique_ptr<stbi_uc, void (*)(void*)> pixels(stbi_load(path.c_str(), &w, &h, &channels, 3),
                                                     stbi_image_free);
    if (!pixels || w < 1 || h < 1) {
        const char* reason = stbi_failure_reason();
        throw InputError(path + ": expected a PNG or JPG texture (" +
                         (reason != nullptr ? reason : "unreadable") + ")");
    }
    Texture t;
    t.path = path;
    t.width = w;
    t.height = h;
    const std::size_t n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 3;
    t.rgb.resize(n);
    const auto& table = srgb8_to_linear_table();
    for (std::size_t i = 0; i < n; ++i) {
        t.rgb[i] = table[pixels.get()[i]];
    }
    t.build_mips();
    return t;
}

Texture Texture::from_pixels(std::string name, int width, int height, const float* pixels,
                             int channels, bool srgb, bool bottom_up) {
    if (width < 1 || height < 1 || (channels != 3 && channels != 4)) {
        throw InputError(name +
                         ": expected a texture of at least 1x1 pixels with 3 or 4 "
                         "channels, got " +
                         std::to_string(width) + "x" + std::to_string(height) + "x" +
                         std::to_string(channels));
    }
    Texture t;
    t.path = std::move(name);
    t.width = width;
    t.height = height;
    t.rgb.resize(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 3);
    for (int y = 0; y < height; ++y) {
        const int source_row = bottom_up ? height - 1 - y : y;
        for (int x = 0; x < width; ++x) {
            const float* p =
                pixels + (static_cast<std::size_t>(source_row) * static_cast<std::size_t>(width) +
                          static_cast<std::size_t>(x)) *
                             static_cast<std::size_t>(channels);
            for (int c = 0; c < 3; ++c) {
                if (!std::isfinite(p[c])) {
                    throw InputError(t.path + ": texture pixel (" + std::to_string(x) + ", " +
                                     std::to_string(source_row) + ") is not finite");
                }
                t.rgb[(static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                       static_cast<std::size_t>(x)) *
                          3 +
                      static_cast<std::size_t>(c)] = srgb ? srgb_to_linear(p[c]) : p[c];
            }
        }
    }
    t.build_mips();
    return t;
}

glm::vec3 Texture::texel(int x, int y) const {
    const std::size_t i = (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                           static_cast<std::size_t>(x)) *
                          3;
    return {rgb[i], rgb[i + 1], rgb[i + 2]};
}

namespace {

// i (a whole number) modulo n into [0, n): integer arithmetic for the coordinates a sampler
// meets (fmod was a tenth of a mesh bake), fmod beyond them.
int wrap_index(double i, int n) {
    constexpr double kIntegerRange = 1e15;
    if (i >= 0.0 && i < static_cast<double>(n)) {
        return static_cast<int>(i); // inside the image: no division
    }
    if (std::abs(i) < kIntegerRange) {
        const std::int64_t m = static_cast<std::int64_t>(i) % n;
        return static_cast<int>(m < 0 ? m + n : m);
    }
    const double m = std::fmod(i, static_cast<double>(n));
    return static_cast<int>(m < 0.0 ? m + n : m);
}

// Bilinear with repeat wrap over one level's texels (3 floats each, row 0 the top row).
glm::vec3 bilinear(const float* rgb, int width, int height, const glm::vec2& uv) {
    // Continuous texel coordinates with texel centres on integers; v is flipped because OBJ
    // texture coordinates have v up while image rows go down.
    const double fx = static_cast<double>(uv.x) * width - 0.5;
    const double fy = (1.0 - static_cast<double>(uv.y)) * height - 0.5;
    if (!std::isfinite(fx) || !std::isfinite(fy)) {
        return glm::vec3(0.0f);
    }
    const double x0f = std::floor(fx);
    const double y0f = std::floor(fy);
    const auto ax = static_cast<float>(fx - x0f);
    const auto ay = static_cast<float>(fy - y0f);
    const int x0 = wrap_index(x0f, width);
    const int x1 = x0 + 1 == width ? 0 : x0 + 1;
    const int y0 = wrap_index(y0f, height);
    const int y1 = y0 + 1 == height ? 0 : y0 + 1;
    auto at = [&](int x, int y) {
        const std::size_t i = (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                               static_cast<std::size_t>(x)) *
                              3;
        return glm::vec3(rgb[i], rgb[i + 1], rgb[i + 2]);
    };
    const glm::vec3 top = at(x0, y0) * (1.0f - ax) + at(x1, y0) * ax;
    const glm::vec3 bottom = at(x0, y1) * (1.0f - ax) + at(x1, y1) * ax;
    return top * (1.0f - ay) + bottom * ay;
}

Texture::Level halved(const float* rgb, int width, int height) {
    Texture::Level out;
    out.width = (width + 1) / 2;
    out.height = (height + 1) / 2;
    out.rgb.resize(static_cast<std::size_t>(out.width) * static_cast<std::size_t>(out.height) * 3);
    for (int y = 0; y < out.height; ++y) {
        const int ys[2] = {(2 * y) % height, (2 * y + 1) % height};
        for (int x = 0; x < out.width; ++x) {
            const int xs[2] = {(2 * x) % width, (2 * x + 1) % width};
            for (int c = 0; c < 3; ++c) {
                float sum = 0.0f;
                for (const int sy : ys) {
                    for (const int sx : xs) {
                        sum += rgb[(static_cast<std::size_t>(sy) * static_cast<std::size_t>(width) +
                                    static_cast<std::size_t>(sx)) *
                                       3 +
                                   static_cast<std::size_t>(c)];
                    }
                }
                out.rgb[(static_cast<std::size_t>(y) * static_cast<std::size_t>(out.width) +
                         static_cast<std::size_t>(x)) *
                            3 +
                        static_cast<std::size_t>(c)] = 0.25f * sum;
            }
        }
    }
    return out;
}

} // namespace

glm::vec3 Texture::sample(const glm::vec2& uv) const {
    if (width < 1 || height < 1) {
        return glm::vec3(1.0f);
    }
    return bilinear(rgb.data(), width, height, uv);
}

glm::vec3 Texture::sample(const glm::vec2& uv, double footprint_texels) const {
    // Level L averages 2^L texels a side, so a footprint of f texels reads level log2(f).
    if (!(footprint_texels > 1.0) || mips.empty()) {
        return sample(uv);
    }
    const double lod = std::min(std::log2(footprint_texels), static_cast<double>(mips.size()));
    const int lower = static_cast<int>(std::floor(lod));
    const auto blend = static_cast<float>(lod - lower);
    auto level = [&](int l) {
        if (l == 0) {
            return sample(uv);
        }
        const Level& m = mips[static_cast<std::size_t>(l - 1)];
        return bilinear(m.rgb.data(), m.width, m.height, uv);
    };
    const glm::vec3 a = level(lower);
    if (blend <= 0.0f || lower >= static_cast<int>(mips.size())) {
        return a;
    }
    return a * (1.0f - blend) + level(lower + 1) * blend;
}

void Texture::build_mips() {
    mips.clear();
    mips.reserve(32);
    const float* rgb_level = rgb.data();
    int w = width;
    int h = height;
    while (w > 1 || h > 1) {
        mips.push_back(halved(rgb_level, w, h));
        rgb_level = mips.back().rgb.data();
        w = mips.back().width;
        h = mips.back().height;
    }
}

} // namespace lfprobe
