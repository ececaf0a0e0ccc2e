// Blender's camera model (docs/DESIGN.md §3) as Cycles renders it: fields of view, sensor fit,
// shift, pixel-centre rays, the top row, equirectangular panoramas and JSON errors.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <string>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "lfprobe/camera.hpp"
#include "lfprobe/error.hpp"

using namespace lfprobe;
using nlohmann::json;

namespace {

constexpr double kPi = std::numbers::pi;

double degrees(double radians) {
    return radians * 180.0 / kPi;
}

Camera camera_from(const json& j) {
    return Camera::from_json(j, "test camera");
}

// tan of the angle off the view axis (−Z) along camera x and y.
glm::dvec2 tangents(const glm::dvec3& d) {
    return {d.x / -d.z, d.y / -d.z};
}

void expect_near(const glm::dvec3& a, const glm::dvec3& b, double tolerance) {
    EXPECT_NEAR(a.x, b.x, tolerance);
    EXPECT_NEAR(a.y, b.y, tolerance);
    EXPECT_NEAR(a.z, b.z, tolerance);
}

// A file in a fresh temporary folder, removed with it.
class TempFile {
public:
    explicit TempFile(const std::string& contents) {
        folder_ = std::filesystem::temp_directory_path() /
                  ("lfprobe_camera_test_" + std::to_string(std::random_device{}()));
        std::filesystem::create_directories(folder_);
        path_ = (folder_ / "camera.json").string();
        std::ofstream(path_) << contents;
    }
    ~TempFile() {
        std::error_code ignored;
        std::filesystem::remove_all(folder_, ignored);
    }
    TempFile(const TempFile&) = delete;
    TempFile& operator=(const TempFile&) = delete;
    [[nodiscard]] const std::string& path() const { return path_; }

private:
    std::filesystem::path folder_;
    std::string path_;
};

} // namespace

TEST(Camera, BlenderDefaultsReproduceKnownFieldsOfView) {
    const Camera c = camera_from(json::object());
    EXPECT_EQ(c.type, CameraType::Perspective);
    EXPECT_EQ(c.width, 1920);
    EXPECT_EQ(c.height, 1080);
    EXPECT_EQ(c.lens, 50.0);
    EXPECT_EQ(c.sensor_width, 36.0);
    EXPECT_EQ(c.sensor_height, 24.0);
    EXPECT_EQ(c.sensor_fit, SensorFit::Auto);
    EXPECT_EQ(c.clip_start, 0.1);
    EXPECT_EQ(c.clip_end, 1000.0);
    EXPECT_DOUBLE_EQ(c.latitude_min, -kPi / 2);
    EXPECT_DOUBLE_EQ(c.longitude_max, kPi);
    // 50 mm on a 36 mm sensor: the classic 39.6° horizontal angle of view.
    EXPECT_NEAR(degrees(c.horizontal_fov()), 39.5978, 1e-3);
    EXPECT_NEAR(degrees(c.vertical_fov()), degrees(2.0 * std::atan(18.0 / 50.0 * 1080.0 / 1920.0)),
                1e-9);
    // The left and right image edges at mid-height lie at ±FOV/2.
    const glm::dvec3 left = c.camera_direction(0.0, 540.0);
    const glm::dvec3 right = c.camera_direction(1920.0, 540.0);
    EXPECT_NEAR(tangents(left).x, -18.0 / 50.0, 1e-12);
    EXPECT_NEAR(tangents(right).x, 18.0 / 50.0, 1e-12);
    EXPECT_NEAR(tangents(left).y, 0.0, 1e-12);
    // lens 35 mm
    const Camera wide = camera_from({{"lens", 35.0}});
    EXPECT_NEAR(degrees(wide.horizontal_fov()), 54.4322, 1e-3);
}

TEST(Camera, SensorFitFollowsBlendersRules) {
    // AUTO: sensor_width spans the larger image dimension.
    const Camera portrait = camera_from({{"resolution", {1080, 1920}}});
    EXPECT_NEAR(degrees(portrait.vertical_fov()), 39.5978, 1e-3);
    EXPECT_LT(portrait.horizontal_fov(), portrait.vertical_fov());
    const Camera square = camera_from({{"resolution", {1000, 1000}}});
    EXPECT_NEAR(degrees(square.horizontal_fov()), 39.5978, 1e-3);
    EXPECT_NEAR(degrees(square.vertical_fov()), 39.5978, 1e-3);
    // HORIZONTAL: sensor_width spans the width, even in portrait.
    const Camera horizontal =
        camera_from({{"resolution", {1080, 1920}}, {"sensor_fit", "HORIZONTAL"}});
    EXPECT_NEAR(degrees(horizontal.horizontal_fov()), 39.5978, 1e-3);
    // VERTICAL: sensor_height spans the height.
    const Camera vertical = camera_from({{"sensor_fit", "VERTICAL"}});
    EXPECT_NEAR(degrees(vertical.vertical_fov()), degrees(2.0 * std::atan(12.0 / 50.0)), 1e-9);
    EXPECT_NEAR(tangents(vertical.camera_direction(960.0, 0.0)).y, 12.0 / 50.0, 1e-12);
    // Non-square pixels: 960 pixels twice as wide look like 1920.
    const Camera wide_pixels = camera_from({{"resolution", {960, 1080}}, {"pixel_aspect_x", 2.0}});
    EXPECT_NEAR(degrees(wide_pixels.horizontal_fov()), 39.5978, 1e-3);
}

TEST(Camera, ShiftIsInUnitsOfTheFittedSensorDimension) {
    // Landscape, AUTO: horizontal fit, so both shifts are in units of the sensor width.
    const Camera c = camera_from({{"shift_x", 0.25}, {"shift_y", 0.1}});
    const glm::dvec2 centre = tangents(c.camera_direction(960.0, 540.0));
    EXPECT_NEAR(centre.x, 0.25 * 36.0 / 50.0, 1e-12);
    EXPECT_NEAR(centre.y, 0.1 * 36.0 / 50.0, 1e-12);
    // Portrait, AUTO: the width's sensor size spans the height; the same units.
    const Camera p = camera_from({{"resolution", {1080, 1920}}, {"shift_x", 0.1}});
    EXPECT_NEAR(tangents(p.camera_direction(540.0, 960.0)).x, 0.1 * 36.0 / 50.0, 1e-12);
    // VERTICAL fit: units of sensor_height.
    const Camera v = camera_from({{"sensor_fit", "VERTICAL"}, {"shift_x", 0.1}});
    EXPECT_NEAR(tangents(v.camera_direction(960.0, 540.0)).x, 0.1 * 24.0 / 50.0, 1e-12);
    // Shift moves the image, not the angle of view.
    EXPECT_NEAR(c.horizontal_fov(), camera_from(json::object()).horizontal_fov(), 1e-15);
}

TEST(Camera, PixelCentreRaysAndTheTopRowIsUp) {
    const Camera c = camera_from(json::object());
    const double mm_per_pixel = 36.0 / 1920.0;
    // Pixel (0, 0) is the top-left pixel: its ray goes through its centre.
    const Ray r = c.pixel_ray(0, 0);
    const glm::dvec3 expected = glm::normalize(
        glm::dvec3((0.5 - 960.0) * mm_per_pixel, (540.0 - 0.5) * mm_per_pixel, -50.0));
    expect_near(r.direction, expected, 1e-12);
    EXPECT_GT(r.direction.y, 0.0); // top row: +Y side of the camera
    EXPECT_LT(c.pixel_ray(0, 1079).direction.y, 0.0);
    // Sampler offsets: (0, 0) is the pixel's top-left corner.
    const glm::dvec2 corner = tangents(c.pixel_ray(0, 0, 0.0, 0.0).direction);
    EXPECT_NEAR(corner.x, -18.0 / 50.0, 1e-12);
    EXPECT_NEAR(corner.y, 540.0 * mm_per_pixel / 50.0, 1e-12);
    // Neighbouring pixel centres are one pixel apart on the sensor.
    EXPECT_NEAR(tangents(c.pixel_ray(1, 0).direction).x - tangents(r.direction).x,
                mm_per_pixel / 50.0, 1e-12);
    // Clipping is by planes: the ray starts at z = -clip_start.
    EXPECT_NEAR(c.pixel_ray(960, 540, 0.0, 0.0).t_min, 0.1, 1e-12);
    EXPECT_NEAR((r.t_min * r.direction).z, -0.1, 1e-12);
    EXPECT_NEAR((r.t_max * r.direction).z, -1000.0, 1e-9);
}

TEST(Camera, MatrixWorldPlacesAndTurnsTheCamera) {
    // Blender's "front" camera: rotation 90° about X, at (1, -5, 2): looks along +Y, up is +Z.
    // Scale is cleared as Cycles does.
    const json j{
        {"matrix_world",
         {{2.0, 0.0, 0.0, 1.0}, {0.0, 0.0, -2.0, -5.0}, {0.0, 2.0, 0.0, 2.0}, {0, 0, 0, 1}}}};
    const Camera c = camera_from(j);
    const Ray centre = c.world_ray(960.0, 540.0);
    expect_near(centre.origin, glm::dvec3(1.0, -5.0, 2.0), 1e-15);
    expect_near(centre.direction, glm::dvec3(0.0, 1.0, 0.0), 1e-12);
    EXPECT_GT(c.pixel_ray(960, 0).direction.z, 0.0); // top row: up
    EXPECT_LT(c.pixel_ray(0, 540).direction.x, 0.0); // left column: −X
    // In a probe set's local frame the offset is subtracted in double.
    const glm::dvec3 offset(500000.25, 4000000.5, 100.0);
    json far = j;
    far["matrix_world"][0][3] = 500001.25;
    far["matrix_world"][1][3] = 3999995.5;
    far["matrix_world"][2][3] = 102.0;
    const Ray local = camera_from(far).local_pixel_ray(960, 540, offset);
    expect_near(local.origin, glm::dvec3(1.0, -5.0, 2.0), 1e-9);
}

TEST(Camera, EquirectangularDirectionsFollowCycles) {
    const Camera c = camera_from({{"type", "PANO_EQUIRECT"}, {"resolution", {2000, 1000}}});
    expect_near(c.camera_direction(1000.0, 500.0), glm::dvec3(0.0, 0.0, -1.0), 1e-12);  // ahead
    expect_near(c.camera_direction(500.0, 500.0), glm::dvec3(-1.0, 0.0, 0.0), 1e-12);   // left
    expect_near(c.camera_direction(1500.0, 500.0), glm::dvec3(1.0, 0.0, 0.0), 1e-12);   // right
    expect_near(c.camera_direction(0.0, 500.0), glm::dvec3(0.0, 0.0, 1.0), 1e-12);      // behind
    expect_near(c.camera_direction(1000.0, 0.0), glm::dvec3(0.0, 1.0, 0.0), 1e-12);     // up
    expect_near(c.camera_direction(1000.0, 1000.0), glm::dvec3(0.0, -1.0, 0.0), 1e-12); // down
    expect_near(c.camera_direction(0.0, 0.0), glm::dvec3(0.0, 1.0, 0.0), 1e-12); // top corner
    // Corner pixel centres: almost straight up, half a pixel off the seam.
    const glm::dvec3 corner = c.pixel_ray(0, 0).direction;
    EXPECT_NEAR(corner.y, std::cos(0.5 * kPi / 1000.0), 1e-12);
    EXPECT_GT(corner.z, 0.0); // the left edge is behind the camera
    // Spheres, not planes, clip a panorama.
    EXPECT_EQ(c.pixel_ray(3, 7).t_min, 0.1);
    // A partial range: ±90° of longitude, ±45° of latitude.
    const Camera part = camera_from({{"type", "PANO_EQUIRECT"},
                                     {"resolution", {1000, 500}},
                                     {"longitude_min", -kPi / 2},
                                     {"longitude_max", kPi / 2},
                                     {"latitude_min", -kPi / 4},
                                     {"latitude_max", kPi / 4}});
    expect_near(part.camera_direction(0.0, 250.0), glm::dvec3(-1.0, 0.0, 0.0), 1e-12);
    expect_near(part.camera_direction(500.0, 0.0), glm::dvec3(0.0, std::sqrt(0.5), -std::sqrt(0.5)),
                1e-12);
    // Blender's own spelling.
    const Camera blender = camera_from(
        {{"type", "PANO"}, {"panorama_type", "EQUIRECTANGULAR"}, {"resolution", {2000, 1000}}});
    EXPECT_EQ(blender.type, CameraType::PanoramaEquirect);
}

TEST(Camera, ProjectIsTheInverseOfTheRay) {
    std::mt19937 rng(4);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const json turned{
        {"matrix_world",
         {{0.6, -0.8, 0.0, 1.0}, {0.0, 0.0, -1.0, -2.0}, {0.8, 0.6, 0.0, 1.5}, {0, 0, 0, 1}}},
        {"resolution", {640, 480}},
        {"shift_x", 0.05},
        {"sensor_fit", "VERTICAL"}};
    json pano = turned;
    pano["type"] = "PANO_EQUIRECT";
    pano["longitude_min"] = -2.0;
    pano["longitude_max"] = 2.5;
    for (const json& j : {turned, pano}) {
        const Camera c = camera_from(j);
        for (int i = 0; i < 200; ++i) {
            const double x = u(rng) * 640.0;
            const double y = u(rng) * 480.0;
            const Ray ray = c.world_ray(x, y);
            const double distance = 0.5 + 10.0 * u(rng);
            glm::dvec2 xy;
            double back = 0.0;
            ASSERT_TRUE(c.project(ray.at(distance), xy, back));
            EXPECT_NEAR(xy.x, x, 1e-7);
            EXPECT_NEAR(xy.y, y, 1e-7);
            EXPECT_NEAR(back, distance, 1e-9);
        }
        glm::dvec2 xy;
        double distance = 0.0;
        EXPECT_FALSE(c.project(c.position(), xy, distance)); // inside the near clip
    }
}

TEST(Camera, JsonRoundTripsAndBadJsonNamesTheFileAndTheKey) {
    const Camera c = camera_from({{"type", "PANO_EQUIRECT"},
                                  {"resolution", {320, 160}},
                                  {"lens", 24.0},
                                  {"latitude_min", -1.0}});
    const Camera again = camera_from(c.to_json());
    EXPECT_EQ(again.to_json(), c.to_json());

    auto message_of = [](const std::string& contents) -> std::string {
        const TempFile file(contents);
        try {
            (void)read_camera_json(file.path());
        } catch (const InputError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find(file.path()), std::string::npos) << what;
            return what;
        }
        ADD_FAILURE() << "no InputError for " << contents;
        return "";
    };
    EXPECT_NE(message_of(R"({"lens": "fifty"})").find("'lens'"), std::string::npos);
    EXPECT_NE(message_of(R"({"lens": -5})").find("'lens'"), std::string::npos);
    EXPECT_NE(message_of(R"({"resolution": [0, 10]})").find("'resolution'"), std::string::npos);
    EXPECT_NE(message_of(R"({"resolution": [1920]})").find("'resolution'"), std::string::npos);
    EXPECT_NE(
        message_of(R"({"matrix_world": [[1, 0, 0], [0, 1, 0], [0, 0, 1]]})").find("'matrix_world'"),
        std::string::npos);
    EXPECT_NE(message_of(R"({"sensor_fit": "DIAGONAL"})").find("'sensor_fit'"), std::string::npos);
    EXPECT_NE(message_of(R"({"type": "ORTHO"})").find("'type'"), std::string::npos);
    EXPECT_NE(message_of(R"({"type": "PANO", "panorama_type": "FISHEYE_EQUIDISTANT"})")
                  .find("'panorama_type'"),
              std::string::npos);
    EXPECT_NE(message_of(R"({"clip_start": 5, "clip_end": 1})").find("'clip_end'"),
              std::string::npos);
    EXPECT_NE(message_of(R"({"lens": 50,)").find("camera file is not valid JSON"),
              std::string::npos);
    EXPECT_NE(message_of(R"([1, 2, 3])").find("JSON object"), std::string::npos);
    EXPECT_THROW((void)read_camera_json("/nonexistent/lfprobe/camera.json"), IoError);
}
