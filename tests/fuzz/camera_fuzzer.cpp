// libFuzzer harness: a camera file, then a render through a grid of probes with it (the
// camera-then-trace path of a user's `render`). The camera reader and CameraRays promise that a
// camera they accept makes finite rays at every pixel; small images are rendered whole, through
// a 2×2×2 grid of analytic 8×8 probes of a box room.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string_view>

#include "fuzz_support.hpp"
#include "lfprobe/camera.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/input_limits.hpp"
#include "lfprobe/render.hpp"
#include "trace_scenes.hpp"

namespace {

const lfprobe::ProbeField& grid_field() {
    using namespace lfprobe;
    static const ProbeField field = [] {
        const testing::BoxRoomScene scene = testing::empty_box_room();
        const ProbeGrid grid = ProbeGrid::spanning({-1.0, -0.75, 0.5}, {1.0, 0.75, 2.0}, {2, 2, 2});
        return testing::analytic_field(scene, ProbePlacement::from_grid(grid), 8);
    }();
    return field;
}

bool finite_ray(const lfprobe::Ray& ray) {
    for (int a = 0; a < 3; ++a) {
        if (!std::isfinite(ray.origin[a]) || !std::isfinite(ray.direction[a])) {
            return false;
        }
    }
    return true;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace lfprobe;
    const std::string path = fuzz::write_scratch_file(
        "camera.json", std::string_view(reinterpret_cast<const char*>(data), size));
    Camera camera;
    try {
        camera = read_camera_json(path);
        CameraRays(camera).require_finite_rays();
    } catch (const InputError&) {
        return 0;
    } catch (const IoError&) {
        return 0;
    }
    fuzz::expect(camera.width >= 1 && camera.height >= 1 &&
                     static_cast<long long>(camera.width) * camera.height <=
                         input_limit(InputLimit::CameraPixels),
                 "an accepted camera's resolution is outside its limits");
    // Every pixel of an accepted camera has a finite ray; sampled on a grid of at most 32×32
    // pixels, corners and edges included, for large images.
    const CameraRays rays(camera);
    const int step_x = std::max(1, (camera.width - 1) / 31);
    const int step_y = std::max(1, (camera.height - 1) / 31);
    for (int y = 0; y < camera.height;
         y = (y == camera.height - 1) ? camera.height : std::min(y + step_y, camera.height - 1)) {
        for (int x = 0; x < camera.width;
             x = (x == camera.width - 1) ? camera.width : std::min(x + step_x, camera.width - 1)) {
            fuzz::expect(finite_ray(rays.pixel_ray(x, y)),
                         "an accepted camera makes a ray that is not finite");
        }
    }
    if (static_cast<long long>(camera.width) * camera.height <= 64 * 64) {
        RenderSettings settings;
        settings.trace.mode = FieldMode::Grid;
        try {
            const RenderedImage image = render_probe_view(grid_field(), camera, settings);
            (void)image;
        } catch (const InputError&) {
            // Refusing is allowed; crashing is not.
        }
    }
    return 0;
}
