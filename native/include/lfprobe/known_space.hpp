// Where a probe set's probes know something about space (docs/DESIGN.md §4 "Rays that no probe
// can answer"): the voxels that hold a surface one of them stored (KnownSpace, for the set),
// and the voxels one probe saw free, in front of a surface it stored (SeenVoxels, per probe).
// A trace uses them to stop asking probes that cannot answer:
//   - a probe takes a ray on from where the others left it only where it saw that point free
//     (else its start texel is unknown, or behind its surface) or near a surface (a HIT there):
//     a probe that did neither is not asked;
//   - a probe answers HIT, or keeps a fallback, only near a surface it stored, and a set
//     without empty texels never answers MISS: past the last surface voxel along the ray that
//     the probes have not yet proven free, none can answer.
// Each answer of the field is the same with and without this; only the probes asked differ.
//
// The set's surfaces are built per probe from its texels and merged (the result does not depend
// on the order), written beside the probes at bake time, so that a set opened lazily has them
// without reading a probe. A trace dilates them once for its settings (mask): by the thickness
// or the fallback, whichever is larger, plus a few texel footprints at each voxel's distance, so
// that every point where a probe can meet its surface lies in a surface voxel of the mask. A
// probe's seen voxels are marked conservatively when the probe is read, and need no dilation.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "lfprobe/probe_map.hpp"
#include "lfprobe/ray.hpp"
#include "lfprobe/seen_directions.hpp"

namespace lfprobe {

inline constexpr const char* kKnownSpaceName = "known_space.bin";

// A dense bit per voxel over a box.
class VoxelMask {
public:
    VoxelMask() = default;
    VoxelMask(const glm::dvec3& origin, double voxel, const std::array<int, 3>& dims);

    // The largest t in [t_from, t_to] at which the ray is in a set voxel, or -inf when it meets
    // none there.
    [[nodiscard]] double last_set_t(const Ray& ray, double t_from, double t_to) const;
    // The same, with where the ray enters that voxel: {t_enter, t_leave} within [t_from, t_to],
    // or {-inf, -inf}.
    [[nodiscard]] std::pair<double, double> last_set_span(const Ray& ray, double t_from,
                                                          double t_to) const;
    // The first stretch of [t_from, t_to] inside the mask's box where the ray is in an unset
    // voxel: {t_enter, t_leave}, or {+inf, +inf} when it meets none there.
    [[nodiscard]] std::pair<double, double> first_unset_span(const Ray& ray, double t_from,
                                                             double t_to) const;
    // A mask `factor` times coarser whose voxel is set where any of its voxels is.
    [[nodiscard]] VoxelMask pooled(int factor) const;
    // Whether the voxel holding `point` is set (false outside the box). Inline, as is_set: a
    // trace asks it for every probe and cell a ray passes, and every voxel its walks cross.
    [[nodiscard]] bool contains(const glm::dvec3& point) const {
        if (bits_.empty()) {
            return false;
        }
        std::array<int, 3> cell{};
        for (int a = 0; a < 3; ++a) {
            const double u = std::floor((point[a] - origin_[a]) / voxel_);
            if (!(u >= 0.0 && u < static_cast<double>(dims_[static_cast<std::size_t>(a)]))) {
                return false;
            }
            cell[static_cast<std::size_t>(a)] = static_cast<int>(u);
        }
        return is_set(cell[0], cell[1], cell[2]);
    }

    [[nodiscard]] bool is_set(int x, int y, int z) const {
        const std::size_t i = index(x, y, z);
        return (bits_[i >> 6] >> (i & 63)) & 1U;
    }
    void set(int x, int y, int z);
    // Sets voxels x0..x1 (inclusive) of row (y, z): a word at a time, where a voxel at a time
    // was most of a mask's build (the first frame's).
    void set_run(int x0, int x1, int y, int z) {
        const std::size_t first = index(x0, y, z);
        const std::size_t last = index(x1, y, z);
        for (std::size_t w = first >> 6; w <= last >> 6; ++w) {
            const std::size_t lo = w == first >> 6 ? first & 63 : 0;
            const std::size_t hi = w == last >> 6 ? last & 63 : 63;
            const std::uint64_t upto = hi == 63 ? ~std::uint64_t{0} : (std::uint64_t{2} << hi) - 1;
            bits_[w] |= upto & ~((std::uint64_t{1} << lo) - 1);
        }
    }
    [[nodiscard]] const std::array<int, 3>& dims() const { return dims_; }
    [[nodiscard]] double voxel() const { return voxel_; }
    [[nodiscard]] const glm::dvec3& origin() const { return origin_; }
    [[nodiscard]] std::size_t set_count() const;
    [[nodiscard]] std::size_t memory_bytes() const { return bits_.size() * sizeof(std::uint64_t); }

private:
    [[nodiscard]] std::size_t index(int x, int y, int z) const {
        return static_cast<std::size_t>(x) +
               static_cast<std::size_t>(dims_[0]) *
                   (static_cast<std::size_t>(y) +
                    static_cast<std::size_t>(dims_[1]) * static_cast<std::size_t>(z));
    }

    glm::dvec3 origin_{0.0};
    double voxel_ = 1.0;
    std::array<int, 3> dims_{0, 0, 0};
    std::vector<std::uint64_t> bits_;
};

// What a trace asks of the known space, for one setting of thickness and fallback: the surface
// voxels dilated so that every point where a probe can meet a stored surface is in one.
struct KnownSpaceMask {
    VoxelMask surfaces;
    VoxelMask coarse_surfaces; // surfaces pooled: a ray's walk skips their empty stretches

    // surfaces.last_set_t, walking the coarse voxels and only the fine ones inside a set one.
    [[nodiscard]] double last_surface_t(const Ray& ray, double t_from, double t_to) const;
};

// The voxels one probe saw free (in front of a surface it stored), marked conservatively: a
// voxel is marked when some texel its directions reach (the rectangle of its corners' images
// in the octahedral map, per octant, one texel wider) holds a known surface at least as far as
// its nearest point. Kept in blocks of 8³ voxels, only where the probe saw something.
class SeenVoxels {
public:
    static constexpr double kVoxel = 0.1;

    SeenVoxels() = default;
    explicit SeenVoxels(const ProbeMap& map);

    // Whether the voxel holding `point` (in the set's local frame) is marked; true beyond the
    // region marked voxel by voxel where the probe saw further than it.
    [[nodiscard]] bool contains(const glm::dvec3& point) const;
    // Whether `point` lies where the probe saw further than its voxels were marked (then it
    // counts as seen).
    [[nodiscard]] bool beyond_exact_region(const glm::dvec3& point) const;
    // Marks every voxel `other` marks (the union: what any of several probes saw).
    void merge(const SeenVoxels& other);
    // The same voxels as a dense mask over the box of its blocks: a lookup without a search,
    // for unions asked about many times a ray; an empty mask when that would take more than
    // `max_bytes`.
    [[nodiscard]] VoxelMask dense(std::size_t max_bytes) const;
    [[nodiscard]] std::size_t voxel_count() const;
    [[nodiscard]] std::size_t memory_bytes() const { return blocks_.size() * sizeof(Block); }
    // Forgets the marked voxels, keeping the region (for a union held densely elsewhere).
    void drop_voxels() { std::vector<Block>().swap(blocks_); }

    // Appended to / read from a known-space file's bytes.
    void write_to(std::string& out) const;
    [[nodiscard]] static SeenVoxels read_from(const std::string& in, std::size_t& at,
                                              const std::string& path);
    friend bool operator==(const SeenVoxels& a, const SeenVoxels& b);

private:
    struct Block {
        std::int32_t x, y, z;              // block index: voxels 8x..8x+7, ...
        std::array<std::uint64_t, 8> bits; // bit (x + 8y) of word z
        friend bool operator==(const Block&, const Block&) = default;
    };
    std::vector<Block> blocks_; // sorted by (z, y, x)
    bool beyond_ = false;       // saw past [exact_low_, exact_high_): everything there counts
    glm::dvec3 exact_low_{0.0};
    glm::dvec3 exact_high_{0.0};
};

// What several probes saw together (the union of their SeenVoxels), as a trace asks it per
// ray: dense (a bit per voxel) where that fits a budget, else the merged blocks searched.
class SeenUnion {
public:
    // Adds one probe's seen voxels; null (a probe the known space does not list) makes the
    // union hold every point, so that such a probe is never passed over.
    void add(const SeenVoxels* seen);
    // Turns the union dense where its box takes at most `max_bytes`.
    void densify(std::size_t max_bytes);
    // The first t in [t_from, t_to] found outside both the union and `surfaces`, +inf when none
    // is (or the union is not held densely). Every point of the ray before a probe's HIT or
    // fallback meeting lies in one of the two (known_space.hpp), so no probe can answer past
    // it. Each voxel of the union the ray crosses unset is judged at the middle of the ray's
    // stretch in it: a point that lies outside both proves the ray leaves what is known, and a
    // stretch judged covered only lets the bound fall later (never wrongly early).
    [[nodiscard]] double first_unknown_t(const Ray& ray, double t_from, double t_to,
                                         const VoxelMask& surfaces) const;
    [[nodiscard]] bool contains(const glm::dvec3& point) const {
        return everywhere_ ||
               (is_dense_ ? dense_.contains(point) || sparse_.beyond_exact_region(point)
                          : sparse_.contains(point));
    }

private:
    SeenVoxels sparse_;
    VoxelMask dense_;
    bool is_dense_ = false;
    bool everywhere_ = false;
};

class KnownSpace {
public:
    // The voxel edge bakes use: fine enough that a trace's dilation (a few centimetres at the
    // default thickness and fallback) dominates it, coarse enough that a room's surfaces take a
    // few hundred thousand voxels.
    static constexpr double kSurfaceVoxel = 0.025;

    KnownSpace() = default;

    // Adds the surfaces and the seen voxels of `map`, probe `index` of the set (in the set's
    // local frame). Probes may be added into separate KnownSpaces (on several threads) and
    // merged; each probe is added once.
    void add_probe(const ProbeMap& map, std::size_t index);
    void merge(const KnownSpace& other);
    // The known space of a set of one probe (a probe baked on its own) as probe `index` of
    // another set: InputError unless it holds exactly one probe.
    [[nodiscard]] KnownSpace as_probe(std::size_t index) const;
    // What probe `index` saw free; null when it was not added.
    [[nodiscard]] const SeenVoxels* seen_by(std::size_t index) const;
    // The directions probe `index` knows; null when it was not added, or the file was written
    // before they were kept.
    [[nodiscard]] const SeenDirections* directions_of(std::size_t index) const;
    [[nodiscard]] std::size_t probes_added() const { return seen_.size(); }

    // Whether any probe added has an empty texel (a MISS is possible): then the known space
    // proves nothing about a ray's answer, and traces do not use it.
    [[nodiscard]] bool has_empty_texels() const { return has_empty_; }
    [[nodiscard]] std::size_t surface_voxel_count() const { return surfaces_.size(); }
    [[nodiscard]] double farthest_distance() const { return farthest_; }

    // The mask for a trace whose surfaces count within `margin` metres (the larger of the
    // thickness and the fallback, plus the distance quantum of packed probes) plus
    // `footprint_texels` texel footprints at their distance. A dense box is coarsened (never
    // shrunk) where it would exceed `max_side` voxels on an axis, or where dilating far surfaces
    // voxel by voxel would take too long.
    [[nodiscard]] KnownSpaceMask mask(double margin, double footprint_texels,
                                      int max_side = 512) const;

    // Binary file, written atomically; read throws InputError on a malformed file.
    void write(const std::string& path) const;
    [[nodiscard]] static KnownSpace read(const std::string& path);

    friend bool operator==(const KnownSpace& a, const KnownSpace& b);

private:
    struct SurfaceVoxel {
        std::int32_t x, y, z;
        float footprint; // the largest texel footprint (distance × sqrt(4π) / N) in the voxel
        friend bool operator==(const SurfaceVoxel&, const SurfaceVoxel&) = default;
    };
    static bool surface_order(const SurfaceVoxel& a, const SurfaceVoxel& b);
    static bool same_surface_voxel(const SurfaceVoxel& a, const SurfaceVoxel& b);
    class VoxelTable; // one entry a voxel while a probe is added
    void normalise();

    bool has_empty_ = false;
    double farthest_ = 0.0;
    std::vector<SurfaceVoxel> surfaces_;                     // sorted by (z, y, x), one per voxel
    std::vector<std::pair<std::uint64_t, SeenVoxels>> seen_; // by probe index
    std::vector<std::pair<std::uint64_t, SeenDirections>> directions_; // by probe index
};

// Adds the known space of the one-probe set in `probe_folder` to the set in `set_folder` as its
// probe `index` (a set grown a probe at a time, as adaptive placement does), written atomically.
// False, with the set's file removed, where either has none (a set whose known space lacks a
// probe's surfaces must not use it): the set then asks every probe on.
bool append_known_space(const std::string& set_folder, const std::string& probe_folder,
                        std::size_t index);

} // namespace lfprobe
