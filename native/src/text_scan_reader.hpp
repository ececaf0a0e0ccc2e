// Readers for the text scan formats: the .xyz family (.xyz, .txt, .asc, .csv) and Leica .pts.
#pragma once

#include <string>

#include "lfprobe/mapped_file.hpp"
#include "lfprobe/progress.hpp"
#include "lfprobe/scan_reader.hpp"

namespace lfprobe::detail {

// `columns` is ScanReadOptions::columns (empty: from the header or the column count).
[[nodiscard]] ScanFile read_xyz_scan(const MappedFile& file, const std::string& columns,
                                     Progress* progress);
[[nodiscard]] ScanFile read_pts_scan(const MappedFile& file, const std::string& columns,
                                     Progress* progress);

} // namespace lfprobe::detail
