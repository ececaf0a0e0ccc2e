// Bindings of the renderer: probe-traced views, the splat baseline, rendered images.
#include <cstdint>
#include <cstring>
#include <memory>
#include <optional>
#include <string>

#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <tbb/task_arena.h>

#include "binding_helpers.hpp"
#include "bindings.hpp"
#include "job.hpp"
#include "lfprobe/camera.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/image_exr.hpp"
#include "lfprobe/image_files.hpp"
#include "lfprobe/probe_field.hpp"
#include "lfprobe/render.hpp"
#include "lfprobe/splat_render.hpp"

namespace py = pybind11;

namespace lfprobe::python {

namespace {

py::dict render_stats_dict(const RenderStats& s) {
    py::dict d;
    d["rays"] = s.rays;
    d["hits"] = s.hits;
    d["misses"] = s.misses;
    d["unknown"] = s.unknown;
    d["steps"] = s.steps;
    d["probes_tried"] = s.probes_tried;
    d["holes_filled"] = s.holes_filled;
    d["holes_left"] = s.holes_left;
    d["guessed"] = s.guessed;
    d["seconds"] = s.seconds;
    d["rays_per_second"] = s.rays_per_second();
    d["mean_steps"] = s.mean_steps();
    d["mean_probes"] = s.mean_probes();
    return d;
}

py::dict splat_stats_dict(const SplatStats& s, double geometry_seconds) {
    py::dict d;
    d["points"] = s.points;
    d["drawn"] = s.drawn;
    d["fragments"] = s.fragments;
    d["covered"] = s.covered;
    d["seconds"] = s.seconds;
    d["points_per_second"] = s.points_per_second();
    d["geometry_seconds"] = geometry_seconds;
    return d;
}

// The image's sampling and colour: samples per pixel, radiance filter, probes blended.
struct Fidelity {
    int spp = RenderSettings{}.samples_per_pixel;
    std::string filter = radiance_filter_name(FieldTraceSettings{}.filter);
    int blend = FieldTraceSettings{}.blend;
    int hole_fill = RenderSettings{}.hole_fill_pixels;
    bool prefer_measured = FieldTraceSettings{}.prefer_measured;
};

RenderSettings render_settings(const std::string& mode, double thickness, bool use_coarse_levels,
                               int tile_size, const Fidelity& fidelity = {},
                               double fallback_thickness = TraceSettings{}.fallback_thickness,
                               int max_probes_per_ray = FieldTraceSettings{}.max_probes_per_ray,
                               bool stop_where_no_probe_can_answer = true) {
    RenderSettings settings;
    settings.trace.stop_where_no_probe_can_answer = stop_where_no_probe_can_answer;
    settings.trace.max_probes_per_ray = max_probes_per_ray;
    settings.trace.mode = field_mode_from_name(mode);
    settings.trace.probe.thickness = thickness;
    settings.trace.probe.fallback_thickness = fallback_thickness;
    settings.trace.probe.use_coarse_levels = use_coarse_levels;
    settings.tile_size = tile_size;
    settings.samples_per_pixel = fidelity.spp;
    settings.trace.filter = radiance_filter_from_name(fidelity.filter);
    settings.trace.blend = fidelity.blend;
    settings.hole_fill_pixels = fidelity.hole_fill;
    settings.trace.prefer_measured = fidelity.prefer_measured;
    return settings;
}

py::dict image_dict(RenderedImage&& image, const std::string& metadata) {
    const auto h = static_cast<py::ssize_t>(image.height);
    const auto w = static_cast<py::ssize_t>(image.width);
    auto copy = [](auto& v, std::vector<py::ssize_t> shape) {
        using T = typename std::decay_t<decltype(v)>::value_type;
        py::array_t<T> a(shape);
        std::memcpy(a.mutable_data(), v.data(), v.size() * sizeof(T));
        return a;
    };
    py::dict d;
    d["width"] = image.width;
    d["height"] = image.height;
    d["rgba"] = copy(image.rgba, {h, w, 4});
    d["depth"] = copy(image.depth, {h, w});
    d["normal"] = copy(image.normal, {h, w, 3});
    d["status"] = copy(image.status, {h, w});
    d["probe"] = copy(image.probe, {h, w});
    d["steps"] = copy(image.steps, {h, w});
    if (!image.guessed.empty()) {
        d["guessed"] = copy(image.guessed, {h, w});
    }
    d["metadata"] = metadata;
    return d;
}

} // namespace

void bind_render(py::module_& m) {
    py::enum_<TraceStatus>(m, "TraceStatus")
        .value("MISS", TraceStatus::Miss)
        .value("HIT", TraceStatus::Hit)
        .value("UNKNOWN", TraceStatus::Unknown);

    py::class_<ProbeField, std::shared_ptr<ProbeField>>(
        m, "ProbeField", "A loaded probe set: maps and coarse levels, ready to trace.")
        .def_static(
            "load",
            [](const std::string& folder, int coarse_resolution, const py::object& storage,
               double distance_step, bool lazy) {
                const std::optional<ProbeStorage> chosen = storage_from(storage, distance_step);
                py::gil_scoped_release release;
                return std::make_shared<ProbeField>(
                    ProbeField::load(folder, nullptr, coarse_resolution, chosen, lazy));
            },
            py::arg("folder"), py::arg("coarse_resolution") = 0, py::arg("storage") = py::none(),
            py::arg("distance_step") = 0.0, py::arg("lazy") = false,
            "Load a probe set; coarse_resolution is the size of the coarsest min-distance level "
            "kept (0: every level down to 1x1). storage: how the probes are held in memory: "
            "None (as the manifest says), \"full\", \"compact\" (8-bit sRGB radiance, 16-bit "
            "distance in steps of distance_step metres, default 1 mm, 8+8-bit octahedral normals, "
            "no confidence) or a dict like the manifest's \"storage\". lazy: read only the "
            "manifest now (and check every probe file is there); each probe's maps are decoded "
            "the first time a trace reaches it.")
        .def_property_readonly("storage",
                               [](const ProbeField& f) { return storage_dict(f.storage()); })
        .def_property_readonly("probe_count", &ProbeField::probe_count)
        .def_property_readonly("loaded_probe_count", &ProbeField::loaded_probe_count,
                               "Probes whose maps are in memory (fewer while a lazily opened "
                               "set has not been traced everywhere).")
        .def_property_readonly("is_grid", &ProbeField::is_grid)
        .def_property_readonly("memory_bytes", &ProbeField::memory_bytes)
        .def_property_readonly("world_offset",
                               [](const ProbeField& f) {
                                   const glm::dvec3 o = f.world_offset();
                                   return py::make_tuple(o.x, o.y, o.z);
                               })
        .def(
            "trace_throughput",
            [](std::shared_ptr<ProbeField> field, const std::string& camera,
               const std::string& mode, int threads, int repeats, const std::string& start,
               const std::string& colour) {
                const Camera cam = camera_from(camera);
                if (start != "camera" && start != "answer") {
                    throw InputError(
                        "trace_throughput: start must be \"camera\" or \"answer\", got \"" + start +
                        "\"");
                }
                if (colour != "default" && colour != "texel") {
                    throw InputError(
                        "trace_throughput: colour must be \"default\" or \"texel\", got \"" +
                        colour + "\"");
                }
                // "texel": the answering texel's colour alone (nearest, no blending), the
                // colour a lookup gives and the paper's trace returns: a render's answers with
                // filter "nearest" and blend 1 (the filters' edge refinement left out too).
                Fidelity fidelity;
                if (colour == "texel") {
                    fidelity.filter = radiance_filter_name(RadianceFilter::Nearest);
                    fidelity.blend = 1;
                }
                const RenderSettings settings =
                    render_settings(mode, TraceSettings{}.thickness, true, 32, fidelity);
                const ThroughputStart from =
                    start == "answer" ? ThroughputStart::Answer : ThroughputStart::Camera;
                ThroughputResult r;
                {
                    py::gil_scoped_release release;
                    r = on_threads(threads, [&] {
                        return probe_trace_throughput(*field, cam, settings, repeats, from);
                    });
                }
                return throughput_dict(r);
            },
            py::arg("camera"), py::arg("mode") = "auto", py::arg("threads") = 0,
            py::arg("repeats") = 3, py::arg("start") = "camera", py::arg("colour") = "default",
            "Probe-trace rays per second measured as embree_throughput measures Embree's: the "
            "camera's pixel-centre rays made beforehand, trace only, fastest of `repeats`. "
            "start=\"answer\": each ray starts where its own trace from the camera ended (its "
            "HIT, or as far as an UNKNOWN proved it free), so that no empty space is left to "
            "skip: the cost of a trace however little it walks. colour=\"default\": each HIT "
            "coloured as a render colours it (bilinear, blended over the probes that see the "
            "point); \"texel\": the answering texel's colour alone, as a lookup gives it (a "
            "render's answers with filter=\"nearest\", blend=1), without the colour's further "
            "lookups.")
        .def(
            "start_render",
            [](std::shared_ptr<ProbeField> field, const std::string& camera,
               const std::string& mode, int threads, double thickness, bool use_coarse_levels,
               int tile_size, int spp, const std::string& filter, int blend,
               double fallback_thickness, int max_probes_per_ray,
               bool stop_where_no_probe_can_answer, int hole_fill, bool prefer_measured) {
                const Camera cam = camera_from(camera);
                const RenderSettings settings = render_settings(
                    mode, thickness, use_coarse_levels, tile_size,
                    {spp, filter, blend, hole_fill, prefer_measured}, fallback_thickness,
                    max_probes_per_ray, stop_where_no_probe_can_answer);
                using Result = std::pair<RenderedImage, RenderStats>;
                return std::make_unique<Job>(
                    std::function<Result(Progress&)>([=](Progress& progress) {
                        return on_threads(threads, [&] {
                            RenderStats stats;
                            RenderedImage image =
                                render_probe_view(*field, cam, settings, &progress, &stats);
                            return Result{std::move(image), stats};
                        });
                    }),
                    std::function<py::object(Result &&)>([](Result&& r) -> py::object {
                        return py::make_tuple(image_dict(std::move(r.first), ""),
                                              render_stats_dict(r.second));
                    }));
            },
            py::arg("camera"), py::arg("mode") = "auto", py::arg("threads") = 0,
            py::arg("thickness") = TraceSettings{}.thickness, py::arg("use_coarse_levels") = true,
            py::arg("tile_size") = RenderSettings{}.tile_size, py::arg("spp") = Fidelity{}.spp,
            py::arg("filter") = Fidelity{}.filter, py::arg("blend") = Fidelity{}.blend,
            py::arg("fallback_thickness") = TraceSettings{}.fallback_thickness,
            py::arg("max_probes_per_ray") = FieldTraceSettings{}.max_probes_per_ray,
            py::arg("stop_where_no_probe_can_answer") = true,
            py::arg("hole_fill") = Fidelity{}.hole_fill,
            py::arg("prefer_measured") = Fidelity{}.prefer_measured,
            "Start tracing a view in the background (the Blender engine's F12): a Job with "
            "progress in pixels, cancel(), and result() = (image dict, stats dict) as render() "
            "returns.")
        .def(
            "render",
            [](std::shared_ptr<ProbeField> field, const std::string& camera,
               const std::string& output, const std::string& mode, int threads, double thickness,
               bool use_coarse_levels, int tile_size, int spp, const std::string& filter, int blend,
               double fallback_thickness, int max_probes_per_ray,
               bool stop_where_no_probe_can_answer, int hole_fill, bool prefer_measured) {
                const Camera cam = camera_from(camera);
                const RenderSettings settings = render_settings(
                    mode, thickness, use_coarse_levels, tile_size,
                    {spp, filter, blend, hole_fill, prefer_measured}, fallback_thickness,
                    max_probes_per_ray, stop_where_no_probe_can_answer);
                RenderStats stats;
                RenderedImage image;
                {
                    py::gil_scoped_release release;
                    image = on_threads(threads, [&] {
                        return render_probe_view_to_exr(*field, cam, settings, output, nullptr,
                                                        &stats);
                    });
                }
                return py::make_tuple(image_dict(std::move(image), ""), render_stats_dict(stats));
            },
            py::arg("camera"), py::arg("output") = "", py::arg("mode") = "auto",
            py::arg("threads") = 0, py::arg("thickness") = TraceSettings{}.thickness,
            py::arg("use_coarse_levels") = true, py::arg("tile_size") = RenderSettings{}.tile_size,
            py::arg("spp") = Fidelity{}.spp, py::arg("filter") = Fidelity{}.filter,
            py::arg("blend") = Fidelity{}.blend,
            py::arg("fallback_thickness") = TraceSettings{}.fallback_thickness,
            py::arg("max_probes_per_ray") = FieldTraceSettings{}.max_probes_per_ray,
            py::arg("stop_where_no_probe_can_answer") = true,
            py::arg("hole_fill") = Fidelity{}.hole_fill,
            py::arg("prefer_measured") = Fidelity{}.prefer_measured,
            "Trace a view (camera: a JSON path or text); returns (image dict, stats dict) and "
            "writes the EXR when output is given. threads=0 uses every core. spp: samples per "
            "pixel (1 or a square; colour and coverage averaged, the rest from the pixel "
            "centre); filter: \"nearest\" or \"bilinear\" (a HIT's colour from its texel or "
            "interpolated over the same surface); blend: probes a HIT's colour is blended from "
            "(1: the answering probe alone); max_probes_per_ray: at most that many probes asked "
            "about a ray (0: no bound; a bound is not exact); hole_fill: holes of UNKNOWN pixels "
            "at most that many pixels across are coloured from the HIT pixels around them, "
            "their status kept (-1: 5 % of the image's larger side; 0: off); prefer_measured: "
            "a HIT on a hole-filled texel waits for the other probes' measured answers (False: "
            "the first HIT wins, as the paper).");

    m.def(
        "start_render",
        [](const std::string& folder, const std::string& camera, const std::string& output,
           const std::string& mode, int threads, double thickness, bool use_coarse_levels,
           const py::object& storage, double distance_step, int spp, const std::string& filter,
           int blend, double fallback_thickness, int max_probes_per_ray, int hole_fill,
           bool prefer_measured) {
            const Camera cam = camera_from(camera);
            const RenderSettings settings =
                render_settings(mode, thickness, use_coarse_levels, 32,
                                {spp, filter, blend, hole_fill, prefer_measured},
                                fallback_thickness, max_probes_per_ray);
            const std::optional<ProbeStorage> chosen = storage_from(storage, distance_step);
            return std::make_unique<Job>(
                std::function<RenderStats(Progress&)>([=](Progress& progress) {
                    return on_threads(threads, [&] {
                        return render_probe_set_to_exr(folder, cam, settings, chosen, output,
                                                       &progress);
                    });
                }),
                std::function<py::object(RenderStats &&)>(
                    [](RenderStats&& s) -> py::object { return render_stats_dict(s); }));
        },
        py::arg("folder"), py::arg("camera"), py::arg("output"), py::arg("mode") = "auto",
        py::arg("threads") = 0, py::arg("thickness") = TraceSettings{}.thickness,
        py::arg("use_coarse_levels") = true, py::arg("storage") = py::none(),
        py::arg("distance_step") = 0.0, py::arg("spp") = Fidelity{}.spp,
        py::arg("filter") = Fidelity{}.filter, py::arg("blend") = Fidelity{}.blend,
        py::arg("fallback_thickness") = TraceSettings{}.fallback_thickness,
        py::arg("max_probes_per_ray") = FieldTraceSettings{}.max_probes_per_ray,
        py::arg("hole_fill") = Fidelity{}.hole_fill,
        py::arg("prefer_measured") = Fidelity{}.prefer_measured,
        "Start rendering the probe set in `folder` from `camera` (JSON path or text) into the EXR "
        "`output`; the Job's result is the stats dict. storage as for ProbeField.load.");

    m.def(
        "start_splat",
        [](std::shared_ptr<PointCloud> cloud, const std::string& camera, const std::string& output,
           double radius_scale, double fixed_radius, int threads, const std::string& cache_dir) {
            const Camera cam = camera_from(camera);
            SplatSettings settings;
            settings.radius_scale = radius_scale;
            settings.fixed_radius = fixed_radius;
            using Result = std::pair<SplatStats, double>;
            auto work = [=](Progress& progress) {
                return on_threads(threads, [&] {
                    double geometry_seconds = 0.0;
                    const SplatStats stats = splat_cloud_to_exr(
                        *cloud, cam, settings, output, &progress, &geometry_seconds, cache_dir);
                    return Result{stats, geometry_seconds};
                });
            };
            return std::make_unique<Job>(
                std::function<Result(Progress&)>(work),
                std::function<py::object(Result &&)>(
                    [](Result&& r) -> py::object { return splat_stats_dict(r.first, r.second); }));
        },
        py::arg("cloud"), py::arg("camera"), py::arg("output"), py::arg("radius_scale") = 0.8,
        py::arg("fixed_radius") = 0.0, py::arg("threads") = 0, py::arg("cache_dir") = "",
        "Start drawing the cloud as z-buffered splats (sized by the local spacing, or "
        "fixed_radius metres when > 0) into the EXR `output`; the Job's result is the stats. "
        "cache_dir: the prepared-cloud cache a bake of the cloud reads and writes; the local "
        "spacing is read from it when there, and cached there when estimated (\"\": none).");

    m.def(
        "read_image",
        [](const std::string& path) {
            std::string metadata;
            RenderedImage image;
            {
                py::gil_scoped_release release;
                image = read_rendered_exr(path, &metadata);
            }
            return image_dict(std::move(image), metadata);
        },
        py::arg("path"),
        "A rendered EXR as arrays (h, w[, c]): rgba, depth, normal, status, probe, steps; "
        "metadata is the JSON text the renderer stored.");
    m.def(
        "read_exr_channels",
        [](const std::string& path) {
            ExrChannels exr;
            {
                py::gil_scoped_release release;
                exr = read_exr_channels(path);
            }
            py::dict channels;
            for (auto& [name, values] : exr.channels) {
                py::array_t<float> a(
                    {static_cast<py::ssize_t>(exr.height), static_cast<py::ssize_t>(exr.width)});
                std::memcpy(a.mutable_data(), values.data(), values.size() * sizeof(float));
                channels[py::str(name)] = a;
            }
            return py::make_tuple(channels, py::make_tuple(exr.width, exr.height));
        },
        py::arg("path"),
        "Every channel of any OpenEXR file (any compression, scanline or tiled, every part) "
        "over its display window: ({name: (h, w) float32}, (w, h)).");
    m.def(
        "read_stored_image",
        [](const std::string& path) {
            StoredImage image;
            {
                py::gil_scoped_release release;
                image = read_stored_image(path);
            }
            py::array_t<std::uint16_t> a({static_cast<py::ssize_t>(image.height),
                                          static_cast<py::ssize_t>(image.width),
                                          static_cast<py::ssize_t>(image.channels)});
            std::memcpy(a.mutable_data(), image.values.data(),
                        image.values.size() * sizeof(std::uint16_t));
            return py::make_tuple(a, image.bits);
        },
        py::arg("path"),
        "A PNG's or JPEG's stored codes (stb_image, 8 or 16 bits): ((h, w, c) uint16, bits).");
}

} // namespace lfprobe::python
