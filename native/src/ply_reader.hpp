// Reader for .ply point clouds: ascii, binary_little_endian and binary_big_endian.
#pragma once

#include "lfprobe/mapped_file.hpp"
#include "lfprobe/progress.hpp"
#include "lfprobe/scan_reader.hpp"

namespace lfprobe::detail {

[[nodiscard]] ScanFile read_ply_scan(const MappedFile& file, Progress* progress);

} // namespace lfprobe::detail
