#include "lfprobe/local_geometry.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vector_relational.hpp>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include "lfprobe/error.hpp"
#include "lfprobe/morton.hpp"

#include "cpu_features.hpp"
#include "few_keys_sort.hpp"

namespace lfprobe {

namespace {

// A leaf of the implicit octree over the Morton-sorted points: the largest aligned cells that
// hold at most kLeafPoints points. A query's neighbours are searched in the 3×3×3 block of
// cells of its leaf's size around it, its own cell first and then cells by how far they are,
// skipping those whose nearest face lies beyond the k-th found. On a surface a leaf holds
// between a quarter of kLeafPoints and all of it, so the 13 nearest lie well within one cell:
// the block nearly always settles the search. (32 was the fastest of 12-96 on a room cloud.)
constexpr std::uint32_t kLeafPoints = 32;

struct Leaf {
    std::uint32_t begin = 0; // run in the sorted points
    std::uint32_t end = 0;
    int shift = 0; // its cells span 2^shift base cells per axis
};

// The first sorted key not below `key`, searched outward from `hint`: a cell's neighbours lie
// near it along the curve, so galloping from there touches a few cache lines where a binary
// search over the whole cloud touches twenty.
std::uint32_t lower_bound_near(const std::vector<std::uint64_t>& keys, std::uint64_t key,
                               std::uint32_t hint) {
    const auto n = static_cast<std::uint32_t>(keys.size());
    std::uint32_t lo = 0;
    std::uint32_t hi = n;
    if (hint < n && keys[hint] < key) {
        std::uint32_t step = 1;
        lo = hint + 1;
        while (hint + step < n && keys[hint + step] < key) {
            lo = hint + step + 1;
            step *= 2;
        }
        hi = std::min(n, hint + step);
    } else {
        std::uint32_t step = 1;
        hi = std::min(hint, n);
        while (step <= hint && keys[hint - step] >= key) {
            hi = hint - step;
            step *= 2;
        }
        lo = step <= hint ? hint - step + 1 : 0;
        lo = std::min(lo, hi);
    }
    return static_cast<std::uint32_t>(std::lower_bound(keys.begin() + lo, keys.begin() + hi, key) -
                                      keys.begin());
}

// The sorted points whose keys lie in the cell `cell_key` of level `shift`, searched from
// `hint`.
std::pair<std::uint32_t, std::uint32_t> cell_run(const std::vector<std::uint64_t>& keys,
                                                 std::uint64_t cell_key, int shift,
                                                 std::uint32_t hint) {
    const int bits = 3 * shift;
    const std::uint32_t first = lower_bound_near(keys, cell_key << bits, hint);
    return {first, lower_bound_near(keys, (cell_key + 1) << bits, first)};
}

void split_into_leaves(const std::vector<std::uint64_t>& keys, std::uint32_t begin,
                       std::uint32_t end, int shift, std::vector<Leaf>& leaves) {
    if (end - begin <= kLeafPoints || shift == 0) {
        leaves.push_back({begin, end, shift});
        return;
    }
    const int child_bits = 3 * (shift - 1);
    std::uint32_t b = begin;
    while (b < end) {
        const std::uint64_t limit = ((keys[b] >> child_bits) + 1) << child_bits;
        const auto e = static_cast<std::uint32_t>(
            std::lower_bound(keys.begin() + b, keys.begin() + end, limit) - keys.begin());
        split_into_leaves(keys, b, e, shift - 1, leaves);
        b = e;
    }
}

// Keys a collect may write past the last it keeps (collect_avx2 writes four at a time).
constexpr std::size_t kCollectPadding = 8;

// One candidate's key: its squared distance's bits above its index, so that keys order by
// distance, then index.
inline std::uint64_t neighbour_key(float d2, std::uint32_t q) {
    return (std::uint64_t{std::bit_cast<std::uint32_t>(d2)} << 32) | q;
}

std::size_t collect_scalar(const glm::vec3* positions, std::uint32_t begin, std::uint32_t end,
                           const glm::vec3& p, float limit, std::uint64_t* scratch,
                           std::size_t count) {
    for (std::uint32_t q = begin; q < end; ++q) {
        const glm::vec3 d = positions[q] - p;
        const float d2 = glm::dot(d, d);
        scratch[count] = neighbour_key(d2, q);
        count += d2 <= limit ? 1 : 0;
    }
    return count;
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define LFPROBE_COLLECT_AVX2 1
static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "points are read as packed floats");

// For each mask of four 64-bit keys, the 32-bit lanes that move the masked keys to the front,
// in order.
struct PackLanes {
    alignas(32) std::int32_t lanes[8];
};
static_assert(sizeof(PackLanes) == sizeof(__m256i));
const std::array<PackLanes, 16> kPackKeys = [] {
    std::array<PackLanes, 16> table{};
    for (unsigned mask = 0; mask < 16; ++mask) {
        int to = 0;
        for (int key = 0; key < 4; ++key) {
            if ((mask >> key) & 1U) {
                table[mask].lanes[2 * to] = 2 * key;
                table[mask].lanes[2 * to + 1] = 2 * key + 1;
                ++to;
            }
        }
    }
    return table;
}();

// collect_scalar eight points at a time: the same squared distances bit for bit (the same
// products and sums in the same order, no fused multiply-add), the same keys in the same order.
// The points are stored x y z x y z ...: three 8-float loads hold eight of them, and five
// shuffles sort their coordinates into an x, a y and a z vector. Most candidates lie beyond
// the limit; the keys of those within are packed to the front without a branch.
__attribute__((target("avx2"))) std::size_t
collect_avx2(const glm::vec3* positions, std::uint32_t begin, std::uint32_t end,
             std::uint32_t available, const glm::vec3& p, float limit, std::uint64_t* scratch,
             std::size_t count) {
    const __m256 px = _mm256_set1_ps(p.x);
    const __m256 py = _mm256_set1_ps(p.y);
    const __m256 pz = _mm256_set1_ps(p.z);
    const __m256 lim = _mm256_set1_ps(limit);
    const __m256i lane_numbers = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    // Entry m: the permutation for mask m (each 32 bytes, aligned).
    const auto* pack_table = reinterpret_cast<const __m256i*>(kPackKeys.data());
    std::uint32_t q = begin;
    // The last eight may reach past `end` (never past `available`): lanes past it are left out.
    for (; q < end && q + 8 <= available; q += 8) {
        const unsigned kept = end - q >= 8 ? 0xFFU : (1U << (end - q)) - 1U;
        const float* f = &positions[q].x;
        // Lanes, low 128 bits | high 128 bits:
        // a: x0 y0 z0 x1 | x4 y4 z4 x5,  b: y1 z1 x2 y2 | y5 z5 x6 y6,
        // c: z2 x3 y3 z3 | z6 x7 y7 z7.
        const __m256 a =
            _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(f)), _mm_loadu_ps(f + 12), 1);
        const __m256 b = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(f + 4)),
                                              _mm_loadu_ps(f + 16), 1);
        const __m256 c = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(f + 8)),
                                              _mm_loadu_ps(f + 20), 1);
        // x2 y2 x3 y3 and y0 z0 y1 z1 (per 128-bit half), then each coordinate's four.
        const __m256 xy = _mm256_shuffle_ps(b, c, _MM_SHUFFLE(2, 1, 3, 2));
        const __m256 yz = _mm256_shuffle_ps(a, b, _MM_SHUFFLE(1, 0, 2, 1));
        const __m256 x = _mm256_shuffle_ps(a, xy, _MM_SHUFFLE(2, 0, 3, 0));
        const __m256 y = _mm256_shuffle_ps(yz, xy, _MM_SHUFFLE(3, 1, 2, 0));
        const __m256 z = _mm256_shuffle_ps(yz, c, _MM_SHUFFLE(3, 0, 3, 1));
        const __m256 dx = _mm256_sub_ps(x, px);
        const __m256 dy = _mm256_sub_ps(y, py);
        const __m256 dz = _mm256_sub_ps(z, pz);
        const __m256 d2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)),
                                        _mm256_mul_ps(dz, dz));
        const unsigned within =
            kept & static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(d2, lim, _CMP_LE_OQ)));
        // The keys, index in the low half: lanes 0-3 and 4-7, each packed to the front of its
        // four by the mask's bits and written whole (the store may run past what is kept; the
        // next write or the caller's count covers it): no branch on which lanes are within.
        const __m256i index =
            _mm256_add_epi32(_mm256_set1_epi32(static_cast<int>(q)), lane_numbers);
        const __m256i bits = _mm256_castps_si256(d2);
        const __m256i low = _mm256_unpacklo_epi32(index, bits);  // keys 0 1 | 4 5
        const __m256i high = _mm256_unpackhi_epi32(index, bits); // keys 2 3 | 6 7
        const __m256i first = _mm256_permute2x128_si256(low, high, 0x20);
        const __m256i second = _mm256_permute2x128_si256(low, high, 0x31);
        const __m256i pack_first = _mm256_load_si256(pack_table + (within & 15U));
        const __m256i pack_second = _mm256_load_si256(pack_table + (within >> 4U));
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(scratch + count),
                            _mm256_permutevar8x32_epi32(first, pack_first));
        count += static_cast<std::size_t>(std::popcount(within & 15U));
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(scratch + count),
                            _mm256_permutevar8x32_epi32(second, pack_second));
        count += static_cast<std::size_t>(std::popcount(within >> 4U));
    }
    return collect_scalar(positions, std::min(q, end), end, p, limit, scratch, count);
}
#else
#define LFPROBE_COLLECT_AVX2 0
#endif

// The k nearest sorted points to one query, ascending by (squared distance, sorted index):
// ties go to the smaller index, so the set and its order do not depend on the order the
// candidates are offered in. A candidate is one 64-bit key, the distance's bits above the
// index (a non-negative float's bits order as the float does), so that order is one integer
// comparison. Candidates are collected without branching and the k smallest picked from them
// at the end: inserting each into a sorted list as it came cost a mispredicted branch or two
// per candidate, two fifths of the search's time.
class NearestSet {
public:
    explicit NearestSet(std::size_t k)
        : capacity_(k), keys_(std::max(k, few_keys_sort::kMaxKeys)) {}

    // Collects, from the sorted points [begin, end) of the `available` in `positions`, those
    // within `limit` (squared) of `p`, as keys (squared distance's bits, index) in index order;
    // `scratch` must hold end - begin + kCollectPadding more keys past `count`. Eight points at
    // a time where the CPU has AVX2 (collect_avx2): this loop was most of the estimate's
    // instructions.
    static std::size_t collect(const glm::vec3* positions, std::uint32_t begin, std::uint32_t end,
                               std::uint32_t available, const glm::vec3& p, float limit,
                               std::uint64_t* scratch, std::size_t count, bool vectors) {
#if LFPROBE_COLLECT_AVX2
        if (vectors && kCpuHasAvx2) {
            return collect_avx2(positions, begin, end, available, p, limit, scratch, count);
        }
#else
        (void)available;
        (void)vectors;
#endif
        return collect_scalar(positions, begin, end, p, limit, scratch, count);
    }

    // Keeps the k smallest of the `count` collected keys (all of them when fewer), sorted. Up to
    // 32 keys (nine queries in ten collect 8 to 31) go through a sorting network (few_keys_sort:
    // AVX2 where `vectors`): its compare-exchanges branch on nothing, where inserting each key
    // into a sorted run mispredicted where the run ended, a quarter of the estimate's time;
    // `scratch` must be readable for 32 keys. More keys (a second search without a limit) are
    // each inserted into a sorted run at the front of `scratch` (where it has been read
    // already), or turned away at one comparison once the run holds k and the key is past its
    // last. The keys are distinct (their indices differ), so both give the same k keys in the
    // same order.
    void settle(std::uint64_t* scratch, std::size_t count, bool vectors) {
        const std::size_t kept = std::min(count, capacity_);
        if (count <= few_keys_sort::kMaxKeys) {
            few_keys_sort::smallest_sorted(scratch, count, kept, keys_.data(), vectors);
            size_ = kept;
            return;
        }
        std::size_t size = 0;
        for (std::size_t q = 0; q < count; ++q) {
            const std::uint64_t key = scratch[q];
            if (size == kept) {
                if (key >= scratch[kept - 1]) {
                    continue;
                }
                --size;
            }
            std::size_t at = size++;
            while (at > 0 && scratch[at - 1] > key) {
                scratch[at] = scratch[at - 1];
                --at;
            }
            scratch[at] = key;
        }
        std::copy(scratch, scratch + kept, keys_.begin());
        size_ = kept;
    }

    [[nodiscard]] std::size_t size() const {
        return size_;
    }
    [[nodiscard]] std::size_t capacity() const {
        return capacity_;
    }
    [[nodiscard]] bool full() const {
        return size_ == capacity_;
    }
    [[nodiscard]] float d2(std::size_t q) const {
        return std::bit_cast<float>(static_cast<std::uint32_t>(keys_[q] >> 32));
    }
    [[nodiscard]] std::uint32_t index(std::size_t q) const {
        return static_cast<std::uint32_t>(keys_[q]);
    }

private:
    std::size_t capacity_;
    std::vector<std::uint64_t> keys_; // the first size_ are the nearest; room for a whole sort
    std::size_t size_ = 0;
};

// The 27 cells of a block around its middle one, the middle first, then its face, edge and
// corner neighbours (each ring in z, y, x order): the nearest candidates come first, so the
// rest are mostly turned away by their cell's distance alone.
constexpr std::array<glm::i8vec3, 27> kBlockOffsets = [] {
    std::array<glm::i8vec3, 27> offsets{};
    std::size_t next = 0;
    for (int ring = 0; ring <= 3; ++ring) {
        for (int dz = -1; dz <= 1; ++dz) {
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                    if ((dx < 0 ? -dx : dx) + (dy < 0 ? -dy : dy) + (dz < 0 ? -dz : dz) == ring) {
                        offsets[next++] = glm::i8vec3(dx, dy, dz);
                    }
                }
            }
        }
    }
    return offsets;
}();

// Searches the k nearest points of the sorted point `j` among the 3×3×3 block of cells of
// level `shift` around its own, growing the block a level at a time until the k-th nearest
// lies closer than the block's nearest face (then nothing outside can be nearer) or the block
// is the whole cube. `runs` is scratch space.
class BlockSearch {
public:
    BlockSearch(const morton::SortedPoints& sorted, const glm::vec3* positions, bool vectors)
        : sorted_(sorted), positions_(positions), vectors_(vectors),
          scratch_(2 * few_keys_sort::kMaxKeys) {}

    // The runs of sorted points in the block of level `shift` around the cell `cell`, in the
    // order of kBlockOffsets.
    void gather(const glm::u64vec3& cell, int shift, std::uint32_t hint) {
        runs_.clear();
        const auto cells =
            static_cast<std::int64_t>(std::uint64_t{1} << (morton::kBitsPerAxis - shift));
        // Each axis's three coordinates in the block, spread to their place in a key once (nine
        // spreads of 21 bits, where a key per cell took 81), and whether they lie in the cube
        // (outside it there are no points).
        std::array<std::array<std::uint64_t, 3>, 3> spread{};
        std::array<std::array<bool, 3>, 3> inside{};
        for (std::size_t a = 0; a < 3; ++a) {
            for (std::size_t d = 0; d < 3; ++d) {
                const std::int64_t c =
                    static_cast<std::int64_t>(cell[static_cast<int>(a)]) + static_cast<int>(d) - 1;
                inside[a][d] = c >= 0 && c < cells;
                spread[a][d] =
                    inside[a][d] ? morton::spread_bits(static_cast<std::uint64_t>(c)) << a : 0;
            }
        }
        for (const glm::i8vec3& offset : kBlockOffsets) {
            const auto x = static_cast<std::size_t>(offset.x + 1);
            const auto y = static_cast<std::size_t>(offset.y + 1);
            const auto z = static_cast<std::size_t>(offset.z + 1);
            if (!inside[0][x] || !inside[1][y] || !inside[2][z]) {
                continue;
            }
            const auto [b, e] = run_of(spread[0][x] | spread[1][y] | spread[2][z], shift, hint);
            if (b < e) {
                runs_.push_back({b, e, offset});
            }
        }
        block_cell_ = cell;
        block_shift_ = shift;
        // Room for every point of the block, so that a search need not check as it collects.
        std::size_t points = 0;
        for (const Run& run : runs_) {
            points += run.end - run.begin;
        }
        if (scratch_.size() < points + kCollectPadding) {
            scratch_.resize(2 * (points + kCollectPadding));
        }
    }

    // The sorted points of cell `cell_key` at level `shift`, remembered: the next leaf along the
    // curve is mostly the same size and beside this one, so its block shares most cells with
    // this one's, and their runs were searched for already (each a pair of galloping searches,
    // a tenth of the estimate).
    std::pair<std::uint32_t, std::uint32_t> run_of(std::uint64_t cell_key, int shift,
                                                   std::uint32_t hint) {
        KnownRun& known =
            known_runs_[((cell_key * 0x9E3779B97F4A7C15ull) >> 56) ^ static_cast<unsigned>(shift)];
        if (known.shift != shift || known.cell_key != cell_key) {
            const auto [b, e] = cell_run(sorted_.keys, cell_key, shift, hint);
            known = {cell_key, shift, b, e};
        }
        return {known.begin, known.end};
    }

    // The k nearest of the sorted point `j` within the gathered block, of those within `limit`
    // (squared; cells wholly beyond it are skipped): exact whenever k points lie within it.
    void search(std::uint32_t j, NearestSet& nearest, float limit) {
        const glm::vec3 p = positions_[j];
        // p's offsets from its cell's lower and upper faces, for the distance to a neighbour.
        const float h = sorted_.cell_size(block_shift_);
        const glm::vec3 local = p - sorted_.origin;
        const glm::vec3 below = local - glm::vec3(block_cell_) * h;
        const glm::vec3 above = glm::vec3(h) - below;
        // The squared gap to a neighbouring cell along each axis, by the cell's offset (-1, 0,
        // +1): summed per cell in axis order, the same sums as gap by gap, without a branch.
        std::array<std::array<float, 3>, 3> gaps{};
        for (int a = 0; a < 3; ++a) {
            gaps[a][0] = below[a] > 0.0f ? below[a] * below[a] : 0.0f;
            gaps[a][2] = above[a] > 0.0f ? above[a] * above[a] : 0.0f;
        }
        std::size_t count = 0;
        for (const Run& run : runs_) {
            const float gap2 = gaps[0][static_cast<std::size_t>(run.offset.x + 1)] +
                               gaps[1][static_cast<std::size_t>(run.offset.y + 1)] +
                               gaps[2][static_cast<std::size_t>(run.offset.z + 1)];
            // Strictly beyond: a point at the limit itself is still collected.
            if (gap2 > limit) {
                continue;
            }
            count = NearestSet::collect(positions_, run.begin, run.end,
                                        static_cast<std::uint32_t>(sorted_.keys.size()), p, limit,
                                        scratch_.data(), count, vectors_);
        }
        nearest.settle(scratch_.data(), count, vectors_);
    }

    // The k nearest within the block, at first within `guess` (squared; the previous query's
    // k-th, widened), which turns most candidates away before they are kept; when fewer than k
    // lie within it, again within a limit widened for the shortfall, and at last without one.
    void search_from_guess(std::uint32_t j, NearestSet& nearest, float guess) {
        search(j, nearest, guess);
        if (!nearest.full()) {
            // Found f < k: on a surface the k lie within k / f times the area, so within that
            // many times the squared guess (and half again, as the guess had): about 1.5 k
            // candidates again. Without a limit a second search took in 120 on average, one
            // query in twenty, and a fifth of all candidates.
            const float found = static_cast<float>(std::max<std::size_t>(nearest.size(), 1));
            search(j, nearest, guess * 1.5f * static_cast<float>(nearest.capacity()) / found);
            if (!nearest.full()) {
                search(j, nearest, std::numeric_limits<float>::infinity());
            }
        }
    }

    // Whether the k nearest found in the gathered block are the k nearest of the cloud: the
    // k-th lies nearer than every face of the block that has cells beyond it.
    [[nodiscard]] bool settles(std::uint32_t j, const NearestSet& nearest) const {
        if (block_shift_ >= morton::kBitsPerAxis) {
            return true;
        }
        if (!nearest.full()) {
            return false;
        }
        const float h = sorted_.cell_size(block_shift_);
        const std::uint64_t cells = std::uint64_t{1} << (morton::kBitsPerAxis - block_shift_);
        const glm::vec3 local = positions_[j] - sorted_.origin;
        float reach = std::numeric_limits<float>::infinity();
        for (int a = 0; a < 3; ++a) {
            const auto c = static_cast<float>(block_cell_[a]);
            if (block_cell_[a] > 0) {
                reach = std::min(reach, local[a] - (c - 1.0f) * h);
            }
            if (block_cell_[a] + 1 < cells) {
                reach = std::min(reach, (c + 2.0f) * h - local[a]);
            }
        }
        // A margin for the rounding of cell bounds computed in float.
        reach -= 1e-5f * sorted_.cube_size;
        return reach > 0.0f && nearest.d2(nearest.size() - 1) <= reach * reach;
    }

    // Search, growing the block until it settles.
    void nearest_of(std::uint32_t j, int shift, NearestSet& nearest) {
        for (int s = shift;; ++s) {
            if (s != shift || block_shift_ != shift) {
                gather(morton::cell(sorted_.keys[j] >> (3 * s)), s, j);
            }
            // The k found in a smaller block bound the k-th of a larger one from above.
            search(j, nearest,
                   nearest.full() ? nearest.d2(nearest.size() - 1)
                                  : std::numeric_limits<float>::infinity());
            if (settles(j, nearest)) {
                return;
            }
        }
    }

private:
    struct Run {
        std::uint32_t begin = 0;
        std::uint32_t end = 0;
        glm::i8vec3 offset{0}; // the cell's place in the block
    };
    const morton::SortedPoints& sorted_;
    const glm::vec3* positions_; // the points in sorted order
    bool vectors_;               // LocalGeometryOptions::vector_instructions
    std::vector<Run> runs_;
    std::vector<std::uint64_t> scratch_; // the candidates of one search (settle reads 32)
    struct KnownRun {
        std::uint64_t cell_key = 0;
        int shift = -1; // none yet
        std::uint32_t begin = 0;
        std::uint32_t end = 0;
    };
    std::array<KnownRun, 256> known_runs_{}; // by a hash of the cell (run_of)
    glm::u64vec3 block_cell_{0};
    int block_shift_ = -1;
};

// A point's SurfaceEdge from `to_mean`, the offset of its neighbours' mean: the part of it in
// the tangent plane of `normal` (all of it without a normal), in spacings.
SurfaceEdge surface_edge(const glm::dvec3& to_mean, const glm::vec3& normal, float spacing) {
    SurfaceEdge edge;
    const glm::dvec3 n(normal);
    const glm::dvec3 tangential =
        glm::dot(n, n) > 0.0 ? to_mean - glm::dot(to_mean, n) * n : to_mean;
    const double length = glm::length(tangential);
    if (!(spacing > 0.0f) || !(length > 0.0)) {
        return edge;
    }
    for (int a = 0; a < 3; ++a) {
        edge.inward[a] = static_cast<std::int8_t>(std::lround(127.0 * tangential[a] / length));
    }
    edge.offset = static_cast<std::uint8_t>(
        std::min(255.0, std::round(64.0 * length / static_cast<double>(spacing))));
    return edge;
}

} // namespace

std::vector<std::uint32_t> morton_order(const std::vector<glm::vec3>& positions) {
    return morton::sort_points(positions).order;
}

namespace {

// Cyclic Jacobi: slow (several sweeps of rotations) but exact however close the eigenvalues lie.
glm::vec3 jacobi_smallest_eigenvector(const double covariance[3][3]) {
    double a[3][3];
    double v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            a[i][j] = covariance[i][j];
        }
    }
    // Cyclic Jacobi: each rotation zeroes one off-diagonal element; a handful of sweeps
    // converge to machine precision for 3×3.
    for (int sweep = 0; sweep < 32; ++sweep) {
        const double off = std::abs(a[0][1]) + std::abs(a[0][2]) + std::abs(a[1][2]);
        const double scale = std::abs(a[0][0]) + std::abs(a[1][1]) + std::abs(a[2][2]);
        if (off <= 1e-300 || off <= 1e-15 * scale) {
            break;
        }
        for (int p = 0; p < 2; ++p) {
            for (int q = p + 1; q < 3; ++q) {
                if (a[p][q] == 0.0) {
                    continue;
                }
                const double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                const double t =
                    (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1.0));
                const double c = 1.0 / std::sqrt(t * t + 1.0);
                const double s = t * c;
                for (int k = 0; k < 3; ++k) {
                    const double akp = a[k][p];
                    const double akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 3; ++k) {
                    const double apk = a[p][k];
                    const double aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for (int k = 0; k < 3; ++k) {
                    const double vkp = v[k][p];
                    const double vkq = v[k][q];
                    v[k][p] = c * vkp - s * vkq;
                    v[k][q] = s * vkp + c * vkq;
                }
            }
        }
    }
    int smallest = 0;
    for (int i = 1; i < 3; ++i) {
        if (a[i][i] < a[smallest][smallest]) {
            smallest = i;
        }
    }
    const glm::dvec3 e{v[0][smallest], v[1][smallest], v[2][smallest]};
    return glm::vec3(glm::normalize(e));
}

} // namespace

glm::vec3 smallest_eigenvector(const double covariance[3][3]) {
    // The smallest eigenvalue as the characteristic cubic's smallest root, then its
    // eigenvector as the largest cross product of two rows of A - λI, which span the plane
    // orthogonal to it. On a surface's neighbourhood the two other eigenvalues lie far above
    // it, and the cross product is exact to rounding; λ's own rounding (~1e-16 of the largest
    // eigenvalue) tilts the vector by as little.
    // Where the two smallest eigenvalues lie close (points along a line, a zero matrix), the
    // rows barely span a plane and Jacobi decides. Jacobi alone was a seventh of the whole
    // estimate on the lab room's 0.1° scans, whose points lie nearly exactly on their surfaces.
    double scale = 0.0;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            scale = std::max(scale, std::abs(covariance[i][j]));
        }
    }
    if (!(scale > 0.0) || !std::isfinite(scale)) {
        return jacobi_smallest_eigenvector(covariance);
    }
    const double inverse_scale = 1.0 / scale;
    double b[3][3];
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            b[i][j] = covariance[i][j] * inverse_scale;
        }
    }
    // The characteristic polynomial det(B - λI) = -λ³ + tλ² - mλ + d. A covariance has no
    // negative eigenvalue, and left of its smallest root the polynomial is convex and falling,
    // so Newton's method from λ = 0 climbs to that root without passing it, quadratically
    // where the next root lies apart (a surface: two or three steps). It stops where a step no
    // longer moves λ up (rounding, or a singular matrix whose root is 0 itself).
    const double t = b[0][0] + b[1][1] + b[2][2];
    const double m = b[0][0] * b[1][1] - b[0][1] * b[0][1] + b[0][0] * b[2][2] - b[0][2] * b[0][2] +
                     b[1][1] * b[2][2] - b[1][2] * b[1][2];
    const double d = b[0][0] * (b[1][1] * b[2][2] - b[1][2] * b[1][2]) -
                     b[0][1] * (b[0][1] * b[2][2] - b[1][2] * b[0][2]) +
                     b[0][2] * (b[0][1] * b[1][2] - b[1][1] * b[0][2]);
    double lambda = 0.0;
    for (int step = 0; step < 64; ++step) {
        const double f = ((t - lambda) * lambda - m) * lambda + d;
        const double slope = (2.0 * t - 3.0 * lambda) * lambda - m;
        if (!(slope < 0.0)) {
            break;
        }
        const double next = lambda - f / slope;
        if (!(next > lambda)) {
            break;
        }
        lambda = next;
    }
    // The gap to the next eigenvalues sets the cross products' lengths below: p is their scale.
    const double p = std::sqrt(std::max(t * t - 3.0 * m, 0.0)) / 3.0;
    if (!(p > 1e-12)) {
        return jacobi_smallest_eigenvector(covariance); // three equal eigenvalues
    }
    const glm::dvec3 row0(b[0][0] - lambda, b[0][1], b[0][2]);
    const glm::dvec3 row1(b[0][1], b[1][1] - lambda, b[1][2]);
    const glm::dvec3 row2(b[0][2], b[1][2], b[2][2] - lambda);
    const glm::dvec3 candidates[3] = {glm::cross(row0, row1), glm::cross(row0, row2),
                                      glm::cross(row1, row2)};
    int best = 0;
    double best_length2 = glm::dot(candidates[0], candidates[0]);
    for (int k = 1; k < 3; ++k) {
        const double length2 = glm::dot(candidates[k], candidates[k]);
        if (length2 > best_length2) {
            best = k;
            best_length2 = length2;
        }
    }
    // The cross product's length is about the product of the other two eigenvalues' distances
    // from λ (p² scale); below 1e-5 p of the nearer one, rounding would tilt the vector by
    // more than float precision.
    if (!(best_length2 > 1e-10 * p * p * p * p)) {
        return jacobi_smallest_eigenvector(covariance);
    }
    return glm::vec3(candidates[best] / std::sqrt(best_length2));
}

LocalGeometry estimate_local_geometry(const PointCloud& cloud, const LocalGeometryOptions& options,
                                      Progress* progress) {
    if (options.normal_neighbours < 3 || options.spacing_neighbours < 1) {
        throw InputError("local geometry: need at least 3 neighbours for normals and 1 for "
                         "spacing");
    }
    const std::size_t n = cloud.size();
    LocalGeometry result;
    if (n == 0) {
        return result;
    }
    // Sized side by side: zeroing 210 MB for 10 M points on one thread took 0.11 s. (Not
    // advised for huge pages, nor are the arrays below: the estimate runs once per cloud, and a
    // first fault of huge pages waits while the kernel compacts memory the page cache has
    // fragmented: 0.4-0.7 s more for 10 M points, repaid only when the memory is reused.)
    tbb::parallel_invoke([&] { result.normals.resize(n); },
                         [&] {
                             result.spacing.resize(n);
                             result.oriented.resize(n);
                         },
                         [&] { result.edges.resize(n); });
    if (progress != nullptr) {
        progress->begin_stage("indexing points", 1);
    }
    // Neighbours are searched in the cells of the points' Morton order: queries and their
    // candidates sit close together in memory, and a block of cells is a few runs of it.
    const morton::SortedPoints sorted = morton::sort_points(cloud.positions);
    // What the search reads and writes per point, in the sorted order: the cloud's arrays are
    // in file order, and reading or writing them at each point's place amid the search's
    // arithmetic missed the cache at every point; copied in and out in tight loops, many of
    // those misses are in flight at once.
    // Left unset until written on all cores (every element is): zeroing them first on one
    // thread, 330 MB for 10 M points, took a twentieth of the estimate.
    const auto positions = std::make_unique_for_overwrite<glm::vec3[]>(n);
    const auto scan_of = std::make_unique_for_overwrite<std::uint32_t[]>(n);
    const auto normals_in_order = std::make_unique_for_overwrite<glm::vec3[]>(n);
    const auto spacing_in_order = std::make_unique_for_overwrite<float[]>(n);
    const auto oriented_in_order = std::make_unique_for_overwrite<std::uint8_t[]>(n);
    std::vector<SurfaceEdge> edges_in_order;
    std::vector<Leaf> leaves;
    tbb::parallel_invoke(
        [&] {
            tbb::parallel_for(std::size_t{0}, n, [&](std::size_t j) {
                positions[j] = cloud.positions[sorted.order[j]];
                scan_of[j] = cloud.scan_index[sorted.order[j]];
            });
        },
        [&] { edges_in_order.resize(n); },
        [&] {
            split_into_leaves(sorted.keys, 0, static_cast<std::uint32_t>(n), morton::kBitsPerAxis,
                              leaves);
        });
    if (progress != nullptr) {
        progress->throw_if_cancelled();
        progress->begin_stage("estimating normals and spacing", n);
    }
    const bool use_file_normals = options.keep_file_normals && cloud.has_normals();
    const std::size_t k = static_cast<std::size_t>(
                              std::max(options.normal_neighbours, options.spacing_neighbours + 1)) +
                          1;
    const std::size_t normal_count = static_cast<std::size_t>(options.normal_neighbours) + 1;
    constexpr std::size_t kLeavesPerTask = 256;
    tbb::parallel_for(
        std::size_t{0}, (leaves.size() + kLeavesPerTask - 1) / kLeavesPerTask,
        [&](std::size_t task) {
            if (progress != nullptr) {
                progress->throw_if_cancelled();
            }
            BlockSearch block(sorted, positions.get(), options.vector_instructions);
            NearestSet nearest(k);
            // Neighbouring queries have k-th distances alike: 1.5 times the last one's squared
            // distance (1.22 times the distance) takes in about 1.5 k candidates on a surface
            // and needs a second search for 5 % of queries (1.3: 12 %, slower; 2: more
            // candidates, slower; a 10 M-point room).
            float guess = std::numeric_limits<float>::infinity();
            std::size_t done = 0;
            const std::size_t last = std::min(leaves.size(), (task + 1) * kLeavesPerTask);
            for (std::size_t l = task * kLeavesPerTask; l < last; ++l) {
                const Leaf& leaf = leaves[l];
                block.gather(morton::cell(sorted.keys[leaf.begin] >> (3 * leaf.shift)), leaf.shift,
                             leaf.begin);
                for (std::uint32_t j = leaf.begin; j < leaf.end; ++j) {
                    block.search_from_guess(j, nearest, guess);
                    if (!block.settles(j, nearest)) {
                        block.nearest_of(j, leaf.shift + 1, nearest);
                        block.gather(morton::cell(sorted.keys[leaf.begin] >> (3 * leaf.shift)),
                                     leaf.shift, leaf.begin);
                    }
                    const std::size_t found = nearest.size();
                    guess = found > 0 && nearest.d2(found - 1) > 0.0f
                                ? 1.5f * nearest.d2(found - 1)
                                : std::numeric_limits<float>::infinity();
                    const glm::vec3 p = positions[j];
                    // Spacing: mean distance to the nearest distinct neighbours (duplicates
                    // skipped).
                    double spacing_sum = 0.0;
                    int spacing_count = 0;
                    for (std::size_t q = 0; q < found && spacing_count < options.spacing_neighbours;
                         ++q) {
                        if (nearest.d2(q) > 0.0f) {
                            spacing_sum += std::sqrt(static_cast<double>(nearest.d2(q)));
                            ++spacing_count;
                        }
                    }
                    const float spacing =
                        spacing_count > 0 ? static_cast<float>(spacing_sum / spacing_count) : 0.0f;
                    spacing_in_order[j] = spacing;

                    glm::vec3 normal(0.0f);
                    std::uint8_t oriented = 0;
                    const std::size_t m = std::min(found, normal_count);
                    glm::dvec3 mean(0.0);
                    for (std::size_t q = 0; q < m; ++q) {
                        mean += glm::dvec3(positions[nearest.index(q)]);
                    }
                    mean /= static_cast<double>(std::max<std::size_t>(m, 1));
                    if (use_file_normals) {
                        normal = cloud.normals[sorted.order[j]];
                        oriented = 1;
                    } else {
                        // The upper triangle; the lower mirrors it (each product is the same
                        // either way round).
                        double cov[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
                        for (std::size_t q = 0; q < m; ++q) {
                            const glm::dvec3 e = glm::dvec3(positions[nearest.index(q)]) - mean;
                            for (int r = 0; r < 3; ++r) {
                                for (int c = r; c < 3; ++c) {
                                    cov[r][c] += e[r] * e[c];
                                }
                            }
                        }
                        cov[1][0] = cov[0][1];
                        cov[2][0] = cov[0][2];
                        cov[2][1] = cov[1][2];
                        if (m >= 3) {
                            normal = smallest_eigenvector(cov);
                        }
                    }
                    const ScanSource& scan = cloud.scans[scan_of[j]];
                    if (scan.has_scanner && glm::dot(normal, normal) > 0.0f) {
                        const glm::vec3 to_scanner = glm::vec3(scan.scanner - glm::dvec3(p));
                        if (glm::dot(normal, to_scanner) < 0.0f) {
                            normal = -normal;
                        }
                        oriented = 1;
                    }
                    normals_in_order[j] = normal;
                    oriented_in_order[j] = oriented;
                    edges_in_order[j] = surface_edge(mean - glm::dvec3(p), normal, spacing);
                }
                done += leaf.end - leaf.begin;
            }
            if (progress != nullptr) {
                progress->advance(done);
            }
        });
    tbb::parallel_for(std::size_t{0}, n, [&](std::size_t j) {
        const std::uint32_t i = sorted.order[j];
        result.normals[i] = normals_in_order[j];
        result.spacing[i] = spacing_in_order[j];
        result.oriented[i] = oriented_in_order[j];
        result.edges[i] = edges_in_order[j];
    });
    result.spatial_order = sorted.order;
    return result;
}

} // namespace lfprobe
