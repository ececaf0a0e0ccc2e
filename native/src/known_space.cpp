#include "lfprobe/known_space.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <optional>
#include <tuple>

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>

#include "known_space_bytes.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/octahedral.hpp"
#include "lfprobe/probe_exr.hpp"

namespace lfprobe {

using namespace known_space_bytes;

namespace {

constexpr char kKnownSpaceMagic[8] = {'L', 'F', 'P', 'K', 'N', 'O', 'W', 'N'};
constexpr char kDirectionsMagic[8] = {'D', 'I', 'R', 'E', 'C', 'T', 'N', 'S'};
// Voxel indices stay well inside int32 and a dense mask's arithmetic.
constexpr double kMaxVoxelIndex = 1 << 28;
// Rows of a probe's map whose surface voxels are gathered together (KnownSpace::add_probe).
constexpr int kRowsPerSurfaceBand = 32;

// A voxel or block index, each coordinate within `limit`.
std::array<std::int32_t, 3> take_index(const std::string& in, std::size_t& at,
                                       const std::string& path, double limit, const char* what) {
    std::array<std::int32_t, 3> index{};
    for (std::int32_t& i : index) {
        i = take<std::int32_t>(in, at, path);
        if (!(std::abs(static_cast<double>(i)) < limit)) {
            throw InputError(path + ": a " + std::string(what) +
                             " of the known-space file is out of range");
        }
    }
    return index;
}

} // namespace

// --- VoxelMask -----------------------------------------------------------------------------

VoxelMask::VoxelMask(const glm::dvec3& origin, double voxel, const std::array<int, 3>& dims)
    : origin_(origin), voxel_(voxel), dims_(dims) {
    const std::size_t count = static_cast<std::size_t>(dims[0]) *
                              static_cast<std::size_t>(dims[1]) * static_cast<std::size_t>(dims[2]);
    bits_.assign((count + 63) / 64, 0);
}

void VoxelMask::set(int x, int y, int z) {
    const std::size_t i = index(x, y, z);
    bits_[i >> 6] |= std::uint64_t{1} << (i & 63);
}

std::size_t VoxelMask::set_count() const {
    std::size_t count = 0;
    for (const std::uint64_t word : bits_) {
        count += static_cast<std::size_t>(__builtin_popcountll(word));
    }
    return count;
}

double VoxelMask::last_set_t(const Ray& ray, double t_from, double t_to) const {
    return last_set_span(ray, t_from, t_to).second;
}

namespace {

// A walk through a box of voxels along a ray, from a voxel on forwards (t rising) or backwards:
// the voxel it is in, and the t at which the ray crosses that voxel's face ahead on each axis
// (±inf on an axis the ray runs parallel to).
struct VoxelWalk {
    std::array<int, 3> cell{};
    std::array<int, 3> step{};
    std::array<double, 3> t_cross{};
    std::array<double, 3> t_delta{};
    bool forward = true;

    VoxelWalk(const Ray& ray, double t_start, bool forwards, const glm::dvec3& origin, double voxel,
              const std::array<int, 3>& dims)
        : forward(forwards) {
        const glm::dvec3 p = ray.at(t_start);
        for (int a = 0; a < 3; ++a) {
            const auto k = static_cast<std::size_t>(a);
            const double u = (p[a] - origin[a]) / voxel;
            cell[k] = std::clamp(static_cast<int>(std::floor(u)), 0, dims[k] - 1);
            const double d = ray.direction[a];
            if (d == 0.0) {
                step[k] = 0;
                t_cross[k] = (forward ? 1.0 : -1.0) * std::numeric_limits<double>::infinity();
                t_delta[k] = 0.0;
                continue;
            }
            step[k] = (d > 0.0) == forward ? 1 : -1;
            const int face = step[k] > 0 ? cell[k] + 1 : cell[k];
            t_cross[k] = (origin[a] + voxel * face - ray.origin[a]) / d;
            t_delta[k] = voxel / std::abs(d);
        }
    }
    // The axis whose face the ray crosses next.
    [[nodiscard]] std::size_t next_axis() const {
        std::size_t axis = 0;
        for (std::size_t k = 1; k < 3; ++k) {
            if (forward ? t_cross[k] < t_cross[axis] : t_cross[k] > t_cross[axis]) {
                axis = k;
            }
        }
        return axis;
    }
    // Into the next voxel across `axis`; false where that leaves the box.
    bool cross(std::size_t axis, const std::array<int, 3>& dims) {
        cell[axis] += step[axis];
        if (cell[axis] < 0 || cell[axis] >= dims[axis]) {
            return false;
        }
        t_cross[axis] += forward ? t_delta[axis] : -t_delta[axis];
        return true;
    }
};

// Narrows [lo, hi] to the part of it inside a box of voxels (slabs); false when none is.
bool clip_to_box(const Ray& ray, const glm::dvec3& origin, double voxel,
                 const std::array<int, 3>& dims, double& lo, double& hi) {
    for (int a = 0; a < 3; ++a) {
        clip_to_slab(ray, a, origin[a], origin[a] + voxel * dims[static_cast<std::size_t>(a)], lo,
                     hi);
    }
    return lo <= hi;
}

} // namespace

std::pair<double, double> VoxelMask::first_unset_span(const Ray& ray, double t_from,
                                                      double t_to) const {
    constexpr double none = std::numeric_limits<double>::infinity();
    if (bits_.empty()) {
        return {none, none};
    }
    double lo = t_from;
    double hi = t_to;
    if (!clip_to_box(ray, origin_, voxel_, dims_, lo, hi) || !std::isfinite(lo)) {
        return {none, none};
    }
    // Walk the voxels forwards from `lo` (the mirror of last_set_span's walk).
    VoxelWalk walk(ray, lo, true, origin_, voxel_, dims_);
    double t = lo;
    for (;;) {
        const std::size_t axis = walk.next_axis();
        if (!is_set(walk.cell[0], walk.cell[1], walk.cell[2])) {
            return {t, std::min(walk.t_cross[axis], hi)};
        }
        t = walk.t_cross[axis];
        if (!(t <= hi) || !walk.cross(axis, dims_)) {
            return {none, none};
        }
    }
}

VoxelMask VoxelMask::pooled(int factor) const {
    if (bits_.empty() || factor <= 1) {
        return *this;
    }
    std::array<int, 3> dims{};
    for (std::size_t a = 0; a < 3; ++a) {
        dims[a] = (dims_[a] + factor - 1) / factor;
    }
    VoxelMask coarse(origin_, voxel_ * factor, dims);
    for (int z = 0; z < dims_[2]; ++z) {
        for (int y = 0; y < dims_[1]; ++y) {
            for (int x = 0; x < dims_[0]; ++x) {
                if (is_set(x, y, z)) {
                    coarse.set(x / factor, y / factor, z / factor);
                }
            }
        }
    }
    return coarse;
}

std::pair<double, double> VoxelMask::last_set_span(const Ray& ray, double t_from,
                                                   double t_to) const {
    constexpr double none = -std::numeric_limits<double>::infinity();
    if (bits_.empty()) {
        return {none, none};
    }
    double lo = t_from;
    double hi = t_to;
    if (!clip_to_box(ray, origin_, voxel_, dims_, lo, hi)) {
        return {none, none};
    }
    // Walk the voxels backwards from `hi`: the first occupied one met is the last along the ray.
    VoxelWalk walk(ray, hi, false, origin_, voxel_, dims_);
    double t = hi;
    for (;;) {
        const std::size_t axis = walk.next_axis();
        if (is_set(walk.cell[0], walk.cell[1], walk.cell[2])) {
            return {std::max(walk.t_cross[axis], lo), t};
        }
        t = walk.t_cross[axis];
        if (!(t >= lo) || !walk.cross(axis, dims_)) {
            return {none, none};
        }
    }
}

double KnownSpaceMask::last_surface_t(const Ray& ray, double t_from, double t_to) const {
    constexpr double none = -std::numeric_limits<double>::infinity();
    // A fine voxel more on each side of a coarse one: where the two walks round a boundary
    // differently, the fine one still sees it.
    const double slack = surfaces.voxel() / std::max(glm::length(ray.direction), 1e-300);
    double hi = t_to;
    while (hi >= t_from) {
        const auto [enter, leave] = coarse_surfaces.last_set_span(ray, t_from, hi);
        if (leave == none) {
            return none;
        }
        const double t =
            surfaces.last_set_t(ray, std::max(t_from, enter - slack), std::min(hi, leave + slack));
        if (t != none) {
            return t;
        }
        // On before the coarse voxel just searched: a hair before its entry, so that rounding
        // at the boundary cannot find it again (the fine search's slack covered the hair).
        const double next = enter - 1e-9 * (1.0 + std::abs(enter));
        if (!(next < hi)) {
            return none;
        }
        hi = next;
    }
    return none;
}

// --- KnownSpace --------------------------------------------------------------------------------

namespace {

// The pyramid of a probe's farthest known distance: level 0 is the map (unknown -inf, empty
// +inf), each level above the largest of 2×2 below, while the side stays whole; `top` the
// largest of all.
struct FarthestPyramid {
    explicit FarthestPyramid(const ProbeMap& map) : n(map.resolution) {
        std::vector<float> level(map.texel_count());
        for (std::size_t i = 0; i < level.size(); ++i) {
            const float d = map.distance_at(i);
            level[i] = std::isnan(d) ? -std::numeric_limits<float>::infinity() : d;
            top = std::max(top, level[i]);
        }
        levels.push_back(std::move(level));
        int side = n;
        while (side % 2 == 0 && side > 1) {
            const int half = side / 2;
            const std::vector<float>& below = levels.back();
            std::vector<float> above(static_cast<std::size_t>(half) * half);
            for (int y = 0; y < half; ++y) {
                for (int x = 0; x < half; ++x) {
                    const auto at = [&](int bx, int by) {
                        return below[static_cast<std::size_t>(by) * side + bx];
                    };
                    above[static_cast<std::size_t>(y) * half + x] =
                        std::max(std::max(at(2 * x, 2 * y), at(2 * x + 1, 2 * y)),
                                 std::max(at(2 * x, 2 * y + 1), at(2 * x + 1, 2 * y + 1)));
                }
            }
            levels.push_back(std::move(above));
            side = half;
        }
    }

    // The farthest known distance over every direction within `angle` of `direction` (unit),
    // or more: the 3×3 texels around it at the level whose texels are at least that wide.
    [[nodiscard]] float farthest_within(const glm::dvec3& direction, double angle) const {
        // The narrowest octahedral texel is wider than this share of the mean, sqrt(4π) / N.
        constexpr double kNarrowest = 0.35;
        const double needed = angle * n / (kNarrowest * oct::kTexelAngleTimesN);
        const int k = needed <= 1.0 ? 0 : static_cast<int>(std::ceil(std::log2(needed)));
        if (k >= static_cast<int>(levels.size())) {
            return top;
        }
        const oct::Texel fine = oct::texel_of_direction(glm::vec3(direction), n);
        const int side = n >> k;
        const std::vector<float>& level = levels[static_cast<std::size_t>(k)];
        float farthest = -std::numeric_limits<float>::infinity();
        for (int dy = -1; dy <= 1; ++dy) {
            for (int dx = -1; dx <= 1; ++dx) {
                const oct::Texel t = oct::wrap_texel((fine.x >> k) + dx, (fine.y >> k) + dy, side);
                farthest = std::max(farthest, level[static_cast<std::size_t>(t.y) * side + t.x]);
            }
        }
        return farthest;
    }

    int n;
    float top = -std::numeric_limits<float>::infinity();
    std::vector<std::vector<float>> levels;
};

// Whether the probe at the origin of `pyramid`'s frame may have seen free some point of the
// ball of radius `h` around `centre` (relative to the probe): a direction within the ball's
// angle whose known surface lies at least as far as the ball's nearest point. Loose (the 3×3
// texels of a coarse level); for boxes the octahedral rectangle test below cannot take.
bool may_have_seen(const FarthestPyramid& pyramid, const glm::dvec3& centre, double h) {
    const double r = glm::length(centre);
    if (r <= h) {
        return pyramid.top > -std::numeric_limits<float>::infinity();
    }
    const double angle = std::asin(std::min(1.0, h / r));
    return static_cast<double>(pyramid.farthest_within(centre / r, angle)) >= r - h;
}

// The octahedral uv of direction d (non-zero) as seen from the closed octant of signs `sign`
// (each ±1): on the octant's boundary planes a zero coordinate takes the octant's sign, so that
// the corners of a box inside the octant all map by the octant's own (linear-fractional) map.
glm::dvec2 encode_in_octant(const glm::dvec3& d, const glm::dvec3& sign) {
    const double l1 = std::abs(d.x) + std::abs(d.y) + std::abs(d.z);
    const double px = sign.x * std::abs(d.x) / l1;
    const double py = sign.y * std::abs(d.y) / l1;
    glm::dvec2 p{px, py};
    if (sign.z < 0.0) {
        p = glm::dvec2{(1.0 - std::abs(py)) * sign.x, (1.0 - std::abs(px)) * sign.y};
    }
    return p * 0.5 + 0.5;
}

// Whether the probe may have seen free some point of the box [low, high] (relative to the
// probe) that lies in one closed octant (`sign`): within one octant the octahedral map is
// linear-fractional, so the box maps inside the rectangle of its corners' images; a known
// surface there at least as far as the box's nearest point says yes.
bool may_have_seen_in_octant(const FarthestPyramid& pyramid, const glm::dvec3& low,
                             const glm::dvec3& high, const glm::dvec3& sign) {
    const glm::dvec3 nearest = glm::clamp(glm::dvec3(0.0), low, high);
    const double r_min = glm::length(nearest);
    if (r_min == 0.0) {
        return pyramid.top > -std::numeric_limits<float>::infinity(); // holds the probe
    }
    const int n = pyramid.n;
    double u0 = 1.0;
    double v0 = 1.0;
    double u1 = 0.0;
    double v1 = 0.0;
    for (int c = 0; c < 8; ++c) {
        const glm::dvec3 corner((c & 1) ? high.x : low.x, (c & 2) ? high.y : low.y,
                                (c & 4) ? high.z : low.z);
        if (corner == glm::dvec3(0.0)) {
            return may_have_seen(pyramid, 0.5 * (low + high), 0.5 * glm::length(high - low));
        }
        const glm::dvec2 uv = encode_in_octant(corner, sign);
        u0 = std::min(u0, uv.x);
        v0 = std::min(v0, uv.y);
        u1 = std::max(u1, uv.x);
        v1 = std::max(v1, uv.y);
    }
    // One texel more on every side for rounding: the trace finds texels in float.
    const int x0 = static_cast<int>(std::floor(u0 * n)) - 1;
    const int y0 = static_cast<int>(std::floor(v0 * n)) - 1;
    const int x1 = static_cast<int>(std::floor(u1 * n)) + 1;
    const int y1 = static_cast<int>(std::floor(v1 * n)) + 1;
    if (x0 < 0 || y0 < 0 || x1 >= n || y1 >= n) {
        // At the map's border the texels across it are the mirrored ones: the loose test.
        return may_have_seen(pyramid, 0.5 * (low + high), 0.5 * glm::length(high - low));
    }
    // The finest level at which the rectangle spans at most 2×2 texels.
    int k = 0;
    while (k + 1 < static_cast<int>(pyramid.levels.size()) &&
           ((x1 >> k) - (x0 >> k) > 1 || (y1 >> k) - (y0 >> k) > 1)) {
        ++k;
    }
    if ((x1 >> k) - (x0 >> k) > 1 || (y1 >> k) - (y0 >> k) > 1) {
        return static_cast<double>(pyramid.top) >= r_min;
    }
    const int side = n >> k;
    const std::vector<float>& level = pyramid.levels[static_cast<std::size_t>(k)];
    for (int y = y0 >> k; y <= (y1 >> k); ++y) {
        for (int x = x0 >> k; x <= (x1 >> k); ++x) {
            if (static_cast<double>(level[static_cast<std::size_t>(y) * side + x]) >= r_min) {
                return true;
            }
        }
    }
    return false;
}

// The same for any box (relative to the probe): split at the probe's axis planes into boxes of
// one closed octant each.
bool may_have_seen_box(const FarthestPyramid& pyramid, const glm::dvec3& low,
                       const glm::dvec3& high) {
    std::array<std::array<double, 3>, 3> cuts{}; // per axis: low, [0,] high
    std::array<int, 3> pieces{};
    for (int a = 0; a < 3; ++a) {
        const auto k = static_cast<std::size_t>(a);
        cuts[k][0] = low[a];
        if (low[a] < 0.0 && high[a] > 0.0) {
            cuts[k][1] = 0.0;
            cuts[k][2] = high[a];
            pieces[k] = 2;
        } else {
            cuts[k][1] = high[a];
            pieces[k] = 1;
        }
    }
    for (int iz = 0; iz < pieces[2]; ++iz) {
        for (int iy = 0; iy < pieces[1]; ++iy) {
            for (int ix = 0; ix < pieces[0]; ++ix) {
                const glm::dvec3 lo(cuts[0][static_cast<std::size_t>(ix)],
                                    cuts[1][static_cast<std::size_t>(iy)],
                                    cuts[2][static_cast<std::size_t>(iz)]);
                const glm::dvec3 hi(cuts[0][static_cast<std::size_t>(ix) + 1],
                                    cuts[1][static_cast<std::size_t>(iy) + 1],
                                    cuts[2][static_cast<std::size_t>(iz) + 1]);
                // The piece's octant: the sign of its interior.
                const glm::dvec3 mid = 0.5 * (lo + hi);
                const glm::dvec3 sign(mid.x >= 0.0 ? 1.0 : -1.0, mid.y >= 0.0 ? 1.0 : -1.0,
                                      mid.z >= 0.0 ? 1.0 : -1.0);
                if (may_have_seen_in_octant(pyramid, lo, hi, sign)) {
                    return true;
                }
            }
        }
    }
    return false;
}

constexpr int kBlock = 8; // seen voxels per block side
// Seen voxels are marked out to this many blocks (12.8 m) from the probe, and voxel by voxel in
// at most this many blocks a probe (a million voxel tests); past either, conservatively whole.
constexpr double kReachBlocks = 16.0;
constexpr std::size_t kFineBlocks = 2048;

} // namespace

bool KnownSpace::surface_order(const SurfaceVoxel& a, const SurfaceVoxel& b) {
    if (std::tie(a.z, a.y, a.x) != std::tie(b.z, b.y, b.x)) {
        return std::tie(a.z, a.y, a.x) < std::tie(b.z, b.y, b.x);
    }
    return a.footprint > b.footprint; // unique then keeps the largest
}

bool KnownSpace::same_surface_voxel(const SurfaceVoxel& a, const SurfaceVoxel& b) {
    return a.x == b.x && a.y == b.y && a.z == b.z;
}

namespace {

// Probe `index`'s record in a list sorted by probe index; null when it has none.
template <typename Record>
const Record* record_of(const std::vector<std::pair<std::uint64_t, Record>>& records,
                        std::size_t index) {
    const auto found =
        std::lower_bound(records.begin(), records.end(), static_cast<std::uint64_t>(index),
                         [](const auto& entry, std::uint64_t i) { return entry.first < i; });
    return found != records.end() && found->first == index ? &found->second : nullptr;
}

} // namespace

const SeenVoxels* KnownSpace::seen_by(std::size_t index) const {
    return record_of(seen_, index);
}

const SeenDirections* KnownSpace::directions_of(std::size_t index) const {
    return record_of(directions_, index);
}

KnownSpace KnownSpace::as_probe(std::size_t index) const {
    if (seen_.size() != 1 || directions_.size() > 1) {
        throw InputError(
            "known space: " + std::to_string(std::max(seen_.size(), directions_.size())) +
            " probes where one was expected");
    }
    KnownSpace moved = *this;
    moved.seen_.front().first = index;
    if (!moved.directions_.empty()) {
        moved.directions_.front().first = index;
    }
    return moved;
}

bool append_known_space(const std::string& set_folder, const std::string& probe_folder,
                        std::size_t index) {
    namespace fs = std::filesystem;
    const fs::path set_file = fs::path(set_folder) / kKnownSpaceName;
    const fs::path probe_file = fs::path(probe_folder) / kKnownSpaceName;
    std::error_code ec;
    const bool set_has = fs::is_regular_file(set_file, ec);
    if (!fs::is_regular_file(probe_file, ec) || (!set_has && index > 0)) {
        fs::remove(set_file, ec);
        return false;
    }
    KnownSpace space = set_has ? KnownSpace::read(set_file.string()) : KnownSpace();
    space.merge(KnownSpace::read(probe_file.string()).as_probe(index));
    space.write(set_file.string());
    return true;
}

// A probe's surface voxels as its texels meet them, one entry a voxel: open addressing with
// linear probing, grown at half full.
class KnownSpace::VoxelTable {
public:
    VoxelTable() : slots_(kFirstSize, free_slot()) {}

    // The voxel's entry, added with v's footprint when it is new. The reference holds until the
    // next call.
    SurfaceVoxel& find_or_add(const SurfaceVoxel& v) {
        if (2 * (count_ + 1) > slots_.size()) {
            grow();
        }
        SurfaceVoxel& slot = slots_[place_of(v)];
        if (slot.x == kFree) {
            ++count_;
            slot = v;
        }
        return slot;
    }

    [[nodiscard]] std::vector<SurfaceVoxel> entries() const {
        std::vector<SurfaceVoxel> out;
        out.reserve(count_);
        std::copy_if(slots_.begin(), slots_.end(), std::back_inserter(out),
                     [](const SurfaceVoxel& v) { return v.x != kFree; });
        return out;
    }

private:
    // Voxel indices lie within ±kMaxVoxelIndex: this is none.
    static constexpr std::int32_t kFree = std::numeric_limits<std::int32_t>::min();
    static constexpr std::size_t kFirstSize = 4096;

    static SurfaceVoxel free_slot() { return {kFree, 0, 0, 0.0f}; }

    // The slot holding v's voxel, or the free slot where it goes.
    [[nodiscard]] std::size_t place_of(const SurfaceVoxel& v) const {
        std::uint64_t h = static_cast<std::uint32_t>(v.x) * 0x9E3779B97F4A7C15ULL ^
                          static_cast<std::uint32_t>(v.y) * 0xC2B2AE3D27D4EB4FULL ^
                          static_cast<std::uint32_t>(v.z) * 0x165667B19E3779F9ULL;
        h ^= h >> 32;
        std::size_t i = static_cast<std::size_t>(h) & (slots_.size() - 1);
        while (slots_[i].x != kFree && !same_surface_voxel(slots_[i], v)) {
            i = (i + 1) & (slots_.size() - 1);
        }
        return i;
    }

    void grow() {
        std::vector<SurfaceVoxel> old(2 * slots_.size(), free_slot());
        old.swap(slots_);
        for (const SurfaceVoxel& v : old) {
            if (v.x != kFree) {
                slots_[place_of(v)] = v;
            }
        }
    }

    std::vector<SurfaceVoxel> slots_;
    std::size_t count_ = 0;
};

void KnownSpace::add_probe(const ProbeMap& map, std::size_t index) {
    const int n = map.resolution;
    const double footprint_per_metre = oct::kTexelAngleTimesN / n;
    // Bands of rows in parallel, each keeping one entry a voxel (the largest footprint): a
    // 2048² probe's texels fall in about 230,000 voxels, and an entry a texel run sorted
    // afterwards (2.1 million) cost as much as writing the probe's EXR. The sort makes the
    // bands' order irrelevant.
    const int bands = (n + kRowsPerSurfaceBand - 1) / kRowsPerSurfaceBand;
    std::vector<std::vector<SurfaceVoxel>> parts(static_cast<std::size_t>(bands));
    std::atomic<bool> empty{false};
    std::atomic<bool> too_far{false};
    tbb::parallel_for(0, bands, [&](int band) {
        VoxelTable voxels;
        const int y1 = std::min(n, (band + 1) * kRowsPerSurfaceBand);
        for (int y = band * kRowsPerSurfaceBand; y < y1; ++y) {
            SurfaceVoxel* last = nullptr; // neighbouring texels mostly share a voxel
            for (int x = 0; x < n; ++x) {
                if (empty.load(std::memory_order_relaxed)) {
                    return; // a probe with an empty texel is never asked about: nothing to keep
                }
                const oct::Texel texel{x, y};
                const float d = map.distance_at(oct::texel_index(texel, n));
                if (std::isnan(d)) {
                    continue;
                }
                if (std::isinf(d)) {
                    empty.store(true, std::memory_order_relaxed);
                    continue;
                }
                const glm::dvec3 p = map.position + static_cast<double>(d) *
                                                        glm::dvec3(oct::texel_direction(texel, n));
                const glm::dvec3 u = glm::floor(p / kSurfaceVoxel);
                if (!(std::abs(u.x) < kMaxVoxelIndex && std::abs(u.y) < kMaxVoxelIndex &&
                      std::abs(u.z) < kMaxVoxelIndex)) {
                    too_far.store(true, std::memory_order_relaxed);
                    continue;
                }
                const SurfaceVoxel v{static_cast<std::int32_t>(u.x), static_cast<std::int32_t>(u.y),
                                     static_cast<std::int32_t>(u.z),
                                     static_cast<float>(d * footprint_per_metre)};
                if (last == nullptr || !same_surface_voxel(*last, v)) {
                    last = &voxels.find_or_add(v);
                }
                last->footprint = std::max(last->footprint, v.footprint);
            }
        }
        parts[static_cast<std::size_t>(band)] = voxels.entries();
    });
    KnownSpace probe;
    if (empty.load()) {
        // A set with an empty texel can answer MISS anywhere and never uses its known space:
        // the flag alone, the same whichever rows were read before the empty texel was met.
        probe.has_empty_ = true;
        probe.seen_.emplace_back(index, SeenVoxels());
        merge(probe);
        return;
    }
    if (too_far.load()) {
        throw InputError("known space: a surface of probe " + std::to_string(index) +
                         " lies too far out for voxels of " + std::to_string(kSurfaceVoxel) + " m");
    }
    std::size_t total = 0;
    for (const auto& part : parts) {
        total += part.size();
    }
    probe.surfaces_.reserve(total);
    for (auto& part : parts) {
        for (const SurfaceVoxel& v : part) {
            probe.farthest_ =
                std::max(probe.farthest_, static_cast<double>(v.footprint) / footprint_per_metre);
        }
        probe.surfaces_.insert(probe.surfaces_.end(), part.begin(), part.end());
        std::vector<SurfaceVoxel>().swap(part);
    }
    SeenVoxels seen;
    SeenDirections directions;
    tbb::parallel_invoke(
        [&] { tbb::parallel_sort(probe.surfaces_.begin(), probe.surfaces_.end(), surface_order); },
        [&] { seen = SeenVoxels(map); }, [&] { directions = SeenDirections(map); });
    probe.surfaces_.erase(
        std::unique(probe.surfaces_.begin(), probe.surfaces_.end(), same_surface_voxel),
        probe.surfaces_.end());
    probe.seen_.emplace_back(index, std::move(seen));
    probe.directions_.emplace_back(index, std::move(directions));
    merge(probe);
}

SeenVoxels::SeenVoxels(const ProbeMap& map) {
    const FarthestPyramid pyramid(map);
    if (!(pyramid.top > -std::numeric_limits<float>::infinity())) {
        return; // knows nothing
    }
    const double block = kVoxel * kBlock;
    // An empty texel saw free space without end (a set with empty texels never asks its probes'
    // seen voxels): its probe's voxels reach as far as its surfaces do.
    const double farthest = std::isfinite(pyramid.top) ? static_cast<double>(pyramid.top) : 0.0;
    // Marked out to the probe's farthest surface, or to kReachBlocks blocks from it: beyond that
    // every point counts as seen (a far view through a window or a door costs nothing).
    const double reach = std::min(farthest + block, kReachBlocks * block);
    beyond_ = farthest + block > reach;
    std::array<std::int32_t, 3> low{};
    std::array<std::int32_t, 3> high{};
    for (int a = 0; a < 3; ++a) {
        const double lo = std::floor((map.position[a] - reach) / block);
        const double hi = std::floor((map.position[a] + reach) / block);
        if (!(std::abs(lo) < kMaxVoxelIndex / kBlock && std::abs(hi) < kMaxVoxelIndex / kBlock)) {
            throw InputError("seen voxels: a probe lies too far out (" +
                             std::to_string(map.position[a]) + " m)");
        }
        low[static_cast<std::size_t>(a)] = static_cast<std::int32_t>(lo);
        high[static_cast<std::size_t>(a)] = static_cast<std::int32_t>(hi);
    }
    if (beyond_) {
        exact_low_ = glm::dvec3(low[0], low[1], low[2]) * block;
        exact_high_ = glm::dvec3(high[0] + 1, high[1] + 1, high[2] + 1) * block;
    }
    // Cubes of 2^k blocks, each tested as one before its eight halves: unseen space is passed
    // over at the coarsest cube that shows it.
    std::int32_t side = 1;
    while (side < high[0] - low[0] + 1 || side < high[1] - low[1] + 1 ||
           side < high[2] - low[2] + 1) {
        side *= 2;
    }
    std::size_t fine_blocks = 0;
    const auto visit = [&](const auto& self, std::int32_t bx, std::int32_t by, std::int32_t bz,
                           std::int32_t size) -> void {
        if (bx > high[0] || by > high[1] || bz > high[2]) {
            return;
        }
        const glm::dvec3 corner = glm::dvec3(bx, by, bz) * block - map.position;
        if (!may_have_seen_box(pyramid, corner, corner + block * size)) {
            return;
        }
        if (size > 1) {
            const std::int32_t half = size / 2;
            for (int c = 0; c < 8; ++c) {
                self(self, bx + ((c & 1) ? half : 0), by + ((c & 2) ? half : 0),
                     bz + ((c & 4) ? half : 0), half);
            }
            return;
        }
        Block b{bx, by, bz, {}};
        if (++fine_blocks > kFineBlocks) {
            b.bits.fill(~std::uint64_t{0}); // past the budget: the block whole
            blocks_.push_back(b);
            return;
        }
        bool any = false;
        for (int z = 0; z < kBlock; ++z) {
            for (int y = 0; y < kBlock; ++y) {
                for (int x = 0; x < kBlock; ++x) {
                    const glm::dvec3 from = corner + glm::dvec3(x, y, z) * kVoxel;
                    if (may_have_seen_box(pyramid, from, from + kVoxel)) {
                        b.bits[static_cast<std::size_t>(z)] |= std::uint64_t{1} << (x + kBlock * y);
                        any = true;
                    }
                }
            }
        }
        if (any) {
            blocks_.push_back(b);
        }
    };
    visit(visit, low[0], low[1], low[2], side);
    std::sort(blocks_.begin(), blocks_.end(), [](const Block& p, const Block& q) {
        return std::tie(p.z, p.y, p.x) < std::tie(q.z, q.y, q.x);
    });
}

bool SeenVoxels::beyond_exact_region(const glm::dvec3& point) const {
    return beyond_ &&
           !(point.x >= exact_low_.x && point.y >= exact_low_.y && point.z >= exact_low_.z &&
             point.x < exact_high_.x && point.y < exact_high_.y && point.z < exact_high_.z);
}

bool SeenVoxels::contains(const glm::dvec3& point) const {
    if (beyond_exact_region(point)) {
        return true;
    }
    const glm::dvec3 u = glm::floor(point / kVoxel);
    if (!(std::abs(u.x) < kMaxVoxelIndex && std::abs(u.y) < kMaxVoxelIndex &&
          std::abs(u.z) < kMaxVoxelIndex)) {
        return false;
    }
    const auto vx = static_cast<std::int32_t>(u.x);
    const auto vy = static_cast<std::int32_t>(u.y);
    const auto vz = static_cast<std::int32_t>(u.z);
    // Floor division: block -1 holds voxels -8..-1.
    const auto block_of = [](std::int32_t v) { return v >= 0 ? v / kBlock : (v + 1) / kBlock - 1; };
    const std::array<std::int32_t, 3> key{block_of(vz), block_of(vy), block_of(vx)};
    const auto found =
        std::lower_bound(blocks_.begin(), blocks_.end(), key,
                         [](const Block& b, const std::array<std::int32_t, 3>& k) {
                             return std::tie(b.z, b.y, b.x) < std::tie(k[0], k[1], k[2]);
                         });
    if (found == blocks_.end() || found->x != key[2] || found->y != key[1] || found->z != key[0]) {
        return false;
    }
    const int x = vx - kBlock * key[2];
    const int y = vy - kBlock * key[1];
    const int z = vz - kBlock * key[0];
    return (found->bits[static_cast<std::size_t>(z)] >> (x + kBlock * y)) & 1U;
}

void SeenVoxels::merge(const SeenVoxels& other) {
    // Exact where every part that saw beyond its region is exact: the regions' intersection.
    if (other.beyond_) {
        exact_low_ = beyond_ ? glm::max(exact_low_, other.exact_low_) : other.exact_low_;
        exact_high_ = beyond_ ? glm::min(exact_high_, other.exact_high_) : other.exact_high_;
        beyond_ = true;
    }
    std::vector<Block> merged;
    merged.reserve(blocks_.size() + other.blocks_.size());
    const auto order = [](const Block& a, const Block& b) {
        return std::tie(a.z, a.y, a.x) < std::tie(b.z, b.y, b.x);
    };
    std::merge(blocks_.begin(), blocks_.end(), other.blocks_.begin(), other.blocks_.end(),
               std::back_inserter(merged), order);
    std::size_t kept = 0;
    for (std::size_t i = 0; i < merged.size(); ++i) {
        if (kept > 0 && !order(merged[kept - 1], merged[i])) {
            for (std::size_t w = 0; w < 8; ++w) {
                merged[kept - 1].bits[w] |= merged[i].bits[w];
            }
        } else {
            merged[kept++] = merged[i];
        }
    }
    merged.resize(kept);
    blocks_ = std::move(merged);
}

VoxelMask SeenVoxels::dense(std::size_t max_bytes) const {
    if (blocks_.empty()) {
        return {};
    }
    std::array<std::int64_t, 3> low{blocks_.front().x, blocks_.front().y, blocks_.front().z};
    std::array<std::int64_t, 3> high = low;
    for (const Block& b : blocks_) {
        const std::array<std::int64_t, 3> at{b.x, b.y, b.z};
        for (std::size_t a = 0; a < 3; ++a) {
            low[a] = std::min(low[a], at[a]);
            high[a] = std::max(high[a], at[a]);
        }
    }
    std::array<int, 3> dims{};
    double voxels = 1.0;
    for (std::size_t a = 0; a < 3; ++a) {
        dims[a] = static_cast<int>((high[a] - low[a] + 1) * kBlock);
        voxels *= dims[a];
    }
    if (voxels / 8.0 > static_cast<double>(max_bytes)) {
        return {};
    }
    VoxelMask mask(glm::dvec3(static_cast<double>(low[0]), static_cast<double>(low[1]),
                              static_cast<double>(low[2])) *
                       (kVoxel * kBlock),
                   kVoxel, dims);
    for (const Block& b : blocks_) {
        const std::array<std::int64_t, 3> at{b.x, b.y, b.z};
        for (int z = 0; z < kBlock; ++z) {
            for (int y = 0; y < kBlock; ++y) {
                for (int x = 0; x < kBlock; ++x) {
                    if ((b.bits[static_cast<std::size_t>(z)] >> (x + kBlock * y)) & 1U) {
                        mask.set(static_cast<int>((at[0] - low[0]) * kBlock + x),
                                 static_cast<int>((at[1] - low[1]) * kBlock + y),
                                 static_cast<int>((at[2] - low[2]) * kBlock + z));
                    }
                }
            }
        }
    }
    return mask;
}

void SeenVoxels::write_to(std::string& out) const {
    put(out, static_cast<std::uint8_t>(beyond_ ? 1 : 0));
    for (int a = 0; a < 3; ++a) {
        put(out, exact_low_[a]);
        put(out, exact_high_[a]);
    }
    put(out, static_cast<std::uint64_t>(blocks_.size()));
    for (const Block& b : blocks_) {
        put(out, b.x);
        put(out, b.y);
        put(out, b.z);
        for (const std::uint64_t word : b.bits) {
            put(out, word);
        }
    }
}

SeenVoxels SeenVoxels::read_from(const std::string& in, std::size_t& at, const std::string& path) {
    SeenVoxels seen;
    seen.beyond_ = take<std::uint8_t>(in, at, path) != 0;
    for (int a = 0; a < 3; ++a) {
        seen.exact_low_[a] = take<double>(in, at, path);
        seen.exact_high_[a] = take<double>(in, at, path);
        if (seen.beyond_ && !(seen.exact_low_[a] <= seen.exact_high_[a])) {
            throw InputError(path + ": a seen region of the known-space file is empty or NaN");
        }
    }
    constexpr std::size_t kBlockBytes = 3 * sizeof(std::int32_t) + 8 * sizeof(std::uint64_t);
    seen.blocks_.resize(take_count(in, at, path, kBlockBytes, "seen blocks"));
    for (Block& b : seen.blocks_) {
        const auto [x, y, z] = take_index(in, at, path, kMaxVoxelIndex / kBlock, "seen block");
        b.x = x;
        b.y = y;
        b.z = z;
        for (std::uint64_t& word : b.bits) {
            word = take<std::uint64_t>(in, at, path);
        }
    }
    const auto order = [](const Block& a, const Block& b) {
        return std::tie(a.z, a.y, a.x) < std::tie(b.z, b.y, b.x);
    };
    if (!std::is_sorted(seen.blocks_.begin(), seen.blocks_.end(), order) ||
        std::adjacent_find(seen.blocks_.begin(), seen.blocks_.end(),
                           [&](const Block& a, const Block& b) { return !order(a, b); }) !=
            seen.blocks_.end()) {
        throw InputError(path + ": the seen blocks of the known-space file are out of order");
    }
    return seen;
}

bool operator==(const SeenVoxels& a, const SeenVoxels& b) {
    return a.beyond_ == b.beyond_ && a.exact_low_ == b.exact_low_ &&
           a.exact_high_ == b.exact_high_ && a.blocks_ == b.blocks_;
}

std::size_t SeenVoxels::voxel_count() const {
    std::size_t count = 0;
    for (const Block& b : blocks_) {
        for (const std::uint64_t word : b.bits) {
            count += static_cast<std::size_t>(__builtin_popcountll(word));
        }
    }
    return count;
}

namespace {

// Two lists of per-probe records, each sorted by probe index, as one; a probe in both was added
// twice.
template <typename Record>
std::vector<std::pair<std::uint64_t, Record>>
merged_by_probe(const std::vector<std::pair<std::uint64_t, Record>>& a,
                const std::vector<std::pair<std::uint64_t, Record>>& b) {
    std::vector<std::pair<std::uint64_t, Record>> merged;
    merged.reserve(a.size() + b.size());
    std::merge(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(merged),
               [](const auto& x, const auto& y) { return x.first < y.first; });
    for (std::size_t i = 1; i < merged.size(); ++i) {
        if (merged[i].first == merged[i - 1].first) {
            throw InputError("known space: probe " + std::to_string(merged[i].first) +
                             " was added twice");
        }
    }
    return merged;
}

} // namespace

void KnownSpace::merge(const KnownSpace& other) {
    has_empty_ = has_empty_ || other.has_empty_;
    farthest_ = std::max(farthest_, other.farthest_);
    std::vector<SurfaceVoxel> surfaces;
    surfaces.reserve(surfaces_.size() + other.surfaces_.size());
    std::merge(surfaces_.begin(), surfaces_.end(), other.surfaces_.begin(), other.surfaces_.end(),
               std::back_inserter(surfaces), surface_order);
    surfaces.erase(std::unique(surfaces.begin(), surfaces.end(), same_surface_voxel),
                   surfaces.end());
    surfaces_ = std::move(surfaces);
    seen_ = merged_by_probe(seen_, other.seen_);
    directions_ = merged_by_probe(directions_, other.directions_);
}

void KnownSpace::normalise() {
    // The order never depends on the order probes were added in: a rebuild is bit-identical.
    std::sort(surfaces_.begin(), surfaces_.end(), surface_order);
    surfaces_.erase(std::unique(surfaces_.begin(), surfaces_.end(), same_surface_voxel),
                    surfaces_.end());
}

namespace {

// A dense mask over the boxes [low, high] of fine voxel indices, `factor` fine voxels to one.
VoxelMask dense_mask(const std::array<std::int64_t, 3>& low,
                     const std::array<std::int64_t, 3>& high, double voxel, std::int64_t factor) {
    std::array<int, 3> dims{};
    for (std::size_t a = 0; a < 3; ++a) {
        dims[a] = static_cast<int>((high[a] - low[a] + 1 + factor - 1) / factor);
    }
    const glm::dvec3 origin(static_cast<double>(low[0]) * voxel,
                            static_cast<double>(low[1]) * voxel,
                            static_cast<double>(low[2]) * voxel);
    return VoxelMask(origin, voxel * static_cast<double>(factor), dims);
}

std::int64_t coarsening(const std::array<std::int64_t, 3>& low,
                        const std::array<std::int64_t, 3>& high, int max_side) {
    std::int64_t side = 1;
    for (std::size_t a = 0; a < 3; ++a) {
        side = std::max(side, high[a] - low[a] + 1);
    }
    return std::max<std::int64_t>(1, (side + max_side - 1) / std::max(max_side, 1));
}

} // namespace

KnownSpaceMask KnownSpace::mask(double margin, double footprint_texels, int max_side) const {
    KnownSpaceMask masks;
    constexpr auto big = std::numeric_limits<std::int64_t>::max();
    if (!surfaces_.empty()) {
        // Each voxel's reach in voxels; the box they span, in fine voxel indices.
        std::vector<int> reach(surfaces_.size());
        std::array<std::int64_t, 3> low{big, big, big};
        std::array<std::int64_t, 3> high{-big, -big, -big};
        for (std::size_t i = 0; i < surfaces_.size(); ++i) {
            const SurfaceVoxel& v = surfaces_[i];
            const double r = std::max(margin, 0.0) + footprint_texels * v.footprint;
            reach[i] = static_cast<int>(std::ceil(r / kSurfaceVoxel));
            const std::array<std::int64_t, 3> at{v.x, v.y, v.z};
            for (std::size_t a = 0; a < 3; ++a) {
                low[a] = std::min(low[a], at[a] - reach[i]);
                high[a] = std::max(high[a], at[a] + reach[i]);
            }
        }
        // Coarser mask voxels where the box is large or the cubes to set too many: a coarse
        // voxel is set when any fine voxel in it is, so the mask only grows.
        std::int64_t factor = coarsening(low, high, max_side);
        constexpr double kMaxWork = 2e8;
        for (;;) {
            double work = 0.0;
            for (const int r : reach) {
                const double cells = static_cast<double>(2 * r / factor + 2);
                work += cells * cells * cells;
            }
            if (work <= kMaxWork) {
                break;
            }
            factor *= 2;
        }
        masks.surfaces = dense_mask(low, high, kSurfaceVoxel, factor);
        // A voxel sets the cube of its reach around it. Neighbours along a row (the voxels come
        // sorted by z, y, x) with the same reach set the same rows, so their cubes are joined
        // into one box first and each of its rows is set once: the same mask, where the cubes
        // one by one were most of the mask's build (its first frame's).
        struct Box {
            std::int64_t y, z, x_low, x_high;
            int reach;
        };
        const auto set_box = [&](const Box& box) {
            const std::array<std::int64_t, 3> lo{box.x_low, box.y - box.reach, box.z - box.reach};
            const std::array<std::int64_t, 3> hi{box.x_high, box.y + box.reach, box.z + box.reach};
            std::array<int, 3> from{};
            std::array<int, 3> to{};
            for (std::size_t a = 0; a < 3; ++a) {
                from[a] = static_cast<int>((lo[a] - low[a]) / factor);
                to[a] = static_cast<int>((hi[a] - low[a]) / factor);
            }
            for (int z = from[2]; z <= to[2]; ++z) {
                for (int y = from[1]; y <= to[1]; ++y) {
                    masks.surfaces.set_run(from[0], to[0], y, z);
                }
            }
        };
        std::optional<Box> box;
        for (std::size_t i = 0; i < surfaces_.size(); ++i) {
            const SurfaceVoxel& v = surfaces_[i];
            const std::int64_t x_low = std::int64_t{v.x} - reach[i];
            const std::int64_t x_high = std::int64_t{v.x} + reach[i];
            // Joined where the runs overlap or touch: their union is one run, and so is its
            // floor division into coarse voxels.
            if (box && box->y == v.y && box->z == v.z && box->reach == reach[i] &&
                x_low <= box->x_high + 1 && x_high >= box->x_low - 1) {
                box->x_low = std::min(box->x_low, x_low);
                box->x_high = std::max(box->x_high, x_high);
                continue;
            }
            if (box) {
                set_box(*box);
            }
            box = Box{v.y, v.z, x_low, x_high, reach[i]};
        }
        if (box) {
            set_box(*box);
        }
        masks.coarse_surfaces = masks.surfaces.pooled(4);
    }
    return masks;
}

void KnownSpace::write(const std::string& path) const {
    std::string out(kKnownSpaceMagic, sizeof(kKnownSpaceMagic));
    put(out, static_cast<std::uint8_t>(has_empty_ ? 1 : 0));
    put(out, farthest_);
    put(out, static_cast<std::uint64_t>(surfaces_.size()));
    for (const SurfaceVoxel& v : surfaces_) {
        put(out, v.x);
        put(out, v.y);
        put(out, v.z);
        put(out, v.footprint);
    }
    put(out, static_cast<std::uint64_t>(seen_.size()));
    for (const auto& [index, seen] : seen_) {
        put(out, index);
        seen.write_to(out);
    }
    // A section files written before it lack (they read without it).
    out.append(kDirectionsMagic, sizeof(kDirectionsMagic));
    put(out, static_cast<std::uint64_t>(directions_.size()));
    for (const auto& [index, directions] : directions_) {
        put(out, index);
        directions.write_to(out);
    }
    write_file_atomically(path, out);
}

KnownSpace KnownSpace::read(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        throw MissingFileError(path + ": cannot open the known-space file");
    }
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (bytes.size() < sizeof(kKnownSpaceMagic) ||
        std::memcmp(bytes.data(), kKnownSpaceMagic, sizeof(kKnownSpaceMagic)) != 0) {
        throw InputError(path + ": not a known-space file (expected it to start with LFPKNOWN)");
    }
    std::size_t at = sizeof(kKnownSpaceMagic);
    KnownSpace space;
    space.has_empty_ = take<std::uint8_t>(bytes, at, path) != 0;
    space.farthest_ = take<double>(bytes, at, path);
    constexpr std::size_t kSurfaceBytes = 3 * sizeof(std::int32_t) + sizeof(float);
    space.surfaces_.resize(take_count(bytes, at, path, kSurfaceBytes, "surface voxels"));
    for (SurfaceVoxel& v : space.surfaces_) {
        const auto [x, y, z] = take_index(bytes, at, path, kMaxVoxelIndex, "surface voxel");
        v.x = x;
        v.y = y;
        v.z = z;
        v.footprint = take<float>(bytes, at, path);
        if (!(v.footprint >= 0.0f && std::isfinite(v.footprint))) {
            throw InputError(path + ": a surface voxel's footprint in the known-space file is " +
                             std::to_string(v.footprint));
        }
    }
    // A probe's record: its index, its region (a flag, 6 doubles) and its block count at least.
    constexpr std::size_t kProbeBytes = 8 + 1 + 6 * 8 + 8;
    const std::uint64_t probes = take_count(bytes, at, path, kProbeBytes, "probes");
    for (std::uint64_t i = 0; i < probes; ++i) {
        const auto index = take<std::uint64_t>(bytes, at, path);
        if (!space.seen_.empty() && index <= space.seen_.back().first) {
            throw InputError(path + ": the probes of the known-space file are out of order");
        }
        space.seen_.emplace_back(index, SeenVoxels::read_from(bytes, at, path));
    }
    if (bytes.size() - at >= sizeof(kDirectionsMagic) &&
        std::memcmp(bytes.data() + at, kDirectionsMagic, sizeof(kDirectionsMagic)) == 0) {
        at += sizeof(kDirectionsMagic);
        // A probe's record: its index, its resolution and one word of bits at least.
        constexpr std::size_t kDirectionBytes = 8 + 4 + 8;
        const std::uint64_t count = take_count(bytes, at, path, kDirectionBytes, "probes");
        for (std::uint64_t i = 0; i < count; ++i) {
            const auto index = take<std::uint64_t>(bytes, at, path);
            if (!space.directions_.empty() && index <= space.directions_.back().first) {
                throw InputError(path + ": the probes' directions in the known-space file are "
                                        "out of order");
            }
            space.directions_.emplace_back(index, SeenDirections::read_from(bytes, at, path));
        }
    }
    if (at != bytes.size()) {
        throw InputError(path + ": " + std::to_string(bytes.size() - at) +
                         " bytes follow the known-space file's end");
    }
    space.normalise();
    return space;
}

bool operator==(const KnownSpace& a, const KnownSpace& b) {
    return a.has_empty_ == b.has_empty_ && a.farthest_ == b.farthest_ &&
           a.surfaces_ == b.surfaces_ && a.seen_ == b.seen_ && a.directions_ == b.directions_;
}

void SeenUnion::add(const SeenVoxels* seen) {
    if (seen == nullptr) {
        everywhere_ = true;
    } else {
        sparse_.merge(*seen);
    }
}

double SeenUnion::first_unknown_t(const Ray& ray, double t_from, double t_to,
                                  const VoxelMask& surfaces) const {
    constexpr double none = std::numeric_limits<double>::infinity();
    if (everywhere_ || !is_dense_) {
        return none;
    }
    double t = t_from;
    while (t <= t_to) {
        const auto [enter, leave] = dense_.first_unset_span(ray, t, t_to);
        if (enter == none) {
            return none;
        }
        // A stretch shorter than a quarter voxel (a corner clipped) is not judged: its middle
        // would lie at the voxel's face, where rounding decides.
        const double middle = 0.5 * (enter + leave);
        const glm::dvec3 point = ray.at(middle);
        if ((leave - enter) * glm::length(ray.direction) > 0.25 * dense_.voxel() &&
            !sparse_.beyond_exact_region(point) && !surfaces.contains(point)) {
            return middle;
        }
        // On past this voxel: a hair past its exit, so that rounding cannot find it again.
        const double next = leave + 1e-9 * (1.0 + std::abs(leave));
        if (!(next > t)) {
            return none;
        }
        t = next;
    }
    return none;
}

void SeenUnion::densify(std::size_t max_bytes) {
    dense_ = sparse_.dense(max_bytes);
    is_dense_ = dense_.dims()[0] > 0 || sparse_.voxel_count() == 0;
    if (is_dense_) {
        sparse_.drop_voxels(); // its region stays: what lies beyond it counts as seen
    }
}

} // namespace lfprobe
