#include "few_keys_sort.hpp"

#include <algorithm>
#include <array>
#include <utility>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include "cpu_features.hpp"

namespace lfprobe::few_keys_sort {

namespace {

// Calls visit(a, b) for each compare-exchange of Batcher's odd-even merge sort of n elements (n a
// power of two), in order.
template <class Visit>
constexpr void for_each_batcher_pair(std::size_t n, Visit&& visit) {
    for (std::size_t p = 1; p < n; p <<= 1) {
        for (std::size_t k = p; k >= 1; k >>= 1) {
            for (std::size_t j = k % p; j + k < n; j += 2 * k) {
                for (std::size_t i = 0; i < std::min(k, n - j - k); ++i) {
                    if ((i + j) / (2 * p) == (i + j + k) / (2 * p)) {
                        visit(i + j, i + j + k);
                    }
                }
            }
        }
    }
}

// That sort as a fixed sequence of compare-exchanges, one at a time.
template <std::size_t N>
struct SortingNetwork {
    static constexpr std::size_t kPairs = [] {
        std::size_t pairs = 0;
        for_each_batcher_pair(N, [&](std::size_t, std::size_t) { ++pairs; });
        return pairs;
    }();
    static constexpr std::array<std::pair<std::uint8_t, std::uint8_t>, kPairs> kComparators = [] {
        std::array<std::pair<std::uint8_t, std::uint8_t>, kPairs> out{};
        std::size_t at = 0;
        for_each_batcher_pair(N, [&](std::size_t a, std::size_t b) {
            out[at++] = {static_cast<std::uint8_t>(a), static_cast<std::uint8_t>(b)};
        });
        return out;
    }();

    // Sorts v[0, N) ascending.
    static void sort(std::uint64_t* v) {
#pragma GCC unroll 256
        for (std::size_t c = 0; c < kPairs; ++c) {
            const std::uint64_t a = v[kComparators[c].first];
            const std::uint64_t b = v[kComparators[c].second];
            v[kComparators[c].first] = a < b ? a : b;
            v[kComparators[c].second] = a < b ? b : a;
        }
    }
};

// Padding: sorts after every key.
constexpr std::uint64_t kPadding = ~std::uint64_t{0};

// Sorts them all, in `out`.
void sort_scalar(const std::uint64_t* keys, std::size_t count, std::uint64_t* out) {
    std::fill(std::copy(keys, keys + count, out), out + kMaxKeys, kPadding);
    if (count <= 16) {
        SortingNetwork<16>::sort(out);
    } else {
        SortingNetwork<32>::sort(out);
    }
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define LFPROBE_FEW_KEYS_AVX2 1

// The top bit, flipped to compare unsigned keys as signed.
constexpr std::uint64_t kFlip = std::uint64_t{1} << 63;

// A bitonic merge sort, four keys to a register. AVX2 compares 64-bit lanes
// as signed integers only, so the keys are loaded with their top bit flipped (unsigned order
// becomes signed order) and flipped back when stored.
#define LFPROBE_AVX2 __attribute__((target("avx2"), always_inline)) inline

// Lane by lane: the smaller key to `a`, the larger to `b`.
LFPROBE_AVX2 void order(__m256i& a, __m256i& b) {
    const __m256i a_larger = _mm256_cmpgt_epi64(a, b);
    const __m256i smaller = _mm256_blendv_epi8(a, b, a_larger);
    b = _mm256_blendv_epi8(b, a, a_larger);
    a = smaller;
}

LFPROBE_AVX2 __m256i reversed(__m256i a) {
    return _mm256_permute4x64_epi64(a, _MM_SHUFFLE(0, 1, 2, 3));
}

// Sorts each of `a` and `b`, each a bitonic run of four: compare-exchanges at distance 2, then
// 1, inside each register, both registers in the same instructions.
LFPROBE_AVX2 void sort_bitonic_fours(__m256i& a, __m256i& b) {
    __m256i x = _mm256_permute2x128_si256(a, b, 0x20); // a0 a1 b0 b1
    __m256i y = _mm256_permute2x128_si256(a, b, 0x31); // a2 a3 b2 b3
    order(x, y);                                       // now a = x0 x1 y0 y1, b = x2 x3 y2 y3
    __m256i u = _mm256_unpacklo_epi64(x, y);           // a0 a2 b0 b2
    __m256i v = _mm256_unpackhi_epi64(x, y);           // a1 a3 b1 b3
    order(u, v);
    const __m256i low = _mm256_unpacklo_epi64(u, v);  // a0 a1 b0 b1
    const __m256i high = _mm256_unpackhi_epi64(u, v); // a2 a3 b2 b3
    a = _mm256_permute2x128_si256(low, high, 0x20);
    b = _mm256_permute2x128_si256(low, high, 0x31);
}

// Sorts the bitonic run of eight a0..a3 b0..b3.
LFPROBE_AVX2 void sort_bitonic_eight(__m256i& a, __m256i& b) {
    order(a, b);
    sort_bitonic_fours(a, b);
}

// Sorts the sixteen keys r[0..3] (r[0] lane 0 the first).
LFPROBE_AVX2 void sort_sixteen(__m256i* r) {
    // Each column of the 4×4 (lane i of r[0..3]) sorted by the five-comparator network of four.
    order(r[0], r[1]);
    order(r[2], r[3]);
    order(r[0], r[2]);
    order(r[1], r[3]);
    order(r[1], r[2]);
    // Transposed: each register a sorted run of four.
    const __m256i t0 = _mm256_unpacklo_epi64(r[0], r[1]);
    const __m256i t1 = _mm256_unpackhi_epi64(r[0], r[1]);
    const __m256i t2 = _mm256_unpacklo_epi64(r[2], r[3]);
    const __m256i t3 = _mm256_unpackhi_epi64(r[2], r[3]);
    __m256i c0 = _mm256_permute2x128_si256(t0, t2, 0x20);
    __m256i c1 = _mm256_permute2x128_si256(t1, t3, 0x20);
    __m256i c2 = _mm256_permute2x128_si256(t0, t2, 0x31);
    __m256i c3 = _mm256_permute2x128_si256(t1, t3, 0x31);
    // Runs of four merged into runs of eight: one run reversed makes the pair bitonic.
    c1 = reversed(c1);
    c3 = reversed(c3);
    order(c0, c1);
    order(c2, c3);
    sort_bitonic_fours(c0, c1);
    sort_bitonic_fours(c2, c3);
    // The two runs of eight merged the same way.
    __m256i d0 = reversed(c3);
    __m256i d1 = reversed(c2);
    order(c0, d0);
    order(c1, d1);
    sort_bitonic_eight(c0, c1);
    sort_bitonic_eight(d0, d1);
    r[0] = c0;
    r[1] = c1;
    r[2] = d0;
    r[3] = d1;
}

// Loads keys[4 i, 4 i + 4) flipped, padding past `count`.
LFPROBE_AVX2 __m256i load_four(const std::uint64_t* keys, std::size_t i, __m256i count_lanes) {
    const __m256i flip = _mm256_set1_epi64x(static_cast<long long>(kFlip));
    const __m256i padding = _mm256_set1_epi64x(static_cast<long long>(kPadding ^ kFlip));
    const auto first = static_cast<long long>(4 * i);
    const __m256i at = _mm256_setr_epi64x(first, first + 1, first + 2, first + 3);
    const __m256i loaded =
        _mm256_xor_si256(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(keys + 4 * i)), flip);
    return _mm256_blendv_epi8(padding, loaded, _mm256_cmpgt_epi64(count_lanes, at));
}

// Stores the sorted registers r[0, registers) to `out`, unflipped.
LFPROBE_AVX2 void store(const __m256i* r, std::size_t registers, std::uint64_t* out) {
    const __m256i flip = _mm256_set1_epi64x(static_cast<long long>(kFlip));
    for (std::size_t i = 0; i < registers; ++i) {
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + 4 * i), _mm256_xor_si256(r[i], flip));
    }
}

__attribute__((target("avx2"))) void smallest_sorted_avx2(const std::uint64_t* keys,
                                                          std::size_t count, std::size_t keep,
                                                          std::uint64_t* out) {
    const __m256i count_lanes = _mm256_set1_epi64x(static_cast<long long>(count));
    __m256i r[8];
    for (std::size_t i = 0; i < 4; ++i) {
        r[i] = load_four(keys, i, count_lanes);
    }
    sort_sixteen(r);
    if (count <= 16) {
        store(r, 4, out);
        return;
    }
    for (std::size_t i = 4; i < 8; ++i) {
        r[i] = load_four(keys, i, count_lanes);
    }
    sort_sixteen(r + 4);
    // The two sorted sixteens, the second reversed, form a bitonic 32: the lane-wise smaller
    // keys are the sixteen smallest (a bitonic 16), the larger the sixteen largest, register
    // i of those to r[7 - i].
    for (std::size_t i = 0; i < 4; ++i) {
        __m256i other = reversed(r[7 - i]);
        order(r[i], other);
        r[7 - i] = other;
    }
    order(r[0], r[2]);
    order(r[1], r[3]);
    sort_bitonic_eight(r[0], r[1]);
    sort_bitonic_eight(r[2], r[3]);
    if (keep <= 16) {
        store(r, 4, out);
        return;
    }
    std::swap(r[4], r[7]);
    std::swap(r[5], r[6]);
    order(r[4], r[6]);
    order(r[5], r[7]);
    sort_bitonic_eight(r[4], r[5]);
    sort_bitonic_eight(r[6], r[7]);
    store(r, 8, out);
}

#undef LFPROBE_AVX2
#else
#define LFPROBE_FEW_KEYS_AVX2 0
#endif

} // namespace

void smallest_sorted(const std::uint64_t* keys, std::size_t count, std::size_t keep,
                     std::uint64_t* out, bool vectors) {
#if LFPROBE_FEW_KEYS_AVX2
    if (vectors && kCpuHasAvx2) {
        smallest_sorted_avx2(keys, count, keep, out);
        return;
    }
#else
    (void)vectors;
#endif
    (void)keep; // the one-at-a-time network sorts them all
    sort_scalar(keys, count, out);
}

} // namespace lfprobe::few_keys_sort
