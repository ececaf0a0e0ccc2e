#include "lfprobe/probe_bake.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lfprobe/bake_scratch.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/octahedral.hpp"
#include "lfprobe/point_colours.hpp"
#include "texel_angle_bounds.hpp"

namespace lfprobe {

namespace {

constexpr std::uint64_t kNoPoint = std::numeric_limits<std::uint64_t>::max();
// A texel's winner key: off-centre angle bits (a non-negative float's, so bit 63 is free) over
// the point's id; bit 63 marks the far side of a cell surfel.
constexpr std::uint64_t kFarSide = std::uint64_t{1} << 63;
constexpr std::size_t kPointChunk = 65536;
// Points copied out of the source's arrays at a time (BakePoint): 24 KiB, within L1 or L2.
constexpr std::size_t kGatherBlock = 512;
// A point whose neighbours' mean lies this far off it, in 1/64 spacings (0.28 spacings), is
// taken to be at its surface's edge: at a straight edge the 12 neighbours' mean lies about one
// spacing inward; at a crease, where half of them lie on the other face, about half that;
// inside a surface within about 0.35 spacings (random sampling; near 0 on a scanner's regular
// pattern). An interior point taken for an edge point loses little: its splat past its "edge"
// still claims every texel no other surface reaches, and its neighbours' splats cover the rest.
// Lab room, 0.1° scans, a 2048² probe against the mesh-baked one: texels on another surface
// 0.94 % at 0.6 spacings (38), 0.89 % at 0.28 (18), 0.90 % at 0.09 (6), measured with a
// margin of 0.5 and the own texel's rule past an edge (for_each_splat_texel).
constexpr std::uint8_t kEdgeOffset = 18;

// Below this |cos| between the texel ray and the surfel normal the surfel plane is too
// grazing to extrapolate a depth from, and the point's own radial distance is used.
constexpr float kMinSplatPlaneCosine = 0.05f;

// A point as one probe sees it: offset v from the probe centre, its distance and direction,
// its normal (oriented toward its scanner where that is known, else toward the probe), normal·v
// (its plane's offset) and the reach of its splat's disc in its plane.
struct Surfel {
    glm::vec3 v;
    float dist = 0.0f;
    glm::vec3 dir;
    glm::vec3 normal;
    float normal_v = 0.0f;
    float reach = 0.0f;
    float splat_angle = 0.0f; // the splat's angular radius seen face-on from the probe
    // At a surface's edge: the unit direction to the surface's inside, and how far outward
    // (metres) the disc reaches; a negative reach: not at an edge, the whole disc.
    glm::vec3 inward{0.0f};
    float edge_reach = -1.0f;
};

// Where the ray from the probe centre along unit `texel_dir` meets a point's surface plane:
// the cosine between them, the depth s along the ray, and whether that is within the splat's
// disc. Found once per texel a splat covers: the cut of the splat and the texel's depth both
// read it.
struct PlaneHit {
    float cos_plane = 0.0f;
    float s = 0.0f;
    bool in_disc = false; // false too for a ray parallel to the plane (the disc seen edge-on)
    // In the disc but past the surface's edge (Surfel::edge_reach): the point claims the texel
    // only where no surface is known there.
    bool beyond_edge = false;
    // Outside the splat's core (BakeSettings::splat_core_scale): fills only where no core
    // reaches.
    bool fringe = false;
    // The texel the point lies in: on the texel's front surface it adds its colour whatever
    // kind of claim it made.
    bool own = false;
};

// Inlined: it runs once or twice for every texel every splat covers.
[[gnu::always_inline]] inline PlaneHit plane_hit(const Surfel& p, const glm::vec3& texel_dir) {
    PlaneHit h;
    h.cos_plane = glm::dot(p.normal, texel_dir);
    if (h.cos_plane == 0.0f) {
        return h;
    }
    h.s = p.normal_v / h.cos_plane;
    if (h.s > 0.0f) {
        const glm::vec3 off = h.s * texel_dir - p.v;
        h.in_disc = glm::dot(off, off) <= p.reach * p.reach;
        h.beyond_edge = p.edge_reach >= 0.0f && glm::dot(off, p.inward) < -p.edge_reach;
    }
    return h;
}

// cos(atan2(radius, distance)), the cosine of the angle a radius subtends at a distance (> 0),
// without the arctangent and the cosine: a fifth of a splat's own cost.
float cosine_of_angle_subtended(float radius, float distance) {
    return distance / std::sqrt(distance * distance + radius * radius);
}

// Depth along a texel's ray where it meets the point's surfel plane: exact for planar surfaces
// and consistent between neighbouring texels. A plane too grazing to extrapolate from, or one
// that puts the surface implausibly far from the point (beyond half to twice its distance, and
// outside the splat's disc), falls back to the point's own radial distance.
float surfel_depth(const Surfel& p, const PlaneHit& h) {
    if (std::abs(h.cos_plane) >= kMinSplatPlaneCosine &&
        ((h.s > 0.5f * p.dist && h.s < 2.0f * p.dist) || h.in_disc)) {
        return h.s;
    }
    return p.dist;
}

void keep_smaller(std::uint64_t& slot, std::uint64_t value) {
    std::atomic_ref<std::uint64_t> ref(slot);
    std::uint64_t current = ref.load(std::memory_order_relaxed);
    while (value < current &&
           !ref.compare_exchange_weak(current, value, std::memory_order_relaxed)) {
    }
}

// How much of a texel a point's colour stands for: 1 at the texel's centre, falling to 0 at the
// edge of a disc of the texel's half angle or the point's splat angle, whichever is larger (a
// cloud denser than the texels averages the points in each texel; a sparser one blends the
// nearest points' splats). off_centre is 1 - cos of the angle from the texel's centre.
float texel_colour_weight(float off_centre, float half_texel_angle, float splat_angle) {
    const float radius = std::max(half_texel_angle, splat_angle);
    const float angle2 = 2.0f * off_centre; // 1 - cos θ ≈ θ² / 2
    return std::max(0.0f, 1.0f - angle2 / (radius * radius));
}

// A weighted sum of colours in fixed point, added with atomics: integer sums do not depend on
// the order of the additions, so the mean is the same for any thread count.
struct ColourSum {
    static constexpr float kWeightScale = 4096.0f;  // 12 fractional bits of weight
    static constexpr float kColourScale = 65536.0f; // 16 fractional bits of colour
    // No initialisers, so that a map's worth is made unset and zeroed in parallel (filled).
    std::uint64_t weight;
    std::array<std::uint64_t, 3> rgb;

    // A point's colour in fixed point, made once per point rather than once per texel.
    using Quantised = std::array<std::uint64_t, 3>;
    static Quantised quantised(const glm::vec3& colour) {
        return {quantised(colour.x), quantised(colour.y), quantised(colour.z)};
    }
    void add(const Quantised& colour, float w) {
        const auto qw = static_cast<std::uint64_t>(std::lround(w * kWeightScale));
        if (qw == 0) {
            return;
        }
        std::atomic_ref<std::uint64_t>(weight).fetch_add(qw, std::memory_order_relaxed);
        for (std::size_t c = 0; c < 3; ++c) {
            std::atomic_ref<std::uint64_t>(rgb[c]).fetch_add(colour[c] * qw,
                                                             std::memory_order_relaxed);
        }
    }
    // Colours are non-negative (the readers clamp); larger than 2^16 they saturate.
    static std::uint64_t quantised(float colour) {
        return static_cast<std::uint64_t>(
            std::lround(std::clamp(colour, 0.0f, 65535.0f) * kColourScale));
    }
    // The mean, or `fallback` (one of the colours added) when nothing was added or every colour
    // added was the fallback's: a surface of one colour keeps exactly that colour.
    [[nodiscard]] glm::vec3 mean(const glm::vec3& fallback) const {
        if (weight == 0 ||
            (rgb[0] == quantised(fallback.x) * weight && rgb[1] == quantised(fallback.y) * weight &&
             rgb[2] == quantised(fallback.z) * weight)) {
            return fallback;
        }
        const double scale = 1.0 / (static_cast<double>(weight) * kColourScale);
        return {static_cast<float>(static_cast<double>(rgb[0]) * scale),
                static_cast<float>(static_cast<double>(rgb[1]) * scale),
                static_cast<float>(static_cast<double>(rgb[2]) * scale)};
    }
};

// `count` copies of `value`, written on all cores: a 2048² map's texel buffers are 200 MB,
// which a vector's constructor writes on one thread.
template <class T>
ScratchArray<T> filled(std::size_t count, const T& value) {
    ScratchArray<T> out(count);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, std::size_t{1} << 16),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          std::fill(out.get() + range.begin(), out.get() + range.end(), value);
                      });
    return out;
}

// Non-negative floats order like their bit patterns.
std::uint32_t ordered_bits(float non_negative) {
    return std::bit_cast<std::uint32_t>(non_negative);
}

// A texel's front: its depth's bits, below two flags that order the kinds of splat: a fringe's
// (PlaneHit::fringe) only where no core reaches, and past a surface's edge only where nothing
// else does.
constexpr std::uint64_t kFringe = std::uint64_t{1} << 32;
constexpr std::uint64_t kBeyondEdge = std::uint64_t{1} << 33;

std::uint64_t front_key(const PlaneHit& hit, float depth) {
    return (hit.beyond_edge ? kBeyondEdge : 0u) | (hit.fringe ? kFringe : 0u) | ordered_bits(depth);
}

// What a bake splats, visited j = 0 … count() - 1: id(j) names the visited point (a texel's
// winner among equally central points is the smaller id), and the attributes are read by id.
// Every point of a cloud, in spatial order: neighbouring points write neighbouring texels,
// which keeps the texel buffers in cache.
struct CloudPoints {
    const PointCloud& cloud;
    const LocalGeometry& geometry;
    PointColours colours;
    bool spatial;

    CloudPoints(const PointCloud& c, const LocalGeometry& g)
        : cloud(c), geometry(g), colours(c), spatial(g.spatial_order.size() == c.size()) {}
    [[nodiscard]] std::size_t count() const { return cloud.size(); }
    [[nodiscard]] std::size_t id(std::size_t j) const {
        return spatial ? std::size_t{geometry.spatial_order[j]} : j;
    }
    [[nodiscard]] glm::vec3 position(std::size_t i) const { return cloud.positions[i]; }
    [[nodiscard]] glm::vec3 normal(std::size_t i) const { return geometry.normals[i]; }
    [[nodiscard]] bool oriented(std::size_t i) const { return geometry.oriented[i] != 0; }
    [[nodiscard]] float spacing(std::size_t i) const { return geometry.spacing[i]; }
    [[nodiscard]] SurfaceEdge edge(std::size_t i) const {
        return geometry.edges.size() == cloud.size() ? geometry.edges[i] : SurfaceEdge{};
    }
    [[nodiscard]] glm::vec3 colour(std::size_t i) const { return colours(i); }
    [[nodiscard]] static bool is_cell_surfel(std::size_t /*i*/) { return false; }
    [[nodiscard]] static bool gather_whole() { return false; }
};

// A probe's cut of the point hierarchy: its full-density points first, then its cell surfels.
struct CutPoints {
    const PointCloud& cloud;
    const LocalGeometry& geometry;
    const PointColours& colours;
    const HierarchyCut& cut;
    bool scattered;

    [[nodiscard]] std::size_t count() const { return cut.size(); }
    [[nodiscard]] std::size_t id(std::size_t j) const { return j; }
    [[nodiscard]] const CellSurfel* surfel(std::size_t i) const {
        return i < cut.points.size() ? nullptr : &cut.surfels[i - cut.points.size()];
    }
    [[nodiscard]] glm::vec3 position(std::size_t i) const {
        const CellSurfel* s = surfel(i);
        return s != nullptr ? s->position : cloud.positions[cut.points[i]];
    }
    [[nodiscard]] glm::vec3 normal(std::size_t i) const {
        const CellSurfel* s = surfel(i);
        return s != nullptr ? s->normal : geometry.normals[cut.points[i]];
    }
    [[nodiscard]] bool oriented(std::size_t i) const {
        const CellSurfel* s = surfel(i);
        return s != nullptr ? s->oriented != 0 : geometry.oriented[cut.points[i]] != 0;
    }
    [[nodiscard]] float spacing(std::size_t i) const {
        const CellSurfel* s = surfel(i);
        return s != nullptr ? s->spacing : geometry.spacing[cut.points[i]];
    }
    // A cell surfel stands for a whole cell's points: no edge of its own.
    [[nodiscard]] SurfaceEdge edge(std::size_t i) const {
        return surfel(i) == nullptr && geometry.edges.size() == cloud.size()
                   ? geometry.edges[cut.points[i]]
                   : SurfaceEdge{};
    }
    [[nodiscard]] glm::vec3 colour(std::size_t i) const {
        const CellSurfel* s = surfel(i);
        return s != nullptr ? s->colour : colours(cut.points[i]);
    }
    [[nodiscard]] bool is_cell_surfel(std::size_t i) const { return i >= cut.points.size(); }
    // Whether the cut's points lie scattered over the arrays (a cloud in its own order) rather
    // than in the cut's order (gathered, or a copy in curve order): then the bake copies them
    // out once (id(j) is j).
    [[nodiscard]] bool gather_whole() const { return scattered; }
};

// What the splat passes read of one visited point, copied out of the source's arrays a block
// at a time: a cut's points lie scattered over the cloud's arrays (a cache miss per attribute
// and pass), and a block copied in one tight loop keeps many of those misses in flight where
// the splat's arithmetic between them kept one or two.
struct BakePoint {
    glm::vec3 position;
    float spacing;
    glm::vec3 normal;
    std::uint32_t edge; // the SurfaceEdge's bytes: no initialiser, so an array of these is
                        // left unset until written
    glm::vec3 colour;
    std::uint32_t id;
    bool oriented;
    bool cell_surfel;
};

// A splat's shape as a probe sees it, found by the first pass and read by the second: its
// direction's texel, its search radius, its angular radius and that angle's cosine (an
// arctangent and a cosine a point, and the octahedral encoding). 16 bytes a point.
struct SplatShape {
    std::uint16_t x, y; // resolutions are at most 16384
    std::uint16_t radius;
    float splat_angle;
    float cos_alpha;
};
// Up to this many points keep their shapes (512 MiB): a cut stays below it (about twice the
// probe's texels); a bake of every point of a larger cloud finds them again instead.
constexpr std::size_t kMaxKeptShapes = std::size_t{32} << 20;

template <class Source>
BakePoint bake_point(const Source& source, std::size_t i) {
    BakePoint b{};
    b.position = source.position(i);
    b.spacing = source.spacing(i);
    b.normal = source.normal(i);
    b.edge = std::bit_cast<std::uint32_t>(source.edge(i));
    b.colour = source.colour(i);
    b.id = static_cast<std::uint32_t>(i);
    b.oriented = source.oriented(i);
    b.cell_surfel = source.is_cell_surfel(i);
    return b;
}

// A texel's angle at the settings' resolution, as the cuts take it.
float texel_angle_of(const BakeSettings& settings) {
    return static_cast<float>(oct::kTexelAngleTimesN) / static_cast<float>(settings.resolution);
}

CutRule cut_rule_of(const BakeSettings& settings) {
    return {texel_angle_of(settings), settings.lod_texels, settings.lod_colour_tolerance};
}

void check_bake_arguments(const BakeSettings& settings, std::size_t points,
                          const LocalGeometry& geometry, const glm::dvec3& centre) {
    const int n = settings.resolution;
    if (n < 2 || n > 16384) {
        throw InputError("bake: resolution must be between 2 and 16384, got " + std::to_string(n));
    }
    if (!(settings.splat_plane_reach > 0.0f) || !std::isfinite(settings.splat_plane_reach)) {
        throw InputError("bake: splat_plane_reach must be a positive number of splat radii");
    }
    if (!(settings.lod_texels >= 0.0f) || !std::isfinite(settings.lod_texels)) {
        throw InputError("bake: lod_texels must be a finite number of texels, 0 or more");
    }
    if (!(settings.lod_colour_tolerance >= 0.0f) || !std::isfinite(settings.lod_colour_tolerance)) {
        throw InputError(
            "bake: lod_colour_tolerance must be a finite colour difference, 0 or more");
    }
    if (points > std::numeric_limits<std::uint32_t>::max()) {
        throw InputError("bake: at most 2^32-1 points per cloud");
    }
    if (geometry.normals.size() != points || geometry.spacing.size() != points) {
        throw InputError("bake: local geometry does not belong to this cloud");
    }
    if (!(std::isfinite(centre.x) && std::isfinite(centre.y) && std::isfinite(centre.z))) {
        throw InputError("bake: probe position must be finite");
    }
}

template <class Source>
ProbeMap bake_from(const Source& source, const glm::dvec3& centre, const BakeSettings& settings,
                   Progress* progress) {
    const int n = settings.resolution;
    ProbeMap map(n, centre);
    const std::size_t texels = map.texel_count();
    const TexelAngleBounds& texel_angles = TexelAngleBounds::of(n);
    // Scratch arrays come from the set's scope where there is one (bake_scratch.hpp).
    const ScratchArray<glm::vec3> directions(texels);
    tbb::parallel_for(0, n, [&](int y) {
        for (int x = 0; x < n; ++x) {
            directions[oct::texel_index({x, y}, n)] = oct::texel_direction({x, y}, n);
        }
    });
    const int max_radius = std::max(1, std::min(settings.max_splat_radius_texels, n / 2));
    const std::size_t count = source.count();

    // A point as this probe sees it; false for a point at the probe centre (no direction).
    auto surfel_of = [&](const BakePoint& b, Surfel& p) {
        p.v = glm::vec3(glm::dvec3(b.position) - centre);
        p.dist = glm::length(p.v);
        if (!(p.dist >= settings.min_distance)) {
            return false;
        }
        p.dir = p.v / p.dist;
        p.normal = !b.oriented && glm::dot(b.normal, p.v) > 0.0f ? -b.normal : b.normal;
        p.normal_v = glm::dot(p.normal, p.v);
        p.reach = settings.splat_plane_reach * settings.splat_scale * b.spacing;
        const auto edge = std::bit_cast<SurfaceEdge>(b.edge);
        if (settings.splat_edge_margin >= 0.0f && edge.offset >= kEdgeOffset) {
            p.inward = glm::normalize(glm::vec3(edge.inward[0], edge.inward[1], edge.inward[2]));
            p.edge_reach = settings.splat_edge_margin * b.spacing;
        }
        return true;
    };
    // Calls visit(texel, surfel, plane hit) for every texel point i's splat covers: the texels
    // in the cone of the splat radius seen face-on whose ray meets the point's surface plane
    // within splat_plane_reach splat radii of the point (BakeSettings says why).
    // The splat's shape as the first pass found it, kept for the second when the points are
    // few enough (SplatShape): the direction's texel, the cone and the search radius.
    const ScratchArray<SplatShape> shapes(count <= kMaxKeptShapes ? count : 0);
    auto for_each_splat_texel = [&](const BakePoint& b, std::size_t j, bool again, auto&& visit) {
        Surfel p;
        if (!surfel_of(b, p)) {
            return;
        }
        oct::Texel home;
        float cos_alpha = 0.0f;
        int r = 0;
        if (again && shapes) {
            const SplatShape& shape = shapes[j];
            home = {shape.x, shape.y};
            p.splat_angle = shape.splat_angle;
            cos_alpha = shape.cos_alpha;
            r = shape.radius;
        } else {
            home = oct::texel_of_direction(p.dir, n);
            const float splat_radius = settings.splat_scale * b.spacing;
            p.splat_angle = std::atan2(splat_radius, p.dist);
            cos_alpha = cosine_of_angle_subtended(splat_radius, p.dist);
            // A neighbour k texels away lies at least (k - 0.5) texel angles from `dir`.
            r = texel_angles.search_radius(home, p.splat_angle, max_radius);
            if (shapes) {
                shapes[j] = {static_cast<std::uint16_t>(home.x), static_cast<std::uint16_t>(home.y),
                             static_cast<std::uint16_t>(r), p.splat_angle, cos_alpha};
            }
        }
        // Made when a neighbour first needs it: most points claim only their own texel.
        float cos_core = std::numeric_limits<float>::quiet_NaN();
        auto core_cosine = [&] {
            if (std::isnan(cos_core)) {
                cos_core =
                    settings.splat_core_scale >= settings.splat_scale
                        ? -2.0f // every covered texel is core
                        : cosine_of_angle_subtended(settings.splat_core_scale * b.spacing, p.dist);
            }
            return cos_core;
        };
        // A point with no surface (too few neighbours for a normal) keeps the whole cone.
        const bool has_plane = glm::dot(p.normal, p.normal) > 0.0f;
        // The point always claims its own texel; neighbours only inside its cone where their
        // ray meets the point's surface plane near the point. Its own texel is a core's claim
        // only where the texel's centre lies on the point's disc and not past its surface's
        // edge; else the point fills it as a fringe, or as a splat past its edge: with several
        // points a texel, the nearest surface won every texel any of its points fell in, and a
        // foreground grew by up to a texel along its silhouettes. A point alone still shows.
        // Lab room, 0.1° scans, a 2048² probe against the mesh-baked one: texels on another
        // surface 0.97 → 0.86 %, with kEdgeOffset as it is now. (A splat_edge_margin of 0.2
        // would make it 0.78 %, but thins the hard scene's blinds: 1 % of their pixels then
        // show the facade behind them.)
        auto claim = [&](std::size_t t, bool own) {
            const glm::vec3& texel_dir = directions[t];
            PlaneHit hit = plane_hit(p, texel_dir);
            if (!own && has_plane && !hit.in_disc) {
                return;
            }
            // Its own texel: a fringe where the texel's centre lies off the point's disc.
            hit.fringe =
                own ? has_plane && !hit.in_disc : glm::dot(texel_dir, p.dir) < core_cosine();
            hit.own = own;
            visit(t, p, hit);
        };
        const int side = 2 * r + 1;
        if (home.x >= r && home.y >= r && home.x + r < n && home.y + r < n && side <= 32) {
            // Away from the map's edges the square needs no folding and its rows are runs of
            // the direction table: a row's cone test is made for all its texels, without a
            // branch, into a mask of the texels to claim (most of the square lies outside the
            // cone, and a branch per texel mispredicted often).
            for (int dy = -r; dy <= r; ++dy) {
                const std::size_t first = oct::texel_index({home.x - r, home.y + dy}, n);
                std::uint32_t mask = 0;
                for (int k = 0; k < side; ++k) {
                    mask |= static_cast<std::uint32_t>(
                                !(glm::dot(directions[first + static_cast<std::size_t>(k)], p.dir) <
                                  cos_alpha))
                            << k;
                }
                if (dy == 0) {
                    mask |= std::uint32_t{1} << r;
                }
                while (mask != 0) {
                    const int k = std::countr_zero(mask);
                    mask &= mask - 1;
                    claim(first + static_cast<std::size_t>(k), dy == 0 && k == r);
                }
            }
            return;
        }
        for (int dy = -r; dy <= r; ++dy) {
            for (int dx = -r; dx <= r; ++dx) {
                const std::size_t t =
                    oct::texel_index(oct::wrap_texel(home.x + dx, home.y + dy, n), n);
                const bool own = dx == 0 && dy == 0;
                if (!own && glm::dot(directions[t], p.dir) < cos_alpha) {
                    continue;
                }
                claim(t, own);
            }
        }
    };
    // A scattered cut (Source::gather_whole) is copied out once for both passes and the resolve, in
    // parallel: its points bound the copy (about the probe's texels), where a whole cloud's
    // copy would grow with the cloud, so that one is copied a block at a time per pass.
    // Left unset until the copy writes it: zeroing first would touch every page on one thread.
    const ScratchArray<BakePoint> gathered(source.gather_whole() ? count : 0);
    if (gathered) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, kGatherBlock),
                          [&](const tbb::blocked_range<std::size_t>& range) {
                              for (std::size_t j = range.begin(); j < range.end(); ++j) {
                                  gathered[j] = bake_point(source, source.id(j));
                              }
                          });
    }
    auto over_points = [&](const char* stage, auto&& per_point) {
        if (progress != nullptr) {
            progress->begin_stage(stage, count);
        }
        tbb::parallel_for(
            std::size_t{0}, (count + kPointChunk - 1) / kPointChunk, [&](std::size_t chunk) {
                if (progress != nullptr) {
                    progress->throw_if_cancelled();
                }
                const std::size_t end = std::min(count, (chunk + 1) * kPointChunk);
                if (gathered) {
                    for (std::size_t j = chunk * kPointChunk; j < end; ++j) {
                        per_point(gathered[j], j);
                    }
                } else {
                    std::array<BakePoint, kGatherBlock> block;
                    for (std::size_t b = chunk * kPointChunk; b < end; b += kGatherBlock) {
                        const std::size_t m = std::min(kGatherBlock, end - b);
                        for (std::size_t q = 0; q < m; ++q) {
                            block[q] = bake_point(source, source.id(b + q));
                        }
                        for (std::size_t q = 0; q < m; ++q) {
                            per_point(block[q], b + q);
                        }
                    }
                }
                if (progress != nullptr) {
                    progress->advance(end - chunk * kPointChunk);
                }
            });
    };

    // Pass 1: the nearest surface depth per texel among the splats of its first kind: cores,
    // then fringes, then splats past their surface's edge (front_key).
    // All bits set: no splat yet (above every depth, of any kind).
    const auto front = filled(texels, ~std::uint64_t{0});
    over_points("splatting points: depth", [&](const BakePoint& b, std::size_t j) {
        for_each_splat_texel(b, j, false, [&](std::size_t t, const Surfel& p, const PlaneHit& hit) {
            keep_smaller(front[t], front_key(hit, surfel_depth(p, hit)));
        });
    });
    // Pass 2: the points on that front surface (within a surface thickness of about the point
    // spacing). The one whose direction is closest to the texel's centre gives the texel its
    // normal (and, through its plane, its depth); the colour is the mean of all of them,
    // weighted by how much of the texel each covers (texel_colour_weight): a texel's radiance
    // is the average of what it covers, not one sample. Sums are integers, so the colour is
    // the same for any thread count and any order of the points.
    const float half_texel_angle =
        0.5f * static_cast<float>(oct::kTexelAngleTimesN) / static_cast<float>(n);
    const auto winner = filled(texels, kNoPoint);
    const auto colour_sums = filled(texels, ColourSum{0, {0, 0, 0}});
    over_points("splatting points: colour", [&](const BakePoint& b, std::size_t j) {
        const float thickness = b.spacing;
        const ColourSum::Quantised rgb = ColourSum::quantised(b.colour);
        for_each_splat_texel(b, j, true, [&](std::size_t t, const Surfel& p, const PlaneHit& hit) {
            const float depth = surfel_depth(p, hit);
            const bool same_kind = hit.beyond_edge == ((front[t] & kBeyondEdge) != 0) &&
                                   hit.fringe == ((front[t] & kFringe) != 0);
            if (!same_kind && !hit.own) {
                return; // a splat past its edge where another surface is known, or the reverse
            }
            const float nearest = std::bit_cast<float>(static_cast<std::uint32_t>(front[t]));
            const float within = std::max(thickness, 1e-3f * nearest);
            if (depth > nearest + within || (!same_kind && depth < nearest - within)) {
                return; // behind the front, or (a point in the texel) on a nearer surface
            }
            // A cell surfel is as thick as its cell, so the far side of a thin object can lie
            // within it of the near side: one whose known normal faces away from the probe is
            // that far side. It gives no colour, and wins a texel only where no surfel facing
            // the probe reaches it (the top bit orders it last).
            const bool far_side = b.cell_surfel && b.oriented && p.normal_v > 0.0f;
            // From the chord: 1 - dot rounds to steps of 6e-8 near 1, a sixth of a 2048² texel's
            // half angle squared (the colour weights came in sixths, the winner's order in ties).
            const glm::vec3 chord = directions[t] - p.dir;
            const float off_centre = 0.5f * glm::dot(chord, chord);
            keep_smaller(winner[t],
                         (far_side ? kFarSide : std::uint64_t{0}) |
                             (static_cast<std::uint64_t>(ordered_bits(off_centre)) << 32) | b.id);
            if (!far_side) {
                colour_sums[t].add(
                    rgb, texel_colour_weight(off_centre, half_texel_angle, p.splat_angle));
            }
        });
    });

    // Resolve every texel's winning point and colour into the maps.
    auto resolve = [&](std::size_t t) {
        const auto id = static_cast<std::uint32_t>(winner[t] & 0xffffffffu);
        const BakePoint b = gathered ? gathered[id] : bake_point(source, id);
        const glm::vec3 rgb = colour_sums[t].mean(b.colour);
        Surfel p{};
        (void)surfel_of(b, p); // a winner was splatted, so it has a direction
        // BakeSettings::face_the_probe: a winner facing away is turned toward the centre.
        const glm::vec3 normal = settings.face_the_probe && glm::dot(p.normal, directions[t]) > 0.0f
                                     ? -p.normal
                                     : p.normal;
        map.set_surface(t, surfel_depth(p, plane_hit(p, directions[t])), rgb, normal, 1.0f);
    };
    // With the hole fill on, a texel that no splat's core reached (only a fringe, or a splat
    // past its surface's edge: front_key's flags) goes to the fill first. Such a claim fills a
    // sliver beside a silhouette where the scans did not see the surface behind, and grew the
    // near surface there by up to a texel; the fill continues the surface behind (a
    // disocclusion) or the near one across a gap in it. Where the fill leaves it unknown (a
    // hole too wide, or open to what no scan saw) the claim stands: no sliver is left unknown
    // that a splat reached. Lab room, 0.1° scans, the demo's 2048² grid, four views, 16 samples
    // a pixel: PSNR at a probe -0.07 to +0.14 dB, 0.4 m from one +0.06 to +0.09, 0.77 m -0.06
    // to +0.35 (docs/DESIGN.md §4; ProbeBake.ASliverOnlyAFringeReachesIsTheFillsFirst).
    const int fill_width = hole_fill_width(settings);
    const bool fills_holes = fill_width > 0;
    auto only_fringes = [&](std::size_t t) { return (front[t] & (kFringe | kBeyondEdge)) != 0; };
    tbb::parallel_for(std::size_t{0}, texels, [&](std::size_t t) {
        if (winner[t] != kNoPoint && !(fills_holes && only_fringes(t))) {
            resolve(t);
        }
    });
    if (progress != nullptr) {
        progress->throw_if_cancelled();
    }
    // The paper's bake (no hole filling) keeps what its points show; a gap is opened only
    // where the fill can close it.
    if (fills_holes) {
        (void)open_gaps_in_nearer_surfaces(
            map, std::min(sieve_gap_reach(n), std::max(1, fill_width / 2)));
    }
    fill_small_holes(map, fill_width);
    if (fills_holes) {
        std::atomic<bool> restored{false};
        tbb::parallel_for(std::size_t{0}, texels, [&](std::size_t t) {
            if (winner[t] != kNoPoint && only_fringes(t) && map.state(t) == TexelState::Unknown) {
                resolve(t);
                restored.store(true, std::memory_order_relaxed);
            }
        });
        if (restored.load()) {
            // A restored claim closes off again a hole that, joined through the sliver to a
            // wider one, was too wide for the fill: a second fill fills it, as before the
            // sliver went to the fill (the demo's 2048² grid: 22,171 texels; the real pump
            // room's 512² grid: 0.21 % of its texels, 16 of its view's 13,501 HIT pixels lost
            // instead of 139; ProbeBake.AHoleARestoredSliverClosesOffIsFilledByASecondFill).
            fill_small_holes(map, fill_width);
        }
    }
    return map;
}

} // namespace

ProbeMap bake_probe_from_cloud(const PointCloud& cloud, const LocalGeometry& geometry,
                               const glm::dvec3& centre, const BakeSettings& settings,
                               Progress* progress) {
    check_bake_arguments(settings, cloud.size(), geometry, centre);
    return bake_from(CloudPoints(cloud, geometry), centre, settings, progress);
}

int default_hole_fill_texels(int resolution) {
    return std::max(4, static_cast<int>(std::lround(12.0 * resolution / 512.0)));
}

int hole_fill_width(const BakeSettings& settings) {
    return settings.hole_fill_texels < 0 ? default_hole_fill_texels(settings.resolution)
                                         : settings.hole_fill_texels;
}

PointHierarchy hierarchy_for_bakes(const PointCloud& cloud, const LocalGeometry& geometry,
                                   const BakeSettings& settings, Progress* progress) {
    return settings.lod_texels > 0.0f ? build_point_hierarchy(cloud, geometry, progress)
                                      : PointHierarchy{};
}

ProbeMap bake_probe_from_hierarchy(const PointCloud& cloud, const LocalGeometry& geometry,
                                   const PointHierarchy& hierarchy, const glm::dvec3& centre,
                                   const BakeSettings& settings, Progress* progress) {
    check_bake_arguments(settings, cloud.size(), geometry, centre);
    if (!(settings.lod_texels > 0.0f) || hierarchy.levels.empty()) {
        return bake_from(CloudPoints(cloud, geometry), centre, settings, progress);
    }
    if (hierarchy.order.size() != cloud.size()) {
        throw InputError("bake: the point hierarchy does not belong to this cloud");
    }
    const HierarchyCut cut = cut_for_probe(hierarchy, centre, cut_rule_of(settings), progress);
    const PointColours colours(cloud, hierarchy.intensity);
    return bake_from(CutPoints{cloud, geometry, colours, cut, true}, centre, settings, progress);
}

HierarchyCut cut_for_bake(const PointHierarchyView& hierarchy, const glm::dvec3& centre,
                          const BakeSettings& settings, const std::string& source,
                          Progress* progress) {
    if (!(settings.lod_texels > 0.0f) || !std::isfinite(settings.lod_texels)) {
        throw InputError("bake: " + source +
                         " bakes from the point hierarchy's cuts; lod_texels must be above 0");
    }
    if (settings.resolution < 2 || settings.resolution > 16384) {
        throw InputError("bake: resolution must be between 2 and 16384, got " +
                         std::to_string(settings.resolution));
    }
    if (!(std::isfinite(centre.x) && std::isfinite(centre.y) && std::isfinite(centre.z))) {
        throw InputError("bake: probe position must be finite");
    }
    return cut_for_probe(hierarchy, centre, cut_rule_of(settings), progress);
}

ProbeMap bake_probe_from_gathered_cut(const PointCloud& points, const LocalGeometry& geometry,
                                      const HierarchyCut& cut, const glm::dvec3& centre,
                                      const BakeSettings& settings, Progress* progress) {
    check_bake_arguments(settings, points.size(), geometry, centre);
    if (!points.has_colors() && points.size() > 0) {
        throw InputError("bake: a gathered cut carries its points' colours");
    }
    for (const std::uint32_t i : cut.points) {
        if (i >= points.size()) {
            throw InputError("bake: a cut names a point it did not gather");
        }
    }
    const PointColours colours(points);
    return bake_from(CutPoints{points, geometry, colours, cut, false}, centre, settings, progress);
}

} // namespace lfprobe
