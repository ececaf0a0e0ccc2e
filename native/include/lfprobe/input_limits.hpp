// The limits on what lfprobe reads, so that no file can exhaust memory (README, "Limits on what
// is read"). Each has a default and an environment variable that raises or lowers it, for the
// user whose genuine input is bigger (a 16k texture, a 12k panorama) or whose machine is smaller.
#pragma once

#include <cstdint>
#include <string>

namespace lfprobe {

enum class InputLimit {
    CameraPixels,         // LFPROBE_MAX_CAMERA_PIXELS, default 8192 × 8192
    TexturePixels,        // LFPROBE_MAX_TEXTURE_PIXELS, default 8192 × 8192
    ImagePixels,          // LFPROBE_MAX_IMAGE_PIXELS (images compared), default 8192 × 8192
    MaterialLibraryBytes, // LFPROBE_MAX_MTL_BYTES, default 64 MiB
    ObjBytes,             // LFPROBE_MAX_OBJ_BYTES, default 8 GiB
};

// The limit in force: the environment variable's value when set, else the default. InputError
// naming the variable when it is set to anything but a whole number from 1 to 2^62.
[[nodiscard]] std::int64_t input_limit(InputLimit which);

// The environment variable that overrides `which`, for messages ("... set LFPROBE_MAX_... to
// accept more").
[[nodiscard]] const char* input_limit_variable(InputLimit which);

// "at most N (set VARIABLE to change it)": the tail of every message that refuses an input for
// its size.
[[nodiscard]] std::string input_limit_hint(InputLimit which);

} // namespace lfprobe
