#include "lfprobe/image_exr.hpp"

#include <cmath>
#include <filesystem>
#include <limits>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>
#include <nlohmann/json.hpp>

#include "lfprobe/error.hpp"
#include "lfprobe/image_metadata.hpp"
#include "lfprobe/probe_exr.hpp"

namespace lfprobe {

namespace {

constexpr const char* kImageFormatAttribute = "lfprobe/format";
constexpr const char* kImageFormatValue = "lfprobe-render 1";
constexpr const char* kMetadataAttribute = "lfprobe/render";

// The float planes of a file, in channel order.
struct Planes {
    std::vector<float> status;
    std::vector<float> probe;
    std::vector<float> steps;
    std::vector<float> object;  // empty when the image has no object channel
    std::vector<float> guessed; // empty when the image has no guessed channel
};

// The analysis channels, written as a pass name and a one-letter channel ("status.X"): Blender's
// multilayer reader takes the last '.' token as the channel id and accepts only one letter (or
// red, green, blue, alpha); Blender 3.4 drops a channel named "status" ("unknown channel token")
// and so loses the pass. X is the id Blender itself gives one-channel passes (IndexOB.X, value
// AOVs, this engine's LFP Status.X). Files written before carry the bare names; both are read.
struct AnalysisChannel {
    const char* name; // written
    const char* old_name;
};
constexpr AnalysisChannel kStatus{"status.X", "status"};
constexpr AnalysisChannel kProbe{"probe.X", "probe"};
constexpr AnalysisChannel kSteps{"steps.X", "steps"};
constexpr AnalysisChannel kObject{"object.X", "object"};
constexpr AnalysisChannel kGuessed{"guessed.X", "guessed.X"}; // no older name

// The names of the analysis channels in one file.
struct AnalysisNames {
    const char* status = kStatus.name;
    const char* probe = kProbe.name;
    const char* steps = kSteps.name;
    const char* object = kObject.name;
    const char* guessed = kGuessed.name;
};

// The name `channel` has in `header`: the current one, else the older one; nullptr for neither.
const char* find_analysis_channel(const Imf::Header& header, const AnalysisChannel& channel) {
    for (const char* name : {channel.name, channel.old_name}) {
        if (header.channels().findChannel(name) != nullptr) {
            return name;
        }
    }
    return nullptr;
}

Imf::FrameBuffer frame_buffer(RenderedImage& image, Planes& planes, const AnalysisNames& names) {
    const std::size_t w = static_cast<std::size_t>(image.width);
    Imf::FrameBuffer fb;
    auto interleaved = [&](const char* name, float* base, std::size_t stride) {
        fb.insert(name, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(base),
                                   stride * sizeof(float), stride * sizeof(float) * w));
    };
    const char* rgba_names[4] = {"R", "G", "B", "A"};
    for (std::size_t c = 0; c < 4; ++c) {
        interleaved(rgba_names[c], image.rgba.data() + c, 4);
    }
    interleaved("Z", image.depth.data(), 1);
    const char* normal_names[3] = {"N.X", "N.Y", "N.Z"};
    for (std::size_t c = 0; c < 3; ++c) {
        interleaved(normal_names[c], image.normal.data() + c, 3);
    }
    interleaved(names.status, planes.status.data(), 1);
    interleaved(names.probe, planes.probe.data(), 1);
    interleaved(names.steps, planes.steps.data(), 1);
    if (!planes.object.empty()) {
        interleaved(names.object, planes.object.data(), 1);
    }
    if (!planes.guessed.empty()) {
        interleaved(names.guessed, planes.guessed.data(), 1);
    }
    return fb;
}

// Blender reads these as they are: R G B A as the Combined pass, Z as Depth, N.X N.Y N.Z as N.
constexpr const char* kBaseChannels[] = {"R", "G", "B", "A", "Z", "N.X", "N.Y", "N.Z"};

} // namespace

std::string ImageMetadata::dump() const {
    nlohmann::json j{{"renderer", renderer}};
    j.update(source);
    j["camera"] = camera;
    j["settings"] = settings;
    j["stats"] = stats;
    return j.dump();
}

void write_rendered_exr(const std::string& path, const RenderedImage& image,
                        const ImageMetadata& metadata) {
    write_rendered_exr(path, image, metadata.dump());
}

void write_rendered_exr(const std::string& path, const RenderedImage& image,
                        const std::string& metadata) {
    if (image.width < 1 || image.height < 1) {
        throw InputError(path + ": cannot write an empty image");
    }
    const std::size_t n = image.pixel_count();
    Planes planes;
    planes.status.resize(n);
    planes.probe.resize(n);
    planes.steps.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        planes.status[i] = static_cast<float>(image.status[i]);
        planes.probe[i] = static_cast<float>(image.probe[i]);
        planes.steps[i] = static_cast<float>(image.steps[i]);
    }
    if (!image.object.empty()) {
        if (image.object.size() != n) {
            throw InputError(path + ": the object channel does not match the image size");
        }
        planes.object.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            planes.object[i] = static_cast<float>(image.object[i]);
        }
    }
    if (!image.guessed.empty()) {
        if (image.guessed.size() != n) {
            throw InputError(path + ": the guessed channel does not match the image size");
        }
        planes.guessed.assign(image.guessed.begin(), image.guessed.end());
    }
    Imf::Header header(image.width, image.height);
    header.compression() = Imf::ZIP_COMPRESSION;
    const AnalysisNames names;
    for (const char* name : kBaseChannels) {
        header.channels().insert(name, Imf::Channel(Imf::FLOAT));
    }
    for (const char* name : {names.status, names.probe, names.steps}) {
        header.channels().insert(name, Imf::Channel(Imf::FLOAT));
    }
    if (!planes.object.empty()) {
        header.channels().insert(names.object, Imf::Channel(Imf::FLOAT));
    }
    if (!planes.guessed.empty()) {
        header.channels().insert(names.guessed, Imf::Channel(Imf::FLOAT));
    }
    header.insert(kImageFormatAttribute, Imf::StringAttribute(kImageFormatValue));
    if (!metadata.empty()) {
        header.insert(kMetadataAttribute, Imf::StringAttribute(metadata));
    }
    const std::string tmp = temporary_path_for(path);
    try {
        {
            Imf::OutputFile file(tmp.c_str(), header);
            // The writer only reads through the slices; one layout serves both directions.
            file.setFrameBuffer(frame_buffer(const_cast<RenderedImage&>(image), planes, names));
            file.writePixels(image.height);
        }
        std::filesystem::rename(tmp, path);
    } catch (const std::exception& e) {
        std::error_code ignored;
        std::filesystem::remove(tmp, ignored);
        throw IoError(path + ": cannot write rendered EXR (" + e.what() + ")");
    }
}

RenderedImage read_rendered_exr(const std::string& path, std::string* metadata) {
    if (!std::filesystem::exists(path)) {
        throw MissingFileError(path + ": no such image");
    }
    try {
        Imf::InputFile file(path.c_str());
        const Imath::Box2i window = file.header().dataWindow();
        const int w = window.max.x - window.min.x + 1;
        const int h = window.max.y - window.min.y + 1;
        if (window.min.x != 0 || window.min.y != 0 || w < 1 || h < 1) {
            throw InputError(path + ": expected a data window starting at (0, 0)");
        }
        const auto missing = [&](const std::string& name) {
            return InputError(path + ": expected channel '" + name +
                              "' of a rendered image (R G B A Z N.X N.Y N.Z status.X probe.X "
                              "steps.X, or before them status probe steps)");
        };
        for (const char* name : kBaseChannels) {
            if (file.header().channels().findChannel(name) == nullptr) {
                throw missing(name);
            }
        }
        const auto require = [&](const AnalysisChannel& channel) {
            const char* name = find_analysis_channel(file.header(), channel);
            if (name == nullptr) {
                throw missing(channel.name);
            }
            return name;
        };
        AnalysisNames names;
        names.status = require(kStatus);
        names.probe = require(kProbe);
        names.steps = require(kSteps);
        names.object = find_analysis_channel(file.header(), kObject);
        names.guessed = find_analysis_channel(file.header(), kGuessed);
        if (metadata != nullptr) {
            const auto* attr =
                file.header().findTypedAttribute<Imf::StringAttribute>(kMetadataAttribute);
            *metadata = attr != nullptr ? attr->value() : std::string();
        }
        RenderedImage image(w, h);
        Planes planes;
        planes.status.resize(image.pixel_count());
        planes.probe.resize(image.pixel_count());
        planes.steps.resize(image.pixel_count());
        if (names.object != nullptr) {
            planes.object.resize(image.pixel_count());
        }
        if (names.guessed != nullptr) {
            planes.guessed.resize(image.pixel_count());
        }
        file.setFrameBuffer(frame_buffer(image, planes, names));
        file.readPixels(0, h - 1);
        // The integer channels are floats in the file: a value that is no whole number in
        // range (NaN, 1e30) would be undefined behaviour to convert.
        const auto whole = [&](float v, double lo, double hi, const char* channel) {
            if (!(v >= lo && v <= hi) || v != std::floor(v)) {
                throw InputError(path + ": channel '" + channel + "' holds " + std::to_string(v) +
                                 "; expected whole numbers from " + std::to_string(lo) + " to " +
                                 std::to_string(hi));
            }
            return v;
        };
        constexpr double kIndexMax = 2147483647.0;
        for (std::size_t i = 0; i < image.pixel_count(); ++i) {
            image.status[i] =
                static_cast<std::uint8_t>(whole(planes.status[i], 0.0, 2.0, names.status));
            image.probe[i] =
                static_cast<std::int32_t>(whole(planes.probe[i], -1.0, kIndexMax, names.probe));
            image.steps[i] =
                static_cast<std::uint32_t>(whole(planes.steps[i], 0.0, 4294967295.0, names.steps));
        }
        for (const float o : planes.object) {
            image.object.push_back(
                static_cast<std::int32_t>(whole(o, -1.0, kIndexMax, names.object)));
        }
        for (const float g : planes.guessed) {
            image.guessed.push_back(static_cast<std::uint8_t>(whole(g, 0.0, 1.0, names.guessed)));
        }
        return image;
    } catch (const InputError&) {
        throw;
    } catch (const std::exception& e) {
        throw InputError(path + ": not a readable rendered EXR (" + e.what() + ")");
    }
}

} // namespace lfprobe
