// Bindings of probe planning: per-probe resolution from the data, classification, moves and
// drops, and the bake of a planned set. Options come as a dict so that the CLI and the add-on
// name only what they change; logic stays in the core.
#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "binding_helpers.hpp"
#include "bindings.hpp"
#include "job.hpp"
#include "lfprobe/cloud_bake.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/local_geometry.hpp"
#include "lfprobe/probe_placement.hpp"
#include "lfprobe/probe_plan.hpp"

namespace py = pybind11;

namespace lfprobe::python {

namespace {

PlanSettings plan_settings_from(const py::dict& options) {
    PlanSettings s;
    for (const auto& item : options) {
        const auto key = py::str(item.first).cast<std::string>();
        const py::handle v = item.second;
        if (key == "auto_resolution") {
            s.auto_resolution = v.cast<bool>();
        } else if (key == "resolution") {
            s.fixed_resolution = v.cast<int>();
        } else if (key == "min_resolution") {
            s.resolution.min_resolution = v.cast<int>();
        } else if (key == "max_resolution") {
            s.resolution.max_resolution = v.cast<int>();
        } else if (key == "footprint") {
            s.resolution.footprint = v.cast<double>();
        } else if (key == "quantile") {
            s.resolution.quantile = v.cast<double>();
        } else if (key == "samples_per_spacing") {
            s.resolution.samples_per_spacing = v.cast<double>();
        } else if (key == "classify") {
            s.classify = v.cast<bool>();
        } else if (key == "partly_unknown") {
            s.partly_unknown = v.cast<double>();
        } else if (key == "min_coverage_gain") {
            s.min_coverage_gain = v.cast<double>();
        } else if (key == "clearance") {
            s.classes.clearance = v.cast<double>();
        } else if (key == "cell_reach") {
            s.classes.cell_reach = v.cast<double>();
        } else if (key == "max_move") {
            s.max_move = v.cast<double>();
        } else if (key == "drop") {
            s.drop = v.cast<bool>();
        } else if (key == "classify_resolution") {
            s.classify_resolution = v.cast<int>();
        } else if (!set_bake_setting(s.bake, key, v)) {
            // "resolution" is taken above: a plan's fixed resolution, not the bake's.
            throw InputError("plan: unknown option '" + key +
                             "' (expected auto_resolution, min_resolution, max_resolution, "
                             "footprint, quantile, samples_per_spacing, classify, clearance, "
                             "cell_reach, max_move, partly_unknown, min_coverage_gain, drop, "
                             "classify_resolution, " +
                             kBakeSettingNames + ")");
        }
    }
    return s;
}

struct PlanArgs {
    std::vector<std::vector<double>> positions;
    std::optional<std::vector<double>> grid_min;
    std::optional<std::vector<double>> grid_max;
    std::optional<std::vector<int>> counts;
};

} // namespace

void bind_plan(py::module_& m) {
    m.def(
        "grid_positions",
        [](const std::vector<double>& grid_min, const std::vector<double>& grid_max,
           const std::vector<int>& counts) {
            if (counts.size() != 3) {
                throw InputError("grid_positions: expected three counts");
            }
            const std::vector<glm::dvec3> positions =
                ProbeGrid::spanning(dvec3_from(grid_min, "grid_min"),
                                    dvec3_from(grid_max, "grid_max"),
                                    {counts[0], counts[1], counts[2]})
                    .positions();
            py::array_t<double> out({static_cast<py::ssize_t>(positions.size()), py::ssize_t{3}});
            double* p = out.mutable_data();
            for (const glm::dvec3& q : positions) {
                *p++ = q.x;
                *p++ = q.y;
                *p++ = q.z;
            }
            return out;
        },
        py::arg("grid_min"), py::arg("grid_max"), py::arg("counts"),
        "The probes of a grid spanning the box grid_min..grid_max with `counts` probes per axis, "
        "as the bake places them: (n, 3) float64, x fastest, then y, then z; an axis with one "
        "probe has it at the box's centre.");
    m.def(
        "start_plan_probes",
        [](std::shared_ptr<PointCloud> cloud, std::vector<std::vector<double>> positions,
           std::optional<std::vector<double>> grid_min, std::optional<std::vector<double>> grid_max,
           std::optional<std::vector<int>> counts, const py::dict& options) {
            const PlanSettings settings = plan_settings_from(options);
            const ProbePlacement placement =
                placement_from(positions, grid_min, grid_max, counts, cloud->world_offset);
            const glm::dvec3 offset = cloud->world_offset;
            return std::make_unique<Job>(
                std::function<ProbePlan(Progress&)>([=](Progress& progress) {
                    const LocalGeometry geometry = estimate_local_geometry(*cloud, {}, &progress);
                    const PointHierarchy hierarchy =
                        hierarchy_for_bakes(*cloud, geometry, settings.bake, &progress);
                    return plan_probes(*cloud, geometry, placement, settings, &progress,
                                       &hierarchy);
                }),
                std::function<py::object(ProbePlan &&)>([offset](ProbePlan&& plan) -> py::object {
                    return py::module_::import("json").attr("loads")(plan.to_json(offset).dump());
                }));
        },
        py::arg("cloud"), py::arg("positions") = std::vector<std::vector<double>>{},
        py::arg("grid_min") = py::none(), py::arg("grid_max") = py::none(),
        py::arg("counts") = py::none(), py::arg("options") = py::dict(),
        "Start planning probes (world coordinates): per probe the resolution the data supports, "
        "its class (useful, inside, too_close, blind, idle), moves and drops. The Job's result "
        "is a list of dicts, one per probe.");

    m.def(
        "start_bake_planned_probe_set",
        [](std::shared_ptr<PointCloud> cloud, const std::string& folder,
           std::vector<std::vector<double>> positions, std::optional<std::vector<double>> grid_min,
           std::optional<std::vector<double>> grid_max, std::optional<std::vector<int>> counts,
           const std::string& sources_json, const py::dict& options, const std::string& cache_dir) {
            const PlanSettings settings = plan_settings_from(options);
            const ProbePlacement placement =
                placement_from(positions, grid_min, grid_max, counts, cloud->world_offset);
            const nlohmann::json sources = sources_from(sources_json);
            return std::make_unique<Job>(
                std::function<BakeSummary(Progress&)>([=](Progress& progress) {
                    const CloudBakeSource source =
                        prepare_cloud_bake(cloud, settings.bake, {}, &progress, cache_dir);
                    const ProbePlan plan = plan_probes(*cloud, source.geometry, placement, settings,
                                                       &progress, &source.hierarchy);
                    BakeSummary summary =
                        bake_planned_probe_set(*cloud, source.geometry, placement, plan, settings,
                                               folder, sources, &progress, &source.hierarchy);
                    summary.normals_seconds = source.normals_seconds;
                    summary.hierarchy_seconds = source.hierarchy_seconds;
                    summary.prepared_from_cache = source.from_cache;
                    return summary;
                }),
                std::function<py::object(BakeSummary &&)>(
                    [](BakeSummary&& s) -> py::object { return bake_summary_dict(s, true); }));
        },
        py::arg("cloud"), py::arg("folder"),
        py::arg("positions") = std::vector<std::vector<double>>{}, py::arg("grid_min") = py::none(),
        py::arg("grid_max") = py::none(), py::arg("counts") = py::none(),
        py::arg("sources_json") = "[]", py::arg("options") = py::dict(), py::arg("cache_dir") = "",
        "Start planning and baking a probe set (bake --auto): each probe at its planned position "
        "and resolution, dropped probes as all-unknown placeholders; the plan goes into the "
        "manifest. cache_dir as bake_probe_set's. The Job's result is the summary dict.");
}

} // namespace lfprobe::python
