#include "lfprobe/image_files.hpp"

#include <cstdint>
#include <exception>
#include <filesystem>
#include <memory>
#include <type_traits>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputPart.h>
#include <ImfMultiPartInputFile.h>
#include <ImfPartType.h>
#include <stb_image.h>

#include "lfprobe/error.hpp"
#include "lfprobe/input_limits.hpp"

namespace lfprobe {

namespace {

void require_file(const std::string& path) {
    std::error_code error;
    if (!std::filesystem::is_regular_file(path, error)) {
        throw MissingFileError(
            path + ": no such image" +
            (std::filesystem::exists(path, error) ? " (not a regular file)" : ""));
    }
}

} // namespace

ExrChannels read_exr_channels(const std::string& path) {
    require_file(path);
    ExrChannels out;
    try {
        Imf::MultiPartInputFile file(path.c_str());
        const Imath::Box2i display = file.header(0).displayWindow();
        const long long width = static_cast<long long>(display.max.x) - display.min.x + 1;
        const long long height = static_cast<long long>(display.max.y) - display.min.y + 1;
        if (width <= 0 || height <= 0 || width * height > input_limit(InputLimit::ImagePixels)) {
            throw InputError(path + ": an EXR display window of " + std::to_string(width) + " × " +
                             std::to_string(height) + " pixels (" +
                             input_limit_hint(InputLimit::ImagePixels) + ")");
        }
        out.width = static_cast<int>(width);
        out.height = static_cast<int>(height);
        const auto pixels = static_cast<std::size_t>(width * height);
        for (int part = 0; part < file.parts(); ++part) {
            const Imf::Header& header = file.header(part);
            if (header.hasType() && Imf::isDeepData(header.type())) {
                throw InputError(path + ": part " + std::to_string(part) +
                                 " holds deep data, which compare does not read");
            }
            const Imath::Box2i data = header.dataWindow();
            // The part of the data window inside the display window.
            const Imath::Box2i shown(Imath::V2i(std::max(data.min.x, display.min.x),
                                                std::max(data.min.y, display.min.y)),
                                     Imath::V2i(std::min(data.max.x, display.max.x),
                                                std::min(data.max.y, display.max.y)));
            Imf::InputPart input(file, part);
            Imf::FrameBuffer frame;
            // Read over the data window into a buffer of its own, then copy what is shown.
            const long long data_width = static_cast<long long>(data.max.x) - data.min.x + 1;
            const long long data_height = static_cast<long long>(data.max.y) - data.min.y + 1;
            if (data_width <= 0 || data_height <= 0 ||
                data_width * data_height > input_limit(InputLimit::ImagePixels)) {
                throw InputError(path + ": an EXR data window of " + std::to_string(data_width) +
                                 " × " + std::to_string(data_height) + " pixels");
            }
            std::map<std::string, std::vector<float>> buffers;
            for (auto c = header.channels().begin(); c != header.channels().end(); ++c) {
                std::vector<float>& buffer = buffers[c.name()];
                buffer.assign(static_cast<std::size_t>(data_width * data_height), 0.0f);
                // The buffer's origin sits at the data window's corner (OpenEXR's convention:
                // the base points at pixel (0, 0)).
                char* base = reinterpret_cast<char*>(buffer.data()) -
                             (static_cast<std::ptrdiff_t>(data.min.x) +
                              static_cast<std::ptrdiff_t>(data.min.y) * data_width) *
                                 static_cast<std::ptrdiff_t>(sizeof(float));
                frame.insert(c.name(),
                             Imf::Slice(Imf::FLOAT, base, sizeof(float),
                                        sizeof(float) * static_cast<std::size_t>(data_width)));
            }
            input.setFrameBuffer(frame);
            input.readPixels(data.min.y, data.max.y);
            for (auto& [name, buffer] : buffers) {
                std::vector<float>& channel = out.channels[name];
                channel.assign(pixels, 0.0f);
                for (int y = shown.min.y; y <= shown.max.y; ++y) {
                    for (int x = shown.min.x; x <= shown.max.x; ++x) {
                        channel[static_cast<std::size_t>(y - display.min.y) *
                                    static_cast<std::size_t>(width) +
                                static_cast<std::size_t>(x - display.min.x)] =
                            buffer[static_cast<std::size_t>(y - data.min.y) *
                                       static_cast<std::size_t>(data_width) +
                                   static_cast<std::size_t>(x - data.min.x)];
                    }
                }
            }
        }
    } catch (const InputError&) {
        throw;
    } catch (const std::exception& e) {
        throw InputError(path + ": not an EXR file OpenEXR can read (" + e.what() + ")");
    }
    return out;
}

StoredImage read_stored_image(const std::string& path) {
    require_file(path);
    int width = 0;
    int height = 0;
    int channels = 0;
    if (stbi_info(path.c_str(), &width, &height, &channels) == 0) {
        const char* reason = stbi_failure_reason();
        throw InputError(path + ": not a PNG or JPEG image stb_image can read (" +
                         (reason != nullptr ? reason : "unknown format") + ")");
    }
    if (width <= 0 || height <= 0 ||
        static_cast<long long>(width) * static_cast<long long>(height) >
            input_limit(InputLimit::ImagePixels)) {
        throw InputError(path + ": an image of " + std::to_string(width) + " × " +
                         std::to_string(height) + " pixels (" +
                         input_limit_hint(InputLimit::ImagePixels) + ")");
    }
    StoredImage image;
    // stb_image's 8- and 16-bit loaders differ only in their sample type.
    const auto load = [&](auto* (*loader)(const char*, int*, int*, int*, int), int bits) {
        using Sample =
            std::remove_pointer_t<decltype(loader(nullptr, nullptr, nullptr, nullptr, 0))>;
        std::unique_ptr<Sample, void (*)(void*)> pixels(
            loader(path.c_str(), &image.width, &image.height, &image.channels, 0), stbi_image_free);
        if (!pixels) {
            const char* reason = stbi_failure_reason();
            throw InputError(path + ": cannot decode the image (" +
                             (reason != nullptr ? reason : "damaged") + ")");
        }
        image.bits = bits;
        const std::size_t count = static_cast<std::size_t>(image.width) *
                                  static_cast<std::size_t>(image.height) *
                                  static_cast<std::size_t>(image.channels);
        image.values.assign(pixels.get(), pixels.get() + count);
    };
    if (stbi_is_16_bit(path.c_str()) != 0) {
        load(&stbi_load_16, 16);
    } else {
        load(&stbi_load, 8);
    }
    return image;
}

} // namespace lfprobe
