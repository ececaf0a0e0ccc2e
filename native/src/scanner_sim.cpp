#include "lfprobe/scanner_sim.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <string>
#include <system_error>
#include <vector>

#include <glm/common.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lfprobe/color.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/probe_exr.hpp"
#include "lfprobe/world_offset.hpp"

namespace lfprobe {

namespace {

// SplitMix64: a counter-based generator, so that each ray's noise is independent of the
// order (and the threads) in which rays are traced.
std::uint64_t splitmix(std::uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

double unit_uniform(std::uint64_t bits) {
    // 53 random bits in (0, 1): never 0, so the logarithm below is finite.
    return (static_cast<double>(bits >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}

// Standard normal sample for ray k (Box–Muller).
double gaussian(std::uint64_t seed, std::uint64_t k) {
    const std::uint64_t a = splitmix(seed * 0x100000001B3ull ^ splitmix(2 * k));
    const std::uint64_t b = splitmix(a ^ splitmix(2 * k + 1));
    const double u1 = unit_uniform(a);
    const double u2 = unit_uniform(b);
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

struct Pattern {
    int azimuths = 0;
    int elevations = 0; // rows below the zenith
    double step = 0.0;  // radians
    double elevation_min = 0.0;
    double azimuth_start = 0.0; // radians
    [[nodiscard]] std::uint64_t rays() const {
        return static_cast<std::uint64_t>(azimuths) * static_cast<std::uint64_t>(elevations) + 1;
    }
};

Pattern pattern_of(const ScannerSettings& s) {
    if (!(s.step_deg > 0.0) || s.step_deg > 90.0) {
        throw InputError("scan: step_deg must be in (0, 90], got " + std::to_string(s.step_deg));
    }
    if (!(s.vertical_fov_deg > 0.0) || s.vertical_fov_deg > 360.0) {
        throw InputError("scan: vertical_fov must be in (0, 360], got " +
                         std::to_string(s.vertical_fov_deg));
    }
    if (!(s.horizontal_fov_deg > 0.0) || s.horizontal_fov_deg > 360.0) {
        throw InputError("scan: horizontal_fov must be in (0, 360], got " +
                         std::to_string(s.horizontal_fov_deg));
    }
    if (!std::isfinite(s.horizontal_start_deg)) {
        throw InputError("scan: horizontal_start must be a finite angle in degrees");
    }
    if (!(s.noise_mm >= 0.0)) {
        throw InputError("scan: noise_mm must be at least 0");
    }
    Pattern p;
    const double deg = std::numbers::pi / 180.0;
    p.step = s.step_deg * deg;
    p.azimuths = std::max(1, static_cast<int>(std::lround(s.horizontal_fov_deg / s.step_deg)));
    p.azimuth_start = std::fmod(s.horizontal_start_deg, 360.0) * deg;
    const double span = std::min(180.0, s.vertical_fov_deg / 2.0); // from the zenith down
    p.elevation_min = (90.0 - span) * deg;
    // Rows strictly below the zenith: j·step < span (the row at j·step = span is the zenith).
    p.elevations = static_cast<int>(std::floor(span / s.step_deg - 1e-9)) + 1;
    if (p.elevations > 200000 || static_cast<double>(p.azimuths) * p.elevations > 5.0e8) {
        throw InputError("scan: step_deg gives too many rays");
    }
    return p;
}

// The 8-bit sRGB value a simulated scan stores for a linear colour channel, as a scanner's file
// holds it.
int srgb_byte(float linear) {
    return static_cast<int>(std::lround(linear_to_srgb(std::clamp(linear, 0.0f, 1.0f)) * 255.0f));
}

} // namespace

std::vector<SimulatedPoint> simulate_scan(const EmbreeScene& scene, const ScannerSettings& settings,
                                          Progress* progress, ScanStats* stats) {
    const Pattern p = pattern_of(settings);
    const glm::dvec3 local_origin = settings.position - scene.mesh().world_offset;
    const double sigma_per_metre = settings.noise_mm * 1e-3 / 10.0;
    // The footprint's width per metre of range: the angle between neighbouring rays.
    const double spread = settings.filter_textures ? p.step : 0.0;
    // Row j < elevations: elevation_min + j·step; row `elevations` is the zenith (one ray).
    const int rows = p.elevations + 1;
    std::vector<std::vector<SimulatedPoint>> per_row(static_cast<std::size_t>(rows));
    if (progress != nullptr) {
        progress->begin_stage("scanning", static_cast<std::uint64_t>(rows));
    }
    const auto start = std::chrono::steady_clock::now();
    tbb::parallel_for(tbb::blocked_range<int>(0, rows), [&](const tbb::blocked_range<int>& r) {
        for (int j = r.begin(); j < r.end(); ++j) {
            if (progress != nullptr) {
                progress->throw_if_cancelled();
            }
            const bool zenith = j == p.elevations;
            const double elevation = zenith ? std::numbers::pi / 2.0 : p.elevation_min + j * p.step;
            const int count = zenith ? 1 : p.azimuths;
            auto& out = per_row[static_cast<std::size_t>(j)];
            // A row's rays a packet at a time: neighbours a step apart, traced together
            // (EmbreeScene::intersect_coherent).
            constexpr int kPacket = static_cast<int>(EmbreeScene::kPacket);
            std::array<Ray, EmbreeScene::kPacket> rays;
            std::array<MeshHit, EmbreeScene::kPacket> hits;
            for (int first = 0; first < count; first += kPacket) {
                const int live = std::min(kPacket, count - first);
                for (int q = 0; q < live; ++q) {
                    const double azimuth = p.azimuth_start + (first + q) * p.step;
                    Ray& ray = rays[static_cast<std::size_t>(q)];
                    ray.origin = local_origin;
                    ray.direction = zenith ? glm::dvec3(0.0, 0.0, 1.0)
                                           : glm::dvec3(std::cos(elevation) * std::cos(azimuth),
                                                        std::cos(elevation) * std::sin(azimuth),
                                                        std::sin(elevation));
                    ray.t_max = settings.max_range;
                }
                scene.intersect_coherent(rays.data(), static_cast<std::size_t>(live), spread,
                                         hits.data());
                for (int q = 0; q < live; ++q) {
                    const MeshHit& h = hits[static_cast<std::size_t>(q)];
                    if (!h.hit) {
                        continue;
                    }
                    const std::uint64_t index =
                        static_cast<std::uint64_t>(j) * static_cast<std::uint64_t>(p.azimuths) +
                        static_cast<std::uint64_t>(first + q);
                    const double range =
                        h.t + sigma_per_metre * h.t * gaussian(settings.seed, index);
                    out.push_back(SimulatedPoint{
                        settings.position + range * rays[static_cast<std::size_t>(q)].direction,
                        h.base_color});
                }
            }
            if (progress != nullptr) {
                progress->advance(1);
            }
        }
    });
    std::vector<SimulatedPoint> points;
    for (auto& row : per_row) {
        points.insert(points.end(), row.begin(), row.end());
    }
    if (stats != nullptr) {
        stats->rays = p.rays();
        stats->points = points.size();
        stats->seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    return points;
}

namespace {

// The longest line format_xyz_line writes: three coordinates of at most 1e15 m (world_offset.hpp
// bounds them far below) at 6 decimals, three bytes, spaces and the newline.
constexpr std::size_t kMaxXyzLine = 3 * 24 + 3 * 4 + 1;

// Writes "x y z r g b\n" for a point at `first` as printf("%.6f %.6f %.6f %d %d %d\n") would;
// returns the end.
char* format_xyz_line(char* first, const glm::dvec3& position, const glm::vec3& colour) {
    char* const last = first + kMaxXyzLine;
    for (int axis = 0; axis < 3; ++axis) {
        const std::to_chars_result written =
            std::to_chars(first, last, position[axis], std::chars_format::fixed, 6);
        if (written.ec != std::errc{}) {
            throw InputError("simulated scan: a point's coordinate " +
                             std::to_string(position[axis]) + " is too large to write");
        }
        first = written.ptr;
        *first++ = ' ';
    }
    for (int c = 0; c < 3; ++c) {
        first = std::to_chars(first, last, srgb_byte(colour[c])).ptr;
        *first++ = c < 2 ? ' ' : '\n';
    }
    return first;
}

} // namespace

ScanStats write_simulated_scan(const EmbreeScene& scene, const ScannerSettings& settings,
                               const std::string& path, Progress* progress) {
    ScanStats stats;
    const std::vector<SimulatedPoint> points = simulate_scan(scene, settings, progress, &stats);
    std::string text;
    text.reserve(points.size() * 48 + 256);
    char line[256];
    std::snprintf(line, sizeof line, "# scanner %.6f %.6f %.6f\n", settings.position.x,
                  settings.position.y, settings.position.z);
    text += line;
    std::snprintf(line, sizeof line,
                  "# lfprobe simulated scan: step %g deg, vertical fov %g deg, noise %g mm at "
                  "10 m, seed %llu\n",
                  settings.step_deg, settings.vertical_fov_deg, settings.noise_mm,
                  static_cast<unsigned long long>(settings.seed));
    text += line;
    if (settings.horizontal_fov_deg < 360.0) {
        std::snprintf(line, sizeof line,
                      "# partial sweep: horizontal fov %g deg from azimuth %g deg\n",
                      settings.horizontal_fov_deg, settings.horizontal_start_deg);
        text += line;
    }
    // The lines "x y z r g b" (%.6f, bytes) formatted in blocks on all cores with to_chars,
    // which prints what printf prints: one core's snprintf took twice the scan's time.
    constexpr std::size_t kPointsPerBlock = 1 << 16;
    const std::size_t blocks = (points.size() + kPointsPerBlock - 1) / kPointsPerBlock;
    std::vector<std::string> parts(blocks);
    tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
        std::string& part = parts[b];
        const std::size_t end = std::min(points.size(), (b + 1) * kPointsPerBlock);
        part.resize((end - b * kPointsPerBlock) * kMaxXyzLine);
        char* out = part.data();
        for (std::size_t i = b * kPointsPerBlock; i < end; ++i) {
            out = format_xyz_line(out, points[i].position, points[i].color);
        }
        part.resize(static_cast<std::size_t>(out - part.data()));
    });
    for (const std::string& part : parts) {
        text += part;
    }
    write_file_atomically(path, text);
    return stats;
}

PointCloud simulate_scans_cloud(const EmbreeScene& scene,
                                const std::vector<ScannerSettings>& scanners, Progress* progress,
                                std::vector<ScanStats>* stats) {
    std::vector<std::vector<SimulatedPoint>> scans;
    glm::dvec3 lo(std::numeric_limits<double>::infinity());
    glm::dvec3 hi(-std::numeric_limits<double>::infinity());
    std::size_t total = 0;
    for (const ScannerSettings& settings : scanners) {
        ScanStats scan_stats;
        scans.push_back(simulate_scan(scene, settings, progress, &scan_stats));
        for (const SimulatedPoint& q : scans.back()) {
            lo = glm::min(lo, q.position);
            hi = glm::max(hi, q.position);
        }
        total += scans.back().size();
        if (stats != nullptr) {
            stats->push_back(scan_stats);
        }
    }
    PointCloud cloud;
    cloud.world_offset = world_offset_for_bounds(lo, hi);
    cloud.positions.resize(total);
    cloud.colors.resize(total);
    cloud.scan_index.resize(total);
    const std::array<float, 256>& decode = srgb8_to_linear_table();
    const auto byte = [](float linear) { return static_cast<std::size_t>(srgb_byte(linear)); };
    std::size_t first = 0;
    for (std::size_t k = 0; k < scans.size(); ++k) {
        if (progress != nullptr) {
            progress->throw_if_cancelled();
        }
        std::vector<SimulatedPoint>& points = scans[k];
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 1 << 14),
                          [&](const tbb::blocked_range<std::size_t>& r) {
                              for (std::size_t i = r.begin(); i < r.end(); ++i) {
                                  const SimulatedPoint& q = points[i];
                                  cloud.positions[first + i] =
                                      glm::vec3(q.position - cloud.world_offset);
                                  cloud.colors[first + i] =
                                      glm::vec3(decode[byte(q.color.x)], decode[byte(q.color.y)],
                                                decode[byte(q.color.z)]);
                                  cloud.scan_index[first + i] = static_cast<std::uint32_t>(k);
                              }
                          });
        ScanSource source;
        source.path = "simulated scan " + std::to_string(k);
        source.point_count = points.size();
        source.scanner = scanners[k].position - cloud.world_offset;
        source.has_scanner = true;
        cloud.scans.push_back(source);
        first += points.size();
        points = std::vector<SimulatedPoint>(); // freed as soon as it is in the cloud
    }
    return cloud;
}

} // namespace lfprobe
