// Planning a probe set from the data before the full bake (issue "model only what a scene
// needs"): per probe, the resolution its points support (probe_resolution.hpp), and what it is
// good for (probe_classification.hpp) from a quick low-resolution bake; probes inside geometry
// are moved within a bounded distance, probes against a wall where the move lets them see
// more, and probes that stay useless are dropped:
// kept as a tiny placeholder map, so that a grid stays a grid and its walk stays valid, while
// their memory all but vanishes (a placeholder answers UNKNOWN, and the walk asks the next
// probe).
#pragma once

#include <string>
#include <vector>

#include <glm/vec3.hpp>
#include <nlohmann/json_fwd.hpp>

#include "lfprobe/local_geometry.hpp"
#include "lfprobe/point_cloud.hpp"
#include "lfprobe/point_hierarchy.hpp"
#include "lfprobe/probe_bake.hpp"
#include "lfprobe/probe_classification.hpp"
#include "lfprobe/probe_placement.hpp"
#include "lfprobe/probe_resolution.hpp"
#include "lfprobe/probe_set.hpp"
#include "lfprobe/progress.hpp"

namespace lfprobe {

struct PlanSettings {
    bool auto_resolution = true;
    int fixed_resolution = 512; // when not auto_resolution
    ResolutionSettings resolution;
    bool classify = true;
    ClassificationSettings classes; // cell_reach 0 = taken from the grid spacing
    int classify_resolution = 64;   // of the quick bakes that classify
    double max_move = 0.0;          // metres; 0 = 0.45 × the smallest grid spacing (0.25 m loose)
    bool drop = true;
    // A too-close probe, or a useful one that sees more than `partly_unknown` of its sphere
    // unknown, is moved (away from the near side; toward what it sees) only when the move makes
    // it see at least `min_coverage_gain` more of its sphere (fewer unknown texels). A
    // light-field probe next to a surface still holds that surface and what lies on its open
    // side: on the hard scene, moving the two probes 1.5 cm from the pillar 2–5 cm away cost
    // the view beside the pillar 0.3 dB and gained no coverage. A probe on a wall's plane, half
    // of whose sphere looks behind the wall where nothing was scanned, gains and moves.
    // Inside probes are always moved out.
    double partly_unknown = 0.25;
    double min_coverage_gain = 0.01;
    int placeholder_resolution = 8; // what a dropped probe keeps
    BakeSettings bake;              // splat and hole-fill settings of every bake
};

struct PlannedProbe {
    glm::dvec3 original{0.0}; // where the placement put it (local frame)
    glm::dvec3 position{0.0}; // where it will be baked
    int resolution = 0;
    ProbeClass found = ProbeClass::Useful; // before any move
    ProbeClass kind = ProbeClass::Useful;  // after the moves
    bool moved = false;
    bool dropped = false;
    ResolutionChoice choice;
    ProbeClassification classification; // at `position`
};

struct ProbePlan {
    std::vector<PlannedProbe> probes;
    [[nodiscard]] nlohmann::json to_json(const glm::dvec3& world_offset) const;
};

// `hierarchy`: the cloud's point hierarchy for settings.bake (hierarchy_for_bakes), which the
// quick bakes that classify then bake from, like the probes' own bakes: their cost follows their
// few texels, not the cloud (every point splatted into 64² texels took 0.35 s a probe from 3.5 M
// points). Without it (null or empty) they bake from every point.
[[nodiscard]] ProbePlan plan_probes(const PointCloud& cloud, const LocalGeometry& geometry,
                                    const ProbePlacement& placement, const PlanSettings& settings,
                                    Progress* progress = nullptr,
                                    const PointHierarchy* hierarchy = nullptr);

// Bakes the planned probes (each at its own position and resolution) into `folder` like
// bake_probe_set_from_cloud; the plan goes into the manifest's bake settings. `hierarchy`:
// the cloud's point hierarchy for settings.bake when the caller has it (prepare_cloud_bake),
// else it is built here.
[[nodiscard]] BakeSummary
bake_planned_probe_set(const PointCloud& cloud, const LocalGeometry& geometry,
                       const ProbePlacement& placement, const ProbePlan& plan,
                       const PlanSettings& settings, const std::string& folder,
                       const nlohmann::json& sources, Progress* progress = nullptr,
                       const PointHierarchy* hierarchy = nullptr);

} // namespace lfprobe
