// Blender's camera model (docs/DESIGN.md §3), as Cycles renders it: perspective and equirectangular
// panorama cameras, read from the small JSON file the add-on writes from a Blender camera.
//
// Image coordinates: pixel (x, y) covers [x, x+1) × [y, y+1) with y = 0 the TOP row (EXR
// scanline 0, the top of Blender's image). Its ray goes through (x + 0.5, y + 0.5) unless a
// sampler offset says otherwise.
#pragma once

#include <string>

#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <nlohmann/json_fwd.hpp>

#include "lfprobe/ray.hpp"

namespace lfprobe {

enum class CameraType {
    Perspective,      // Blender "PERSP"
    PanoramaEquirect, // Blender "PANO" with panorama_type "EQUIRECTANGULAR"; lfprobe
                      // "PANO_EQUIRECT"
};

enum class SensorFit { Auto, Horizontal, Vertical };

// The most pixels a camera file may ask for: input_limits.hpp (8192 × 8192 by default; a
// rendered image takes 41 bytes a pixel in memory).

struct Camera {
    // Defaults are Blender's (DNA_camera_defaults.h: lens 50, sensor 36 × 24, clip 0.1 / 1000,
    // latitude ±π/2, longitude ±π; render resolution 1920 × 1080, pixel aspect 1).
    CameraType type = CameraType::Perspective;
    glm::dmat4 matrix_world{1.0}; // camera to world (glm is column-major: m[column][row])
    int width = 1920;
    int height = 1080;
    double lens = 50.0;          // mm
    double sensor_width = 36.0;  // mm
    double sensor_height = 24.0; // mm
    SensorFit sensor_fit = SensorFit::Auto;
    double shift_x = 0.0; // in units of the fitted sensor dimension, as in Blender
    double shift_y = 0.0;
    double clip_start = 0.1;
    double clip_end = 1000.0;
    double latitude_min = -1.5707963267948966;
    double latitude_max = 1.5707963267948966;
    double longitude_min = -3.141592653589793;
    double longitude_max = 3.141592653589793;
    double pixel_aspect_x = 1.0; // scene.render.pixel_aspect_x
    double pixel_aspect_y = 1.0;

    // Reads the JSON of docs/DESIGN.md §3; `where` names the source in errors. Omitted keys keep
    // Blender's defaults. Throws InputError naming `where` and the offending key.
    [[nodiscard]] static Camera from_json(const nlohmann::json& j, const std::string& where);
    // A perspective camera at `eye` looking at `target`, world +Z up (as a Blender camera
    // aimed with a Track To constraint), clip_start 0.01 m; the other fields keep defaults.
    [[nodiscard]] static Camera look_at(const glm::dvec3& eye, const glm::dvec3& target, int width,
                                        int height, double lens = 50.0);
    [[nodiscard]] nlohmann::json to_json() const;

    // Camera position in world coordinates.
    [[nodiscard]] glm::dvec3 position() const;
    // The rotation part of matrix_world with the scale cleared (unit columns), as Cycles'
    // transform_clear_scale does.
    [[nodiscard]] glm::dmat3 rotation() const;

    // Unit direction in Blender camera space (−Z forward, +Y up) through image point
    // (image_x, image_y), measured in pixels from the top-left corner of the image.
    [[nodiscard]] glm::dvec3 camera_direction(double image_x, double image_y) const;

    // World-space ray through image point (image_x, image_y), clipped as Cycles clips: at the
    // planes z = -clip_start and z = -clip_end for a perspective camera, at the spheres of
    // those radii for a panorama.
    [[nodiscard]] Ray world_ray(double image_x, double image_y) const;
    // The ray of pixel (x, y) through (x + sample_x, y + sample_y).
    [[nodiscard]] Ray pixel_ray(int x, int y, double sample_x = 0.5, double sample_y = 0.5) const;
    // The same ray in a probe set's local frame: world_offset is subtracted in double.
    [[nodiscard]] Ray local_pixel_ray(int x, int y, const glm::dvec3& world_offset,
                                      double sample_x = 0.5, double sample_y = 0.5) const;

    // Where a world point lands: image coordinates (pixels from the top-left corner) and its
    // distance from the camera. False when it is behind the camera, outside the clip range or
    // outside the panorama's range. The inverse of world_ray.
    [[nodiscard]] bool project(const glm::dvec3& world_point, glm::dvec2& image_xy,
                               double& distance) const;
    // The same in steps, for projecting many points: world to Blender camera space (the
    // inverse of matrix_world with the scale cleared), then camera space to the image.
    [[nodiscard]] glm::dmat3 world_to_camera_rotation() const;
    [[nodiscard]] bool project_camera_space(const glm::dvec3& camera_point, glm::dvec2& image_xy,
                                            double& distance) const;
    // Pixels (across, down) spanned by a unit length perpendicular to the line of sight at
    // camera-space point `camera_point`: how large a patch there appears.
    [[nodiscard]] glm::dvec2 pixels_per_unit_at(const glm::dvec3& camera_point) const;

    // Perspective only: the full angles of view across the image's width and height, in
    // radians (without shift).
    [[nodiscard]] double horizontal_fov() const;
    [[nodiscard]] double vertical_fov() const;
    // Perspective only: pixels per unit of tan(angle) at the image centre; a patch of size s
    // at camera depth z covers about s / z * pixels_per_tangent() pixels.
    [[nodiscard]] double pixels_per_tangent() const;
};

// A camera's rays with the work per camera (rotation with the scale cleared, viewplane,
// panorama range) done once: what the renderers ask for every pixel. The rays are exactly
// Camera::world_ray's (which is this class used once).
class CameraRays {
public:
    explicit CameraRays(const Camera& camera);

    // InputError unless every ray of the image is finite: a lens, sensor, shift or angle range
    // that passes the camera file's checks one by one can still make rays of inf or NaN
    // together (a lens of 1e-300 mm), which no renderer must see. The rays are linear in the
    // image's coordinates up to normalisation, so the corners and the centre decide.
    void require_finite_rays() const;

    [[nodiscard]] glm::dvec3 camera_direction(double image_x, double image_y) const;
    [[nodiscard]] Ray world_ray(double image_x, double image_y) const;
    [[nodiscard]] Ray pixel_ray(int x, int y, double sample_x = 0.5, double sample_y = 0.5) const {
        return world_ray(static_cast<double>(x) + sample_x, static_cast<double>(y) + sample_y);
    }
    [[nodiscard]] Ray local_pixel_ray(int x, int y, const glm::dvec3& world_offset,
                                      double sample_x = 0.5, double sample_y = 0.5) const {
        Ray ray = pixel_ray(x, y, sample_x, sample_y);
        ray.origin -= world_offset;
        return ray;
    }

private:
    bool panorama_ = false;
    double width_ = 1.0;
    double height_ = 1.0;
    glm::dvec3 position_{0.0};
    glm::dmat3 rotation_{1.0};
    // Perspective: the viewplane (units of tan(fov/2)) and tan(fov/2).
    double left_ = -1.0;
    double right_ = 1.0;
    double bottom_ = -1.0;
    double top_ = 1.0;
    double tan_half_fov_ = 1.0;
    // Panorama: Cycles' equirectangular range.
    double phi_scale_ = 0.0;
    double phi_offset_ = 0.0;
    double theta_scale_ = 0.0;
    double theta_offset_ = 0.0;
    double clip_start_ = 0.0;
    double clip_end_ = 0.0;
};

// The pixel sampling the ground truth and the probe render share: n×n samples per pixel at the
// centres of an n×n grid of strata. samples_per_axis returns n for a perfect square
// samples_per_pixel (1, 4, 9, ...), else InputError naming `who`.
[[nodiscard]] int samples_per_axis(int samples_per_pixel, const std::string& who);
// Where sample s (0 ≤ s < n) of an axis lies in the pixel, in pixels from its edge.
[[nodiscard]] inline double stratum_centre(int s, int n) {
    return (s + 0.5) / n;
}

// Reads a camera JSON file. Throws IoError when it cannot be read, InputError when it is not a
// valid camera (the message names the file and the key).
[[nodiscard]] Camera read_camera_json(const std::string& path);

} // namespace lfprobe
