// Bindings of the mesh side: loading meshes, Embree ground truth and throughput, probe sets
// baked from meshes, simulated scans. Logic stays in the core; these only convert arguments.
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <variant>

#include <nlohmann/json.hpp>
#include <pybind11/numpy.h>
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
#include "lfprobe/texture.hpp"

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

// Rows of an optional (rows, width) float array, or empty when None.
template <int Width>
std::vector<glm::vec<Width, float>> optional_rows(const py::object& value, std::size_t rows,
                                                  const char* what) {
    std::vector<glm::vec<Width, float>> out;
    if (value.is_none()) {
        return out;
    }
    const auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(value);
    if (!a || a.ndim() != 2 || static_cast<std::size_t>(a.shape(0)) != rows ||
        a.shape(1) != Width) {
        throw InputError(std::string("mesh_from_arrays: expected ") + what + " of shape (" +
                         std::to_string(rows) + ", " + std::to_string(Width) + ")");
    }
    out.resize(rows);
    std::memcpy(out.data(), a.data(), rows * Width * sizeof(float));
    return out;
}

std::vector<std::uint32_t> optional_ids(const py::object& value, std::size_t count,
                                        std::size_t limit, const char* what) {
    if (value.is_none()) {
        return std::vector<std::uint32_t>(count, 0);
    }
    const auto a =
        py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(value);
    if (!a || a.ndim() != 1 || static_cast<std::size_t>(a.shape(0)) != count) {
        throw InputError(std::string("mesh_from_arrays: expected ") + what + " of shape (" +
                         std::to_string(count) + ",)");
    }
    std::vector<std::uint32_t> out(count);
    for (std::size_t i = 0; i < count; ++i) {
        const std::int64_t v = a.data()[i];
        if (v < 0 || static_cast<std::size_t>(v) >= limit) {
            throw InputError(std::string("mesh_from_arrays: ") + what + "[" + std::to_string(i) +
                             "] = " + std::to_string(v) + " is out of range (expected 0 to " +
                             std::to_string(limit == 0 ? 0 : limit - 1) + ")");
        }
        out[i] = static_cast<std::uint32_t>(v);
    }
    return out;
}

Material material_from_dict(const py::handle& item, std::size_t index) {
    if (!py::isinstance<py::dict>(item)) {
        throw InputError("mesh_from_arrays: materials[" + std::to_string(index) +
                         "] is not a dict");
    }
    const auto d = py::reinterpret_borrow<py::dict>(item);
    Material mat;
    mat.name = d.contains("name") ? py::str(d["name"]).cast<std::string>()
                                  : "material " + std::to_string(index);
    if (d.contains("base_color")) {
        const auto c = d["base_color"].cast<std::vector<float>>();
        if (c.size() < 3) {
            throw InputError("mesh_from_arrays: material '" + mat.name +
                             "' base_color needs 3 values");
        }
        mat.base_color = glm::vec3(c[0], c[1], c[2]);
    }
    if (d.contains("texture") && !d["texture"].is_none()) {
        const py::object tex = d["texture"];
        if (py::isinstance<py::str>(tex)) {
            mat.texture = std::make_shared<const Texture>(Texture::load(tex.cast<std::string>()));
        } else {
            const auto a =
                py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(tex);
            if (!a || a.ndim() != 3 || (a.shape(2) != 3 && a.shape(2) != 4)) {
                throw InputError("mesh_from_arrays: material '" + mat.name +
                                 "' texture must be a path or an (h, w, 3|4) float array");
            }
            const bool srgb = d.contains("texture_srgb") ? d["texture_srgb"].cast<bool>() : true;
            const bool bottom_up =
                d.contains("texture_bottom_up") ? d["texture_bottom_up"].cast<bool>() : true;
            mat.texture = std::make_shared<const Texture>(Texture::from_pixels(
                mat.name + " texture", static_cast<int>(a.shape(1)), static_cast<int>(a.shape(0)),
                a.data(), static_cast<int>(a.shape(2)), srgb, bottom_up));
        }
    }
    return mat;
}

Mesh mesh_from_arrays(
    const py::array_t<double, py::array::c_style | py::array::forcecast>& vertices,
    const py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>& triangles,
    const py::object& corner_uvs, const py::object& corner_colors, const py::object& corner_normals,
    const py::object& material, const py::object& object, const py::list& materials,
    const std::vector<std::string>& object_names, const std::string& name) {
    if (vertices.ndim() != 2 || vertices.shape(1) != 3) {
        throw InputError("mesh_from_arrays: expected vertices of shape (V, 3)");
    }
    if (triangles.ndim() != 2 || triangles.shape(1) != 3) {
        throw InputError("mesh_from_arrays: expected triangles of shape (T, 3)");
    }
    const auto vertex_count = static_cast<std::size_t>(vertices.shape(0));
    const auto tri_count = static_cast<std::size_t>(triangles.shape(0));
    Mesh mesh;
    mesh.path = name;
    std::vector<glm::dvec3> world(vertex_count);
    std::memcpy(world.data(), vertices.data(), vertex_count * 3 * sizeof(double));
    mesh.set_world_vertices(world);
    mesh.triangles.resize(tri_count);
    for (std::size_t t = 0; t < tri_count; ++t) {
        for (std::size_t k = 0; k < 3; ++k) {
            const std::int64_t v = triangles.data()[3 * t + k];
            if (v < 0 || static_cast<std::size_t>(v) >= vertex_count) {
                throw InputError("mesh_from_arrays: triangle " + std::to_string(t) +
                                 " names vertex " + std::to_string(v) + ", expected 0 to " +
                                 std::to_string(vertex_count == 0 ? 0 : vertex_count - 1));
            }
            mesh.triangles[t][k] = static_cast<std::uint32_t>(v);
        }
    }
    mesh.corner_uvs = optional_rows<2>(corner_uvs, 3 * tri_count, "corner_uvs");
    mesh.corner_colors = optional_rows<3>(corner_colors, 3 * tri_count, "corner_colors");
    mesh.corner_normals = optional_rows<3>(corner_normals, 3 * tri_count, "corner_normals");
    for (std::size_t i = 0; i < materials.size(); ++i) {
        mesh.materials.push_back(material_from_dict(materials[i], i));
    }
    if (mesh.materials.empty()) {
        mesh.materials.push_back(Material{"default", glm::vec3(0.8f), nullptr});
    }
    mesh.object_names = object_names;
    if (mesh.object_names.empty()) {
        mesh.object_names.emplace_back("default");
    }
    mesh.material = optional_ids(material, tri_count, mesh.materials.size(), "material");
    mesh.object = optional_ids(object, tri_count, mesh.object_names.size(), "object");
    mesh.validate(name);
    return mesh;
}

// A simulated scanner's settings as start_simulate_scan and start_simulate_scans take them.
ScannerSettings scanner_settings(const std::vector<double>& position, double step_deg,
                                 double noise_mm, double vertical_fov, std::uint64_t seed,
                                 double horizontal_fov, double horizontal_start,
                                 bool filter_textures) {
    ScannerSettings s;
    s.position = dvec3_from(position, "scanner position");
    s.step_deg = step_deg;
    s.noise_mm = noise_mm;
    s.vertical_fov_deg = vertical_fov;
    s.horizontal_fov_deg = horizontal_fov;
    s.horizontal_start_deg = horizontal_start;
    s.seed = seed;
    s.filter_textures = filter_textures;
    return s;
}

// A scan's figures as Python sees them.
py::dict scan_stats_dict(const ScanStats& st) {
    py::dict d;
    d["rays"] = st.rays;
    d["points"] = st.points;
    d["seconds"] = st.seconds;
    return d;
}

} // namespace

void bind_mesh(py::module_& m) {
    py::class_<LoadedMesh, MeshHandle>(m, "Mesh",
                                       "A triangle mesh (OBJ+MTL or PLY) with its Embree scene.")
        .def_property_readonly("path", [](const LoadedMesh& h) { return h.mesh.path; })
        .def_property_readonly("triangle_count",
                               [](const LoadedMesh& h) { return h.mesh.triangle_count(); })
        .def("__len__", [](const LoadedMesh& h) { return h.mesh.triangle_count(); })
        .def_property_readonly(
            "bounds",
            [](const LoadedMesh& h) {
                const MeshBounds b = h.mesh.bounds();
                const glm::dvec3 lo = h.mesh.world_offset + glm::dvec3(b.min);
                const glm::dvec3 hi = h.mesh.world_offset + glm::dvec3(b.max);
                return py::make_tuple(py::make_tuple(lo.x, lo.y, lo.z),
                                      py::make_tuple(hi.x, hi.y, hi.z));
            },
            "World bounds ((min), (max)) of the vertices that triangles use.")
        .def_property_readonly("world_offset",
                               [](const LoadedMesh& h) {
                                   const glm::dvec3 o = h.mesh.world_offset;
                                   return py::make_tuple(o.x, o.y, o.z);
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
        "mesh_from_arrays",
        [](const py::array_t<double, py::array::c_style | py::array::forcecast>& vertices,
           const py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>& triangles,
           const py::object& corner_uvs, const py::object& corner_colors,
           const py::object& corner_normals, const py::object& material, const py::object& object,
           const py::list& materials, const std::vector<std::string>& object_names,
           const std::string& name) {
            auto handle = std::make_shared<LoadedMesh>();
            handle->mesh =
                mesh_from_arrays(vertices, triangles, corner_uvs, corner_colors, corner_normals,
                                 material, object, materials, object_names, name);
            py::gil_scoped_release release;
            handle->scene = std::make_unique<EmbreeScene>(handle->mesh);
            return handle;
        },
        py::arg("vertices"), py::arg("triangles"), py::arg("corner_uvs") = py::none(),
        py::arg("corner_colors") = py::none(), py::arg("corner_normals") = py::none(),
        py::arg("material") = py::none(), py::arg("object") = py::none(),
        py::arg("materials") = py::list(), py::arg("object_names") = std::vector<std::string>{},
        py::arg("name") = "<arrays>",
        "A Mesh from arrays, as the Blender add-on hands objects over: vertices (V, 3) world "
        "positions in double (the world offset is chosen as for scans), triangles (T, 3) vertex "
        "indices; optional per corner (3T, 2) uvs, (3T, 3) linear colours, (3T, 3) normals; "
        "optional per triangle material and object indices (T,). materials: dicts with 'name', "
        "'base_color' (linear r, g, b) and optionally 'texture': an image path, or an array "
        "(h, w, 3 or 4) of floats with 'texture_srgb' (default True: values are sRGB-encoded, "
        "as Blender's byte images give them) and 'texture_bottom_up' (default True: row 0 is the "
        "bottom row, as Blender's Image.pixels are).");

    m.def(
        "start_ground_truth",
        [](MeshArg mesh, const std::string& camera, const std::string& output, int spp, int threads,
           bool filter_textures) {
            const Camera cam = camera_from(camera);
            GroundTruthSettings settings;
            settings.samples_per_pixel = spp;
            settings.filter_textures = filter_textures;
            return std::make_unique<Job>(
                std::function<GroundTruthStats(Progress&)>([=](Progress& progress) {
                    progress.begin_stage("loading mesh", 1);
                    const MeshHandle h = resolve(mesh);
                    return on_threads(threads, [&] {
                        return ground_truth_to_exr(*h->scene, h->mesh.path, cam, settings, output,
                                                   &progress);
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
        py::arg("threads") = 0, py::arg("filter_textures") = GroundTruthSettings{}.filter_textures,
        "Start an Embree ground truth render of `mesh` (path or Mesh) from `camera` (JSON path or "
        "text) into the EXR `output`; spp is 1 or a square. filter_textures: each sample's "
        "texture colour is the mean over its footprint (texture LOD), else point-sampled. The "
        "Job's result is the stats dict.");

    m.def(
        "embree_throughput",
        [](MeshArg mesh, const std::string& camera, int threads, int repeats, int packet) {
            const Camera cam = camera_from(camera);
            ThroughputResult r;
            {
                py::gil_scoped_release release;
                const MeshHandle h = resolve(mesh);
                r = on_threads(threads,
                               [&] { return embree_throughput(*h->scene, cam, repeats, packet); });
            }
            return throughput_dict(r);
        },
        py::arg("mesh"), py::arg("camera"), py::arg("threads") = 0, py::arg("repeats") = 3,
        py::arg("packet") = 1,
        "Embree primary rays per second on the camera's pixel-centre rays (trace only, fastest of "
        "`repeats`); `packet` rays per Embree call: 1 (rtcIntersect1) or 4, 8, 16 (its packet "
        "API).");

    m.def(
        "start_bake_probe_set_from_mesh",
        [](MeshArg mesh, const std::string& folder, int resolution,
           std::vector<std::vector<double>> positions, std::optional<std::vector<double>> grid_min,
           std::optional<std::vector<double>> grid_max, std::optional<std::vector<int>> counts,
           const std::string& sources_json, int supersample, bool filter_textures) {
            // Checked now so that bad placements raise at once; made local to the mesh's world
            // offset once the job has the mesh.
            (void)placement_from(positions, grid_min, grid_max, counts, glm::dvec3(0.0));
            const nlohmann::json sources = sources_from(sources_json);
            MeshBakeSettings settings;
            settings.resolution = resolution;
            settings.supersample = supersample;
            settings.filter_textures = filter_textures;
            return std::make_unique<Job>(
                std::function<BakeSummary(Progress&)>([=](Progress& progress) {
                    progress.begin_stage("loading mesh", 1);
                    const MeshHandle h = resolve(mesh);
                    const ProbePlacement placement =
                        placement_from(positions, grid_min, grid_max, counts, h->mesh.world_offset);
                    return bake_probe_set_from_mesh(*h->scene, placement, settings, folder, sources,
                                                    &progress);
                }),
                std::function<py::object(BakeSummary &&)>(
                    [](BakeSummary&& s) -> py::object { return bake_summary_dict(s, false); }));
        },
        py::arg("mesh"), py::arg("folder"), py::arg("resolution") = 512,
        py::arg("positions") = std::vector<std::vector<double>>{}, py::arg("grid_min") = py::none(),
        py::arg("grid_max") = py::none(), py::arg("counts") = py::none(),
        py::arg("sources_json") = "[]", py::arg("supersample") = MeshBakeSettings{}.supersample,
        py::arg("filter_textures") = MeshBakeSettings{}.filter_textures,
        "Start baking a probe set from a mesh (path or Mesh) with Embree; the Job's result is the "
        "summary dict. supersample: n×n rays per texel for its colour, counting only those on the "
        "centre ray's surface. filter_textures: each ray's texture colour is the mean over its "
        "footprint (texture LOD), else point-sampled.");

    m.def(
        "start_simulate_scan",
        [](MeshArg mesh, const std::string& out_path, const std::vector<double>& position,
           double step_deg, double noise_mm, double vertical_fov, std::uint64_t seed,
           double horizontal_fov, double horizontal_start, bool filter_textures) {
            const ScannerSettings s =
                scanner_settings(position, step_deg, noise_mm, vertical_fov, seed, horizontal_fov,
                                 horizontal_start, filter_textures);
            return std::make_unique<Job>(
                std::function<ScanStats(Progress&)>([=](Progress& progress) {
                    progress.begin_stage("loading mesh", 1);
                    const MeshHandle h = resolve(mesh);
                    return write_simulated_scan(*h->scene, s, out_path, &progress);
                }),
                std::function<py::object(ScanStats &&)>(
                    [](ScanStats&& st) -> py::object { return scan_stats_dict(st); }));
        },
        py::arg("mesh"), py::arg("out_path"), py::arg("position"), py::arg("step_deg") = 0.5,
        py::arg("noise_mm") = 2.0, py::arg("vertical_fov") = 300.0, py::arg("seed") = 1,
        py::arg("horizontal_fov") = ScannerSettings{}.horizontal_fov_deg,
        py::arg("horizontal_start") = ScannerSettings{}.horizontal_start_deg,
        py::arg("filter_textures") = ScannerSettings{}.filter_textures,
        "Start a simulated scan of `mesh` from `position` (world) into the .xyz `out_path`; the "
        "Job's result is {rays, points, seconds}. horizontal_fov < 360 sweeps only the azimuths "
        "[horizontal_start, horizontal_start + horizontal_fov) degrees (from +X toward +Y), a "
        "partial sweep. filter_textures: each point's colour is the texture's mean over its "
        "footprint (the step times the range), as a scanner's camera pixel records it; else the "
        "texture at the hit alone.");

    m.def(
        "start_simulate_scans",
        [](MeshArg mesh, const std::vector<std::vector<double>>& positions, double step_deg,
           double noise_mm, double vertical_fov, const std::vector<std::uint64_t>& seeds,
           double horizontal_fov, double horizontal_start, bool filter_textures) {
            if (!seeds.empty() && seeds.size() != positions.size()) {
                throw InputError("simulated scans: give one seed per scanner position, or none");
            }
            std::vector<ScannerSettings> scanners;
            for (std::size_t k = 0; k < positions.size(); ++k) {
                scanners.push_back(scanner_settings(positions[k], step_deg, noise_mm, vertical_fov,
                                                    seeds.empty() ? k + 1 : seeds[k],
                                                    horizontal_fov, horizontal_start,
                                                    filter_textures));
            }
            struct Scanned {
                PointCloud cloud;
                std::vector<ScanStats> stats;
            };
            return std::make_unique<Job>(
                std::function<Scanned(Progress&)>([=](Progress& progress) {
                    progress.begin_stage("loading mesh", 1);
                    const MeshHandle h = resolve(mesh);
                    Scanned scanned;
                    scanned.cloud =
                        simulate_scans_cloud(*h->scene, scanners, &progress, &scanned.stats);
                    return scanned;
                }),
                std::function<py::object(Scanned &&)>([](Scanned&& scanned) -> py::object {
                    py::list stats;
                    for (const ScanStats& st : scanned.stats) {
                        stats.append(scan_stats_dict(st));
                    }
                    py::dict d;
                    d["cloud"] = std::make_shared<PointCloud>(std::move(scanned.cloud));
                    d["stats"] = stats;
                    return d;
                }));
        },
        py::arg("mesh"), py::arg("positions"), py::arg("step_deg") = 0.5, py::arg("noise_mm") = 2.0,
        py::arg("vertical_fov") = 300.0, py::arg("seeds") = std::vector<std::uint64_t>{},
        py::arg("horizontal_fov") = ScannerSettings{}.horizontal_fov_deg,
        py::arg("horizontal_start") = ScannerSettings{}.horizontal_start_deg,
        py::arg("filter_textures") = ScannerSettings{}.filter_textures,
        "Start simulated scans of `mesh` from each of `positions` (world), as start_simulate_scan "
        "takes them (seeds: one per position; none: 1, 2, ...), into one PointCloud with no file "
        "between: the cloud load_scans gives of their files, but for the positions' 6 decimals. "
        "The Job's result is {cloud, stats: one {rays, points, seconds} per scanner}.");
}

} // namespace lfprobe::python
