#include "lfprobe/probe_field.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <utility>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include "lfprobe/enum_names.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/grid_walk.hpp"
#include "lfprobe/probe_blend.hpp"
#include "lfprobe/probe_storage.hpp"

namespace lfprobe {

namespace {

// Probes a ray already asked, and how far each proved the ray free: asking again from no
// further on would give the same UNKNOWN. One slot per probe index mod 64, looked up directly
// (a ray of a partial scan asks the same few probes again and again): two probes of one ray
// that share a slot evict each other, and re-asking a probe is only wasted work, never wrong.
class TriedProbes {
public:
    [[nodiscard]] bool worth_asking(std::size_t probe, double from) const {
        const std::size_t slot = probe & 63U;
        return ((listed_ >> slot) & 1U) == 0 || slots_[slot].probe != probe ||
               from > slots_[slot].free_until;
    }
    void remember(std::size_t probe, double free_until) {
        const std::size_t slot = probe & 63U;
        slots_[slot] = {probe, free_until};
        listed_ |= std::uint64_t{1} << slot;
    }

private:
    struct Entry {
        std::size_t probe;
        double free_until;
    };
    // Read only where listed_ has the slot's bit: left unset, as most rays use a few.
    std::array<Entry, 64> slots_;
    std::uint64_t listed_ = 0;
};

// A probe's coarse levels down to `coarsest`. They bound what the trace reads: the packed
// distances when packed, and are held in the same 16-bit steps then.
MinDistancePyramid levels_of(const ProbeMap& map, int coarsest) {
    MinDistancePyramid levels(decoded_distances(map), map.resolution, coarsest);
    if (map.packed.distance_step > 0.0) {
        levels.quantise(map.packed.distance_step);
    }
    return levels;
}

// Asks probe `index` about the ray from `state.free_until` on; true when it answered.
struct FieldQuery {
    const ProbeField& field;
    const Ray& ray;
    const TraceSettings& settings;
    FieldTraceResult result;

    bool ask(std::size_t index) {
        if (checking()) {
            // A probe that saw neither free space nor a surface where the ray now starts would
            // answer UNKNOWN there: not asked (known_space.hpp).
            if (!start_near_surface() && !field.saw_free(index, start())) {
                return false;
            }
        }
        Ray local = ray;
        local.t_min = std::max(ray.t_min, result.free_until);
        // Its trace would stop at its first texel, UNKNOWN, proving nothing: not asked (nor
        // read). Judged the same for every ray whether the probe is in memory or not.
        if (known != nullptr && field.passes_over(index, local, settings)) {
            return false;
        }
        const ProbeTraceResult r = field.trace_one(index, local, settings);
        result.steps += r.steps();
        ++result.probes_tried;
        if (r.status == TraceStatus::Unknown) {
            result.free_until = std::max(result.free_until, r.free_until);
            if (r.has_fallback) {
                keep(KeptHit::kFallback, index, r, r.t_fallback, r.fallback_texel);
            }
            return false;
        }
        if (prefer_measured && r.status == TraceStatus::Hit && field.is_inferred(index, r.texel)) {
            keep(KeptHit::kGuess, index, r, r.t, r.texel);
            return false; // asked on from the same start: another probe may have measured it
        }
        answer(index, r, r.status, r.t, r.free_until, r.texel);
        return true;
    }

    // Probe `index`'s answer, its colour and normal from `r`, as the field's.
    void answer(std::size_t index, const ProbeTraceResult& r, TraceStatus status, double t,
                double free_until, oct::Texel texel) {
        result.status = status;
        result.t = t;
        result.free_until = free_until;
        result.radiance = r.radiance;
        result.normal = r.normal;
        result.probe = static_cast<int>(index);
        result.texel = texel;
    }

    // A HIT kept while other probes are asked, answered only if none of them does: a HIT on
    // a hole-filled texel (FieldTraceSettings::prefer_measured) outranks a probe's fallback
    // meeting (ProbeTraceResult::has_fallback), and of two of a kind the nearer along the ray
    // is kept. A later probe that proves the ray free past a fallback does not drop it: that
    // probe judged with the 1 cm thickness, and on a one-station scan its view behind the edge
    // is the hole fill's guess (the pump room's silhouettes stayed UNKNOWN when it did).
    void keep(int rank, std::size_t index, const ProbeTraceResult& r, double t, oct::Texel texel) {
        if (kept.rank < rank || (kept.rank == rank && kept.t <= t)) {
            return;
        }
        kept = {r, index, t, texel, rank};
    }

    // No probe answered: a HIT on the kept one, else UNKNOWN.
    void finish_unanswered() {
        if (kept.rank == KeptHit::kNone) {
            result.status = TraceStatus::Unknown;
            return;
        }
        answer(kept.probe, kept.result, TraceStatus::Hit, kept.t, kept.t, kept.texel);
    }

    // No probe is asked any more: FieldTraceSettings::max_probes_per_ray were asked, or the ray
    // is proven free past every surface voxel along it (stop_where_no_probe_can_answer,
    // known_space.hpp): a later probe could neither meet a surface nor keep a fallback (both
    // lie in surface voxels at or past where it starts), and a set without empty texels has no
    // MISS.
    [[nodiscard]] bool done() {
        if (max_probes > 0 && result.probes_tried >= static_cast<std::uint32_t>(max_probes)) {
            return true;
        }
        if (!checking()) {
            return false;
        }
        if (result.free_until != checked_from) {
            checked_from = result.free_until; // stuck rays ask again from the same point
            if (!start_near_surface() && !field.seen_by_any(start())) {
                return true; // no probe saw where the ray now starts, nor a surface there
            }
        }
        if (result.probes_tried < 2) {
            return false; // a ray one of the first probes answers never pays for the walk below
        }
        if (std::isnan(last_surface_t)) {
            if (start_near_surface()) {
                // A surface voxel holds where the ray now starts, and the probes proved the ray
                // free up to there: the last one before the first point no probe saw lies at or
                // past the start, and the walk below would not stop the ray now. (Were a point
                // before the start unseen after all, asking on costs asks, never an answer.)
                // Most rays of a complete scan that a third probe answers then never walk.
                return false;
            }
            // Past the first point no probe saw and no surface holds, none can answer either:
            // the last surface voxel before it bounds where a later probe can meet one.
            last_surface_t = known->last_surface_t(
                ray, ray.t_min, std::min(ray.t_max, field.first_unknown_t(ray, ray.t_min, *known)));
        }
        return result.free_until > last_surface_t;
    }

    // Whether the known space is asked: once a first probe did not answer. Most rays of a
    // complete scan are answered by the first probe asked, and pay nothing for it.
    [[nodiscard]] bool checking() const { return known != nullptr && result.probes_tried > 0; }

    // Where the ray now starts, and whether a surface voxel holds that point: asked for every
    // cell and probe until the ray moves on, so found once per start.
    [[nodiscard]] const glm::dvec3& start() {
        update_start();
        return start_point;
    }
    [[nodiscard]] bool start_near_surface() {
        update_start();
        return start_in_surface;
    }
    void update_start() {
        if (result.free_until != start_t) {
            start_t = result.free_until;
            start_point = ray.at(std::max(ray.t_min, result.free_until));
            start_in_surface = known->surfaces.contains(start_point);
        }
    }

    struct KeptHit {
        static constexpr int kGuess = 0; // ranks: the lower is kept
        static constexpr int kFallback = 1;
        static constexpr int kNone = 2;
        ProbeTraceResult result;
        std::size_t probe = 0;
        double t = std::numeric_limits<double>::infinity();
        oct::Texel texel{-1, -1};
        int rank = kNone;
    } kept;
    int max_probes = 0;
    const KnownSpaceMask* known = nullptr;
    double checked_from = std::numeric_limits<double>::quiet_NaN();
    double start_t = std::numeric_limits<double>::quiet_NaN(); // update_start's free_until
    glm::dvec3 start_point{0.0};
    bool start_in_surface = false;
    // The last t along the ray in a surface voxel (-inf: none); NaN until first needed.
    double last_surface_t = std::numeric_limits<double>::quiet_NaN();
    bool prefer_measured = true; // FieldTraceSettings::prefer_measured
};

// Candidate probes ordered by squared distance to `point`, ties by index (deterministic).
struct Candidate {
    double distance2;
    std::size_t index;
    friend bool operator<(const Candidate& a, const Candidate& b) {
        return a.distance2 < b.distance2 || (a.distance2 == b.distance2 && a.index < b.index);
    }
};

// Asks the candidates in order, again while one of them pushed the proven-free distance past
// where another had stopped (that one may now see further), up to a few passes. True when a
// probe answered.
bool ask_in_passes(FieldQuery& query, TriedProbes& tried, const Candidate* candidates,
                   std::size_t count) {
    constexpr int kMaxPasses = 4;
    for (int pass = 0; pass < kMaxPasses; ++pass) {
        const double before = query.result.free_until;
        for (std::size_t k = 0; k < count; ++k) {
            const std::size_t index = candidates[k].index;
            if (!tried.worth_asking(index, std::max(query.ray.t_min, query.result.free_until))) {
                continue;
            }
            if (query.done()) {
                return false;
            }
            if (query.ask(index)) {
                return true;
            }
            tried.remember(index, query.result.free_until);
        }
        if (!(query.result.free_until > before)) {
            break;
        }
    }
    return false;
}

// Sorts a handful of candidates (std::sort on a small std::array trips GCC 12's
// -Warray-bounds).
void sort_candidates(Candidate* first, std::size_t count) {
    for (std::size_t i = 1; i < count; ++i) {
        const Candidate c = first[i];
        std::size_t j = i;
        for (; j > 0 && c < first[j - 1]; --j) {
            first[j] = first[j - 1];
        }
        first[j] = c;
    }
}

constexpr auto field_mode_names = std::to_array<EnumName<FieldMode>>({
    {FieldMode::Auto, "auto"},
    {FieldMode::Nearest, "nearest"},
    {FieldMode::Grid, "grid"},
});

} // namespace

FieldMode field_mode_from_name(const std::string& name) {
    return value_named_or_throw(field_mode_names, name,
                                "probe field: mode '" + name +
                                    "' is not one of auto, nearest, grid");
}

const char* field_mode_name(FieldMode mode) {
    return name_of(field_mode_names, mode);
}

struct ProbeField::RadianceMipCache {
    std::once_flag built;
    std::atomic<bool> ready{false};
    std::vector<RadianceMips> mips;
};

namespace fs = std::filesystem;

// The known space's masks for each distinct (margin, footprint) a trace asked for; the last
// one asked is read without the lock (one render asks with the same settings for every ray).
struct ProbeField::KnownSpaceMasks {
    struct Entry {
        double margin;
        double footprint_texels;
        KnownSpaceMask mask;
    };
    // What any probe saw, what each probe saw, and per grid cell what its corner probes saw
    // (built once).
    std::once_flag unions_built;
    // Read before every per-ray query: an inline load where call_once is a library call.
    std::atomic<bool> unions_ready{false};
    SeenUnion any;
    std::vector<SeenUnion> cells;
    std::vector<SeenUnion> probes; // each a union of one
    // Each probe's known directions; null where the known space has none of its resolution.
    std::vector<const SeenDirections*> directions;
    // Added to their distance bounds: a packed probe's distances load up to a step off (its own
    // step where coarser, pack_probe; a surface nearer than half a step loads as one step), and
    // two steps keep each bound above the loaded distance through every rounding on the way.
    double directions_slack = 0.0;
    std::mutex mutex;
    std::vector<std::unique_ptr<Entry>> entries; // never removed: pointers stay valid
    std::atomic<const Entry*> last{nullptr};
};

struct ProbeField::ProbeSlots {
    explicit ProbeSlots(std::size_t count) : slots(count) {}
    std::vector<ProbeSlot> slots; // sized once: slots never move
};

ProbeField::ProbeField()
    : radiance_mips_(std::make_shared<RadianceMipCache>()),
      known_space_masks_(std::make_shared<KnownSpaceMasks>()) {}

const KnownSpaceMask* ProbeField::known_space_mask(const TraceSettings& settings) const {
    if (!uses_known_space()) {
        return nullptr;
    }
    // Where a probe can meet a stored surface, or keep one as its fallback: within the larger
    // of the two thicknesses of it in depth, plus the texel term, and within the texel's cone
    // sideways; an eye near the probe may take a neighbouring texel's surface (the edge rules).
    // Three footprints cover the widest octahedral texel's half-diagonal and one neighbour.
    constexpr double kSidewaysTexels = 3.0;
    double margin = std::max(settings.thickness, settings.fallback_thickness);
    const double step = storage().distance_step;
    if (step > 0.0) {
        // A packed probe's distances are off by up to one step, its own when coarser.
        margin += std::max(step, known_space_->farthest_distance() / 65534.0);
    }
    const double texels = std::max(settings.thickness_texels, 0.0) + kSidewaysTexels;
    KnownSpaceMasks& masks = *known_space_masks_;
    const KnownSpaceMasks::Entry* last = masks.last.load(std::memory_order_acquire);
    if (last != nullptr && last->margin == margin && last->footprint_texels == texels) {
        return &last->mask;
    }
    const std::lock_guard<std::mutex> lock(masks.mutex);
    for (const auto& entry : masks.entries) {
        if (entry->margin == margin && entry->footprint_texels == texels) {
            masks.last.store(entry.get(), std::memory_order_release);
            return &entry->mask;
        }
    }
    masks.entries.push_back(std::make_unique<KnownSpaceMasks::Entry>(
        KnownSpaceMasks::Entry{margin, texels, known_space_->mask(margin, texels)}));
    masks.last.store(masks.entries.back().get(), std::memory_order_release);
    return &masks.entries.back()->mask;
}

bool ProbeField::uses_known_space() const {
    return known_space_ != nullptr && !known_space_->has_empty_texels();
}

bool ProbeField::is_inferred(std::size_t i, oct::Texel texel) const {
    const ProbeMap& map = probe(i);
    return map.state(oct::texel_index(texel, map.resolution)) == TexelState::Inferred;
}

bool ProbeField::saw_free(std::size_t i, const glm::dvec3& point) const {
    if (known_space_ == nullptr) {
        return true;
    }
    build_seen_unions();
    const auto& probes = known_space_masks_->probes;
    return i >= probes.size() || probes[i].contains(point);
}

bool ProbeField::passes_over(std::size_t i, const Ray& ray, const TraceSettings& settings) const {
    if (known_space_ == nullptr) {
        return false;
    }
    build_seen_unions();
    const SeenDirections* directions = known_space_masks_->directions.at(i);
    if (directions == nullptr) {
        return false;
    }
    Ray local = ray;
    local.origin = ray.origin - probe_position(i);
    return directions->dismisses(local, settings, known_space_masks_->directions_slack);
}

bool ProbeField::seen_by_any(const glm::dvec3& point) const {
    build_seen_unions();
    return known_space_masks_->any.contains(point);
}

double ProbeField::first_unknown_t(const Ray& ray, double t_from,
                                   const KnownSpaceMask& known) const {
    build_seen_unions();
    return known_space_masks_->any.first_unknown_t(ray, t_from, ray.t_max, known.surfaces);
}

bool ProbeField::seen_by_corners(const GridCell& cell, const glm::dvec3& point) const {
    build_seen_unions();
    const ProbeGrid& g = grid();
    const auto cells = [&](std::size_t a) { return std::max(g.counts[a] - 1, 1); };
    const std::size_t i =
        static_cast<std::size_t>(cell[0]) +
        static_cast<std::size_t>(cells(0)) *
            (static_cast<std::size_t>(cell[1]) +
             static_cast<std::size_t>(cells(1)) * static_cast<std::size_t>(cell[2]));
    return known_space_masks_->cells.at(i).contains(point);
}

void ProbeField::build_seen_unions() const {
    KnownSpaceMasks& masks = *known_space_masks_;
    if (masks.unions_ready.load(std::memory_order_acquire)) {
        return;
    }
    std::call_once(masks.unions_built, [&] {
        build_seen_unions_once(masks);
        masks.unions_ready.store(true, std::memory_order_release);
    });
}

void ProbeField::build_seen_unions_once(KnownSpaceMasks& masks) const {
    if (known_space_ == nullptr) {
        return;
    }
    // Dense unions cost one bit per 10 cm voxel of their box: 128 MiB for the cells
    // together at most, 32 MiB for the whole set's.
    constexpr std::size_t kCellsBudget = std::size_t{128} << 20;
    constexpr std::size_t kProbesBudget = std::size_t{256} << 20;
    masks.probes.resize(probe_count());
    masks.directions.resize(probe_count());
    const double step = storage().distance_step;
    masks.directions_slack =
        step > 0.0 ? 2.0 * std::max(step, known_space_->farthest_distance() / kLargestDistanceCode)
                   : 0.0;
    for (std::size_t i = 0; i < probe_count(); ++i) {
        const SeenDirections* directions = known_space_->directions_of(i);
        if (directions != nullptr && directions->resolution() == probe_resolution(i)) {
            masks.directions[i] = directions;
        }
        const SeenVoxels* seen = known_space_->seen_by(i);
        masks.any.add(seen);
        masks.probes[i].add(seen);
    }
    masks.any.densify(std::size_t{32} << 20);
    tbb::parallel_for(std::size_t{0}, probe_count(), [&](std::size_t i) {
        masks.probes[i].densify(std::min(kProbesBudget / probe_count(), std::size_t{2} << 20));
    });
    if (!is_grid()) {
        return;
    }
    const ProbeGrid& g = grid();
    std::array<int, 3> cells{};
    for (std::size_t a = 0; a < 3; ++a) {
        cells[a] = std::max(g.counts[a] - 1, 1);
    }
    masks.cells.resize(static_cast<std::size_t>(cells[0]) * cells[1] * cells[2]);
    tbb::parallel_for(std::size_t{0}, masks.cells.size(), [&](std::size_t i) {
        const GridCell cell{static_cast<int>(i % cells[0]),
                            static_cast<int>((i / cells[0]) % cells[1]),
                            static_cast<int>(i / (static_cast<std::size_t>(cells[0]) * cells[1]))};
        std::array<std::size_t, 8> corners{};
        const std::size_t count = grid_cell_corners(g, cell, corners);
        for (std::size_t k = 0; k < count; ++k) {
            masks.cells[i].add(known_space_->seen_by(corners[k]));
        }
        masks.cells[i].densify(kCellsBudget / masks.cells.size());
    });
}

void ProbeField::build_known_space_from_probes() {
    std::vector<KnownSpace> parts(probe_count());
    tbb::parallel_for(std::size_t{0}, probe_count(),
                      [&](std::size_t i) { parts[i].add_probe(probe(i), i); });
    // Pairwise, so that each voxel is merged about log2(probes) times.
    for (std::size_t width = 1; width < parts.size(); width *= 2) {
        tbb::parallel_for(std::size_t{0}, parts.size(), 2 * width, [&](std::size_t i) {
            if (i + width < parts.size()) {
                parts[i].merge(parts[i + width]);
                parts[i + width] = KnownSpace();
            }
        });
    }
    known_space_ = std::make_shared<const KnownSpace>(std::move(parts.front()));
}

const ProbeField::ProbeSlot& ProbeField::slot(std::size_t i) const {
    const ProbeSlot& s = slots_->slots.at(i);
    if (!s.ready.load(std::memory_order_acquire)) {
        fill_slot(i);
    }
    return s;
}

void ProbeField::fill_slot(std::size_t i) const {
    ProbeSlot& s = slots_->slots.at(i);
    // A read that throws leaves the slot empty: the next use tries again and reports again.
    std::call_once(s.once, [&] {
        s.map = read_probe(folder_, manifest_, i);
        if (!manifest_.storage.is_full()) {
            pack_probe(s.map, manifest_.storage);
        }
        s.levels = levels_of(s.map, coarsest_level_);
        s.ready.store(true, std::memory_order_release);
    });
}

std::size_t ProbeField::loaded_probe_count() const {
    std::size_t loaded = 0;
    for (const ProbeSlot& s : slots_->slots) {
        loaded += s.ready.load(std::memory_order_acquire) ? 1 : 0;
    }
    return loaded;
}

const RadianceMips& ProbeField::radiance_mips(std::size_t i) const {
    RadianceMipCache& cache = *radiance_mips_;
    std::call_once(cache.built, [&] {
        cache.mips.resize(probe_count());
        tbb::parallel_for(std::size_t{0}, probe_count(),
                          [&](std::size_t k) { cache.mips[k] = RadianceMips(probe(k)); });
        cache.ready.store(true, std::memory_order_release);
    });
    return cache.mips.at(i);
}

ProbeField ProbeField::load(const std::string& folder, Progress* progress, int coarse_resolution,
                            const std::optional<ProbeStorage>& storage, bool lazy) {
    if (coarse_resolution < 0) {
        throw InputError(
            "probe field: coarse_resolution must be 0 (every level) or positive, got " +
            std::to_string(coarse_resolution));
    }
    ProbeField field;
    field.coarsest_level_ = std::max(coarse_resolution, 1);
    field.manifest_ = read_manifest(folder);
    field.folder_ = folder;
    const std::size_t count = field.manifest_.probes.size();
    if (count == 0) {
        throw InputError(folder + ": the probe set holds no probes");
    }
    field.check_placement();
    if (storage.has_value()) {
        use_storage(field.manifest_, *storage);
    }
    field.slots_ = std::make_shared<ProbeSlots>(count);
    if (!field.manifest_.known_space_file.empty()) {
        field.known_space_ = std::make_shared<const KnownSpace>(
            KnownSpace::read((fs::path(folder) / field.manifest_.known_space_file).string()));
    }
    if (lazy) {
        // Every probe's file must be there now, so that a missing one is a clear error of
        // opening the set rather than a surprise in the middle of a frame.
        for (const ProbeRecord& record : field.manifest_.probes) {
            const fs::path path = fs::path(folder) / record.file;
            std::error_code error;
            if (!fs::is_regular_file(path, error)) {
                throw MissingFileError(path.string() + ": no such probe file (listed in " + folder +
                                       "/manifest.json)");
            }
        }
        field.note_what_probes_know(false);
        return field;
    }
    if (progress != nullptr) {
        progress->begin_stage("loading probes", count);
    }
    tbb::parallel_for(std::size_t{0}, count, [&](std::size_t i) {
        if (progress != nullptr) {
            progress->throw_if_cancelled();
        }
        field.fill_slot(i);
        if (progress != nullptr) {
            progress->advance(1);
        }
    });
    for (std::size_t i = 0; i < count; ++i) {
        field.manifest_.probes[i].memory_bytes = field.probe(i).memory_bytes();
    }
    field.note_what_probes_know(true);
    if (field.known_space_ == nullptr) {
        field.build_known_space_from_probes(); // a set baked before bakes wrote it
    }
    return field;
}

ProbeField::ProbeField(const ProbePlacement& placement, std::vector<ProbeMap> probes,
                       const glm::dvec3& world_offset)
    : radiance_mips_(std::make_shared<RadianceMipCache>()),
      known_space_masks_(std::make_shared<KnownSpaceMasks>()) {
    manifest_.world_offset = world_offset;
    manifest_.placement = placement;
    if (probes.empty()) {
        throw InputError("probe field: no probes given");
    }
    for (std::size_t i = 0; i < probes.size(); ++i) {
        ProbeRecord record;
        record.file = probe_file_name(i);
        record.position = probes[i].position;
        record.resolution = probes[i].resolution;
        record.memory_bytes = probes[i].memory_bytes();
        manifest_.probes.push_back(record);
    }
    check_placement();
    slots_ = std::make_shared<ProbeSlots>(probes.size());
    tbb::parallel_for(std::size_t{0}, probes.size(), [&](std::size_t i) {
        if (!probes[i].is_complete()) {
            throw InputError("probe field: probe " + std::to_string(i) + " has no maps");
        }
        ProbeSlot& s = slots_->slots[i];
        std::call_once(s.once, [&] {
            s.map = std::move(probes[i]);
            s.levels = levels_of(s.map, 1);
            s.ready.store(true, std::memory_order_release);
        });
    });
    note_what_probes_know(true);
    build_known_space_from_probes();
}

void ProbeField::note_what_probes_know(bool from_maps) {
    knows_nothing_.assign(probe_count(), 0);
    for (std::size_t i = 0; i < probe_count(); ++i) {
        // A record without coverage (all zero) is not taken for one that knows nothing.
        const ProbeCoverage c = from_maps ? coverage_of(probe(i)) : manifest_.probes[i].coverage;
        knows_nothing_[i] =
            c.unknown >= 1.0 && c.surface == 0.0 && c.inferred == 0.0 && c.empty == 0.0 ? 1 : 0;
    }
}

void ProbeField::check_placement() const {
    const std::size_t count = manifest_.probes.size();
    if (!manifest_.placement.is_grid) {
        return;
    }
    const ProbeGrid& g = manifest_.placement.grid;
    for (int a = 0; a < 3; ++a) {
        const int c = g.counts[static_cast<std::size_t>(a)];
        if (c < 1) {
            throw InputError("probe field: grid counts must be at least 1 per axis");
        }
        if (c > 1 && !(g.spacing[a] > 0.0 && std::isfinite(g.spacing[a]))) {
            throw InputError("probe field: grid spacing must be positive on an axis with " +
                             std::to_string(c) + " probes");
        }
    }
    if (g.probe_count() != count) {
        throw InputError("probe field: the grid has " + std::to_string(g.probe_count()) +
                         " probes but " + std::to_string(count) + " were given");
    }
}

std::size_t ProbeField::memory_bytes() const {
    std::size_t bytes = 0;
    for (const ProbeSlot& s : slots_->slots) {
        if (s.ready.load(std::memory_order_acquire)) {
            bytes += s.map.memory_bytes() + s.levels.memory_bytes();
        }
    }
    if (radiance_mips_->ready.load(std::memory_order_acquire)) {
        for (const RadianceMips& m : radiance_mips_->mips) {
            bytes += m.memory_bytes();
        }
    }
    return bytes;
}

FieldMode ProbeField::resolve_mode(const FieldTraceSettings& settings) const {
    switch (settings.mode) {
    case FieldMode::Auto:
        return is_grid() ? FieldMode::Grid : FieldMode::Nearest;
    case FieldMode::Grid:
        if (!is_grid()) {
            throw InputError("probe field: grid tracing needs a probe set laid out as a grid");
        }
        return FieldMode::Grid;
    case FieldMode::Nearest:
        break;
    }
    return FieldMode::Nearest;
}

ProbeTraceResult ProbeField::trace_one(std::size_t probe, const Ray& ray,
                                       const TraceSettings& settings) const {
    const ProbeSlot& s = slot(probe);
    Ray local = ray;
    local.origin = ray.origin - s.map.position;
    return trace_probe(s.map, &s.levels, local, settings);
}

FieldTraceResult ProbeField::trace(const Ray& ray, const FieldTraceSettings& settings) const {
    FieldTraceResult result = resolve_mode(settings) == FieldMode::Grid
                                  ? trace_grid(ray, settings)
                                  : trace_nearest(ray, settings);
    see_edge_as_the_centre_does(ray, result, settings);
    shade_hit(*this, ray, result, settings);
    return result;
}

namespace {

// A HIT on what the probe's centre sees in texel `seen` (a surface at r_seen), moved onto the
// ray: the eye's offset from the centre is a small fraction of the distance, so the
// first-order shift along the ray is exact enough. Nothing changes where that falls outside
// the ray's interval.
void see_texel_as_the_centre_does(const ProbeMap& map, const Ray& ray, oct::Texel seen,
                                  double r_seen, FieldTraceResult& hit) {
    const double t = r_seen - glm::dot(ray.origin - map.position, ray.direction);
    if (!(t >= ray.t_min && t <= ray.t_max)) {
        return;
    }
    const std::size_t i = oct::texel_index(seen, map.resolution);
    hit.status = TraceStatus::Hit;
    hit.t = t;
    hit.free_until = t;
    hit.texel = seen;
    hit.normal = map.normal_at(i);
    hit.radiance = map.radiance_at(i);
}

} // namespace

void ProbeField::see_edge_as_the_centre_does(const Ray& ray, FieldTraceResult& hit,
                                             const FieldTraceSettings& settings) const {
    if (settings.filter == RadianceFilter::Nearest || hit.probe < 0) {
        return;
    }
    if (hit.status == TraceStatus::Miss) {
        see_edge_of_a_miss_as_the_centre_does(ray, hit);
        return;
    }
    if (hit.status != TraceStatus::Hit) {
        return;
    }
    const ProbeMap& map = probe(static_cast<std::size_t>(hit.probe));
    const int n = map.resolution;
    const glm::dvec3 offset = ray.origin - map.position;
    // Parallax between the eye's and the probe's view of the hit, in texels.
    if (glm::length(offset) > kEdgeParallaxTexels * oct::kTexelAngleTimesN / n * hit.t) {
        return;
    }
    const glm::dvec3 from_centre = ray.at(hit.t) - map.position;
    const double r = glm::length(from_centre);
    const oct::Texel seen = majority_surface_texel(
        map, from_centre, hit.texel, surface_thickness(settings.probe, r, map.resolution));
    if (seen.x == hit.texel.x && seen.y == hit.texel.y) {
        return;
    }
    const double r_seen = static_cast<double>(map.distance_at(oct::texel_index(seen, n)));
    if (std::isnan(r_seen)) {
        return;
    }
    if (std::isinf(r_seen)) {
        hit.status = TraceStatus::Miss;
        hit.t = std::numeric_limits<double>::infinity();
        hit.free_until = ray.t_max;
        hit.texel = {-1, -1};
        return;
    }
    see_texel_as_the_centre_does(map, ray, seen, r_seen, hit);
}

// A MISS through the empty texel of the ray's direction, from an eye near the probe that
// answered: the centre's lookup judges the edge between that texel and a surface beside it
// (a thin slat against open space) by the bilinear weight's majority, and may see the
// surface. The eye sees it too where its parallax at the surface is as small as for a HIT.
void ProbeField::see_edge_of_a_miss_as_the_centre_does(const Ray& ray,
                                                       FieldTraceResult& hit) const {
    const ProbeMap& map = probe(static_cast<std::size_t>(hit.probe));
    const int n = map.resolution;
    const oct::Texel met = oct::texel_of_direction(glm::vec3(glm::normalize(ray.direction)), n);
    if (!std::isinf(map.distance_at(oct::texel_index(met, n)))) {
        return; // the probe proved the ray free in front of a surface, not through open space
    }
    const oct::Texel seen = majority_surface_texel(map, ray.direction, met, 0.0);
    if (seen.x == met.x && seen.y == met.y) {
        return;
    }
    const double r_seen = static_cast<double>(map.distance_at(oct::texel_index(seen, n)));
    if (!std::isfinite(r_seen)) {
        return;
    }
    const glm::dvec3 offset = ray.origin - map.position;
    if (glm::length(offset) > kEdgeParallaxTexels * oct::kTexelAngleTimesN / n * r_seen) {
        return;
    }
    see_texel_as_the_centre_does(map, ray, seen, r_seen, hit);
}

FieldTraceResult ProbeField::trace_nearest(const Ray& ray,
                                           const FieldTraceSettings& settings) const {
    FieldQuery query{*this, ray, settings.probe, {}, {}, settings.max_probes_per_ray};
    query.result.free_until = ray.t_min;
    query.prefer_measured = settings.prefer_measured;
    if (settings.stop_where_no_probe_can_answer) {
        query.known = known_space_mask(settings.probe);
    }
    const std::size_t wanted =
        std::min(probe_count(), static_cast<std::size_t>(std::max(settings.max_probes, 1)));
    // The `wanted` nearest, kept sorted in a small buffer.
    std::array<Candidate, 64> best{};
    const std::size_t keep = std::min(wanted, best.size());
    std::size_t kept = 0;
    for (std::size_t i = 0; i < probe_count(); ++i) {
        const glm::dvec3 to = probe_position(i) - ray.origin;
        const Candidate c{glm::dot(to, to), i};
        if (kept < keep) {
            best[kept++] = c;
            std::push_heap(best.begin(), best.begin() + static_cast<long>(kept));
        } else if (c < best[0]) {
            std::pop_heap(best.begin(), best.begin() + static_cast<long>(kept));
            best[kept - 1] = c;
            std::push_heap(best.begin(), best.begin() + static_cast<long>(kept));
        }
    }
    std::sort_heap(best.begin(), best.begin() + static_cast<long>(kept));
    TriedProbes tried;
    // Probes that know nothing answer UNKNOWN where the ray starts, proving nothing: not asked
    // (they still count among the `wanted` nearest, as when they were asked).
    if (settings.skip_probes_that_know_nothing) {
        kept = static_cast<std::size_t>(
            std::remove_if(best.begin(), best.begin() + static_cast<long>(kept),
                           [&](const Candidate& c) { return knows_nothing(c.index); }) -
            best.begin());
    }
    if (ask_in_passes(query, tried, best.data(), kept)) {
        return query.result;
    }
    query.finish_unanswered();
    return query.result;
}

FieldTraceResult ProbeField::trace_grid(const Ray& ray, const FieldTraceSettings& settings) const {
    GridWalk walk(grid(), ray);
    if (!walk.meets_grid()) {
        return trace_nearest(ray, settings); // the ray never meets the grid's box
    }
    FieldQuery query{*this, ray, settings.probe, {}, {}, settings.max_probes_per_ray};
    query.result.free_until = ray.t_min;
    query.prefer_measured = settings.prefer_measured;
    if (settings.stop_where_no_probe_can_answer) {
        query.known = known_space_mask(settings.probe);
    }
    TriedProbes tried;
    while (const std::optional<GridCellSpan> span = walk.next()) {
        // A cell the ray already left behind the proven-free distance has nothing to add.
        if (span->t_leave >= query.result.free_until || span->first) {
            if (query.checking()) {
                // A cell none of whose corners saw where the ray now starts, with no surface
                // there: each of them would be passed over (FieldQuery::ask).
                if (!query.start_near_surface() && !seen_by_corners(span->cell, query.start())) {
                    continue;
                }
            }
            const glm::dvec3 entry = ray.at(std::max(span->t_enter, query.result.free_until));
            std::array<std::size_t, 8> corner_index{};
            const std::size_t corner_count = grid_cell_corners(grid(), span->cell, corner_index);
            std::array<Candidate, 8> corners{};
            std::size_t useful = 0;
            for (std::size_t k = 0; k < corner_count; ++k) {
                const std::size_t index = corner_index[k];
                if (settings.skip_probes_that_know_nothing && knows_nothing(index)) {
                    continue;
                }
                const glm::dvec3 to = probe_position(index) - entry;
                corners[useful++] = Candidate{glm::dot(to, to), index};
            }
            if (useful == 0) {
                continue; // a cell whose probes know nothing: no one to ask
            }
            sort_candidates(corners.data(), useful);
            if (ask_in_passes(query, tried, corners.data(), useful)) {
                return query.result;
            }
            if (query.done()) {
                break;
            }
        }
    }
    query.finish_unanswered();
    return query.result;
}

} // namespace lfprobe
