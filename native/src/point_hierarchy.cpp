#include "lfprobe/point_hierarchy.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include "lfprobe/error.hpp"
#include "lfprobe/morton.hpp"
#include "lfprobe/point_colours.hpp"

namespace lfprobe {

namespace {

constexpr int kFacings = 7;
constexpr std::uint8_t kNoFacing = 6;
// The coarsest level's cells are a sixteenth of the cube: few enough to visit every one for
// each probe, fine enough that a probe's own cell is small.
constexpr int kTopCellsPerAxisLog2 = 4;
// The finest level's cells are about the median point spacing: a cell of the level above
// already stands for a handful of points.
constexpr float kFinestCellSpacings = 1.0f;
constexpr std::size_t kCellChunk = 4096;
// A cut takes a cell's surfels only where each stands for at least this many points.
constexpr std::uint32_t kMinPointsPerSurfel = 4;

// Which of the six axis facings a normal has; unoriented normals (arbitrary sign) are turned
// to the positive side of their dominant axis first, so both signs of one surface meet.
std::uint8_t facing_of(glm::vec3 normal, bool oriented) {
    const glm::vec3 a = glm::abs(normal);
    if (!(a.x + a.y + a.z > 0.0f)) {
        return kNoFacing;
    }
    const int axis = a.x >= a.y && a.x >= a.z ? 0 : (a.y >= a.z ? 1 : 2);
    const bool negative = normal[axis] < 0.0f;
    return static_cast<std::uint8_t>(2 * axis + (negative && oriented ? 1 : 0));
}

// Sums of one facing of one cell, in double: the sums run in a fixed order (the points' or the
// children's), so the hierarchy is the same for any thread count.
struct FacingSum {
    glm::dvec3 position{0.0};
    glm::dvec3 normal{0.0};
    glm::dvec3 colour{0.0};
    double spacing = 0.0;
    std::uint64_t count = 0;
    std::uint64_t oriented = 0;

    void add(const glm::vec3& p, const glm::vec3& n, const glm::vec3& c, float s, bool o,
             std::uint64_t weight) {
        const auto w = static_cast<double>(weight);
        position += w * glm::dvec3(p);
        normal += w * glm::dvec3(n);
        colour += w * glm::dvec3(c);
        spacing += w * static_cast<double>(s);
        count += weight;
        oriented += o ? weight : 0;
    }
    [[nodiscard]] CellSurfel surfel(std::uint8_t facing, float min_spacing) const {
        CellSurfel s;
        const double inv = 1.0 / static_cast<double>(count);
        s.position = glm::vec3(position * inv);
        const double length = glm::length(normal);
        s.normal = length > 1e-9 * static_cast<double>(count) ? glm::vec3(normal / length)
                                                              : glm::vec3(0.0f);
        s.colour = glm::vec3(colour * inv);
        s.spacing = std::max(static_cast<float>(spacing * inv), min_spacing);
        s.count = static_cast<std::uint32_t>(
            std::min<std::uint64_t>(count, std::numeric_limits<std::uint32_t>::max()));
        s.facing = facing;
        s.oriented = oriented == count ? 1 : 0;
        return s;
    }
};

// One cell's sums per facing. A cell nearly always holds one or two facings: only those are
// cleared and read, not all seven (which cost more than the sums themselves).
class CellSums {
public:
    void add(std::uint8_t facing, const glm::vec3& p, const glm::vec3& n, const glm::vec3& c,
             float s, bool o, std::uint64_t weight) {
        const auto bit = static_cast<std::uint8_t>(1u << facing);
        if ((used_ & bit) == 0) {
            sums_[facing] = FacingSum{};
            used_ = static_cast<std::uint8_t>(used_ | bit);
        }
        sums_[facing].add(p, n, c, s, o, weight);
    }
    // Appends the cell's surfels in facing order and clears the sums; returns how many.
    std::uint32_t emit(std::vector<CellSurfel>& out, float min_spacing) {
        std::uint32_t emitted = 0;
        for (std::uint8_t f = 0; f < kFacings; ++f) {
            if ((used_ & (1u << f)) != 0) {
                out.push_back(sums_[f].surfel(f, min_spacing));
                ++emitted;
            }
        }
        used_ = 0;
        return emitted;
    }

private:
    std::array<FacingSum, kFacings> sums_;
    std::uint8_t used_ = 0;
};

// Fills a level's surfels: per chunk of cells, `visitor_for(first, last)` gives the function
// `visit(cell, sums)` that adds a cell's members, and the non-empty facings become the cell's
// surfels in facing order. Chunks run on all cores and are joined in order.
template <class VisitorFor>
void fill_surfels(PointHierarchy::Level& level, VisitorFor&& visitor_for, Progress* progress) {
    const std::size_t cells = level.cell_count();
    const std::size_t chunks = (cells + kCellChunk - 1) / kCellChunk;
    std::vector<std::vector<CellSurfel>> chunk_surfels(chunks);
    std::vector<std::uint32_t> per_cell(cells, 0);
    const float min_spacing = kCellSurfelSpacing * level.cell_size;
    tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t chunk) {
        if (progress != nullptr) {
            progress->throw_if_cancelled();
        }
        const std::size_t end = std::min(cells, (chunk + 1) * kCellChunk);
        std::vector<CellSurfel>& out = chunk_surfels[chunk];
        auto visit = visitor_for(chunk * kCellChunk, end);
        CellSums sums;
        for (std::size_t c = chunk * kCellChunk; c < end; ++c) {
            visit(c, sums);
            per_cell[c] = sums.emit(out, min_spacing);
        }
    });
    level.first_surfel.assign(cells + 1, 0);
    for (std::size_t c = 0; c < cells; ++c) {
        level.first_surfel[c + 1] = level.first_surfel[c] + per_cell[c];
    }
    level.surfels.reserve(level.first_surfel[cells]);
    for (const std::vector<CellSurfel>& part : chunk_surfels) {
        level.surfels.insert(level.surfels.end(), part.begin(), part.end());
    }
}

// The cells of keys >> (3·shift) over sorted `keys`: their keys and the runs they start.
void split_runs(const std::vector<std::uint64_t>& keys, int shift,
                std::vector<std::uint64_t>& cell_keys, std::vector<std::uint32_t>& first) {
    cell_keys.clear();
    first.clear();
    const int bits = 3 * shift;
    for (std::size_t i = 0; i < keys.size(); ++i) {
        const std::uint64_t k = keys[i] >> bits;
        if (cell_keys.empty() || cell_keys.back() != k) {
            cell_keys.push_back(k);
            first.push_back(static_cast<std::uint32_t>(i));
        }
    }
    first.push_back(static_cast<std::uint32_t>(keys.size()));
}

float median_spacing(const std::vector<float>& spacing) {
    const std::size_t step = std::max<std::size_t>(1, spacing.size() / 8192);
    std::vector<float> sample;
    for (std::size_t i = 0; i < spacing.size(); i += step) {
        if (spacing[i] > 0.0f && std::isfinite(spacing[i])) {
            sample.push_back(spacing[i]);
        }
    }
    if (sample.empty()) {
        return 0.0f;
    }
    std::nth_element(sample.begin(), sample.begin() + sample.size() / 2, sample.end());
    return sample[sample.size() / 2];
}

} // namespace

std::size_t PointHierarchy::memory_bytes() const {
    std::size_t bytes = order.size() * sizeof(std::uint32_t);
    for (const Level& level : levels) {
        bytes += level.cell_keys.size() * sizeof(std::uint64_t) +
                 (level.first_point.size() + level.first_child.size() + level.first_surfel.size()) *
                     sizeof(std::uint32_t) +
                 level.surfels.size() * sizeof(CellSurfel);
    }
    return bytes;
}

std::size_t PointHierarchy::surfel_count() const {
    std::size_t count = 0;
    for (const Level& level : levels) {
        count += level.surfels.size();
    }
    return count;
}

PointHierarchy build_point_hierarchy(const PointCloud& cloud, const LocalGeometry& geometry,
                                     Progress* progress) {
    const std::size_t n = cloud.size();
    if (geometry.normals.size() != n || geometry.spacing.size() != n ||
        geometry.oriented.size() != n) {
        throw InputError("point hierarchy: local geometry does not belong to this cloud");
    }
    if (n > std::numeric_limits<std::uint32_t>::max()) {
        throw InputError("point hierarchy: at most 2^32-1 points per cloud");
    }
    PointHierarchy h;
    if (n == 0) {
        return h;
    }
    if (progress != nullptr) {
        progress->begin_stage("building the point hierarchy", 1);
    }
    morton::SortedPoints sorted = morton::sort_points(cloud.positions, geometry.spatial_order);
    if (progress != nullptr) {
        progress->throw_if_cancelled();
    }
    h.origin = sorted.origin;
    h.cube_size = sorted.cube_size;
    h.order = std::move(sorted.order);
    const std::vector<std::uint64_t>& keys = sorted.keys;
    const float base_cell = sorted.cell_size(0);

    // Levels from cells of about two point spacings up to a sixteenth of the cube.
    const float spacing = median_spacing(geometry.spacing);
    const int top_shift = morton::kBitsPerAxis - kTopCellsPerAxisLog2;
    int finest_shift = top_shift + 1; // no level: the cloud is too sparse for its extent
    if (spacing > 0.0f) {
        const float cells = kFinestCellSpacings * spacing / base_cell;
        finest_shift = std::max(1, static_cast<int>(std::ceil(std::log2(std::max(cells, 1.0f)))));
    }
    h.intensity = PointColours::intensity_range(cloud);
    const PointColours colour_of(cloud, h.intensity);
    for (int shift = finest_shift; shift <= top_shift; ++shift) {
        PointHierarchy::Level level;
        level.shift = shift;
        level.cell_size = sorted.cell_size(shift);
        if (h.levels.empty()) {
            split_runs(keys, shift, level.cell_keys, level.first_point);
            fill_surfels(
                level,
                [&](std::size_t first_cell, std::size_t last_cell) {
                    // The chunk's points in curve order, gathered in one tight loop first: the
                    // cloud's arrays are in file order, and a loop that does nothing but load
                    // keeps many of those scattered reads in flight at once.
                    const std::uint32_t first = level.first_point[first_cell];
                    const std::uint32_t count = level.first_point[last_cell] - first;
                    std::vector<glm::vec3> position(count);
                    std::vector<glm::vec3> normal(count);
                    std::vector<glm::vec3> colour(count);
                    std::vector<float> point_spacing(count);
                    std::vector<std::uint8_t> oriented(count);
                    for (std::uint32_t k = 0; k < count; ++k) {
                        const std::uint32_t i = h.order[first + k];
                        position[k] = cloud.positions[i];
                        normal[k] = geometry.normals[i];
                        colour[k] = colour_of(i);
                        point_spacing[k] = geometry.spacing[i];
                        oriented[k] = geometry.oriented[i];
                    }
                    return
                        [&level, first, position = std::move(position), normal = std::move(normal),
                         colour = std::move(colour), point_spacing = std::move(point_spacing),
                         oriented = std::move(oriented)](std::size_t c, CellSums& sums) {
                            for (std::uint32_t j = level.first_point[c];
                                 j < level.first_point[c + 1]; ++j) {
                                const std::uint32_t k = j - first;
                                const bool known_sign = oriented[k] != 0;
                                glm::vec3 towards = normal[k];
                                const std::uint8_t f = facing_of(towards, known_sign);
                                // An unoriented normal joins its facing with the facing's sign.
                                if (!known_sign && f != kNoFacing && towards[f / 2] < 0.0f) {
                                    towards = -towards;
                                }
                                sums.add(f, position[k], towards, colour[k], point_spacing[k],
                                         known_sign, 1);
                            }
                        };
                },
                progress);
        } else {
            const PointHierarchy::Level& below = h.levels.back();
            split_runs(below.cell_keys, 1, level.cell_keys, level.first_child);
            level.first_point.resize(level.first_child.size());
            for (std::size_t c = 0; c < level.first_child.size(); ++c) {
                level.first_point[c] = below.first_point[level.first_child[c]];
            }
            fill_surfels(
                level,
                [&](std::size_t /*first_cell*/, std::size_t /*last_cell*/) {
                    return [&](std::size_t c, CellSums& sums) {
                        for (std::uint32_t k = below.first_surfel[level.first_child[c]];
                             k < below.first_surfel[level.first_child[c + 1]]; ++k) {
                            const CellSurfel& s = below.surfels[k];
                            sums.add(s.facing, s.position, s.normal, s.colour, s.spacing,
                                     s.oriented != 0, s.count);
                        }
                    };
                },
                progress);
        }
        // Each level's cell keys are the finest keys >> 3·shift, its cells' Morton keys.
        h.levels.push_back(std::move(level));
    }
    return h;
}

namespace {

// Distance from `p` to the axis-aligned box [lo, lo + size]³.
float box_distance(const glm::vec3& p, const glm::vec3& lo, float size) {
    const glm::vec3 d = glm::max(glm::max(lo - p, p - (lo + glm::vec3(size))), glm::vec3(0.0f));
    return glm::length(d);
}

// Cell `cell`'s run in `runs` (cells + 1 offsets), checked to lie within [0, limit].
std::pair<std::uint32_t, std::uint32_t>
run_of(std::span<const std::uint32_t> runs, std::size_t cell, std::size_t limit, const char* what) {
    const std::uint32_t first = runs[cell];
    const std::uint32_t last = runs[cell + 1];
    if (first > last || last > limit) {
        throw IoError(std::string("point hierarchy: a cell's run of ") + what +
                      " lies outside its array (the hierarchy's file is damaged)");
    }
    return {first, last};
}

CellSurfel surfel_at(const PointHierarchyView::Level& level, std::uint32_t i) {
    CellSurfel s;
    std::memcpy(static_cast<void*>(&s), level.surfels + std::size_t{i} * sizeof(CellSurfel),
                sizeof(CellSurfel));
    return s;
}

// Whether the surfels of cell `cell`'s children (surfels [first_surfel, last_surfel) are its
// own) say no more than its own: each within `colour_tolerance` per channel of the cell's
// surfel of the same facing, and within `plane_tolerance` of that surfel's plane.
bool children_agree(const PointHierarchyView& h, std::size_t level_index, std::size_t cell,
                    std::uint32_t first_surfel, std::uint32_t last_surfel, float colour_tolerance,
                    float plane_tolerance) {
    const PointHierarchyView::Level& level = h.levels[level_index];
    const PointHierarchyView::Level& below = h.levels[level_index - 1];
    std::array<CellSurfel, kFacings> own{};
    std::array<bool, kFacings> has{};
    for (std::uint32_t k = first_surfel; k < last_surfel; ++k) {
        const CellSurfel s = surfel_at(level, k);
        if (s.facing >= kFacings) {
            return false;
        }
        own[s.facing] = s;
        has[s.facing] = true;
    }
    const auto [first_child, last_child] =
        run_of(level.first_child, cell, below.cell_count(), "children");
    for (std::uint32_t child = first_child; child < last_child; ++child) {
        const auto [first, last] = run_of(below.first_surfel, child, below.surfel_count, "surfels");
        for (std::uint32_t k = first; k < last; ++k) {
            const CellSurfel c = surfel_at(below, k);
            if (c.facing >= kFacings || !has[c.facing]) {
                return false;
            }
            const CellSurfel& p = own[c.facing];
            const glm::vec3 dc = glm::abs(c.colour - p.colour);
            if (!(std::max({dc.x, dc.y, dc.z}) <= colour_tolerance) ||
                !(std::abs(glm::dot(p.normal, c.position - p.position)) <= plane_tolerance)) {
                return false;
            }
        }
    }
    return true;
}

void collect(const PointHierarchyView& h, std::size_t level_index, std::size_t cell,
             const glm::vec3& centre, const CutRule& rule, HierarchyCut& out) {
    const PointHierarchyView::Level& level = h.levels[level_index];
    const glm::u64vec3 c = morton::cell(level.cell_keys[cell]);
    const glm::vec3 lo = h.origin + glm::vec3(c) * level.cell_size;
    const float d = box_distance(centre, lo, level.cell_size);
    // One surfel per facing and cell: at most lod_texels texels apart at d? And worth it: a
    // cell whose surfels stand for hardly more points than they are (a sparse cloud) would
    // only blur them (its surfels splat wider than its points), so its points are taken.
    const auto [first_point, last_point] = run_of(level.first_point, cell, h.point_count, "points");
    const auto [first_surfel, last_surfel] =
        run_of(level.first_surfel, cell, level.surfel_count, "surfels");
    const std::uint32_t points = last_point - first_point;
    const std::uint32_t surfels = last_surfel - first_surfel;
    if (surfels > kFacings) {
        throw IoError("point hierarchy: a cell holds more surfels than facings (the hierarchy's "
                      "file is damaged)");
    }
    const float reach = rule.lod_texels * rule.texel_angle * d; // lod_texels texels at d
    const bool fine_enough = level.cell_size <= reach;
    const bool agrees = !fine_enough && rule.colour_tolerance > 0.0f && level_index > 0 &&
                        level.cell_size <= 2.0f * reach &&
                        children_agree(h, level_index, cell, first_surfel, last_surfel,
                                       rule.colour_tolerance, 0.5f * rule.texel_angle * d);
    if ((fine_enough || agrees) && points >= kMinPointsPerSurfel * surfels) {
        const std::size_t at = out.surfels.size();
        out.surfels.resize(at + surfels);
        if (surfels > 0) {
            std::memcpy(static_cast<void*>(out.surfels.data() + at),
                        level.surfels + std::size_t{first_surfel} * sizeof(CellSurfel),
                        std::size_t{surfels} * sizeof(CellSurfel));
        }
        return;
    }
    if (level_index == 0) {
        if (h.order.empty()) {
            for (std::uint32_t k = first_point; k < last_point; ++k) {
                out.points.push_back(k);
            }
        } else {
            out.points.insert(out.points.end(), h.order.begin() + first_point,
                              h.order.begin() + last_point);
        }
        return;
    }
    const PointHierarchyView::Level& below = h.levels[level_index - 1];
    const auto [first_child, last_child] =
        run_of(level.first_child, cell, below.cell_count(), "children");
    // What a built hierarchy always is, checked because a mapped file's runs are read here
    // without having been checked whole: a cell's children are its own (their keys lie in its
    // key's eighth, in order) and their points tile its points. So no cell is visited twice
    // and no point is taken twice, however the file was damaged.
    std::uint32_t next_point = first_point;
    for (std::uint32_t child = first_child; child < last_child; ++child) {
        const std::uint64_t key = below.cell_keys[child];
        const auto [child_first, child_last] =
            run_of(below.first_point, child, h.point_count, "points");
        if ((key >> 3) != level.cell_keys[cell] ||
            (child > first_child && key <= below.cell_keys[child - 1]) ||
            child_first != next_point) {
            throw IoError("point hierarchy: a cell's children are not its own (the hierarchy's "
                          "file is damaged)");
        }
        next_point = child_last;
    }
    if (next_point != last_point) {
        throw IoError("point hierarchy: a cell's children do not hold its points (the "
                      "hierarchy's file is damaged)");
    }
    for (std::uint32_t child = first_child; child < last_child; ++child) {
        collect(h, level_index - 1, child, centre, rule, out);
    }
}

} // namespace

PointHierarchyView PointHierarchyView::of(const PointHierarchy& hierarchy) {
    PointHierarchyView v;
    v.origin = hierarchy.origin;
    v.cube_size = hierarchy.cube_size;
    v.point_count = hierarchy.order.size();
    v.order = hierarchy.order;
    for (const PointHierarchy::Level& level : hierarchy.levels) {
        Level l;
        l.shift = level.shift;
        l.cell_size = level.cell_size;
        l.cell_keys = level.cell_keys;
        l.first_point = level.first_point;
        l.first_child = level.first_child;
        l.first_surfel = level.first_surfel;
        l.surfels = reinterpret_cast<const std::byte*>(level.surfels.data());
        l.surfel_count = level.surfels.size();
        v.levels.push_back(l);
    }
    return v;
}

HierarchyCut cut_for_probe(const PointHierarchy& hierarchy, const glm::dvec3& centre,
                           const CutRule& rule, Progress* progress) {
    if (hierarchy.levels.empty() || !(rule.lod_texels > 0.0f)) {
        HierarchyCut cut;
        cut.points = hierarchy.order;
        return cut;
    }
    return cut_for_probe(PointHierarchyView::of(hierarchy), centre, rule, progress);
}

HierarchyCut cut_for_probe(const PointHierarchyView& hierarchy, const glm::dvec3& centre,
                           const CutRule& rule, Progress* progress) {
    HierarchyCut cut;
    if (hierarchy.levels.empty() || !(rule.lod_texels > 0.0f)) {
        if (hierarchy.order.empty()) {
            cut.points.resize(hierarchy.point_count);
            for (std::size_t k = 0; k < cut.points.size(); ++k) {
                cut.points[k] = static_cast<std::uint32_t>(k);
            }
        } else {
            cut.points.assign(hierarchy.order.begin(), hierarchy.order.end());
        }
        return cut;
    }
    if (!hierarchy.order.empty() && hierarchy.order.size() != hierarchy.point_count) {
        throw IoError("point hierarchy: its order does not hold every point");
    }
    for (std::size_t l = 0; l < hierarchy.levels.size(); ++l) {
        const PointHierarchyView::Level& level = hierarchy.levels[l];
        const std::size_t runs = level.cell_count() + 1;
        if (level.first_point.size() != runs || level.first_surfel.size() != runs ||
            level.first_child.size() != (l == 0 ? 0 : runs)) {
            throw IoError("point hierarchy: a level's runs do not match its cells (the "
                          "hierarchy's file is damaged)");
        }
    }
    const PointHierarchyView::Level& top = hierarchy.levels.back();
    for (std::size_t cell = 1; cell < top.cell_count(); ++cell) {
        if (top.cell_keys[cell] <= top.cell_keys[cell - 1]) {
            throw IoError("point hierarchy: the top level's cells are out of order (the "
                          "hierarchy's file is damaged)");
        }
    }
    const glm::vec3 c(centre);
    std::vector<HierarchyCut> parts(top.cell_count());
    tbb::parallel_for(std::size_t{0}, top.cell_count(), [&](std::size_t cell) {
        if (progress != nullptr) {
            progress->throw_if_cancelled();
        }
        collect(hierarchy, hierarchy.levels.size() - 1, cell, c, rule, parts[cell]);
    });
    std::size_t points = 0;
    std::size_t surfels = 0;
    for (const HierarchyCut& part : parts) {
        points += part.points.size();
        surfels += part.surfels.size();
    }
    cut.points.reserve(points);
    cut.surfels.reserve(surfels);
    for (const HierarchyCut& part : parts) {
        cut.points.insert(cut.points.end(), part.points.begin(), part.points.end());
        cut.surfels.insert(cut.surfels.end(), part.surfels.begin(), part.surfels.end());
    }
    return cut;
}

} // namespace lfprobe
