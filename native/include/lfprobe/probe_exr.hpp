// One probe as one OpenEXR file (docs/DESIGN.md §3): R, G, B radiance and A confidence (half),
// Z radial distance (float32; NaN unknown, +inf empty), N.X, N.Y, N.Z normals (half).
// Texel (x, y) is pixel column x, scanline y. Written to a temporary name and renamed.
#pragma once

#include <string>

#include "lfprobe/probe_map.hpp"

namespace lfprobe {

void write_probe_exr(const std::string& path, const ProbeMap& map);

// Throws InputError naming the file when it is not a probe EXR (missing channels, not square).
[[nodiscard]] ProbeMap read_probe_exr(const std::string& path);

// Writes `bytes` to `path` through a temporary file in the same folder and a rename, so
// readers never see a half-written file. Throws IoError.
void write_file_atomically(const std::string& path, const std::string& bytes);

// A temporary name beside `path` that no other writer in this or another process uses
// (PATH.tmp.PID.N). Temporaries of `path` that a killed process left are removed first.
[[nodiscard]] std::string temporary_path_for(const std::string& path);

} // namespace lfprobe
