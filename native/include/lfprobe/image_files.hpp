// Images made by other programs, for comparing against (compare takes any reference and test
// image): every channel of any OpenEXR file, through OpenEXR itself (any compression, scanline
// or tiled, single or multi-part), and the pixels of PNG and JPEG files through stb_image
// (8 and 16 bits). The layer to compare and the sRGB decoding are chosen in Python
// (core/image_files.py).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace lfprobe {

// An OpenEXR file's channels over its display window, top row first; pixels of the display
// window outside a part's data window are 0. Channels of every part, by their full names.
struct ExrChannels {
    int width = 0;
    int height = 0;
    std::map<std::string, std::vector<float>> channels; // width × height each
};

// MissingFileError when there is no such file; InputError naming the file when it is not an
// EXR OpenEXR can read, holds deep data, or is larger than the image pixel limit
// (input_limits.hpp).
[[nodiscard]] ExrChannels read_exr_channels(const std::string& path);

// A PNG's or JPEG's pixels as stored (sRGB codes, 0 to 2^bits - 1), 1 (grey), 2 (grey, alpha),
// 3 (RGB) or 4 (RGBA) channels interleaved.
struct StoredImage {
    int width = 0;
    int height = 0;
    int channels = 0;
    int bits = 8;                      // 8 or 16
    std::vector<std::uint16_t> values; // width × height × channels
};

// MissingFileError when there is no such file; InputError naming the file (and stb_image's
// reason) when it cannot be decoded or is larger than the image pixel limit (input_limits.hpp).
[[nodiscard]] StoredImage read_stored_image(const std::string& path);

// The most pixels an image read for comparison may hold: input_limits.hpp (8192² by default).

} // namespace lfprobe
