#include "lfprobe/point_cloud.hpp"

#include <algorithm>
#include <cmath>

#include "lfprobe/error.hpp"

namespace lfprobe {

PointCloud cloud_from_parts(std::vector<glm::vec3> positions, std::vector<glm::vec3> colors,
                            std::vector<glm::vec3> normals, std::vector<std::uint32_t> scan_index,
                            const std::vector<std::optional<glm::dvec3>>& scanners,
                            const glm::dvec3& world_offset, std::vector<float> intensities,
                            const std::vector<std::string>& scan_paths) {
    const std::size_t n = positions.size();
    for (const glm::vec3& p : positions) {
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
            throw InputError("positions: NaN or infinite coordinate");
        }
    }
    auto check_rows = [n](const std::vector<glm::vec3>& v, const char* what) {
        if (!v.empty() && v.size() != n) {
            throw InputError(std::string(what) + ": expected an array of shape (" +
                             std::to_string(n) + ", 3)");
        }
    };
    check_rows(colors, "colors");
    check_rows(normals, "normals");
    if (!intensities.empty() && intensities.size() != n) {
        throw InputError("intensities: expected an array of shape (" + std::to_string(n) + ",)");
    }
    for (const float v : intensities) {
        if (!std::isfinite(v)) {
            throw InputError("intensities: NaN or infinite value");
        }
    }
    const std::size_t scan_count = std::max<std::size_t>(1, scanners.size());
    if (!scan_paths.empty() && scan_paths.size() != scan_count) {
        throw InputError("scan_paths: expected one path per scan (" + std::to_string(scan_count) +
                         "), got " + std::to_string(scan_paths.size()));
    }
    if (scan_index.empty()) {
        scan_index.assign(n, 0);
    } else if (scan_index.size() != n) {
        throw InputError("scan_index: expected shape (n,)");
    }
    for (const std::uint32_t s : scan_index) {
        if (s >= scan_count) {
            throw InputError("scan_index: " + std::to_string(s) +
                             " names no scan (give one scanner entry per scan)");
        }
    }
    PointCloud cloud;
    cloud.world_offset = world_offset;
    cloud.positions = std::move(positions);
    cloud.colors = std::move(colors);
    cloud.normals = std::move(normals);
    cloud.intensities = std::move(intensities);
    cloud.scan_index = std::move(scan_index);
    cloud.scans.resize(scan_count);
    for (std::size_t s = 0; s < scan_count; ++s) {
        cloud.scans[s].path = scan_paths.empty() ? std::string("array") : scan_paths[s];
        if (s < scanners.size() && scanners[s]) {
            cloud.scans[s].scanner = *scanners[s];
            cloud.scans[s].has_scanner = true;
        }
    }
    for (const std::uint32_t s : cloud.scan_index) {
        ++cloud.scans[s].point_count;
    }
    return cloud;
}

} // namespace lfprobe
