#include "lfprobe/probe_plan.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "lfprobe/error.hpp"
#include "lfprobe/json_input.hpp"

namespace lfprobe {

namespace {

using nlohmann::json;

constexpr int kMaxMoves = 4;
constexpr double kLooseMaxMove = 0.25;

// Inside and too close by class; a useful probe that sees much of its sphere unknown may see
// more a little further on (a probe on a wall's plane, with the unscanned side behind it).
bool needs_move(const ProbeClassification& c, double partly_unknown) {
    return c.kind == ProbeClass::Inside || c.kind == ProbeClass::TooClose ||
           (c.kind == ProbeClass::Useful && c.unknown_fraction > partly_unknown);
}

// A too-close probe that stays where it is still holds its surroundings: kept, not dropped.
bool worth_keeping(ProbeClass c) {
    return c == ProbeClass::Useful || c == ProbeClass::TooClose;
}

ProbeClassification quick_classify(const PointCloud& cloud, const LocalGeometry& geometry,
                                   const PointHierarchy* hierarchy, const glm::dvec3& at,
                                   const PlanSettings& settings,
                                   const ClassificationSettings& classes) {
    BakeSettings quick = settings.bake;
    quick.resolution = settings.classify_resolution;
    quick.face_the_probe = false; // back faces are how a probe inside geometry shows
    // bake_probe_from_hierarchy itself bakes every point where the hierarchy has no levels or
    // lod_texels is 0.
    return classify_probe(hierarchy != nullptr
                              ? bake_probe_from_hierarchy(cloud, geometry, *hierarchy, at, quick)
                              : bake_probe_from_cloud(cloud, geometry, at, quick),
                          classes);
}

// A map of `n`² texels that holds no data: a trace over it answers UNKNOWN at once.
ProbeMap placeholder(int n, const glm::dvec3& at) {
    ProbeMap map(n, at);
    for (std::size_t i = 0; i < map.texel_count(); ++i) {
        map.set_unknown(i);
    }
    return map;
}

} // namespace

json ProbePlan::to_json(const glm::dvec3& world_offset) const {
    json out = json::array();
    for (const PlannedProbe& p : probes) {
        json c{{"surface", p.classification.surface_fraction},
               {"back_faces", p.classification.back_face_fraction},
               {"near", p.classification.near_fraction},
               {"unknown", p.classification.unknown_fraction},
               {"empty", p.classification.empty_fraction}};
        if (std::isfinite(p.classification.nearest_surface)) {
            c["nearest_surface"] = p.classification.nearest_surface;
        }
        out.push_back(json{{"position", json_of(world_offset + p.position)},
                           {"original", json_of(world_offset + p.original)},
                           {"moved_by", glm::length(p.position - p.original)},
                           {"resolution", p.resolution},
                           {"found", probe_class_name(p.found)},
                           {"class", probe_class_name(p.kind)},
                           {"moved", p.moved},
                           {"dropped", p.dropped},
                           {"data_resolution", p.choice.data_resolution},
                           {"footprint_resolution", p.choice.footprint_resolution},
                           {"median_distance", p.choice.median_distance},
                           {"median_spacing", p.choice.median_spacing},
                           {"classification", c}});
    }
    return out;
}

ProbePlan plan_probes(const PointCloud& cloud, const LocalGeometry& geometry,
                      const ProbePlacement& placement, const PlanSettings& settings,
                      Progress* progress, const PointHierarchy* hierarchy) {
    if (placement.positions.empty()) {
        throw InputError("plan: no probe positions given");
    }
    if (cloud.size() == 0) {
        throw InputError("plan: the point cloud is empty");
    }
    if (settings.classify_resolution < 8 || settings.placeholder_resolution < 1 ||
        settings.fixed_resolution < 1 || settings.max_move < 0.0) {
        throw InputError("plan: expected a classify resolution >= 8, placeholder and fixed "
                         "resolutions >= 1, and max_move >= 0");
    }
    ClassificationSettings classes = settings.classes;
    double max_move = settings.max_move;
    if (placement.is_grid) {
        double smallest = std::numeric_limits<double>::infinity();
        double diagonal2 = 0.0;
        for (int a = 0; a < 3; ++a) {
            if (placement.grid.counts[static_cast<std::size_t>(a)] > 1) {
                smallest = std::min(smallest, placement.grid.spacing[a]);
                diagonal2 += placement.grid.spacing[a] * placement.grid.spacing[a];
            }
        }
        if (max_move == 0.0 && std::isfinite(smallest)) {
            max_move = 0.45 * smallest;
        }
        // A probe serves the cells around it: nothing within a cell diagonal leaves it idle.
        if (!(classes.cell_reach > 0.0) && diagonal2 > 0.0) {
            classes.cell_reach = std::sqrt(diagonal2);
        }
    }
    if (max_move == 0.0) {
        max_move = kLooseMaxMove;
    }
    if (!(classes.cell_reach > 0.0)) {
        classes.cell_reach = std::numeric_limits<double>::infinity();
    }
    const std::size_t count = placement.positions.size();
    if (progress != nullptr) {
        progress->begin_stage("planning probes", count);
    }
    ProbePlan plan;
    plan.probes.resize(count);
    for (std::size_t i = 0; i < count; ++i) {
        if (progress != nullptr) {
            progress->throw_if_cancelled();
        }
        PlannedProbe& p = plan.probes[i];
        p.original = placement.positions[i];
        p.position = p.original;
        if (settings.classify) {
            p.classification =
                quick_classify(cloud, geometry, hierarchy, p.position, settings, classes);
            p.found = p.classification.kind;
            const ProbeClassification found = p.classification;
            for (int move = 0;
                 move < kMaxMoves && needs_move(p.classification, settings.partly_unknown);
                 ++move) {
                const ProbeClassification& c = p.classification;
                // Inside: out through the nearest surface. Too close: away from the near side.
                // Partly unknown: toward what it sees.
                glm::dvec3 step = c.toward_known * classes.clearance;
                if (c.kind == ProbeClass::Inside) {
                    step = c.toward_nearest * (c.nearest_surface + classes.clearance);
                } else if (c.kind == ProbeClass::TooClose) {
                    step = c.away_from_near * classes.clearance;
                }
                if (glm::length(step) == 0.0) {
                    break;
                }
                const glm::dvec3 candidate = p.position + step;
                if (glm::length(candidate - p.original) > max_move) {
                    break;
                }
                p.position = candidate;
                p.moved = true;
                p.classification =
                    quick_classify(cloud, geometry, hierarchy, p.position, settings, classes);
            }
            // Out of an object always; elsewhere only where the probe then sees more.
            if (p.moved && p.found != ProbeClass::Inside &&
                !(found.unknown_fraction - p.classification.unknown_fraction >=
                  settings.min_coverage_gain)) {
                p.position = p.original;
                p.moved = false;
                p.classification = found;
            }
            p.kind = p.classification.kind;
            p.dropped = settings.drop && !worth_keeping(p.kind);
            if (p.moved && p.dropped) {
                p.position = p.original; // a move that did not help is not kept
                p.moved = false;
            }
        }
        if (p.dropped) {
            p.resolution = settings.placeholder_resolution;
        } else if (settings.auto_resolution) {
            p.choice = choose_resolution(cloud, geometry, p.position, settings.resolution);
            p.resolution = p.choice.resolution;
        } else {
            p.resolution = settings.fixed_resolution;
        }
        if (progress != nullptr) {
            progress->advance(1);
        }
    }
    return plan;
}

BakeSummary bake_planned_probe_set(const PointCloud& cloud, const LocalGeometry& geometry,
                                   const ProbePlacement& placement, const ProbePlan& plan,
                                   const PlanSettings& settings, const std::string& folder,
                                   const json& sources, Progress* progress,
                                   const PointHierarchy* prepared) {
    if (plan.probes.size() != placement.positions.size()) {
        throw InputError("bake: the plan has " + std::to_string(plan.probes.size()) +
                         " probes, the placement " + std::to_string(placement.positions.size()));
    }
    ProbeSetManifest manifest;
    manifest.world_offset = cloud.world_offset;
    manifest.placement = placement;
    manifest.bake = splat_settings_json(settings.bake);
    manifest.bake.update(json{{"source", "point cloud"},
                              {"resolution", "per probe (planned)"},
                              {"points", cloud.size()},
                              {"resolution_rule",
                               {{"quantile", settings.resolution.quantile},
                                {"samples_per_spacing", settings.resolution.samples_per_spacing},
                                {"footprint", settings.resolution.footprint},
                                {"min_resolution", settings.resolution.min_resolution},
                                {"max_resolution", settings.resolution.max_resolution}}},
                              {"plan", plan.to_json(cloud.world_offset)}});
    manifest.sources = sources;
    const auto hierarchy_start = std::chrono::steady_clock::now();
    PointHierarchy built;
    if (prepared == nullptr) {
        built = hierarchy_for_bakes(cloud, geometry, settings.bake, progress);
    }
    const PointHierarchy& hierarchy = prepared != nullptr ? *prepared : built;
    const double hierarchy_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - hierarchy_start).count();
    BakeSummary summary = write_probe_set(
        folder, std::move(manifest),
        [&](std::size_t i) {
            const PlannedProbe& p = plan.probes[i];
            if (p.dropped) {
                return placeholder(p.resolution, p.position);
            }
            BakeSettings one = settings.bake;
            one.resolution = p.resolution;
            return bake_probe_from_hierarchy(cloud, geometry, hierarchy, p.position, one, progress);
        },
        progress);
    summary.hierarchy_seconds = hierarchy_seconds;
    return summary;
}

} // namespace lfprobe
