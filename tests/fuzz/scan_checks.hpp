// The promises of a parsed scan: one finite position per point, the optional arrays either
// empty or one value per point, colours finite.
#pragma once

#include <cmath>

#include <glm/vec3.hpp>

#include "fuzz_support.hpp"
#include "lfprobe/scan_reader.hpp"

namespace lfprobe::fuzz {

inline bool finite(const glm::vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

inline bool finite(const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

inline void check_scan(const ScanFile& scan) {
    const std::size_t n = scan.positions.size();
    expect(finite(scan.origin), "scan origin is not finite");
    expect(!scan.has_scanner || finite(scan.scanner), "scanner position is not finite");
    expect(scan.colors.empty() || scan.colors.size() == n, "colour count differs from points");
    expect(scan.normals.empty() || scan.normals.size() == n, "normal count differs from points");
    expect(scan.intensities.empty() || scan.intensities.size() == n,
           "intensity count differs from points");
    for (const glm::vec3& p : scan.positions) {
        expect(finite(p), "a point position is not finite");
    }
    for (const glm::vec3& c : scan.colors) {
        expect(finite(c), "a point colour is not finite");
    }
}

} // namespace lfprobe::fuzz
