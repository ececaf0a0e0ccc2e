// Baking probes from a point cloud (docs/DESIGN.md §4): every point is projected into each probe's
// octahedral map and splatted over the texels its footprint covers at that distance (a point
// stands for a patch of about the local spacing), the nearest surface winning per texel; small
// holes are filled by pull-push and marked as inferred, large holes stay unknown.
#pragma once

#include <functional>
#include <string>

#include "lfprobe/local_geometry.hpp"
#include "lfprobe/point_cloud.hpp"
#include "lfprobe/point_hierarchy.hpp"
#include "lfprobe/probe_map.hpp"
#include "lfprobe/progress.hpp"

namespace lfprobe {

struct BakeSettings {
    int resolution = 512;
    // Splat radius as a multiple of the local point spacing. 0.8 of the mean distance to six
    // neighbours covers a square sampling pattern (which needs 0.71 of its pitch) with margin.
    float splat_scale = 0.8f;
    // A neighbouring texel takes a point's splat only where its ray meets the point's surface
    // plane within this many splat radii of the point. The splat cone alone would paint a
    // surface seen edge-on over the directions that pass beside it: a probe next to a wall or
    // a pillar would hide everything near the wall's plane behind false occluders, as wide as
    // the cone (wider the coarser the map). A disc of one splat radius opens holes instead,
    // between scan lines whose spacing along the scanner's beam grows at oblique incidence
    // beyond the mean neighbour distance; two radii close them (measured on the demo scenes).
    float splat_plane_reach = 2.0f;
    // A splat's core: the disc within this many point spacings of the point. A texel any
    // splat's core reaches takes the nearest of those; the rest of a disc (its fringe) fills
    // only texels no core reaches (with the hole fill on, only those it leaves unknown: the
    // fill continues the surface behind a silhouette first). Without it the nearest splat won
    // wherever its fringe reached, and a near object's silhouette, a crease or a surface seen
    // obliquely grew by the fringe's width over what lies behind. A square sampling pattern needs
    // 0.71 of its pitch to be covered, 0.62 of the mean distance to six neighbours; 0.7 leaves a
    // margin for scan lines that oblique incidence draws apart (at 0.625 the hard scene's probe 1.5
    // cm from the pillar saw what lies 0.6 m behind the pillar's face in 125 of the 2,496 texels
    // looking at it, at 0.7 in 15, with whole discs in none). Lab room, 16 samples a pixel, four
    // views: +0.05 to +0.31 dB from 0.1° scans, +0.02 to +0.37 from 0.25°, +0.24 to +0.45 from
    // 1°, no more holes. At splat_scale or more: the whole disc is core, as before.
    float splat_core_scale = 0.7f;
    // A point at its surface's edge (SurfaceEdge: its neighbours lie to one side) splats more
    // than this many point spacings outward (where the surface ends on average: somewhere
    // between the last point and the next that is missing) only onto texels no other surface
    // reaches. A full disc would grow every silhouette by its splat radius, foreground over
    // the background along every edge; a clipped one would leave slivers unknown where the
    // background was never scanned. Negative: full discs at edges too.
    float splat_edge_margin = 0.5f;
    // Largest splat radius in texels; bounds the cost of points very close to a probe.
    int max_splat_radius_texels = 64;
    // Holes up to this many texels across (their width, not their length) are filled and marked
    // inferred; wider ones stay unknown; 0 fills none. Negative: the default width,
    // default_hole_fill_texels, which grows with the resolution (a scanner's shadow covers the
    // same angle at any resolution).
    int hole_fill_texels = -1;
    // A texel's surface is what the probe's centre sees in its direction, so it faces the
    // centre: a winning point whose normal (oriented toward its scanner) faces away, a surface
    // scanned from its other side (a sheet, a thin object's edge where the neighbours' plane
    // tilts), is stored turned toward the centre, and an eye at the probe sees it as a HIT, not
    // as a back face (UNKNOWN). Off: normals as estimated, so that a probe inside an object
    // sees its back faces (the planner's classification, probe_classification.hpp, bakes so).
    bool face_the_probe = true;
    // Points nearer than this to the probe centre are skipped (no direction to speak of).
    float min_distance = 1e-4f;
    // Baking from the point hierarchy (bake_probe_from_hierarchy): a cell's surfels stand in
    // for its points where they are at most this many texels apart as the probe sees them;
    // 0 bakes every point.
    float lod_texels = 1.0f;
    // Above 0, a cell of up to twice lod_texels texels also stands in for its points where its
    // children's surfels agree with its own: their colours within this much per channel
    // (linear) and their points within half a texel of its plane. Where the cloud is much
    // denser than the probe's texels and its colour smooth, the bake then takes about a quarter
    // of the surfels; 0 (the default) keeps to lod_texels.
    float lod_colour_tolerance = 0.0f;
};

// Bakes one probe at `centre` (local frame). `geometry` comes from estimate_local_geometry on
// the same cloud. Runs on all cores; checks progress for cancellation.
[[nodiscard]] ProbeMap bake_probe_from_cloud(const PointCloud& cloud, const LocalGeometry& geometry,
                                             const glm::dvec3& centre, const BakeSettings& settings,
                                             Progress* progress = nullptr);

// Bakes one probe from the cut of `hierarchy` (built from the same cloud and geometry) that its
// resolution needs (settings.lod_texels): the cost follows the probe's texels, not the cloud's
// points, and far surfaces bake from colours averaged over about a texel. With lod_texels 0,
// or a hierarchy with no levels (an empty one: what a caller builds when lod_texels is 0), it
// is bake_probe_from_cloud, bit for bit.
[[nodiscard]] ProbeMap
bake_probe_from_hierarchy(const PointCloud& cloud, const LocalGeometry& geometry,
                          const PointHierarchy& hierarchy, const glm::dvec3& centre,
                          const BakeSettings& settings, Progress* progress = nullptr);

// Bakes one probe from a cut already gathered: `cut.points` index `points` (and `geometry`,
// made for them), whose colours are the ones the bake takes (PointColours of the whole cloud).
// What a process that maps a spatial cloud (spatial_cloud.hpp) bakes from; given the same
// points, surfels and order as bake_probe_from_hierarchy's cut, the same probe, bit for bit.
[[nodiscard]] ProbeMap
bake_probe_from_gathered_cut(const PointCloud& points, const LocalGeometry& geometry,
                             const HierarchyCut& cut, const glm::dvec3& centre,
                             const BakeSettings& settings, Progress* progress = nullptr);

// The cut of `hierarchy` that a bake with `settings` at `centre` takes, the one
// bake_probe_from_hierarchy takes, for bakes from a copy of the points (a spatial cloud, points in
// curve order). InputError, naming `source`, unless lod_texels asks for cuts and the resolution
// and the centre are ones a bake takes.
[[nodiscard]] HierarchyCut cut_for_bake(const PointHierarchyView& hierarchy,
                                        const glm::dvec3& centre, const BakeSettings& settings,
                                        const std::string& source, Progress* progress = nullptr);

// The hierarchy bakes with `settings` take from `cloud`: built (build_point_hierarchy) when
// settings.lod_texels asks for cuts, else empty, which bake_probe_from_hierarchy reads as
// "every point". Built once, it serves every probe of a set.
[[nodiscard]] PointHierarchy hierarchy_for_bakes(const PointCloud& cloud,
                                                 const LocalGeometry& geometry,
                                                 const BakeSettings& settings,
                                                 Progress* progress = nullptr);

// The default hole width at an N×N map: an angle of about 4.8° (12 texels at 512², 24 at
// 1024², 48 at 2048²), at least 4 texels. Wide enough for what four stations leave unseen
// behind a room's furniture as a probe between them sees it (the strip under a desk's edge),
// narrow enough that a partial sweep's unscanned side stays unknown.
[[nodiscard]] int default_hole_fill_texels(int resolution);

// The hole width settings.hole_fill_texels means at settings.resolution (its default where it
// is negative).
[[nodiscard]] int hole_fill_width(const BakeSettings& settings);

// Fills the holes (8-connected unknown texels) of at most hole_fill_texels texels across,
// marking them inferred; wider holes stay unknown, and texels already surface, empty or
// inferred are left as they are. A hole on a silhouette whose border is largely the far
// surface is a disocclusion (what the scans could not see behind the near surface): it is
// filled from that far surface inward, continuing its plane, with confidence halving every
// time the fill reaches twice as far. Any other hole takes a pull-push of the measured texels
// (confidence 0.5 per pyramid level climbed), the nearest surface where the block it draws from
// spans a silhouette.
void fill_small_holes(ProbeMap& map, int hole_fill_texels);

// Marks unknown each measured texel seen through a gap between a nearer surface's splats: one
// that, in each of the 8 texel directions within `reach` texels, has a measured texel nearer
// than its own distance / 1.25. A surface scanned at a grazing angle is sampled sparsely
// along the scanner's rays; seen from above by a probe close to it, its splats leave gaps a
// few texels wide in which the floor behind showed, a wrong surface no later step could tell
// from a right one. As holes in the near surface, fill_small_holes then fills them from it. A
// slit (between the slats of a blind) stays open along its length, and a texel at a
// silhouette has the far surface on one side, so neither is touched. A gap's rim, open across
// the gap where it is wider than the reach, joins the texels closed all round beside it where
// it is closed in 6 directions at about their distance: the hole is the whole gap, whose
// border is then the near surface alone. Returns how many texels it marked.
std::size_t open_gaps_in_nearer_surfaces(ProbeMap& map, int reach);

// The reach of open_gaps_in_nearer_surfaces for an N×N map: the same angle, about 0.9°, at
// every resolution (8 texels at 2048², at least 1).
[[nodiscard]] int sieve_gap_reach(int resolution);

} // namespace lfprobe
