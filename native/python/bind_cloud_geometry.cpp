// A cloud's local geometry (normals, spacing) for Python: what another reconstruction of the
// same scans needs from it (the report's Poisson peer takes its oriented normals), read from
// the prepared-cloud cache a bake or a splat of the cloud left, else estimated once and cached.
#include <chrono>
#include <cstring>
#include <memory>
#include <string>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "binding_helpers.hpp"
#include "bindings.hpp"
#include "job.hpp"
#include "lfprobe/prepared_cloud_cache.hpp"

namespace py = pybind11;

namespace lfprobe::python {

namespace {

struct TimedGeometry {
    LocalGeometry geometry;
    double seconds = 0.0;
};

py::dict geometry_dict(TimedGeometry&& timed) {
    const LocalGeometry& g = timed.geometry;
    const auto n = static_cast<py::ssize_t>(g.normals.size());
    py::array_t<float> normals({n, py::ssize_t{3}});
    std::memcpy(normals.mutable_data(), g.normals.data(), g.normals.size() * sizeof(glm::vec3));
    py::array_t<float> spacing(n);
    std::memcpy(spacing.mutable_data(), g.spacing.data(), g.spacing.size() * sizeof(float));
    py::array_t<bool> oriented(n);
    bool* out = oriented.mutable_data();
    for (py::ssize_t i = 0; i < n; ++i) {
        out[i] = g.oriented.empty() || g.oriented[static_cast<std::size_t>(i)] != 0;
    }
    py::dict d;
    d["normals"] = normals;
    d["spacing"] = spacing;
    d["oriented"] = oriented;
    d["seconds"] = timed.seconds;
    return d;
}

} // namespace

void bind_cloud_geometry(py::module_& m) {
    m.def(
        "start_local_geometry",
        [](std::shared_ptr<PointCloud> cloud, int threads, const std::string& cache_dir) {
            auto work = [=](Progress& progress) {
                return on_threads(threads, [&] {
                    const auto start = std::chrono::steady_clock::now();
                    TimedGeometry timed{cached_local_geometry(*cloud, cache_dir, &progress)};
                    timed.seconds =
                        std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
                            .count();
                    return timed;
                });
            };
            return std::make_unique<Job>(std::function<TimedGeometry(Progress&)>(work),
                                         std::function<py::object(TimedGeometry &&)>(
                                             [](TimedGeometry&& timed) -> py::object {
                                                 return geometry_dict(std::move(timed));
                                             }));
        },
        py::arg("cloud"), py::arg("threads") = 0, py::arg("cache_dir") = "",
        "Start estimating the cloud's local geometry as a bake does (k-nearest-neighbour PCA "
        "normals oriented toward each point's scanner, mean neighbour spacing); the Job's result "
        "is {normals: (n, 3) float32, spacing: (n,) float32 metres, oriented: (n,) bool (false: "
        "no scanner position, the normal's sign is arbitrary), seconds}. cache_dir: the "
        "prepared-cloud cache a bake or splat of the cloud reads and writes; the geometry is read "
        "from it when there and cached there when estimated (\"\": none).");
}

} // namespace lfprobe::python
