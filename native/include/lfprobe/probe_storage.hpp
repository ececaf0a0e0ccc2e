// How a loaded probe holds its channels in memory (issue 7: "storage sized to the data").
//
// A probe is baked and written at full precision (half RGBA, float32 distance, half normals:
// docs/DESIGN.md §3), but a trace reads only three things per texel: the radial distance (every
// texel it visits), and at a hit the radiance and the normal's side. Scan colours are 8-bit
// sRGB, a scanner measures range to millimetres, and the face test needs a normal to about a
// degree; the confidence channel is never read. The compact form keeps exactly that: distance
// as a 16-bit multiple of a step (code 0 unknown, 65535 empty, so the three texel states stay
// apart), radiance as 8-bit sRGB, the normal as an 8+8-bit octahedral code: 7 bytes a texel
// against 18. A field then holds the coarse levels in the same steps (MinDistancePyramid).
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <glm/vec3.hpp>
#include <nlohmann/json_fwd.hpp>

namespace lfprobe {

struct ProbeMap;

// The distance quantum "compact" takes when none is given: 1 mm, half the range noise of a
// FARO-class scanner at 10 m (about 2 mm), so quantisation stays below what the scan carries.
inline constexpr double kDefaultDistanceStep = 0.001;

enum class RadiancePrecision : std::uint8_t {
    Half,  // linear half floats, as on disk (HDR data, meshes with emission)
    Srgb8, // 8-bit sRGB, the precision of scan colours and 8-bit textures
};

enum class NormalPrecision : std::uint8_t {
    Half,  // three half floats, as on disk
    Oct16, // octahedral code, 8 bits per coordinate (at most about 1° off)
};

struct ProbeStorage {
    RadiancePrecision radiance = RadiancePrecision::Half;
    NormalPrecision normal = NormalPrecision::Half;
    // Distance quantum in metres; 0 keeps float32. A probe whose farthest surface does not fit
    // 65534 steps gets a coarser step of its own (recorded in its packed channels).
    double distance_step = 0.0;
    // The A channel (the trace never reads it). Only 8-bit sRGB radiance drops it: half
    // radiance stays RGBA as in the file.
    bool keep_confidence = true;

    [[nodiscard]] bool is_full() const {
        return radiance == RadiancePrecision::Half && normal == NormalPrecision::Half &&
               distance_step == 0.0 && keep_confidence;
    }
    // The one compact format of this header: 8-bit sRGB, oct16 normals, `step` metres.
    [[nodiscard]] static ProbeStorage compact(double step);
    [[nodiscard]] static ProbeStorage full() { return {}; }

    // {"radiance": "half"|"srgb8", "normal": "half"|"oct16", "distance_step": m,
    //  "confidence": bool}
    [[nodiscard]] nlohmann::json to_json() const;
    // "full", "compact" (with `step`, kDefaultDistanceStep when 0) or InputError.
    [[nodiscard]] static ProbeStorage from_name(const std::string& name, double step = 0.0);
    // InputError naming `where` for unknown names or a negative step.
    [[nodiscard]] static ProbeStorage from_json(const nlohmann::json& j, const std::string& where);
    // Bytes one texel takes in memory.
    [[nodiscard]] std::size_t bytes_per_texel() const;
};

// Codes of the 16-bit distance channel.
inline constexpr std::uint16_t kUnknownDistanceCode = 0;
inline constexpr std::uint16_t kEmptyDistanceCode = 0xFFFF;
inline constexpr std::uint16_t kLargestDistanceCode = 0xFFFE;

// The compact channels of one probe. A channel vector is empty when that channel is kept in
// the map's full-precision vectors instead.
struct PackedChannels {
    double distance_step = 0.0;          // metres per code; 0: distance stays float32
    std::vector<std::uint16_t> distance; // codes (see above)
    std::vector<std::uint8_t> srgb;      // 3 per texel
    std::vector<std::uint16_t> normal;   // octahedral, u in the low byte, v in the high
    [[nodiscard]] std::size_t memory_bytes() const {
        return distance.size() * sizeof(std::uint16_t) + srgb.size() +
               normal.size() * sizeof(std::uint16_t);
    }
};

// Linear value of an 8-bit sRGB code (a table: the decode is on the trace's hit path).
[[nodiscard]] float srgb8_to_linear(std::uint8_t code);
// The nearest 8-bit sRGB code of a linear value (clamped to [0, 1]).
[[nodiscard]] std::uint8_t linear_to_srgb8(float linear);

[[nodiscard]] std::uint16_t encode_normal_oct16(const glm::vec3& n);
[[nodiscard]] glm::vec3 decode_normal_oct16(std::uint16_t code);

// Distance `d` (NaN unknown, +inf empty) as a code of `step`, and back.
[[nodiscard]] std::uint16_t encode_distance(float d, double step);
[[nodiscard]] inline float decode_distance(std::uint16_t code, double step) {
    if (code == kUnknownDistanceCode) {
        return std::numeric_limits<float>::quiet_NaN();
    }
    if (code == kEmptyDistanceCode) {
        return std::numeric_limits<float>::infinity();
    }
    return static_cast<float>(static_cast<double>(code) * step);
}

// What packing changed, for reports: the largest distance error on surface texels and whether
// a probe had to take a coarser step than asked, the largest radiance clamped.
struct PackSummary {
    double distance_step = 0.0;
    double max_distance_error = 0.0;
    float max_radiance = 0.0f;
};

// Converts `map` in place to `storage`: its full-precision channels that the storage replaces
// are freed. States are kept exactly (unknown stays unknown, empty stays empty, a surface
// stays a surface). A map already packed is an InputError.
PackSummary pack_probe(ProbeMap& map, const ProbeStorage& storage);

// The decoded distances of a map in either form (NaN unknown, +inf empty), for building its
// coarse levels from exactly what the trace will read.
[[nodiscard]] std::vector<float> decoded_distances(const ProbeMap& map);

} // namespace lfprobe
