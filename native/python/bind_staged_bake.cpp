// A cloud bake in parts (cloud_bake.hpp, probe_set_staging.hpp), for bakes whose probes other
// processes bake: core/cluster_bake.py hands them to Dask workers.
#include <algorithm>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "binding_helpers.hpp"
#include "bindings.hpp"
#include "job.hpp"
#include "lfprobe/cloud_bake.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/json_input.hpp"
#include "lfprobe/probe_set_staging.hpp"

namespace py = pybind11;

namespace lfprobe::python {

namespace {

struct CloudBakeOptions {
    BakeSettings settings;
    LocalGeometryOptions geometry;
};

// The bake settings of `bake_probe_set`, as a dict with its keyword arguments' names.
CloudBakeOptions cloud_bake_options_from(const py::dict& options) {
    CloudBakeOptions o;
    for (const auto& item : options) {
        const auto key = py::str(item.first).cast<std::string>();
        const py::handle v = item.second;
        if (set_bake_setting(o.settings, key, v)) {
            continue;
        }
        if (key == "normal_neighbours") {
            o.geometry.normal_neighbours = v.cast<int>();
        } else {
            throw InputError("bake settings: unknown setting '" + key + "' (expected " +
                             kBakeSettingNames + ", normal_neighbours)");
        }
    }
    return o;
}

py::dict staged_dict(const StagedProbe& staged) {
    py::dict d;
    d["index"] = staged.index;
    d["record"] = probe_record_json(staged.record).dump();
    d["bytes_on_disk"] = staged.bytes_on_disk;
    return d;
}

// Probe positions (the local frame, as cloud_bake_manifest gives them) as a placement.
std::shared_ptr<const ProbePlacement>
placement_of(const std::vector<std::vector<double>>& positions) {
    std::vector<glm::dvec3> local;
    for (const auto& p : positions) {
        local.push_back(dvec3_from(p, "probe position"));
    }
    return std::make_shared<const ProbePlacement>(ProbePlacement::from_positions(local));
}

// A staged bake's Job: `bake` runs in the background; its result is one staged_dict a probe.
std::unique_ptr<Job> staged_bake_job(std::function<std::vector<StagedProbe>(Progress&)> bake) {
    return std::make_unique<Job>(std::move(bake),
                                 std::function<py::object(std::vector<StagedProbe> &&)>(
                                     [](std::vector<StagedProbe>&& staged) -> py::object {
                                         py::list out;
                                         for (const StagedProbe& s : staged) {
                                             out.append(staged_dict(s));
                                         }
                                         return out;
                                     }));
}

} // namespace

void bind_staged_bake(py::module_& m) {
    py::class_<CloudBakeSource, std::shared_ptr<CloudBakeSource>>(
        m, "CloudBakeSource",
        "A cloud ready to bake probes from (normals, spacing, point hierarchy), built once per "
        "process by start_prepare_cloud_bake.")
        .def_property_readonly("point_count",
                               [](const CloudBakeSource& s) { return s.cloud->size(); })
        .def_property_readonly("normals_seconds",
                               [](const CloudBakeSource& s) { return s.normals_seconds; })
        .def_property_readonly("hierarchy_seconds",
                               [](const CloudBakeSource& s) { return s.hierarchy_seconds; })
        .def_property_readonly("from_cache", [](const CloudBakeSource& s) { return s.from_cache; })
        .def_property_readonly(
            "cache_entry", [](const CloudBakeSource& s) { return s.cache_entry; },
            "The prepared-cloud cache entry read or written (\"\" without a cache folder).");

    m.def(
        "start_prepare_cloud_bake",
        [](std::shared_ptr<PointCloud> cloud, const py::dict& settings,
           const std::string& cache_dir) {
            const CloudBakeOptions options = cloud_bake_options_from(settings);
            std::shared_ptr<const PointCloud> shared = std::move(cloud);
            return std::make_unique<Job>(
                std::function<CloudBakeSource(Progress&)>(
                    [shared, options, cache_dir](Progress& progress) {
                        return prepare_cloud_bake(shared, options.settings, options.geometry,
                                                  &progress, cache_dir);
                    }),
                std::function<py::object(CloudBakeSource &&)>([](CloudBakeSource&& s) {
                    return py::cast(std::make_shared<CloudBakeSource>(std::move(s)));
                }));
        },
        py::arg("cloud"), py::arg("settings") = py::dict(), py::arg("cache_dir") = "",
        "Start making a cloud ready to bake from; settings as bake_probe_set's keywords "
        "(resolution, splat_scale, hole_fill_texels, max_splat_radius_texels, normal_neighbours, "
        "lod_texels, lod_colour_tolerance, splat_edge_margin, splat_core_scale, face_the_probe); "
        "cache_dir as "
        "bake_probe_set's. The Job's result is a CloudBakeSource.");

    py::class_<SpatialCloud, std::shared_ptr<SpatialCloud>>(
        m, "SpatialCloud",
        "A prepared cloud mapped from its file (open_spatial_cloud), which a probe's bake reads "
        "only in the parts its cut needs.")
        .def_property_readonly("point_count", &SpatialCloud::point_count)
        .def_property_readonly("file_bytes", &SpatialCloud::file_bytes)
        .def_property_readonly("path", &SpatialCloud::path)
        .def_property_readonly(
            "resident_bytes",
            [](const SpatialCloud& c) -> py::object {
                const std::optional<std::size_t> bytes = c.resident_bytes();
                return bytes ? py::object(py::int_(*bytes)) : py::object(py::none());
            },
            "The file's bytes this process has touched and holds (None where the system does "
            "not say).");

    m.def(
        "start_write_spatial_cloud",
        [](std::shared_ptr<CloudBakeSource> source, const std::string& cache_dir) {
            return std::make_unique<Job>(
                std::function<std::optional<SpatialCloudEntry>(Progress&)>(
                    [source, cache_dir](Progress& progress) {
                        return write_spatial_cloud_of(*source, cache_dir, &progress);
                    }),
                std::function<py::object(std::optional<SpatialCloudEntry> &&)>(
                    [](std::optional<SpatialCloudEntry>&& entry) -> py::object {
                        if (!entry) {
                            return py::none();
                        }
                        py::dict d;
                        d["path"] = entry->path;
                        d["key"] = entry->key_hex;
                        d["written"] = entry->written;
                        return d;
                    }));
        },
        py::arg("source"), py::arg("cache_dir"),
        "Start writing the spatial cloud of `source` into `cache_dir` (unless it is there): the "
        "prepared cloud laid out so that a process bakes from only the parts its probes read. "
        "The Job's result is a dict (path, key, written) or None when the source bakes from "
        "every point (lod_texels 0, or no hierarchy), which a spatial cloud does not serve.");

    m.def(
        "open_spatial_cloud",
        [](const std::string& path, const std::string& key) {
            return std::make_shared<SpatialCloud>(path, key);
        },
        py::arg("path"), py::arg("key"),
        "Maps the spatial cloud at `path` without reading it; IOError unless it is the spatial "
        "cloud of `key` (start_write_spatial_cloud's 'key').");

    m.def(
        "cloud_bake_manifest",
        [](const PointCloud& cloud, std::vector<std::vector<double>> positions,
           std::optional<std::vector<double>> grid_min, std::optional<std::vector<double>> grid_max,
           std::optional<std::vector<int>> counts, bool positions_in_world,
           const std::string& sources_json, const py::dict& settings) {
            const CloudBakeOptions options = cloud_bake_options_from(settings);
            const ProbePlacement placement =
                placement_from(positions, grid_min, grid_max, counts,
                               positions_in_world ? cloud.world_offset : glm::dvec3(0.0));
            if (placement.positions.empty()) {
                throw InputError("bake: no probe positions given");
            }
            const ProbeSetManifest manifest = cloud_bake_manifest(
                cloud, placement, options.settings, options.geometry, sources_from(sources_json));
            py::list local;
            for (const glm::dvec3& p : placement.positions) {
                local.append(py::make_tuple(p.x, p.y, p.z));
            }
            py::dict d;
            d["manifest"] = manifest.to_json().dump();
            d["positions"] = local;
            return d;
        },
        py::arg("cloud"), py::arg("positions") = std::vector<std::vector<double>>{},
        py::arg("grid_min") = py::none(), py::arg("grid_max") = py::none(),
        py::arg("counts") = py::none(), py::arg("positions_in_world") = true,
        py::arg("sources_json") = "[]", py::arg("settings") = py::dict(),
        "The manifest of a cloud bake before its probes are listed (JSON text, 'manifest') and "
        "the probes' positions in the cloud's local frame ('positions').");

    m.def("probe_set_staging_path", &probe_set_staging_path, py::arg("folder"),
          "The staging folder of `folder` (FOLDER.partial), where a bake writes until done.");
    m.def("open_probe_set_staging", &open_probe_set_staging, py::arg("folder"),
          "Empties and creates the staging folder of `folder`; returns its path. InputError "
          "when `folder` holds anything but an earlier probe set.");
    m.def("discard_probe_set_staging", &discard_probe_set_staging, py::arg("folder"),
          "Removes the staging folder of `folder` (a cancelled or failed bake).");

    m.def(
        "start_bake_staged_probes",
        [](std::shared_ptr<CloudBakeSource> source, std::vector<std::vector<double>> positions,
           std::vector<std::size_t> indices, const std::string& staging) {
            auto placement = placement_of(positions);
            return staged_bake_job([source, placement, indices, staging](Progress& progress) {
                return bake_staged_probes(*source, *placement, indices, staging, &progress);
            });
        },
        py::arg("source"), py::arg("positions"), py::arg("indices"), py::arg("staging"),
        "Start baking the probes `indices` (of `positions`, the local frame, as "
        "cloud_bake_manifest gives them) into the staging folder, each written atomically. The "
        "Job's result is one dict per probe: index, record (its manifest entry, JSON text), "
        "bytes_on_disk.");

    m.def(
        "start_bake_staged_probes",
        [](std::shared_ptr<SpatialCloud> cloud, std::vector<std::vector<double>> positions,
           std::vector<std::size_t> indices, const std::string& staging, const py::dict& settings) {
            const BakeSettings bake = cloud_bake_options_from(settings).settings;
            auto placement = placement_of(positions);
            return staged_bake_job([cloud, bake, placement, indices, staging](Progress& progress) {
                return bake_staged_probes(*cloud, bake, *placement, indices, staging, &progress);
            });
        },
        py::arg("source"), py::arg("positions"), py::arg("indices"), py::arg("staging"),
        py::arg("settings"),
        "The same from a SpatialCloud, with the bake settings (as start_prepare_cloud_bake's) "
        "that the source it was written from had: the same probes, bit for bit.");

    m.def(
        "finish_probe_set_staging",
        [](const std::string& folder, const std::string& manifest_json, const py::list& staged) {
            nlohmann::json j = parse_json(manifest_json, folder + " (manifest)");
            std::vector<StagedProbe> probes;
            std::vector<nlohmann::json> records;
            for (const py::handle& item : staged) {
                const auto d = item.cast<py::dict>();
                StagedProbe probe;
                probe.index = d["index"].cast<std::size_t>();
                probe.bytes_on_disk = d["bytes_on_disk"].cast<std::size_t>();
                probes.push_back(probe);
                records.push_back(
                    parse_json(d["record"].cast<std::string>(), folder + " (a probe's record)"));
            }
            std::vector<std::size_t> order(probes.size());
            for (std::size_t k = 0; k < order.size(); ++k) {
                order[k] = k;
            }
            std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
                return probes[a].index < probes[b].index;
            });
            nlohmann::json list = nlohmann::json::array();
            std::vector<StagedProbe> sorted;
            for (std::size_t k = 0; k < order.size(); ++k) {
                if (probes[order[k]].index != k) {
                    throw InputError(folder + ": probe " + std::to_string(k) +
                                     " was not baked (or twice); the set is not complete");
                }
                list.push_back(records[order[k]]);
                sorted.push_back(probes[order[k]]);
            }
            j["probes"] = std::move(list);
            const ProbeSetManifest manifest = ProbeSetManifest::from_json(j, folder);
            for (std::size_t k = 0; k < sorted.size(); ++k) {
                sorted[k].record = manifest.probes[k];
            }
            {
                py::gil_scoped_release release;
                finish_probe_set_staging(folder, manifest);
            }
            BakeSummary summary;
            summary.folder = folder;
            add_staged_figures(summary, sorted);
            return bake_summary_dict(summary, false);
        },
        py::arg("folder"), py::arg("manifest"), py::arg("staged"),
        "Finishes a bake in parts: `manifest` as cloud_bake_manifest gave it, `staged` the dicts "
        "start_bake_staged_probes returned, one per probe in any order. Checks that every probe "
        "is in the staging folder, writes the manifest last and swaps the set in where `folder` "
        "was. Returns the summary's probe count, coverage and byte figures.");
}

} // namespace lfprobe::python
