// A level-of-detail hierarchy over a point cloud, so that baking a probe costs about as much as
// the probe has texels, not as the cloud has points (docs/DESIGN.md §4, "Point hierarchy").
//
// The points are sorted along a Morton curve over the cloud's bounding cube. A level is a grid
// of cubic cells, each twice as wide as the level below; every cell is one run of consecutive
// sorted points, and its children are one run of cells of the level below. A cell holds one
// stand-in surfel per facing of its points (six facings: the dominant axis of the normal and
// its sign, and one for points without a normal), with their mean position and colour and
// their summed normal: a thin wall's two sides, or a table top and the floor under it seen
// from the side, stay apart. Colours are averaged here once, which is the prefilter a texel
// wants when it covers many points.
//
// A probe takes a cut of the hierarchy: the coarsest cells whose surfels are at most
// `lod_texels` texels apart as seen from the probe at the cell's nearest point, and the points
// themselves where even the finest cell is too coarse (near the probe).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/vec3.hpp>

#include "lfprobe/local_geometry.hpp"
#include "lfprobe/point_cloud.hpp"
#include "lfprobe/point_colours.hpp"
#include "lfprobe/progress.hpp"

namespace lfprobe {

// The points of one cell that share a facing, as one surfel.
struct CellSurfel {
    glm::vec3 position{0.0f}; // mean of the members' positions
    glm::vec3 normal{0.0f};   // unit mean of the members' normals; zero where they cancel
    glm::vec3 colour{0.0f};   // mean of the members' colours (PointColours)
    // The splat spacing this surfel stands for: the members' mean spacing, and at least the
    // spacing of surfels on the level's grid (kCellSurfelSpacing cells), so that the surfels
    // of neighbouring cells close up on a surface.
    float spacing = 0.0f;
    std::uint32_t count = 0;   // points it stands for
    std::uint8_t facing = 0;   // 0-5: 2·axis + (component < 0); 6: no normal
    std::uint8_t oriented = 0; // 1 when every member's normal sign was known
};

// Surfels of a cell on a plane through it are about one cell apart, up to √2 cells where the
// plane cuts the cells obliquely: their splats are sized for that.
inline constexpr float kCellSurfelSpacing = 1.5f;

struct PointHierarchy {
    struct Level {
        int shift = 0;                           // a cell spans 2^shift base cells per axis
        float cell_size = 0.0f;                  // metres
        std::vector<std::uint64_t> cell_keys;    // Morton key of the cell at this level
        std::vector<std::uint32_t> first_point;  // cells + 1 entries: runs in `order`
        std::vector<std::uint32_t> first_child;  // cells + 1 entries: runs of the level below
        std::vector<std::uint32_t> first_surfel; // cells + 1 entries: runs in `surfels`
        std::vector<CellSurfel> surfels;
        [[nodiscard]] std::size_t cell_count() const { return cell_keys.size(); }
    };
    // The cloud's intensity range (PointColours), found once for every probe's cut.
    PointColours::IntensityRange intensity;
    glm::vec3 origin{0.0f};           // the bounding cube's minimum corner, local frame
    float cube_size = 0.0f;           // its edge, metres
    std::vector<std::uint32_t> order; // point indices in Morton order
    std::vector<Level> levels;        // finest first; empty: the cut is every point

    [[nodiscard]] std::size_t memory_bytes() const;
    [[nodiscard]] std::size_t surfel_count() const;
};

// A hierarchy's arrays seen without owning them: a PointHierarchy's vectors, or the sections of
// a memory-mapped file (spatial_cloud.hpp), which a cut then reads only where it descends.
struct PointHierarchyView {
    struct Level {
        int shift = 0;
        float cell_size = 0.0f;
        std::span<const std::uint64_t> cell_keys;
        std::span<const std::uint32_t> first_point;
        std::span<const std::uint32_t> first_child;
        std::span<const std::uint32_t> first_surfel;
        // CellSurfel records, read with memcpy: a mapped file's bytes are not objects.
        const std::byte* surfels = nullptr;
        std::size_t surfel_count = 0;
        [[nodiscard]] std::size_t cell_count() const { return cell_keys.size(); }
    };
    glm::vec3 origin{0.0f};
    float cube_size = 0.0f;
    std::size_t point_count = 0;
    // Point indices in Morton order; empty when the points themselves are stored in that order
    // (a cut's points are then their positions along the curve).
    std::span<const std::uint32_t> order;
    std::vector<Level> levels; // finest first

    [[nodiscard]] static PointHierarchyView of(const PointHierarchy& hierarchy);
};

// Builds the hierarchy for `cloud` with the normals and spacing of `geometry` (from
// estimate_local_geometry on the same cloud). Deterministic: the same cloud gives the same
// hierarchy bit for bit, for any thread count. Runs on all cores; cancellable.
[[nodiscard]] PointHierarchy build_point_hierarchy(const PointCloud& cloud,
                                                   const LocalGeometry& geometry,
                                                   Progress* progress = nullptr);

// What one probe bakes from: points of the cloud (indices, in Morton order) where they are
// needed at full density, and cell surfels elsewhere.
struct HierarchyCut {
    std::vector<std::uint32_t> points;
    std::vector<CellSurfel> surfels;
    [[nodiscard]] std::size_t size() const { return points.size() + surfels.size(); }
};

// How a probe's cut is chosen: a cell's surfels stand in for its points where the cell spans at
// most `lod_texels` texels (`texel_angle` radians each) at its nearest point to the probe; with a
// colour tolerance above 0, also where it spans at most twice that and its children's surfels
// agree with its own (colours within the tolerance per channel, points within half a texel of
// its plane): there the children would add nothing the tolerance counts.
struct CutRule {
    float texel_angle = 0.0f;
    float lod_texels = 0.0f;
    float colour_tolerance = 0.0f;
};

// The cut for a probe at `centre` (local frame), in a deterministic order. Over a view, every
// run a visited cell names is checked against its array, so a damaged mapped file gives
// IoError, never a read out of bounds.
[[nodiscard]] HierarchyCut cut_for_probe(const PointHierarchyView& hierarchy,
                                         const glm::dvec3& centre, const CutRule& rule,
                                         Progress* progress = nullptr);
[[nodiscard]] HierarchyCut cut_for_probe(const PointHierarchy& hierarchy, const glm::dvec3& centre,
                                         const CutRule& rule, Progress* progress = nullptr);

} // namespace lfprobe
