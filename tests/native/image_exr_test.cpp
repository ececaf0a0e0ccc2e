// Rendered image EXRs (image_exr.hpp): the channel names written, which Blender's multilayer
// reader takes as passes, and the older names that files written before still carry.
#include <filesystem>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <gtest/gtest.h>

#include "lfprobe/error.hpp"
#include "lfprobe/image_exr.hpp"

using namespace lfprobe;

namespace {

std::string temporary_exr(const std::string& stem) {
    return (std::filesystem::temp_directory_path() /
            (stem + "_" + std::to_string(std::random_device{}()) + ".exr"))
        .string();
}

// A 5×3 image whose every plane differs from pixel to pixel, with the object channel.
RenderedImage varied_image() {
    RenderedImage image(5, 3);
    for (std::size_t i = 0; i < image.pixel_count(); ++i) {
        const float f = static_cast<float>(i);
        for (std::size_t c = 0; c < 4; ++c) {
            image.rgba[4 * i + c] = 0.01f * f + 0.1f * static_cast<float>(c);
        }
        image.depth[i] = 1.0f + 0.5f * f;
        for (std::size_t c = 0; c < 3; ++c) {
            image.normal[3 * i + c] = 0.1f * static_cast<float>(c) - 0.02f * f;
        }
        image.status[i] = static_cast<std::uint8_t>(i % 3);
        image.probe[i] = static_cast<std::int32_t>(i) - 1;
        image.steps[i] = static_cast<std::uint32_t>(1000 * i);
        image.object.push_back(static_cast<std::int32_t>(i % 4) - 1);
        image.guessed.push_back(static_cast<std::uint8_t>(i % 2));
    }
    return image;
}

std::set<std::string> channel_names(const std::string& path) {
    Imf::InputFile file(path.c_str());
    std::set<std::string> names;
    for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it) {
        names.insert(it.name());
    }
    return names;
}

// Writes `planes` (float, one per name) as an EXR of `width` columns, as another writer would.
void write_planes(const std::string& path, int width, int height,
                  const std::vector<std::string>& names, std::vector<std::vector<float>>& planes) {
    Imf::Header header(width, height);
    Imf::FrameBuffer frame;
    for (std::size_t c = 0; c < names.size(); ++c) {
        header.channels().insert(names[c], Imf::Channel(Imf::FLOAT));
        frame.insert(names[c],
                     Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(planes[c].data()),
                                sizeof(float), sizeof(float) * static_cast<std::size_t>(width)));
    }
    Imf::OutputFile file(path.c_str(), header);
    file.setFrameBuffer(frame);
    file.writePixels(height);
}

void expect_same(const RenderedImage& a, const RenderedImage& b) {
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    EXPECT_EQ(a.rgba, b.rgba);
    EXPECT_EQ(a.depth, b.depth);
    EXPECT_EQ(a.normal, b.normal);
    EXPECT_EQ(a.status, b.status);
    EXPECT_EQ(a.probe, b.probe);
    EXPECT_EQ(a.steps, b.steps);
    EXPECT_EQ(a.object, b.object);
    EXPECT_EQ(a.guessed, b.guessed);
}

TEST(RenderedImageExr, AnalysisChannelsAreWrittenAsPassesBlenderReads) {
    const RenderedImage image = varied_image();
    const std::string path = temporary_exr("lfprobe_image_exr");
    write_rendered_exr(path, image);
    const std::set<std::string> names = channel_names(path);
    EXPECT_EQ(names,
              (std::set<std::string>{"R", "G", "B", "A", "Z", "N.X", "N.Y", "N.Z", "status.X",
                                     "probe.X", "steps.X", "object.X", "guessed.X"}));
    // Blender's multilayer reader takes the last '.' token as the channel id and accepts only
    // one letter there (or red, green, blue, alpha).
    for (const std::string& name : names) {
        EXPECT_EQ(name.size() - name.rfind('.'), 2u) << name;
    }
    expect_same(read_rendered_exr(path), image);

    // Without an object channel (probe traces, splats) none is written or read back.
    RenderedImage traced = image;
    traced.object.clear();
    write_rendered_exr(path, traced);
    EXPECT_EQ(channel_names(path).count("object.X"), 0u);
    EXPECT_TRUE(read_rendered_exr(path).object.empty());
    // Without a guessed channel (ground truth, splats) none is written or read back.
    traced.guessed.clear();
    write_rendered_exr(path, traced);
    EXPECT_EQ(channel_names(path).count("guessed.X"), 0u);
    EXPECT_TRUE(read_rendered_exr(path).guessed.empty());
    std::filesystem::remove(path);
}

TEST(RenderedImageExr, FilesWithTheOlderSingleTokenNamesStillRead) {
    // The channels as lfprobe wrote them before status.X and its kind: status, probe, steps,
    // object.
    RenderedImage image = varied_image();
    image.guessed.clear(); // a channel added after the renaming: never under an older name
    const int w = image.width;
    const int h = image.height;
    const std::size_t n = image.pixel_count();
    std::vector<std::string> names = {"R", "G", "B", "A", "Z", "N.X", "N.Y", "N.Z"};
    std::vector<std::vector<float>> planes;
    for (std::size_t c = 0; c < 4; ++c) {
        planes.emplace_back(n);
        for (std::size_t i = 0; i < n; ++i) {
            planes.back()[i] = image.rgba[4 * i + c];
        }
    }
    planes.push_back(image.depth);
    for (std::size_t c = 0; c < 3; ++c) {
        planes.emplace_back(n);
        for (std::size_t i = 0; i < n; ++i) {
            planes.back()[i] = image.normal[3 * i + c];
        }
    }
    const auto add = [&](const char* name, const auto& values) {
        names.emplace_back(name);
        planes.emplace_back(values.begin(), values.end());
    };
    add("status", image.status);
    add("probe", image.probe);
    add("steps", image.steps);
    add("object", image.object);
    const std::string path = temporary_exr("lfprobe_image_exr_old");
    write_planes(path, w, h, names, planes);
    expect_same(read_rendered_exr(path), image);

    // The older names are checked as the new ones are: a status of 2.5 is refused, naming the
    // channel as the file has it.
    planes[8][3] = 2.5f;
    write_planes(path, w, h, names, planes);
    try {
        (void)read_rendered_exr(path);
        ADD_FAILURE() << "a status of 2.5 was read";
    } catch (const InputError& error) {
        EXPECT_NE(std::string(error.what()).find("channel 'status' holds 2.5"), std::string::npos)
            << error.what();
    }

    // Without either name of an analysis channel the file is no rendered image.
    names.erase(names.begin() + 9); // probe
    planes.erase(planes.begin() + 9);
    write_planes(path, w, h, names, planes);
    try {
        (void)read_rendered_exr(path);
        ADD_FAILURE() << "a file without a probe channel was read";
    } catch (const InputError& error) {
        EXPECT_NE(std::string(error.what()).find("expected channel 'probe.X'"), std::string::npos)
            << error.what();
    }
    std::filesystem::remove(path);
}

} // namespace
