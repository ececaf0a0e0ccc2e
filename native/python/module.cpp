// lfprobe._native: a thin binding over the native core. numpy arrays in and out, long work
// run as Jobs with the GIL released, native errors turned into Python exceptions. No
// algorithm lives here.
#include <array>
#include <charconv>
#include <cstring>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "binding_helpers.hpp"
#include "bindings.hpp"
#include "job.hpp"
#include "lfprobe/cloud_bake.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/known_space.hpp"
#include "lfprobe/mesh_bake.hpp"
#include "lfprobe/min_distance_pyramid.hpp"
#include "lfprobe/octahedral.hpp"
#include "lfprobe/probe_exr.hpp"
#include "lfprobe/probe_set.hpp"
#include "lfprobe/radiance_filter.hpp"
#include "lfprobe/render.hpp"
#include "lfprobe/scan_cache.hpp"
#include "lfprobe/scan_reader.hpp"

namespace py = pybind11;
using namespace lfprobe;
using lfprobe::python::bake_summary_dict;
using lfprobe::python::coverage_dict;
using lfprobe::python::dvec3_from;
using lfprobe::python::Job;
using lfprobe::python::placement_from;
using lfprobe::python::sources_from;
using lfprobe::python::storage_dict;
using lfprobe::python::storage_from;

namespace {

using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;
using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

// A read-write (n, 3) float32 view of a vector of glm::vec3 that keeps `owner` alive.
py::array vec3_view(std::vector<glm::vec3>& v, const py::object& owner) {
    return py::array_t<float>({static_cast<py::ssize_t>(v.size()), py::ssize_t{3}},
                              {py::ssize_t{sizeof(glm::vec3)}, py::ssize_t{sizeof(float)}},
                              v.empty() ? nullptr : &v[0].x, owner);
}

template <class T>
py::array vector_view(std::vector<T>& v, const py::object& owner) {
    return py::array_t<T>({static_cast<py::ssize_t>(v.size())}, {py::ssize_t{sizeof(T)}},
                          v.empty() ? nullptr : v.data(), owner);
}

std::vector<glm::vec3> vec3_from(const FloatArray& a, const char* what, py::ssize_t rows) {
    if (a.ndim() != 2 || a.shape(1) != 3 || (rows >= 0 && a.shape(0) != rows)) {
        throw InputError(std::string(what) + ": expected an array of shape (" +
                         (rows >= 0 ? std::to_string(rows) : std::string("n")) + ", 3)");
    }
    std::vector<glm::vec3> out(static_cast<std::size_t>(a.shape(0)));
    if (!out.empty()) {
        std::memcpy(&out[0].x, a.data(), out.size() * sizeof(glm::vec3));
    }
    return out;
}

// The bindings' arguments as the core's options.
PointCloud load_scan_files(const std::vector<std::string>& paths,
                           const std::vector<std::vector<double>>& scanners,
                           const std::optional<std::vector<double>>& world_offset,
                           const std::string& columns, const std::string& cache_dir,
                           Progress& progress) {
    ScanReadOptions options;
    options.columns = columns;
    MergeOptions merge;
    for (const auto& s : scanners) {
        merge.scanners.push_back(dvec3_from(s, "scanner"));
    }
    if (world_offset) {
        merge.world_offset = dvec3_from(*world_offset, "world_offset");
        merge.force_world_offset = true;
    }
    return load_scans(paths, options, merge, cache_dir, &progress);
}

struct BakeRequest {
    std::string folder;
    int resolution = 512;
    std::vector<std::vector<double>> positions;
    std::optional<std::vector<double>> grid_min;
    std::optional<std::vector<double>> grid_max;
    std::optional<std::vector<int>> counts;
    bool positions_in_world = true;
    std::string sources_json = "[]";
    BakeSettings settings;
    LocalGeometryOptions geometry;
    std::string cache_dir; // the prepared-cloud cache; empty: none
};

std::unique_ptr<Job> start_bake(std::shared_ptr<PointCloud> cloud, BakeRequest request) {
    const ProbePlacement placement =
        placement_from(request.positions, request.grid_min, request.grid_max, request.counts,
                       request.positions_in_world ? cloud->world_offset : glm::dvec3(0.0));
    const nlohmann::json sources = sources_from(request.sources_json);
    return std::make_unique<Job>(
        std::function<BakeSummary(Progress&)>([cloud, request, placement,
                                               sources](Progress& progress) {
            return bake_probe_set_from_cloud(*cloud, placement, request.settings, request.geometry,
                                             request.folder, sources, &progress, request.cache_dir);
        }),
        std::function<py::object(BakeSummary &&)>(
            [](BakeSummary&& s) -> py::object { return bake_summary_dict(s, true); }));
}

std::unique_ptr<Job> start_load(std::vector<std::string> paths,
                                std::vector<std::vector<double>> scanners,
                                std::optional<std::vector<double>> world_offset,
                                std::string columns, std::string cache_dir) {
    return std::make_unique<Job>(std::function<PointCloud(Progress&)>([=](Progress& progress) {
                                     return load_scan_files(paths, scanners, world_offset, columns,
                                                            cache_dir, progress);
                                 }),
                                 std::function<py::object(PointCloud &&)>([](PointCloud&& c) {
                                     return py::cast(std::make_shared<PointCloud>(std::move(c)));
                                 }));
}

BakeRequest make_request(const std::string& folder, int resolution,
                         std::vector<std::vector<double>> positions,
                         std::optional<std::vector<double>> grid_min,
                         std::optional<std::vector<double>> grid_max,
                         std::optional<std::vector<int>> counts, bool positions_in_world,
                         const std::string& sources_json, float splat_scale, int hole_fill_texels,
                         int max_splat_radius_texels, int normal_neighbours, float lod_texels,
                         float splat_edge_margin, float splat_core_scale,
                         float lod_colour_tolerance, const std::string& cache_dir) {
    BakeRequest r;
    r.cache_dir = cache_dir;
    r.folder = folder;
    r.resolution = resolution;
    r.positions = std::move(positions);
    r.grid_min = std::move(grid_min);
    r.grid_max = std::move(grid_max);
    r.counts = std::move(counts);
    r.positions_in_world = positions_in_world;
    r.sources_json = sources_json;
    r.settings.resolution = resolution;
    r.settings.splat_scale = splat_scale;
    r.settings.hole_fill_texels = hole_fill_texels;
    r.settings.max_splat_radius_texels = max_splat_radius_texels;
    r.settings.lod_texels = lod_texels;
    r.settings.splat_edge_margin = splat_edge_margin;
    r.settings.splat_core_scale = splat_core_scale;
    r.settings.lod_colour_tolerance = lod_colour_tolerance;
    r.geometry.normal_neighbours = normal_neighbours;
    return r;
}

py::dict probe_dict(ProbeMap&& map) {
    const auto n = static_cast<py::ssize_t>(map.resolution);
    py::array_t<float> rgba({n, n, py::ssize_t{4}});
    py::array_t<float> distance({n, n});
    py::array_t<float> normal({n, n, py::ssize_t{3}});
    py::array_t<std::uint8_t> state({n, n});
    float* prgba = rgba.mutable_data();
    float* pnormal = normal.mutable_data();
    std::uint8_t* pstate = state.mutable_data();
    for (std::size_t i = 0; i < map.rgba.size(); ++i) {
        prgba[i] = static_cast<float>(map.rgba[i]);
    }
    for (std::size_t i = 0; i < map.normal.size(); ++i) {
        pnormal[i] = static_cast<float>(map.normal[i]);
    }
    std::memcpy(distance.mutable_data(), map.distance.data(), map.distance.size() * sizeof(float));
    for (std::size_t i = 0; i < map.texel_count(); ++i) {
        pstate[i] = static_cast<std::uint8_t>(map.state(i));
    }
    py::dict d;
    d["resolution"] = map.resolution;
    d["position"] = py::make_tuple(map.position.x, map.position.y, map.position.z);
    d["rgba"] = rgba;
    d["distance"] = distance;
    d["normal"] = normal;
    d["state"] = state;
    d["coverage"] = coverage_dict(coverage_of(map));
    d["memory_bytes"] = map.memory_bytes();
    return d;
}

// A float setting as the decimal it was written as (0.8f as 0.8, not 0.800000011920929): the
// shortest decimal that reads back as the same float.
double as_written(float value) {
    std::array<char, 32> text{};
    const auto end = std::to_chars(text.data(), text.data() + text.size(), value).ptr;
    return std::stod(std::string(text.data(), end));
}

// The defaults of the core's settings, the one place the CLI, the add-on's properties and the
// report read them from.
py::dict defaults_dict() {
    const RenderSettings render;
    const BakeSettings bake;
    py::dict trace;
    trace["mode"] = field_mode_name(render.trace.mode);
    trace["thickness"] = render.trace.probe.thickness;
    trace["fallback_thickness"] = render.trace.probe.fallback_thickness;
    trace["use_coarse_levels"] = render.trace.probe.use_coarse_levels;
    trace["max_probes"] = render.trace.max_probes;
    trace["max_probes_per_ray"] = render.trace.max_probes_per_ray;
    trace["filter"] = radiance_filter_name(render.trace.filter);
    trace["blend"] = render.trace.blend;
    trace["spp"] = render.samples_per_pixel;
    trace["tile_size"] = render.tile_size;
    trace["hole_fill"] = render.hole_fill_pixels;
    trace["prefer_measured"] = render.trace.prefer_measured;
    py::dict baking;
    baking["resolution"] = bake.resolution;
    baking["splat_scale"] = as_written(bake.splat_scale);
    baking["hole_fill_texels"] = bake.hole_fill_texels;
    baking["max_splat_radius_texels"] = bake.max_splat_radius_texels;
    baking["normal_neighbours"] = LocalGeometryOptions{}.normal_neighbours;
    baking["lod_texels"] = as_written(bake.lod_texels);
    baking["splat_edge_margin"] = as_written(bake.splat_edge_margin);
    baking["splat_core_scale"] = as_written(bake.splat_core_scale);
    baking["lod_colour_tolerance"] = as_written(bake.lod_colour_tolerance);
    baking["supersample"] = MeshBakeSettings{}.supersample;
    py::dict storage;
    storage["distance_step"] = kDefaultDistanceStep;
    py::dict d;
    d["trace"] = trace;
    d["bake"] = baking;
    d["storage"] = storage;
    return d;
}

} // namespace

PYBIND11_MODULE(_native, m) {
    m.doc() = "lfprobe native core: scan import, probe baking, probe sets";
    m.attr("__version__") = LFPROBE_VERSION;
    m.attr("PROBE_SET_FORMAT_VERSION") = kProbeSetFormatVersion;
    m.attr("DEFAULTS") = defaults_dict();

    static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
    static py::exception<IoError> io_error(m, "NativeIOError", PyExc_OSError);
    static py::exception<Cancelled> cancelled(m, "Cancelled", PyExc_Exception);
    // A missing input file is both a native I/O error and Python's FileNotFoundError, so that
    // code catching either sees it (and the command line exits 2, as for other bad input).
    static py::object missing_file = [&] {
        py::object bases = py::make_tuple(io_error, py::handle(PyExc_FileNotFoundError));
        py::object type = py::reinterpret_steal<py::object>(
            PyErr_NewException("lfprobe._native.MissingFileError", bases.ptr(), nullptr));
        if (!type) {
            throw py::error_already_set();
        }
        m.attr("MissingFileError") = type;
        return type;
    }();
    // Messages quote what the input held, which need not be UTF-8 (a camera file's bytes):
    // such bytes come through as \xNN escapes instead of losing the whole message.
    py::register_exception_translator([](std::exception_ptr p) {
        const auto raise = [](const py::handle type, const char* what) {
            PyObject* message = PyUnicode_DecodeUTF8(
                what, static_cast<Py_ssize_t>(std::strlen(what)), "backslashreplace");
            PyErr_SetObject(type.ptr(), message);
            Py_XDECREF(message);
        };
        try {
            if (p) {
                std::rethrow_exception(p);
            }
        } catch (const InputError& e) {
            raise(input_error, e.what());
        } catch (const MissingFileError& e) {
            raise(missing_file, e.what());
        } catch (const IoError& e) {
            raise(io_error, e.what());
        } catch (const Cancelled& e) {
            raise(cancelled, e.what());
        }
    });

    py::enum_<TexelState>(m, "TexelState")
        .value("UNKNOWN", TexelState::Unknown)
        .value("EMPTY", TexelState::Empty)
        .value("SURFACE", TexelState::Surface)
        .value("INFERRED", TexelState::Inferred);

    m.def(
        "oct_encode",
        [](const FloatArray& dirs) {
            const std::vector<glm::vec3> d = vec3_from(dirs, "oct_encode", -1);
            py::array_t<float> uv({static_cast<py::ssize_t>(d.size()), py::ssize_t{2}});
            float* out = uv.mutable_data();
            for (std::size_t i = 0; i < d.size(); ++i) {
                const glm::vec2 e = oct::encode_checked(d[i]);
                out[2 * i] = e.x;
                out[2 * i + 1] = e.y;
            }
            return uv;
        },
        py::arg("directions"), "Octahedral map coordinates uv in [0,1]² of (n, 3) directions.");
    m.def(
        "oct_decode",
        [](const py::array_t<float, py::array::c_style | py::array::forcecast>& uv) {
            if (uv.ndim() != 2 || uv.shape(1) != 2) {
                throw InputError("oct_decode: expected an array of shape (n, 2)");
            }
            const auto n = uv.shape(0);
            py::array_t<float> dirs({n, py::ssize_t{3}});
            const float* in = uv.data();
            float* out = dirs.mutable_data();
            for (py::ssize_t i = 0; i < n; ++i) {
                const glm::vec3 d = oct::decode({in[2 * i], in[2 * i + 1]});
                out[3 * i] = d.x;
                out[3 * i + 1] = d.y;
                out[3 * i + 2] = d.z;
            }
            return dirs;
        },
        py::arg("uv"), "Unit directions of (n, 2) octahedral map coordinates.");

    py::class_<PointCloud, std::shared_ptr<PointCloud>>(m, "PointCloud")
        .def("__len__", &PointCloud::size)
        .def_property_readonly(
            "positions",
            [](py::object self) { return vec3_view(self.cast<PointCloud&>().positions, self); })
        .def_property_readonly("colors",
                               [](py::object self) -> py::object {
                                   auto& c = self.cast<PointCloud&>();
                                   return c.has_colors() ? py::object(vec3_view(c.colors, self))
                                                         : py::none();
                               })
        .def_property_readonly("normals",
                               [](py::object self) -> py::object {
                                   auto& c = self.cast<PointCloud&>();
                                   return c.has_normals() ? py::object(vec3_view(c.normals, self))
                                                          : py::none();
                               })
        .def_property_readonly("intensities",
                               [](py::object self) -> py::object {
                                   auto& c = self.cast<PointCloud&>();
                                   return c.intensities.empty()
                                              ? py::none()
                                              : py::object(vector_view(c.intensities, self));
                               })
        .def_property_readonly(
            "scan_index",
            [](py::object self) { return vector_view(self.cast<PointCloud&>().scan_index, self); })
        .def_property_readonly("world_offset",
                               [](const PointCloud& c) {
                                   return py::make_tuple(c.world_offset.x, c.world_offset.y,
                                                         c.world_offset.z);
                               })
        .def_property_readonly(
            "scans",
            [](const PointCloud& c) {
                py::list out;
                for (const ScanSource& s : c.scans) {
                    py::dict d;
                    d["path"] = s.path;
                    d["points"] = s.point_count;
                    d["scanner"] =
                        s.has_scanner
                            ? py::object(py::make_tuple(s.scanner.x, s.scanner.y, s.scanner.z))
                            : py::object(py::none());
                    out.append(d);
                }
                return out;
            },
            "One dict per scan: path, points, scanner (local frame) or None.")
        .def_static(
            "from_arrays",
            [](const FloatArray& positions, std::optional<FloatArray> colors,
               std::optional<FloatArray> normals,
               std::optional<py::array_t<std::uint32_t, py::array::c_style | py::array::forcecast>>
                   scan_index,
               const std::vector<std::optional<std::vector<double>>>& scanners,
               const std::vector<double>& world_offset,
               std::optional<py::array_t<float, py::array::c_style | py::array::forcecast>>
                   intensities,
               const std::vector<std::string>& scan_paths) {
                const std::vector<glm::vec3> points = vec3_from(positions, "positions", -1);
                const auto n = static_cast<py::ssize_t>(points.size());
                std::vector<std::uint32_t> scans;
                if (scan_index) {
                    if (scan_index->ndim() != 1 || scan_index->shape(0) != n) {
                        throw InputError("scan_index: expected shape (n,)");
                    }
                    scans.assign(scan_index->data(), scan_index->data() + n);
                }
                std::vector<float> intensity;
                if (intensities) {
                    if (intensities->ndim() != 1 || intensities->shape(0) != n) {
                        throw InputError("intensities: expected shape (n,)");
                    }
                    intensity.assign(intensities->data(), intensities->data() + n);
                }
                std::vector<std::optional<glm::dvec3>> scanner_positions;
                for (const auto& s : scanners) {
                    scanner_positions.push_back(s ? std::optional(dvec3_from(*s, "scanner"))
                                                  : std::nullopt);
                }
                auto cloud = std::make_shared<PointCloud>(cloud_from_parts(
                    points, colors ? vec3_from(*colors, "colors", n) : std::vector<glm::vec3>{},
                    normals ? vec3_from(*normals, "normals", n) : std::vector<glm::vec3>{},
                    std::move(scans), scanner_positions, dvec3_from(world_offset, "world_offset"),
                    std::move(intensity), scan_paths));
                return cloud;
            },
            py::arg("positions"), py::arg("colors") = py::none(), py::arg("normals") = py::none(),
            py::arg("scan_index") = py::none(),
            py::arg("scanners") = std::vector<std::optional<std::vector<double>>>{},
            py::arg("world_offset") = std::vector<double>{0.0, 0.0, 0.0},
            py::arg("intensities") = py::none(), py::arg("scan_paths") = std::vector<std::string>{},
            "A cloud from arrays in the local frame: positions (n,3) float32, linear colours, "
            "normals, scan index per point; scanners: one (x,y,z) or None per scan, local frame; "
            "intensities (n,) as the scanner stored them; scan_paths: one file per scan.");

    py::class_<Job>(m, "Job", "Native work running off the Python thread.")
        .def_property_readonly("fraction", [](const Job& j) { return j.progress().fraction(); })
        .def_property_readonly("stage", [](const Job& j) { return j.progress().stage(); })
        .def_property_readonly("done", &Job::done)
        .def("cancel", &Job::cancel, "Ask the work to stop; result() then raises Cancelled.")
        .def("wait", &Job::wait, py::arg("seconds") = -1.0,
             "Wait (GIL released) up to `seconds` (forever when negative); True when done.")
        .def("result", &Job::result, "The result, or the native error as an exception.")
        .def("run", &Job::run, py::arg("callback") = py::none(),
             "Run to the end, calling callback(fraction, stage) every 0.1 s; returning False "
             "from it cancels.");

    m.def(
        "scan_cache_entry_path",
        [](const std::string& path, const std::string& columns, const std::string& cache_dir) {
            ScanReadOptions options;
            options.columns = columns;
            return scan_cache_entry_path(path, options, cache_dir);
        },
        py::arg("path"), py::arg("columns") = "", py::arg("cache_dir") = "",
        "The parse cache's entry for a scan file in cache_dir (it may not exist yet); empty "
        "where the cache does not apply.");
    m.attr("LfprobeWarning") = py::handle(lfprobe::python::lfprobe_warning_type());
    m.def("start_load_scans", &start_load, py::arg("paths"),
          py::arg("scanners") = std::vector<std::vector<double>>{},
          py::arg("world_offset") = py::none(), py::arg("columns") = "", py::arg("cache_dir") = "",
          "Start reading and merging scan files; the Job's result is a PointCloud. scanners are "
          "world coordinates, one per file.");
    m.def(
        "load_scans",
        [](std::vector<std::string> paths, std::vector<std::vector<double>> scanners,
           std::optional<std::vector<double>> world_offset, std::string columns,
           std::string cache_dir, const py::object& progress) {
            auto job = start_load(std::move(paths), std::move(scanners), std::move(world_offset),
                                  std::move(columns), std::move(cache_dir));
            return job->run(progress);
        },
        py::arg("paths"), py::arg("scanners") = std::vector<std::vector<double>>{},
        py::arg("world_offset") = py::none(), py::arg("columns") = "", py::arg("cache_dir") = "",
        py::arg("progress") = py::none(), "load_scans run to the end; see start_load_scans.");

    auto start_bake_fn =
        [](std::shared_ptr<PointCloud> cloud, const std::string& folder, int resolution,
           std::vector<std::vector<double>> positions, std::optional<std::vector<double>> grid_min,
           std::optional<std::vector<double>> grid_max, std::optional<std::vector<int>> counts,
           bool positions_in_world, const std::string& sources_json, float splat_scale,
           int hole_fill_texels, int max_splat_radius_texels, int normal_neighbours,
           float lod_texels, float splat_edge_margin, float splat_core_scale,
           float lod_colour_tolerance, const std::string& cache_dir) {
            return start_bake(std::move(cloud),
                              make_request(folder, resolution, std::move(positions),
                                           std::move(grid_min), std::move(grid_max),
                                           std::move(counts), positions_in_world, sources_json,
                                           splat_scale, hole_fill_texels, max_splat_radius_texels,
                                           normal_neighbours, lod_texels, splat_edge_margin,
                                           splat_core_scale, lod_colour_tolerance, cache_dir));
        };
    const BakeSettings defaults;
    const LocalGeometryOptions geometry_defaults;
    m.def("start_bake_probe_set", start_bake_fn, py::arg("cloud"), py::arg("folder"),
          py::arg("resolution") = defaults.resolution,
          py::arg("positions") = std::vector<std::vector<double>>{},
          py::arg("grid_min") = py::none(), py::arg("grid_max") = py::none(),
          py::arg("counts") = py::none(), py::arg("positions_in_world") = true,
          py::arg("sources_json") = "[]", py::arg("splat_scale") = defaults.splat_scale,
          py::arg("hole_fill_texels") = defaults.hole_fill_texels,
          py::arg("max_splat_radius_texels") = defaults.max_splat_radius_texels,
          py::arg("normal_neighbours") = geometry_defaults.normal_neighbours,
          py::arg("lod_texels") = defaults.lod_texels,
          py::arg("splat_edge_margin") = defaults.splat_edge_margin,
          py::arg("splat_core_scale") = defaults.splat_core_scale,
          py::arg("lod_colour_tolerance") = defaults.lod_colour_tolerance,
          py::arg("cache_dir") = "",
          "Start baking a probe set from a cloud into `folder`; positions or grid corners are "
          "world coordinates unless positions_in_world is False. lod_texels: how many texels "
          "apart the point hierarchy's cell surfels may be where they stand in for points (0: "
          "every point). lod_colour_tolerance: above 0, a cell up to twice as wide also stands in "
          "where "
          "its children's colours agree with its own within this much per channel (linear). "
          "cache_dir: the cloud's normals, spacing and point hierarchy are read "
          "from this folder's prepared-cloud cache when it holds them, and written there "
          "otherwise (empty: computed, not cached). The Job's result is a summary dict.");
    m.def(
        "bake_probe_set",
        [start_bake_fn](
            std::shared_ptr<PointCloud> cloud, const std::string& folder, int resolution,
            std::vector<std::vector<double>> positions, std::optional<std::vector<double>> grid_min,
            std::optional<std::vector<double>> grid_max, std::optional<std::vector<int>> counts,
            bool positions_in_world, const std::string& sources_json, float splat_scale,
            int hole_fill_texels, int max_splat_radius_texels, int normal_neighbours,
            float lod_texels, float splat_edge_margin, float splat_core_scale,
            float lod_colour_tolerance, const std::string& cache_dir, const py::object& progress) {
            auto job = start_bake_fn(
                std::move(cloud), folder, resolution, std::move(positions), std::move(grid_min),
                std::move(grid_max), std::move(counts), positions_in_world, sources_json,
                splat_scale, hole_fill_texels, max_splat_radius_texels, normal_neighbours,
                lod_texels, splat_edge_margin, splat_core_scale, lod_colour_tolerance, cache_dir);
            return job->run(progress);
        },
        py::arg("cloud"), py::arg("folder"), py::arg("resolution") = defaults.resolution,
        py::arg("positions") = std::vector<std::vector<double>>{}, py::arg("grid_min") = py::none(),
        py::arg("grid_max") = py::none(), py::arg("counts") = py::none(),
        py::arg("positions_in_world") = true, py::arg("sources_json") = "[]",
        py::arg("splat_scale") = defaults.splat_scale,
        py::arg("hole_fill_texels") = defaults.hole_fill_texels,
        py::arg("max_splat_radius_texels") = defaults.max_splat_radius_texels,
        py::arg("normal_neighbours") = geometry_defaults.normal_neighbours,
        py::arg("lod_texels") = defaults.lod_texels,
        py::arg("splat_edge_margin") = defaults.splat_edge_margin,
        py::arg("splat_core_scale") = defaults.splat_core_scale,
        py::arg("lod_colour_tolerance") = defaults.lod_colour_tolerance, py::arg("cache_dir") = "",
        py::arg("progress") = py::none(), "bake run to the end; see start_bake_probe_set.");

    lfprobe::python::bind_render(m);
    lfprobe::python::bind_mesh(m);
    lfprobe::python::bind_plan(m);
    lfprobe::python::bind_staged_bake(m);
    lfprobe::python::bind_cloud_geometry(m);

    m.def(
        "append_known_space",
        [](const std::string& set_folder, const std::string& probe_folder, std::size_t index) {
            return append_known_space(set_folder, probe_folder, index);
        },
        py::arg("set_folder"), py::arg("probe_folder"), py::arg("index"),
        "Adds the known space of the one-probe set in probe_folder to the set in set_folder as "
        "its probe `index` (a set grown a probe at a time). False, with the set's known space "
        "removed, where either has none: drop the manifest's \"known_space\" then.");
    m.def(
        "set_probe_set_storage",
        [](const std::string& folder, const py::object& storage, double distance_step) {
            const std::optional<ProbeStorage> chosen = storage_from(storage, distance_step);
            if (!chosen.has_value()) {
                throw InputError("set_probe_set_storage: give \"full\", \"compact\" or a dict");
            }
            const ProbeSetManifest manifest = set_probe_set_storage(folder, *chosen);
            return storage_dict(manifest.storage);
        },
        py::arg("folder"), py::arg("storage"), py::arg("distance_step") = 0.0,
        "Sets how the set's probes load into memory (its manifest's \"storage\"; the EXR files "
        "keep full precision) and the manifest's per-probe memory_bytes.");
    m.def(
        "check_probe_set_manifest",
        [](const std::string& folder) { return read_manifest(folder).to_json().dump(); },
        py::arg("folder"),
        "Reads the set's manifest.json as a render does, refusing what a render would refuse "
        "(format version, probe file names, counts, resolutions, types); returns it as JSON "
        "text.");
    m.def(
        "probe_storage",
        [](const py::object& storage, double distance_step) {
            const std::optional<ProbeStorage> chosen = storage_from(storage, distance_step);
            if (!chosen.has_value()) {
                throw InputError("probe_storage: give \"full\", \"compact\" or a dict");
            }
            return storage_dict(*chosen);
        },
        py::arg("storage"), py::arg("distance_step") = 0.0,
        "A storage (\"full\", \"compact\" with distance_step) as a manifest records it, with "
        "bytes_per_texel: what a probe of N² texels takes in memory is N² times that.");
    m.def(
        "read_probe", [](const std::string& path) { return probe_dict(read_probe_exr(path)); },
        py::arg("path"),
        "One probe EXR as arrays: rgba (n,n,4), distance (n,n), normal (n,n,3), state (n,n) "
        "uint8 TexelState values, plus resolution, position, coverage, memory_bytes.");
    m.def(
        "coarse_min_distance",
        [](const py::array_t<float, py::array::c_style | py::array::forcecast>& distance,
           int coarsest) {
            if (distance.ndim() != 2 || distance.shape(0) != distance.shape(1)) {
                throw InputError("coarse_min_distance: expected a square (n, n) array");
            }
            const int n = static_cast<int>(distance.shape(0));
            const std::vector<float> fine(distance.data(),
                                          distance.data() + static_cast<std::size_t>(n) * n);
            const MinDistancePyramid pyramid(fine, n, coarsest);
            py::list levels;
            for (const MinDistanceLevel& level : pyramid.levels()) {
                const auto r = static_cast<py::ssize_t>(level.resolution);
                py::array_t<float> a({r, r});
                std::memcpy(a.mutable_data(), level.min_distance.data(),
                            level.min_distance.size() * sizeof(float));
                levels.append(a);
            }
            return levels;
        },
        py::arg("distance"), py::arg("coarsest") = 1,
        "The min-distance levels of a distance map, finest first.");
}
