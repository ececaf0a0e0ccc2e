// The limits on what is read, and the environment variables that override them (issue 22: the
// limits are stated and overridable).
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "lfprobe/camera.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/input_limits.hpp"
#include "lfprobe/mesh_reader.hpp"
#include "lfprobe/texture.hpp"

using namespace lfprobe;

namespace {

// Sets an environment variable for the scope of a test, and restores it.
class ScopedVariable {
public:
    ScopedVariable(const char* name, const std::string& value) : name_(name) {
        if (const char* old = std::getenv(name)) {
            old_ = old;
            had_ = true;
        }
        ::setenv(name, value.c_str(), 1);
    }
    ~ScopedVariable() {
        if (had_) {
            ::setenv(name_, old_.c_str(), 1);
        } else {
            ::unsetenv(name_);
        }
    }
    ScopedVariable(const ScopedVariable&) = delete;
    ScopedVariable& operator=(const ScopedVariable&) = delete;

private:
    const char* name_;
    std::string old_;
    bool had_ = false;
};

std::string written(const std::string& name, const std::string& bytes) {
    const auto dir = std::filesystem::temp_directory_path() / "lfprobe_input_limits_test";
    std::filesystem::create_directories(dir);
    const auto path = dir / name;
    std::ofstream(path, std::ios::binary) << bytes;
    return path.string();
}

// A PNG signature and header declaring `side` × `side` pixels, with no pixel data.
std::string png_header(unsigned side) {
    std::string png("\x89PNG\r\n\x1a\n", 8);
    const auto byte = [side](int shift) { return static_cast<unsigned char>(side >> shift); };
    const unsigned char ihdr[] = {0,       0,        0,        13,      'I',     'H',      'D',
                                  'R',     byte(24), byte(16), byte(8), byte(0), byte(24), byte(16),
                                  byte(8), byte(0),  8,        2,       0,       0,        0,
                                  0,       0,        0,        0};
    png.append(reinterpret_cast<const char*>(ihdr), sizeof ihdr);
    return png;
}

std::string message_of(const std::function<void()>& run) {
    try {
        run();
    } catch (const std::exception& e) {
        return e.what();
    }
    return "(accepted)";
}

} // namespace

TEST(InputLimits, DefaultsAreTheStatedOnes) {
    EXPECT_EQ(input_limit(InputLimit::CameraPixels), 8192LL * 8192LL);
    EXPECT_EQ(input_limit(InputLimit::TexturePixels), 8192LL * 8192LL);
    EXPECT_EQ(input_limit(InputLimit::ImagePixels), 8192LL * 8192LL);
    EXPECT_EQ(input_limit(InputLimit::MaterialLibraryBytes), 64LL << 20);
    EXPECT_EQ(input_limit(InputLimit::ObjBytes), 8LL << 30);
}

TEST(InputLimits, AnEnvironmentVariableRaisesTheTextureLimit) {
    const std::string huge = written("huge.png", png_header(16384));
    EXPECT_NE(message_of([&] { (void)Texture::load(huge); }).find("LFPROBE_MAX_TEXTURE_PIXELS"),
              std::string::npos);
    const ScopedVariable raised("LFPROBE_MAX_TEXTURE_PIXELS", std::to_string(16384LL * 16384LL));
    // Past the size check now: refused only because the file holds no pixels.
    const std::string message = message_of([&] { (void)Texture::load(huge); });
    EXPECT_EQ(message.find("LFPROBE_MAX_TEXTURE_PIXELS"), std::string::npos) << message;
    EXPECT_NE(message.find("expected a PNG or JPG"), std::string::npos) << message;
}

TEST(InputLimits, AnEnvironmentVariableLowersTheCameraAndMaterialLimits) {
    const nlohmann::json camera = {{"resolution", {16, 10}}};
    EXPECT_NO_THROW((void)Camera::from_json(camera, "cam.json"));
    {
        const ScopedVariable lowered("LFPROBE_MAX_CAMERA_PIXELS", "100");
        const std::string message =
            message_of([&] { (void)Camera::from_json(camera, "cam.json"); });
        EXPECT_NE(message.find("cam.json"), std::string::npos) << message;
        EXPECT_NE(message.find("LFPROBE_MAX_CAMERA_PIXELS"), std::string::npos) << message;
    }
    written("m.mtl", "newmtl a\nKd 1 0 0\n");
    const std::string obj = written("m.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl "
                                             "a\nf 1 2 3\n");
    EXPECT_NO_THROW((void)read_obj(obj));
    const ScopedVariable lowered("LFPROBE_MAX_MTL_BYTES", "8");
    const std::string message = message_of([&] { (void)read_obj(obj); });
    EXPECT_NE(message.find("m.mtl"), std::string::npos) << message;
    EXPECT_NE(message.find("LFPROBE_MAX_MTL_BYTES"), std::string::npos) << message;
}

TEST(InputLimits, AValueThatIsNotAPositiveWholeNumberIsAnErrorNamingTheVariable) {
    for (const char* value : {"abc", "-5", "0", "1e9", "12 ", "99999999999999999999"}) {
        const ScopedVariable bad("LFPROBE_MAX_OBJ_BYTES", value);
        try {
            (void)input_limit(InputLimit::ObjBytes);
            ADD_FAILURE() << "accepted " << value;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("LFPROBE_MAX_OBJ_BYTES"), std::string::npos);
        }
    }
}
