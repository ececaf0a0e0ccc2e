// Bindings of the mesh side: loading meshes, Embree ground truth and throughput, probe sets
// baked from meshes, simulated scans. Logic stays in the core; these only convert arguments.
#include <memory>
#include <optional>
#include <string>
#include <variant>

#include <pybind11/stl.h>
#include <tbb/task_arena.h>

#include "binding_helpers.hpp"
#include "bindings.hpp"
#include "job.hpp"
#include "lfprobe/camera.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/ground_truth.hpp"
#include "lfprobe/mesh_bake.hpp"
#include "lfprobe/mesh_reader.hpp"
#include "lfprobe/scanner_sim.hpp"

namespace py = pybind11;

namespace lfprobe::python {

namespace {

// A mesh with its Embree scene, built once and shared by every job that uses it.
struct LoadedMesh {
    Mesh mesh;
    std::unique_ptr<EmbreeScene> scene;
};
using MeshHandle = std::shared_ptr<LoadedMesh>;

MeshHandle load_mesh(const std::string& path) {
    auto m = std::make_shared<LoadedMesh>();
    m->mesh = read_mesh(path);
    m->scene = std::make_unique<EmbreeScene>(m->mesh);
    return m;
}

// A path (loaded in the job) or an already loaded mesh.
using MeshArg = std::variant<MeshHandle, std::string>;
MeshHandle resolve(const MeshArg& arg) {
    if (const auto* handle = std::get_if<MeshHandle>(&arg)) {
        return *handle;
    }
    return load_mesh(std::get<std::string>(arg));
}

} // namespace

void bind_mesh(py::module_& m) {
    py::class_<LoadedMesh, MeshHandle>(m, "Mesh",
                                       "A triangle mesh (OBJ+MTL or PLY) with its Embree scene.")
        .def_property_readonly("path", [](const LoadedMesh& h) { return h.mesh.path; })
        .def_property_readonly("triangle_count",
                               [](const LoadedMesh& h) { return h.mesh.triangle_count(); })
        .def("__len__", [](const LoadedMesh& h) { return h.mesh.triangle_count(); })
        .def_property_readonly("bounds",
                               [](const LoadedMesh& h) {
                                   const MeshBounds b = h.mesh.bounds();
                                   return py::make_tuple(py::make_tuple(b.min.x, b.min.y, b.min.z),
                                                         py::make_tuple(b.max.x, b.max.y, b.max.z));
                               })
        .def_property_readonly("objects", [](const LoadedMesh& h) { return h.mesh.object_names; })
        .def_property_readonly("materials", [](const LoadedMesh& h) {
            py::list out;
            for (const Material& mat : h.mesh.materials) {
                py::dict d;
                d["name"] = mat.name;
                d["base_color"] =
                    py::make_tuple(mat.base_color.x, mat.base_color.y, mat.base_color.z);
                d["texture"] = mat.texture ? py::object(py::str(mat.texture->path)) : py::none();
                out.append(d);
            }
            return out;
        });

    m.def(
        "load_mesh",
        [](const std::string& path) {
            py::gil_scoped_release release;
            return load_mesh(path);
        },
        py::arg("path"), "Read an OBJ (+MTL, textures) or PLY mesh and build its Embree scene.");

    m.def(
        "start_ground_truth",
        [](MeshArg mesh, const std::string& camera, const std::string& output, int spp,
           int threads) {
            const Camera cam = camera_from(camera);
            GroundTruthSettings settings;
            settings.samples_per_pixel = spp;
            return std::make_unique<Job>(
                std::function<GroundTruthStats(Progress&)>([=](Progress& progress) {
                    progress.begin_stage("loading mesh", 1);
                    const MeshHandle h = resolve(mesh);
                    return on_threads(threads, [&] {
                        GroundTruthStats stats;
                        const RenderedImage image =
                            render_ground_truth(*h->scene, cam, settings, &progress, &stats);
                        write_rendered_exr(
                            output, image,
                            nlohmann::json{{"ground_truth", h->mesh.path},
                                           {"camera", cam.to_json()},
                                           {"samples_per_pixel", settings.samples_per_pixel},
                                           {"stats", stats.to_json()}}
                                .dump());
                        return stats;
                    });
                }),
                std::function<py::object(GroundTruthStats &&)>(
                    [](GroundTruthStats&& s) -> py::object {
                        py::dict d;
                        d["rays"] = s.rays;
                        d["hits"] = s.hits;
                        d["pixels"] = s.pixels;
                        d["seconds"] = s.seconds;
                        d["rays_per_second"] = s.rays_per_second();
                        return d;
                    }));
        },
        py::arg("mesh"), py::arg("camera"), py::arg("output"), py::arg("spp") = 1,
        py::arg("threads") = 0,
        "Start an Embree ground truth render of `mesh` (path or Mesh) from `camera` (JSON path or "
        "text) into the EXR `output`; spp is 1 or a square. The Job's result is the stats dict.");

    m.def(
        "embree_throughput",
        [](MeshArg mesh, const std::string& camera, int threads, int repeats) {
            const Camera cam = camera_from(camera);
            ThroughputResult r;
            {
                py::gil_scoped_release release;
                const MeshHandle h = resolve(mesh);
                r = on_threads(threads, [&] { return embree_throughput(*h->scene, cam, repeats); });
            }
            py::dict d;
            d["rays"] = r.rays;
            d["hits"] = r.hits;
            d["seconds"] = r.seconds;
            d["rays_per_second"] = r.rays_per_second;
            d["repeats"] = r.repeats;
            return d;
        },
        py::arg("mesh"), py::arg("camera"), py::arg("threads") = 0, py::arg("repeats") = 3,
        "Embree primary rays per second on the camera's pixel-centre rays (trace only, fastest of "
        "`repeats`).");

    m.def(
        "start_bake_probe_set_from_mesh",
        [](MeshArg mesh, const std::string& folder, int resolution,
           std::vector<std::vector<double>> positions, std::optional<std::vector<double>> grid_min,
           std::optional<std::vector<double>> grid_max, std::optional<std::vector<int>> counts,
           const std::string& sources_json, int supersample) {
            // Meshes have world offset 0, so world and local probe positions coincide.
            const ProbePlacement placement =
                placement_from(positions, grid_min, grid_max, counts, glm::dvec3(0.0));
            const nlohmann::json sources = sources_from(sources_json);
            MeshBakeSettings settings;
            settings.resolution = resolution;
            settings.supersample = supersample;
            return std::make_unique<Job>(
                std::function<BakeSummary(Progress&)>([=](Progress& progress) {
                    progress.begin_stage("loading mesh", 1);
                    const MeshHandle h = resolve(mesh);
                    return bake_probe_set_from_mesh(*h->scene, placement, settings, folder, sources,
                                                    &progress);
                }),
                std::function<py::object(BakeSummary &&)>(
                    [](BakeSummary&& s) -> py::object { return bake_summary_dict(s, false); }));
        },
        py::arg("mesh"), py::arg("folder"), py::arg("resolution") = 512,
        py::arg("positions") = std::vector<std::vector<double>>{}, py::arg("grid_min") = py::none(),
        py::arg("grid_max") = py::none(), py::arg("counts") = py::none(),
        py::arg("sources_json") = "[]", py::arg("supersample") = 1,
        "Start baking a probe set from a mesh (path or Mesh) with Embree; the Job's result is the "
        "summary dict.");

    m.def(
        "start_simulate_scan",
        [](MeshArg mesh, const std::string& out_path, const std::vector<double>& position,
           double step_deg, double noise_mm, double vertical_fov, std::uint64_t seed) {
            ScannerSettings s;
            s.position = dvec3_from(position, "scanner position");
            s.step_deg = step_deg;
            s.noise_mm = noise_mm;
            s.vertical_fov_deg = vertical_fov;
            s.seed = seed;
            return std::make_unique<Job>(
                std::function<ScanStats(Progress&)>([=](Progress& progress) {
                    progress.begin_stage("loading mesh", 1);
                    const MeshHandle h = resolve(mesh);
                    return write_simulated_scan(*h->scene, s, out_path, &progress);
                }),
                std::function<py::object(ScanStats &&)>([](ScanStats&& st) -> py::object {
                    py::dict d;
                    d["rays"] = st.rays;
                    d["points"] = st.points;
                    d["seconds"] = st.seconds;
                    return d;
                }));
        },
        py::arg("mesh"), py::arg("out_path"), py::arg("position"), py::arg("step_deg") = 0.5,
        py::arg("noise_mm") = 2.0, py::arg("vertical_fov") = 300.0, py::arg("seed") = 1,
        "Start a simulated scan of `mesh` from `position` (world) into the .xyz `out_path`; the "
        "Job's result is {rays, points, seconds}.");
}

} // namespace lfprobe::python
