#include "lfprobe/probe_storage.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "lfprobe/color.hpp"
#include "lfprobe/enum_names.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/octahedral.hpp"
#include "lfprobe/probe_map.hpp"

namespace lfprobe {

ProbeStorage ProbeStorage::compact(double step) {
    ProbeStorage s;
    s.radiance = RadiancePrecision::Srgb8;
    s.normal = NormalPrecision::Oct16;
    s.distance_step = step;
    s.keep_confidence = false;
    return s;
}

ProbeStorage ProbeStorage::from_name(const std::string& name, double step) {
    if (!std::isfinite(step) || step < 0.0) {
        throw InputError("storage: the distance step must be a positive number of metres");
    }
    if (name == "full") {
        return full();
    }
    if (name == "compact") {
        return compact(step > 0.0 ? step : kDefaultDistanceStep);
    }
    throw InputError("storage: expected \"full\" or \"compact\", got \"" + name + "\"");
}

namespace {

constexpr auto radiance_precision_names = std::to_array<EnumName<RadiancePrecision>>({
    {RadiancePrecision::Half, "half"},
    {RadiancePrecision::Srgb8, "srgb8"},
});
constexpr auto normal_precision_names = std::to_array<EnumName<NormalPrecision>>({
    {NormalPrecision::Half, "half"},
    {NormalPrecision::Oct16, "oct16"},
});

} // namespace

nlohmann::json ProbeStorage::to_json() const {
    return nlohmann::json{{"radiance", name_of(radiance_precision_names, radiance)},
                          {"normal", name_of(normal_precision_names, normal)},
                          {"distance_step", distance_step},
                          {"confidence", keep_confidence}};
}

ProbeStorage ProbeStorage::from_json(const nlohmann::json& j, const std::string& where) {
    if (!j.is_object()) {
        throw InputError(where + ": storage: expected an object with radiance, normal, "
                                 "distance_step, confidence");
    }
    ProbeStorage s;
    try {
        const std::string radiance = j.value("radiance", std::string("half"));
        const std::string normal = j.value("normal", std::string("half"));
        s.radiance = value_named_or_throw(radiance_precision_names, radiance,
                                          where +
                                              ": storage.radiance: expected \"half\" or "
                                              "\"srgb8\", got \"" +
                                              radiance + "\"");
        s.normal = value_named_or_throw(normal_precision_names, normal,
                                        where +
                                            ": storage.normal: expected \"half\" or "
                                            "\"oct16\", got \"" +
                                            normal + "\"");
        s.distance_step = j.value("distance_step", 0.0);
        s.keep_confidence = j.value("confidence", true);
    } catch (const nlohmann::json::exception& e) {
        throw InputError(where + ": storage: " + e.what());
    }
    if (!std::isfinite(s.distance_step) || s.distance_step < 0.0) {
        throw InputError(where + ": storage.distance_step: expected 0 (float32) or a positive "
                                 "number of metres");
    }
    return s;
}

std::size_t ProbeStorage::bytes_per_texel() const {
    std::size_t bytes = distance_step > 0.0 ? 2 : 4;
    // Half radiance keeps the RGBA layout of the file (A interleaved, whatever keep_confidence
    // says); 8-bit sRGB has no A.
    bytes += radiance == RadiancePrecision::Srgb8 ? 3 : 8;
    bytes += normal == NormalPrecision::Oct16 ? 2 : 6;
    return bytes;
}

float srgb8_to_linear(std::uint8_t code) {
    return srgb8_to_linear_table()[code];
}

std::uint8_t linear_to_srgb8(float linear) {
    const float c = linear_to_srgb(std::clamp(linear, 0.0f, 1.0f));
    return static_cast<std::uint8_t>(std::clamp(std::lround(c * 255.0f), 0L, 255L));
}

std::uint16_t encode_normal_oct16(const glm::vec3& n) {
    if (!oct::is_valid_direction(n)) {
        return 0; // no surface: the code is never read
    }
    // 254 steps over [0, 1], so that uv = 0.5 (the axes and the equator's folds) has a code.
    const glm::vec2 uv = oct::encode(n);
    const auto quantise = [](float a) {
        return static_cast<std::uint16_t>(std::clamp(std::lround(a * 254.0f), 0L, 254L));
    };
    return static_cast<std::uint16_t>(quantise(uv.x) | (quantise(uv.y) << 8));
}

glm::vec3 decode_normal_oct16(std::uint16_t code) {
    const glm::vec2 uv(static_cast<float>(code & 0xFF) / 254.0f,
                       static_cast<float>(code >> 8) / 254.0f);
    return glm::normalize(oct::decode(uv));
}

std::uint16_t encode_distance(float d, double step) {
    if (std::isnan(d)) {
        return kUnknownDistanceCode;
    }
    if (std::isinf(d)) {
        return kEmptyDistanceCode;
    }
    // A surface never becomes code 0 (unknown) or 65535 (empty): its state is kept.
    const double code = std::round(static_cast<double>(d) / step);
    return static_cast<std::uint16_t>(
        std::clamp(code, 1.0, static_cast<double>(kLargestDistanceCode)));
}

PackSummary pack_probe(ProbeMap& map, const ProbeStorage& storage) {
    if (map.is_packed()) {
        throw InputError("pack probe: the probe is packed already");
    }
    if (!map.is_complete()) {
        throw InputError("pack probe: the probe map is empty or inconsistent (resolution " +
                         std::to_string(map.resolution) + ")");
    }
    const std::size_t n = map.texel_count();
    PackSummary summary;
    if (storage.distance_step > 0.0) {
        float farthest = 0.0f;
        for (const float d : map.distance) {
            if (std::isfinite(d)) {
                farthest = std::max(farthest, d);
            }
        }
        // The step asked for, or the finest one that still reaches the farthest surface.
        const double step =
            std::max(storage.distance_step, static_cast<double>(farthest) / kLargestDistanceCode);
        std::vector<std::uint16_t> codes(n);
        for (std::size_t i = 0; i < n; ++i) {
            const float d = map.distance[i];
            codes[i] = encode_distance(d, step);
            if (std::isfinite(d)) {
                const double error =
                    std::abs(static_cast<double>(decode_distance(codes[i], step)) - d);
                summary.max_distance_error = std::max(summary.max_distance_error, error);
            }
        }
        map.packed.distance_step = step;
        map.packed.distance = std::move(codes);
        summary.distance_step = step;
        std::vector<float>().swap(map.distance);
    }
    if (storage.normal == NormalPrecision::Oct16) {
        // Filled aside first: the accessors read the packed channel as soon as it is there.
        std::vector<std::uint16_t> codes(n);
        for (std::size_t i = 0; i < n; ++i) {
            codes[i] = encode_normal_oct16(map.normal_at(i));
        }
        map.packed.normal = std::move(codes);
        std::vector<Imath::half>().swap(map.normal);
    }
    if (storage.radiance == RadiancePrecision::Srgb8) {
        std::vector<std::uint8_t> codes(3 * n);
        for (std::size_t i = 0; i < n; ++i) {
            const glm::vec3 rgb = map.radiance_at(i);
            for (int c = 0; c < 3; ++c) {
                summary.max_radiance = std::max(summary.max_radiance, rgb[c]);
                codes[3 * i + static_cast<std::size_t>(c)] = linear_to_srgb8(rgb[c]);
            }
        }
        map.packed.srgb = std::move(codes);
        std::vector<Imath::half>().swap(map.rgba); // A goes with it: the trace never reads it
    }
    return summary;
}

std::vector<float> decoded_distances(const ProbeMap& map) {
    if (map.packed.distance.empty()) {
        return map.distance;
    }
    std::vector<float> out(map.packed.distance.size());
    for (std::size_t i = 0; i < out.size(); ++i) {
        out[i] = decode_distance(map.packed.distance[i], map.packed.distance_step);
    }
    return out;
}

} // namespace lfprobe
