#include "lfprobe/probe_exr.hpp"

#include <cmath>
#include <filesystem>
#include <mutex>
#include <string>
#include <thread>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>
#include <ImfThreading.h>
#include <ImfVecAttribute.h>

#include "lfprobe/error.hpp"

namespace lfprobe {

namespace {

constexpr const char* kFormatAttribute = "lfprobe/format";
constexpr const char* kFormatValue = "lfprobe-probe 1";
constexpr const char* kPositionAttribute = "lfprobe/position";
// Optional: written only for maps that know their texels' coverage (ProbeMap::coverage).
constexpr const char* kCoverageChannel = "coverage";

void use_all_cores_for_exr() {
    static std::once_flag once;
    std::call_once(once, [] {
        Imf::setGlobalThreadCount(
            static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
    });
}

// Slices over the map's arrays, shared by reading and writing so the layout is stated once.
Imf::FrameBuffer probe_frame_buffer(ProbeMap& map) {
    const std::size_t n = static_cast<std::size_t>(map.resolution);
    Imf::FrameBuffer fb;
    const char* rgba_names[4] = {"R", "G", "B", "A"};
    for (std::size_t c = 0; c < 4; ++c) {
        fb.insert(rgba_names[c], Imf::Slice(Imf::HALF, reinterpret_cast<char*>(map.rgba.data() + c),
                                            4 * sizeof(Imath::half), 4 * sizeof(Imath::half) * n));
    }
    fb.insert("Z", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(map.distance.data()),
                              sizeof(float), sizeof(float) * n));
    const char* normal_names[3] = {"N.X", "N.Y", "N.Z"};
    for (std::size_t c = 0; c < 3; ++c) {
        fb.insert(normal_names[c],
                  Imf::Slice(Imf::HALF, reinterpret_cast<char*>(map.normal.data() + c),
                             3 * sizeof(Imath::half), 3 * sizeof(Imath::half) * n));
    }
    if (!map.coverage.empty()) {
        fb.insert(kCoverageChannel,
                  Imf::Slice(Imf::HALF, reinterpret_cast<char*>(map.coverage.data()),
                             sizeof(Imath::half), sizeof(Imath::half) * n));
    }
    return fb;
}

} // namespace

void write_probe_exr(const std::string& path, const ProbeMap& map) {
    use_all_cores_for_exr();
    const int n = map.resolution;
    Imf::Header header(n, n);
    header.compression() = Imf::ZIP_COMPRESSION;
    for (const char* name : {"R", "G", "B", "A", "N.X", "N.Y", "N.Z"}) {
        header.channels().insert(name, Imf::Channel(Imf::HALF));
    }
    header.channels().insert("Z", Imf::Channel(Imf::FLOAT));
    if (!map.coverage.empty()) {
        header.channels().insert(kCoverageChannel, Imf::Channel(Imf::HALF));
    }
    header.insert(kFormatAttribute, Imf::StringAttribute(kFormatValue));
    header.insert(kPositionAttribute,
                  Imf::V3dAttribute(Imath::V3d(map.position.x, map.position.y, map.position.z)));
    const std::string tmp = temporary_path_for(path);
    try {
        {
            Imf::OutputFile file(tmp.c_str(), header);
            // The writer only reads through the slices; the cast lets one layout serve both ways.
            file.setFrameBuffer(probe_frame_buffer(const_cast<ProbeMap&>(map)));
            file.writePixels(n);
        }
        std::filesystem::rename(tmp, path);
    } catch (const std::exception& e) {
        std::error_code ignored;
        std::filesystem::remove(tmp, ignored);
        throw IoError(path + ": cannot write probe EXR (" + e.what() + ")");
    }
}

namespace {

// What a texel can mean (docs/DESIGN.md §3): a distance is NaN (unknown), +inf (empty) or a
// finite number of metres, 0 or more; a confidence lies in [0, 1]; a surface has a radiance and
// a normal that are numbers. Anything else (a negative or -inf distance, a NaN confidence) was
// not written by a bake, and a trace would answer from it without complaint.
void require_meaningful_texels(const ProbeMap& map, const std::string& path) {
    const auto where = [&](std::size_t i) {
        return path + ": texel (" + std::to_string(i % static_cast<std::size_t>(map.resolution)) +
               ", " + std::to_string(i / static_cast<std::size_t>(map.resolution)) + ")";
    };
    for (std::size_t i = 0; i < map.texel_count(); ++i) {
        const float d = map.distance[i];
        if (d < 0.0f) {
            throw InputError(where(i) + ": distance " + std::to_string(d) +
                             " (expected 0 or more metres, NaN for unknown, +inf for empty)");
        }
        if (!map.coverage.empty()) {
            const float coverage = static_cast<float>(map.coverage[i]);
            if (!(coverage >= 0.0f && coverage <= 1.0f)) {
                throw InputError(where(i) + ": coverage " + std::to_string(coverage) +
                                 " (expected a number from 0 to 1)");
            }
        }
        const float confidence = static_cast<float>(map.rgba[4 * i + 3]);
        if (!(confidence >= 0.0f && confidence <= 1.0f)) {
            throw InputError(where(i) + ": confidence (A) " + std::to_string(confidence) +
                             " (expected a number from 0 to 1)");
        }
        if (std::isfinite(d)) {
            const glm::vec3 rgb = map.radiance_at(i);
            const glm::vec3 n = map.normal_at(i);
            if (std::isnan(rgb.x) || std::isnan(rgb.y) || std::isnan(rgb.z) || std::isnan(n.x) ||
                std::isnan(n.y) || std::isnan(n.z)) {
                throw InputError(where(i) + ": a surface texel whose radiance or normal is NaN");
            }
        }
    }
}

} // namespace

ProbeMap read_probe_exr(const std::string& path) {
    use_all_cores_for_exr();
    if (!std::filesystem::exists(path)) {
        throw MissingFileError(path + ": no such probe file");
    }
    try {
        Imf::InputFile file(path.c_str());
        const Imath::Box2i window = file.header().dataWindow();
        const int w = window.max.x - window.min.x + 1;
        const int h = window.max.y - window.min.y + 1;
        if (w != h || w < 1 || window.min.x != 0 || window.min.y != 0) {
            throw InputError(path +
                             ": expected a square probe map with its data window at (0, 0), "
                             "got " +
                             std::to_string(w) + "×" + std::to_string(h));
        }
        const Imf::ChannelList& channels = file.header().channels();
        for (const char* name : {"R", "G", "B", "A", "Z", "N.X", "N.Y", "N.Z"}) {
            if (channels.findChannel(name) == nullptr) {
                throw InputError(path + ": expected channel '" + name +
                                 "' of a probe EXR (R G B A Z N.X N.Y N.Z)");
            }
        }
        glm::dvec3 position(0.0);
        if (const auto* attr =
                file.header().findTypedAttribute<Imf::V3dAttribute>(kPositionAttribute)) {
            position = glm::dvec3(attr->value().x, attr->value().y, attr->value().z);
        }
        ProbeMap map(w, position);
        if (channels.findChannel(kCoverageChannel) != nullptr) {
            map.coverage.assign(map.texel_count(), Imath::half(1.0f));
        }
        file.setFrameBuffer(probe_frame_buffer(map));
        file.readPixels(window.min.y, window.max.y);
        require_meaningful_texels(map, path);
        return map;
    } catch (const InputError&) {
        throw;
    } catch (const std::exception& e) {
        throw InputError(path + ": not a readable probe EXR (" + e.what() + ")");
    }
}

} // namespace lfprobe
