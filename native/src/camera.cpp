// Blender's camera as Cycles renders it. Where each rule comes from (Blender 2.9x–4.x sources):
// - defaults: source/blender/makesdna/DNA_camera_defaults.h (_DNA_DEFAULT_Camera);
// - sensor fit, aspect, shift and field of view: intern/cycles/blender/camera.cpp,
//   blender_camera_viewplane() and blender_camera_sync() (cam->fov = 2 atan(0.5 sensor / lens /
//   aspectratio)); the viewplane of a panorama is [0, 1]² (bcam->pano_viewplane) and its shift
//   is ignored;
// - camera frame: blender_camera_matrix() (perspective: scale(1, 1, −1), Blender looks down −Z;
//   equirectangular: the panorama's +X is the camera's −Z so that the image centre looks where
//   the camera points) followed by transform_clear_scale();
// - raster to screen: intern/cycles/scene/camera.cpp (screentondc from the viewplane, raster
//   y = 0 at the bottom of the image), projection_perspective();
// - equirectangular directions: intern/cycles/kernel/camera/projection.h,
//   equirectangular_range_to_direction(), with the range of Camera::device_update():
//   (lon_min − lon_max, −lon_min, lat_min − lat_max, −lat_min + π/2);
// - clipping: intern/cycles/kernel/camera/camera.h, camera_sample_perspective() (the ray starts
//   on the plane z = −clip_start and ends on z = −clip_end) and camera_sample_panorama()
//   (spheres of radius clip_start and clip_end).
#include "lfprobe/camera.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>
#include <nlohmann/json.hpp>

#include "lfprobe/enum_names.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/input_limits.hpp"
#include "lfprobe/json_input.hpp"

namespace lfprobe {

using nlohmann::json;

namespace {

// The perspective viewplane of blender_camera_viewplane(), in units of tan(fov/2).
struct Viewplane {
    double left = -1.0;
    double right = 1.0;
    double bottom = -1.0;
    double top = 1.0;
    double tan_half_fov = 1.0; // tan(cam->fov / 2)
    double x_aspect = 1.0;
    double y_aspect = 1.0;
};

Viewplane viewplane_of(const Camera& c) {
    const double x_ratio = static_cast<double>(c.width) * c.pixel_aspect_x;
    const double y_ratio = static_cast<double>(c.height) * c.pixel_aspect_y;
    bool horizontal_fit = true;
    double sensor_size = c.sensor_width;
    switch (c.sensor_fit) {
    case SensorFit::Auto:
        // Cycles: strictly wider than tall fits horizontally; a square image fits vertically,
        // which gives the same result since the aspect ratio is then 1.
        horizontal_fit = x_ratio > y_ratio;
        sensor_size = c.sensor_width;
        break;
    case SensorFit::Horizontal:
        horizontal_fit = true;
        sensor_size = c.sensor_width;
        break;
    case SensorFit::Vertical:
        horizontal_fit = false;
        sensor_size = c.sensor_height;
        break;
    }
    Viewplane v;
    const double aspect_ratio = horizontal_fit ? x_ratio / y_ratio : y_ratio / x_ratio;
    v.x_aspect = horizontal_fit ? aspect_ratio : 1.0;
    v.y_aspect = horizontal_fit ? 1.0 : aspect_ratio;
    const double dx = 2.0 * aspect_ratio * c.shift_x;
    const double dy = 2.0 * aspect_ratio * c.shift_y;
    v.left = -v.x_aspect + dx;
    v.right = v.x_aspect + dx;
    v.bottom = -v.y_aspect + dy;
    v.top = v.y_aspect + dy;
    v.tan_half_fov = 0.5 * sensor_size / c.lens / aspect_ratio;
    return v;
}

// Camera::device_update()'s equirectangular_range.
struct EquirectRange {
    double phi_scale, phi_offset, theta_scale, theta_offset;
};

EquirectRange equirect_range_of(const Camera& c) {
    return {c.longitude_min - c.longitude_max, -c.longitude_min, c.latitude_min - c.latitude_max,
            -c.latitude_min + 0.5 * std::numbers::pi};
}

// Panorama space (+X at the image centre, +Z up) to Blender camera space (−Z forward, +Y up):
// blender_camera_matrix()'s rows (0 −1 0), (0 0 1), (−1 0 0).
glm::dvec3 panorama_to_camera(const glm::dvec3& d) {
    return {-d.y, d.z, -d.x};
}
glm::dvec3 camera_to_panorama(const glm::dvec3& c) {
    return {-c.z, -c.x, c.y};
}

// Blender's spellings (bpy.types.Camera.type, .sensor_fit).
constexpr auto camera_type_names = std::to_array<EnumName<CameraType>>({
    {CameraType::Perspective, "PERSP"},
    {CameraType::PanoramaEquirect, "PANO_EQUIRECT"},
});
constexpr auto sensor_fit_names = std::to_array<EnumName<SensorFit>>({
    {SensorFit::Auto, "AUTO"},
    {SensorFit::Horizontal, "HORIZONTAL"},
    {SensorFit::Vertical, "VERTICAL"},
});

[[noreturn]] void bad_key(const std::string& where, const std::string& key,
                          const std::string& expected, const json& got) {
    std::string shown = got.dump();
    if (shown.size() > 80) {
        shown = shown.substr(0, 77) + "...";
    }
    throw InputError(where + ": camera key '" + key + "' must be " + expected + " (got " + shown +
                     ")");
}

double read_number(const json& j, const char* key, double fallback, const std::string& where) {
    if (!j.contains(key)) {
        return fallback;
    }
    const json& v = j.at(key);
    if (!v.is_number() || !std::isfinite(v.get<double>())) {
        bad_key(where, key, "a finite number", v);
    }
    return v.get<double>();
}

double read_positive(const json& j, const char* key, double fallback, const std::string& where) {
    const double v = read_number(j, key, fallback, where);
    if (!(v > 0.0)) {
        bad_key(where, key, "a positive number", j.at(key));
    }
    return v;
}

} // namespace

Camera Camera::from_json(const json& j, const std::string& where) {
    if (!j.is_object()) {
        throw InputError(where + ": a camera must be a JSON object with Blender's camera keys");
    }
    Camera c;
    if (j.contains("type")) {
        const json& t = j.at("type");
        const std::string name = t.is_string() ? t.get<std::string>() : "";
        if (const auto type = value_named(camera_type_names, name)) {
            c.type = *type;
        } else if (name == "PANO") {
            // Blender's own spelling: type PANO with a panorama_type (DNA default: fisheye).
            const json pano = j.value("panorama_type", json("FISHEYE_EQUISOLID"));
            if (!pano.is_string() || pano.get<std::string>() != "EQUIRECTANGULAR") {
                bad_key(where, "panorama_type", "\"EQUIRECTANGULAR\" (the only panorama supported)",
                        pano);
            }
            c.type = CameraType::PanoramaEquirect;
        } else {
            bad_key(where, "type", "\"PERSP\" or \"PANO_EQUIRECT\"", t);
        }
    }
    if (j.contains("matrix_world")) {
        const json& m = j.at("matrix_world");
        auto valid = [&] {
            if (!m.is_array() || m.size() != 4) {
                return false;
            }
            for (const json& row : m) {
                if (!row.is_array() || row.size() != 4) {
                    return false;
                }
                for (const json& v : row) {
                    if (!v.is_number() || !std::isfinite(v.get<double>())) {
                        return false;
                    }
                }
            }
            return true;
        };
        if (!valid()) {
            bad_key(where, "matrix_world", "4 rows of 4 finite numbers (camera to world)", m);
        }
        for (int row = 0; row < 4; ++row) {
            for (int col = 0; col < 4; ++col) {
                c.matrix_world[col][row] =
                    m[static_cast<std::size_t>(row)][static_cast<std::size_t>(col)].get<double>();
            }
        }
        if (glm::determinant(glm::dmat3(c.matrix_world)) == 0.0) {
            bad_key(where, "matrix_world", "an invertible transform", m);
        }
    }
    if (j.contains("resolution")) {
        const json& r = j.at("resolution");
        if (!r.is_array() || r.size() != 2 || !r[0].is_number_integer() ||
            !r[1].is_number_integer() || r[0].get<long long>() < 1 || r[1].get<long long>() < 1 ||
            r[0].get<long long>() > 65536 || r[1].get<long long>() > 65536) {
            bad_key(where, "resolution", "[width, height] in pixels (1 to 65536)", r);
        }
        c.width = r[0].get<int>();
        c.height = r[1].get<int>();
        // An image holds 41 bytes a pixel in memory: the bound keeps one under 3 GB.
        if (static_cast<long long>(c.width) * c.height > input_limit(InputLimit::CameraPixels)) {
            bad_key(where, "resolution",
                    "pixels " + input_limit_hint(InputLimit::CameraPixels) +
                        " (default 8192 × 8192)",
                    r);
        }
    }
    c.lens = read_positive(j, "lens", c.lens, where);
    c.sensor_width = read_positive(j, "sensor_width", c.sensor_width, where);
    c.sensor_height = read_positive(j, "sensor_height", c.sensor_height, where);
    if (j.contains("sensor_fit")) {
        const json& f = j.at("sensor_fit");
        const std::string name = f.is_string() ? f.get<std::string>() : "";
        if (const auto fit = value_named(sensor_fit_names, name)) {
            c.sensor_fit = *fit;
        } else {
            bad_key(where, "sensor_fit", "\"AUTO\", \"HORIZONTAL\" or \"VERTICAL\"", f);
        }
    }
    c.shift_x = read_number(j, "shift_x", c.shift_x, where);
    c.shift_y = read_number(j, "shift_y", c.shift_y, where);
    c.clip_start = read_number(j, "clip_start", c.clip_start, where);
    if (c.clip_start < 0.0) {
        bad_key(where, "clip_start", "a number of at least 0", j.at("clip_start"));
    }
    c.clip_end = read_number(j, "clip_end", c.clip_end, where);
    if (!(c.clip_end > c.clip_start)) {
        bad_key(where, "clip_end", "greater than clip_start (" + std::to_string(c.clip_start) + ")",
                j.contains("clip_end") ? j.at("clip_end") : json(c.clip_end));
    }
    c.latitude_min = read_number(j, "latitude_min", c.latitude_min, where);
    c.latitude_max = read_number(j, "latitude_max", c.latitude_max, where);
    c.longitude_min = read_number(j, "longitude_min", c.longitude_min, where);
    c.longitude_max = read_number(j, "longitude_max", c.longitude_max, where);
    if (c.latitude_min == c.latitude_max) {
        bad_key(where, "latitude_max", "different from latitude_min", j.at("latitude_max"));
    }
    if (c.longitude_min == c.longitude_max) {
        bad_key(where, "longitude_max", "different from longitude_min", j.at("longitude_max"));
    }
    c.pixel_aspect_x = read_positive(j, "pixel_aspect_x", c.pixel_aspect_x, where);
    c.pixel_aspect_y = read_positive(j, "pixel_aspect_y", c.pixel_aspect_y, where);
    return c;
}

json Camera::to_json() const {
    json rows = json::array();
    for (int row = 0; row < 4; ++row) {
        json r = json::array();
        for (int col = 0; col < 4; ++col) {
            r.push_back(matrix_world[col][row]);
        }
        rows.push_back(r);
    }
    return json{{"type", name_of(camera_type_names, type)},
                {"matrix_world", rows},
                {"resolution", {width, height}},
                {"lens", lens},
                {"sensor_width", sensor_width},
                {"sensor_height", sensor_height},
                {"sensor_fit", name_of(sensor_fit_names, sensor_fit)},
                {"shift_x", shift_x},
                {"shift_y", shift_y},
                {"clip_start", clip_start},
                {"clip_end", clip_end},
                {"latitude_min", latitude_min},
                {"latitude_max", latitude_max},
                {"longitude_min", longitude_min},
                {"longitude_max", longitude_max},
                {"pixel_aspect_x", pixel_aspect_x},
                {"pixel_aspect_y", pixel_aspect_y}};
}

glm::dvec3 Camera::position() const {
    return glm::dvec3(matrix_world[3]);
}

glm::dmat3 Camera::rotation() const {
    glm::dmat3 r(matrix_world);
    for (int col = 0; col < 3; ++col) {
        r[col] = glm::normalize(r[col]);
    }
    return r;
}

glm::dvec3 Camera::camera_direction(double image_x, double image_y) const {
    return CameraRays(*this).camera_direction(image_x, image_y);
}

Ray Camera::world_ray(double image_x, double image_y) const {
    return CameraRays(*this).world_ray(image_x, image_y);
}

CameraRays::CameraRays(const Camera& camera)
    : panorama_(camera.type == CameraType::PanoramaEquirect),
      width_(static_cast<double>(camera.width)), height_(static_cast<double>(camera.height)),
      position_(camera.position()), rotation_(camera.rotation()), clip_start_(camera.clip_start),
      clip_end_(camera.clip_end) {
    if (panorama_) {
        const EquirectRange range = equirect_range_of(camera);
        phi_scale_ = range.phi_scale;
        phi_offset_ = range.phi_offset;
        theta_scale_ = range.theta_scale;
        theta_offset_ = range.theta_offset;
    } else {
        const Viewplane vp = viewplane_of(camera);
        left_ = vp.left;
        right_ = vp.right;
        bottom_ = vp.bottom;
        top_ = vp.top;
        tan_half_fov_ = vp.tan_half_fov;
    }
}

void CameraRays::require_finite_rays() const {
    const auto finite = [](const glm::dvec3& v) {
        return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
    };
    for (const double x : {0.0, 0.5 * width_, width_}) {
        for (const double y : {0.0, 0.5 * height_, height_}) {
            const Ray ray = world_ray(x, y);
            if (!finite(ray.origin) || !finite(ray.direction) || std::isnan(ray.t_min) ||
                std::isnan(ray.t_max)) {
                throw InputError("camera: its rays are not finite numbers: the lens, sensor "
                                 "size, shift or panorama range is out of range");
            }
        }
    }
}

glm::dvec3 CameraRays::camera_direction(double image_x, double image_y) const {
    const double raster_x = image_x;
    const double raster_y = height_ - image_y; // Cycles' raster y runs up from the bottom row
    if (panorama_) {
        const double u = raster_x / width_;
        const double v = raster_y / height_;
        const double phi = phi_scale_ * u + phi_offset_;
        const double theta = theta_scale_ * v + theta_offset_;
        const glm::dvec3 d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                           std::cos(theta));
        return glm::normalize(panorama_to_camera(d));
    }
    const double screen_x = left_ + (right_ - left_) * raster_x / width_;
    const double screen_y = bottom_ + (top_ - bottom_) * raster_y / height_;
    return glm::normalize(glm::dvec3(screen_x * tan_half_fov_, screen_y * tan_half_fov_, -1.0));
}

Ray CameraRays::world_ray(double image_x, double image_y) const {
    const glm::dvec3 local = camera_direction(image_x, image_y);
    Ray ray;
    ray.origin = position_;
    ray.direction = glm::normalize(rotation_ * local);
    if (panorama_) {
        ray.t_min = clip_start_;
        ray.t_max = clip_end_;
    } else {
        // The clip planes are perpendicular to the view axis: t = clip / cos(angle to −Z).
        const double inv_cos = 1.0 / -local.z;
        ray.t_min = clip_start_ * inv_cos;
        ray.t_max = clip_end_ * inv_cos;
    }
    return ray;
}

Ray Camera::pixel_ray(int x, int y, double sample_x, double sample_y) const {
    return world_ray(static_cast<double>(x) + sample_x, static_cast<double>(y) + sample_y);
}

Ray Camera::local_pixel_ray(int x, int y, const glm::dvec3& world_offset, double sample_x,
                            double sample_y) const {
    Ray ray = pixel_ray(x, y, sample_x, sample_y);
    ray.origin -= world_offset;
    return ray;
}

bool Camera::project(const glm::dvec3& world_point, glm::dvec2& image_xy, double& distance) const {
    return project_camera_space(world_to_camera_rotation() * (world_point - position()), image_xy,
                                distance);
}

glm::dmat3 Camera::world_to_camera_rotation() const {
    return glm::inverse(rotation());
}

bool Camera::project_camera_space(const glm::dvec3& p, glm::dvec2& image_xy,
                                  double& distance) const {
    distance = glm::length(p);
    const double w = static_cast<double>(width);
    const double h = static_cast<double>(height);
    if (type == CameraType::PanoramaEquirect) {
        if (!(distance >= clip_start && distance <= clip_end) || distance == 0.0) {
            return false;
        }
        const glm::dvec3 d = camera_to_panorama(p);
        const EquirectRange range = equirect_range_of(*this);
        const double theta = std::acos(std::clamp(d.z / distance, -1.0, 1.0));
        const double v = (theta - range.theta_offset) / range.theta_scale;
        // atan2 answers in (−π, π]; the longitude range may lie elsewhere, so try its turns.
        const double phi = std::atan2(d.y, d.x);
        double u = -1.0;
        for (const double turn : {0.0, 2.0 * std::numbers::pi, -2.0 * std::numbers::pi}) {
            const double candidate = (phi + turn - range.phi_offset) / range.phi_scale;
            if (candidate >= 0.0 && candidate <= 1.0) {
                u = candidate;
                break;
            }
        }
        if (u < 0.0 || !(v >= 0.0 && v <= 1.0)) {
            return false;
        }
        image_xy = glm::dvec2(u * w, h - v * h);
        return true;
    }
    const double depth = -p.z; // along the view axis
    if (!(depth >= clip_start && depth <= clip_end) || depth <= 0.0) {
        return false;
    }
    const Viewplane vp = viewplane_of(*this);
    const double screen_x = p.x / depth / vp.tan_half_fov;
    const double screen_y = p.y / depth / vp.tan_half_fov;
    const double raster_x = (screen_x - vp.left) / (vp.right - vp.left) * w;
    const double raster_y = (screen_y - vp.bottom) / (vp.top - vp.bottom) * h;
    image_xy = glm::dvec2(raster_x, h - raster_y);
    return true;
}

glm::dvec2 Camera::pixels_per_unit_at(const glm::dvec3& p) const {
    const double w = static_cast<double>(width);
    const double h = static_cast<double>(height);
    const double distance = glm::length(p);
    if (type == CameraType::PanoramaEquirect) {
        // Pixels per radian, across stretched by 1 / cos(latitude) as the image is.
        const glm::dvec3 d = camera_to_panorama(p);
        const double cos_latitude =
            std::max(std::sqrt(d.x * d.x + d.y * d.y) / std::max(distance, 1e-300), 1e-3);
        return {w / std::abs(longitude_max - longitude_min) / (distance * cos_latitude),
                h / std::abs(latitude_max - latitude_min) / distance};
    }
    const Viewplane vp = viewplane_of(*this);
    const double depth = std::max(-p.z, 1e-300);
    return {w / ((vp.right - vp.left) * vp.tan_half_fov) / depth,
            h / ((vp.top - vp.bottom) * vp.tan_half_fov) / depth};
}

double Camera::horizontal_fov() const {
    const Viewplane vp = viewplane_of(*this);
    return 2.0 * std::atan(vp.x_aspect * vp.tan_half_fov);
}

double Camera::vertical_fov() const {
    const Viewplane vp = viewplane_of(*this);
    return 2.0 * std::atan(vp.y_aspect * vp.tan_half_fov);
}

double Camera::pixels_per_tangent() const {
    const Viewplane vp = viewplane_of(*this);
    return static_cast<double>(width) / ((vp.right - vp.left) * vp.tan_half_fov);
}

Camera read_camera_json(const std::string& path) {
    return Camera::from_json(read_json_file(path, "camera file"), path);
}

Camera Camera::look_at(const glm::dvec3& eye, const glm::dvec3& target, int width, int height,
                       double lens) {
    const glm::dvec3 forward = glm::normalize(target - eye);
    glm::dvec3 right = glm::cross(forward, glm::dvec3(0, 0, 1));
    // Looking straight up or down: any horizontal right vector will do.
    right = glm::length(right) > 1e-12 ? glm::normalize(right) : glm::dvec3(1, 0, 0);
    const glm::dvec3 up = glm::cross(right, forward);
    Camera c;
    c.matrix_world = glm::dmat4(1.0);
    c.matrix_world[0] = glm::dvec4(right, 0.0);
    c.matrix_world[1] = glm::dvec4(up, 0.0);
    c.matrix_world[2] = glm::dvec4(-forward, 0.0);
    c.matrix_world[3] = glm::dvec4(eye, 1.0);
    c.width = width;
    c.height = height;
    c.lens = lens;
    c.clip_start = 0.01;
    return c;
}

int samples_per_axis(int samples_per_pixel, const std::string& who) {
    const int n = static_cast<int>(std::lround(std::sqrt(static_cast<double>(samples_per_pixel))));
    if (samples_per_pixel < 1 || n * n != samples_per_pixel) {
        throw InputError(who + ": samples_per_pixel must be a square (1, 4, 9, 16, ...), got " +
                         std::to_string(samples_per_pixel));
    }
    return n;
}

} // namespace lfprobe
