// A loaded probe set ready for tracing (docs/DESIGN.md §4 "Many probes"): every probe's maps and
// its coarse min-distance levels, and the two ways of asking several probes about one ray.
//
// Nearest: the probes nearest the ray's origin are tried in order of distance (up to
// max_probes); a HIT or a MISS answers, an UNKNOWN passes the ray on to the next probe, which
// starts where the previous ones proved the ray free. Grid: the ray walks the grid's cells
// (3D DDA, any counts, clamped at the faces, never wrapped) and in each cell tries its corner
// probes nearest first from where the ray enters the cell; a ray that misses the grid's box is
// traced nearest-first. Probe traces always start at the distance already proven free, never
// at the grid's box, so surfaces between a camera outside the grid and the grid are seen.
#pragma once

#include <atomic>
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "lfprobe/grid_walk.hpp"
#include "lfprobe/known_space.hpp"
#include "lfprobe/min_distance_pyramid.hpp"
#include "lfprobe/probe_map.hpp"
#include "lfprobe/probe_placement.hpp"
#include "lfprobe/probe_set.hpp"
#include "lfprobe/probe_trace.hpp"
#include "lfprobe/progress.hpp"
#include "lfprobe/radiance_filter.hpp"
#include "lfprobe/radiance_mips.hpp"
#include "lfprobe/ray.hpp"

namespace lfprobe {

enum class FieldMode {
    Auto,    // Grid when the set is laid out as a grid, Nearest otherwise
    Nearest, // nearest probes to the ray origin first
    Grid,    // walk the grid's cells; only for sets laid out as a grid
};

// "auto", "nearest", "grid"; InputError for anything else.
[[nodiscard]] FieldMode field_mode_from_name(const std::string& name);
[[nodiscard]] const char* field_mode_name(FieldMode mode);

struct FieldTraceSettings {
    TraceSettings probe;
    FieldMode mode = FieldMode::Auto;
    int max_probes = 8; // Nearest: how many of the nearest probes are tried
    // How a HIT's colour is read from the probe that answered (radiance_filter.hpp).
    RadianceFilter filter = RadianceFilter::Bilinear;
    // How many probes a HIT's colour is blended from (probe_blend.hpp), the one that answered
    // included, at most 8; 1: the answering probe alone, as the paper does.
    int blend = 4;
    // The angle one of the eye's samples spans (radians): the footprint filter's width. 0: no
    // footprint (the footprint filter reads as bilinear). The renderer sets it from the camera.
    double sample_angle = 0.0;
    // Leave out probes that know nothing (every texel unknown: they answer UNKNOWN wherever a
    // ray starts), and so the cells all of whose corners know nothing (false: ask them; the
    // same answer, only slower; for tests and measurements).
    bool skip_probes_that_know_nothing = true;
    // At most this many probes are asked about one ray (0: as many as the walk reaches); a ray
    // none of them answers is UNKNOWN, or a HIT on a fallback one of them kept. A bound trades
    // answers for time where most rays find no answer (a partial scan's unseen parts): it is
    // not exact, and its effect is measured, not assumed.
    int max_probes_per_ray = 0;
    // Stop asking probes where the set's known space (known_space.hpp) shows that none can
    // answer: the ray now starts where no probe saw free space or a surface, or it is proven
    // free past every surface along it. Only for sets without empty texels (no MISS anywhere)
    // with a known space, as every bake writes (false: ask on; the same answer, only slower;
    // for tests and measurements).
    bool stop_where_no_probe_can_answer = true;
    // A HIT on a hole-filled texel (TexelState::Inferred: the bake's guess where its probe saw
    // nothing) is kept aside while the other probes are asked: a HIT or MISS one of them
    // measured wins, and the guess answers only where none does (before any fallback meeting).
    // An eye at a probe keeps its own lookup, guesses included: from the centre whose hole
    // fill made the guess it scored better than the other probes' answers (docs/DESIGN.md §4).
    // false: the first probe that answers HIT wins, guess or not, as the paper's first-hit rule
    // (and the renderer before 2026-11-27).
    bool prefer_measured = true;
};

struct FieldTraceResult {
    TraceStatus status = TraceStatus::Unknown;
    double t = std::numeric_limits<double>::infinity(); // HIT: distance along the ray
    double free_until = 0.0;  // the ray is proven free on [t_min, free_until]
    glm::vec3 radiance{0.0f}; // HIT: linear RGB
    glm::vec3 normal{0.0f};   // HIT: stored surface normal
    int probe = -1;           // the probe that answered HIT or MISS; -1 when none did
    oct::Texel texel{-1, -1}; // HIT: the texel of that probe
    std::uint32_t steps = 0;  // texels visited (coarse and fine) over every probe tried
    std::uint32_t probes_tried = 0;
};

class ProbeField {
public:
    // Opens the probe set in `folder`: the manifest, then every probe and its coarse levels, in
    // parallel. Progress counts probes; cancellation is honoured between probes. With `lazy`,
    // only the manifest is read and each probe file is checked to be there: a probe's maps are
    // decoded the first time a trace asks for them (from any thread, once), so a view starts
    // at once and loads only the probes it reaches; a probe file that cannot be read is then
    // an error of that trace.
    // `coarse_resolution` is the size of the coarsest min-distance level kept (the level a
    // trace starts its skipping from): 0 or 1 keeps every level down to 1×1; a larger value
    // drops the levels below it (less memory, more steps per ray). `storage` is how the probes
    // are held in memory (probe_storage.hpp); none: as the manifest says (full precision
    // when it says nothing).
    [[nodiscard]] static ProbeField load(const std::string& folder, Progress* progress = nullptr,
                                         int coarse_resolution = 0,
                                         const std::optional<ProbeStorage>& storage = {},
                                         bool lazy = false);

    // A field over probes already in memory, in the placement's index order (probe i of a grid
    // is x + counts[0] * (y + counts[1] * z)). The probes' own positions are where they are
    // traced from. Throws InputError when counts or spacings do not fit.
    ProbeField(const ProbePlacement& placement, std::vector<ProbeMap> probes,
               const glm::dvec3& world_offset = glm::dvec3(0.0));

    [[nodiscard]] const ProbeSetManifest& manifest() const { return manifest_; }
    // The folder it was loaded from; empty for probes built in memory.
    [[nodiscard]] const std::string& folder() const { return folder_; }
    // How the probes are held in memory.
    [[nodiscard]] const ProbeStorage& storage() const { return manifest_.storage; }
    [[nodiscard]] const glm::dvec3& world_offset() const { return manifest_.world_offset; }
    [[nodiscard]] bool is_grid() const { return manifest_.placement.is_grid; }
    [[nodiscard]] const ProbeGrid& grid() const { return manifest_.placement.grid; }
    [[nodiscard]] std::size_t probe_count() const { return manifest_.probes.size(); }
    // Probe i's maps and coarse levels (read on first use when the set was opened lazily).
    [[nodiscard]] const ProbeMap& probe(std::size_t i) const { return slot(i).map; }
    [[nodiscard]] const MinDistancePyramid& levels(std::size_t i) const { return slot(i).levels; }
    // Where probe i stands and its resolution, without reading its maps.
    [[nodiscard]] const glm::dvec3& probe_position(std::size_t i) const {
        return manifest_.probes.at(i).position;
    }
    [[nodiscard]] int probe_resolution(std::size_t i) const {
        return manifest_.probes.at(i).resolution;
    }
    // True when every texel of probe i is unknown: as its manifest record says for a set
    // opened lazily, as its maps say otherwise.
    [[nodiscard]] bool knows_nothing(std::size_t i) const { return knows_nothing_.at(i) != 0; }
    // How many probes' maps are in memory (all of them unless opened lazily).
    [[nodiscard]] std::size_t loaded_probe_count() const;
    // Probe i's prefiltered radiance (the footprint filter's); every probe's are built on the
    // first call, from any thread, and kept: memory only sets that are rendered with it pay.
    [[nodiscard]] const RadianceMips& radiance_mips(std::size_t i) const;
    // Where the probes know something about space (read with the set, or built from the probes
    // when it was opened whole and has no known-space file); null when the set carries none.
    [[nodiscard]] const KnownSpace* known_space() const { return known_space_.get(); }
    // The known space's masks for `settings` (built on first use for each distinct thickness
    // and fallback, from any thread, and kept); null where they cannot prove anything (no known
    // space, or a set with empty texels).
    [[nodiscard]] const KnownSpaceMask* known_space_mask(const TraceSettings& settings) const;
    // Whether probe i may have seen `point` (local frame) free: false only where its known
    // space says it did not (known_space.hpp's SeenVoxels); never reads the probe.
    [[nodiscard]] bool saw_free(std::size_t i, const glm::dvec3& point) const;
    // Whether probe i's texel holds a hole-filled surface (TexelState::Inferred); false in
    // compact storage, which keeps no confidence. Reads the probe (it is in memory once traced).
    [[nodiscard]] bool is_inferred(std::size_t i, oct::Texel texel) const;
    // Whether probe i's trace would answer `ray` (local frame) UNKNOWN where it starts, at its
    // first texel, judged from the directions the known space says it knows (SeenDirections);
    // never reads the probe. False where the known space cannot tell.
    [[nodiscard]] bool passes_over(std::size_t i, const Ray& ray,
                                   const TraceSettings& settings) const;
    // The same for any probe of the set, and for any corner probe of a grid cell.
    [[nodiscard]] bool seen_by_any(const glm::dvec3& point) const;
    [[nodiscard]] bool seen_by_corners(const GridCell& cell, const glm::dvec3& point) const;
    // Where the ray (local frame), from t_from on, first reaches a point that no probe saw
    // free and no surface of `known` holds: no probe can answer past it (SeenUnion's
    // first_unknown_t). +inf where the known space cannot tell.
    [[nodiscard]] double first_unknown_t(const Ray& ray, double t_from,
                                         const KnownSpaceMask& known) const;
    // Maps and coarse levels of every probe in memory, and their prefiltered radiance once a
    // render with the footprint filter has built it.
    [[nodiscard]] std::size_t memory_bytes() const;

    // The mode `settings` asks for, with Auto resolved. InputError for Grid on a set that is
    // not a grid.
    [[nodiscard]] FieldMode resolve_mode(const FieldTraceSettings& settings) const;

    // Traces a ray given in the set's local frame (world minus world_offset); a HIT's colour is
    // filtered and blended as the settings say (probe_blend.hpp). trace_nearest and trace_grid
    // answer visibility only, with the colour of the texel met.
    [[nodiscard]] FieldTraceResult trace(const Ray& ray,
                                         const FieldTraceSettings& settings = {}) const;
    [[nodiscard]] FieldTraceResult trace_nearest(const Ray& ray,
                                                 const FieldTraceSettings& settings = {}) const;
    [[nodiscard]] FieldTraceResult trace_grid(const Ray& ray,
                                              const FieldTraceSettings& settings = {}) const;

    // One probe on its own (the ray in the local frame).
    [[nodiscard]] ProbeTraceResult trace_one(std::size_t probe, const Ray& ray,
                                             const TraceSettings& settings = {}) const;

private:
    // An eye this close to the probe that answered, in texels of parallax at the hit, sees
    // the hit's edge as the probe's centre does: a ray from the centre takes the edge rule of
    // the eye-at-probe lookup (majority_surface_texel), and a ray from within this parallax
    // takes it too, so that a render converges to the lookup's as the eye reaches the probe.
    static constexpr double kEdgeParallaxTexels = 1.0 / 16.0;
    void see_edge_as_the_centre_does(const Ray& ray, FieldTraceResult& hit,
                                     const FieldTraceSettings& settings) const;
    void see_edge_of_a_miss_as_the_centre_does(const Ray& ray, FieldTraceResult& hit) const;

    // One probe's maps, filled once: at load, or at first use for a lazily opened set.
    struct ProbeSlot {
        std::once_flag once;
        std::atomic<bool> ready{false};
        ProbeMap map;
        MinDistancePyramid levels;
    };
    struct ProbeSlots;

    ProbeField();
    void check_placement() const;
    [[nodiscard]] const ProbeSlot& slot(std::size_t i) const;
    void fill_slot(std::size_t i) const;
    void note_what_probes_know(bool from_maps);

    ProbeSetManifest manifest_;
    std::string folder_;
    int coarsest_level_ = 1;
    // Shared, so that copies of a field share what is loaded (the maps never change once read).
    std::shared_ptr<ProbeSlots> slots_;
    struct RadianceMipCache;
    std::shared_ptr<RadianceMipCache> radiance_mips_;
    std::vector<std::uint8_t> knows_nothing_; // per probe: 1 when every texel is unknown
    std::shared_ptr<const KnownSpace> known_space_;
    struct KnownSpaceMasks;
    std::shared_ptr<KnownSpaceMasks> known_space_masks_;
    void build_known_space_from_probes();
    [[nodiscard]] bool uses_known_space() const;
    void build_seen_unions() const;
    void build_seen_unions_once(KnownSpaceMasks& masks) const;
};

} // namespace lfprobe
