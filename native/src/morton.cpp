#include "lfprobe/morton.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

#include <glm/common.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

namespace lfprobe::morton {

namespace {

// The bounding cube of `positions` and the function giving a position's key in it.
struct KeyFrame {
    glm::vec3 origin{0.0f};
    float cube_size = 0.0f;

    explicit KeyFrame(const std::vector<glm::vec3>& positions) {
        // On all cores: minima and maxima are the same in any order.
        using Bounds = std::pair<glm::vec3, glm::vec3>;
        const Bounds empty{glm::vec3(std::numeric_limits<float>::max()),
                           glm::vec3(std::numeric_limits<float>::lowest())};
        const auto [lo, hi] = tbb::parallel_reduce(
            tbb::blocked_range<std::size_t>(0, positions.size(), std::size_t{1} << 16), empty,
            [&](const tbb::blocked_range<std::size_t>& range, Bounds bounds) {
                for (std::size_t i = range.begin(); i < range.end(); ++i) {
                    bounds.first = glm::min(bounds.first, positions[i]);
                    bounds.second = glm::max(bounds.second, positions[i]);
                }
                return bounds;
            },
            [](const Bounds& a, const Bounds& b) {
                return Bounds{glm::min(a.first, b.first), glm::max(a.second, b.second)};
            });
        const glm::vec3 extent = hi - lo;
        origin = lo;
        cube_size = std::max({extent.x, extent.y, extent.z, 1e-6f}) * (1.0f + 1e-6f);
    }
    [[nodiscard]] std::uint64_t key_of(const glm::vec3& p) const {
        const auto cells = static_cast<float>(1u << kBitsPerAxis);
        const glm::vec3 q = (p - origin) / cube_size * cells;
        const auto cell = [&](int a) {
            return static_cast<std::uint64_t>(std::clamp(q[a], 0.0f, cells - 1.0f));
        };
        return key(cell(0), cell(1), cell(2));
    }
};

// A point's key and index. Plain data (a std::pair zeroes itself when made), so that the sort's
// buffers are left unset until written on all cores: zeroing 160 MB on one thread first took
// as long as the sort's counting.
struct Keyed {
    std::uint64_t key;
    std::uint32_t index;
    friend bool operator<(const Keyed& a, const Keyed& b) {
        return a.key < b.key || (a.key == b.key && a.index < b.index);
    }
};

// `n` pairs, unset. Not advised for huge pages: where the page cache has fragmented memory,
// the kernel compacts it to make them at the first fault. The first sort of 10 M points in a
// process took 0.36-0.67 s with the advice, 0.38-0.47 s without; only a repeated sort, reusing
// the freed huge pages, was faster with it (0.22 s).
std::unique_ptr<Keyed[]> keyed_buffer(std::size_t n) {
    return std::make_unique_for_overwrite<Keyed[]>(n);
}

// Sorts the pairs of one bucket, whose keys agree above bit `shift` and which arrive in index
// order. A bucket of a room cloud holds a few hundred to a few thousand points; std::sort's
// comparisons and mispredicted branches over them were a third of sorting the cloud. A counting
// sort on the key's next bits (about as many sub-buckets as pairs; stable, so each run of equal
// bits stays in index order) leaves runs of a few pairs, which an insertion sort on the whole
// pair puts in order.
class BucketSorter {
public:
    void sort(Keyed* first, Keyed* last, int shift) {
        const auto n = static_cast<std::size_t>(last - first);
        if (n <= kSmallBucket || shift <= 0) {
            sort_run(first, last, n);
            return;
        }
        const int bits = std::min({shift, kMaxSubBits, static_cast<int>(std::bit_width(n)) + 1});
        const int low = shift - bits;
        const std::size_t sub_buckets = std::size_t{1} << bits;
        const std::uint64_t mask = sub_buckets - 1;
        // counts_[s + 1] counts sub-bucket s; summed, counts_[s] is where s starts, and after
        // the scatter (which advances it) where s ends.
        std::fill(counts_.begin(), counts_.begin() + static_cast<std::ptrdiff_t>(sub_buckets) + 1,
                  0u);
        for (std::size_t i = 0; i < n; ++i) {
            ++counts_[((first[i].key >> low) & mask) + 1];
        }
        for (std::size_t s = 1; s <= sub_buckets; ++s) {
            counts_[s] += counts_[s - 1];
        }
        scratch_.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            scratch_[counts_[(first[i].key >> low) & mask]++] = first[i];
        }
        std::copy(scratch_.begin(), scratch_.end(), first);
        std::uint32_t begin = 0;
        for (std::size_t s = 0; s < sub_buckets; ++s) {
            const std::uint32_t end = counts_[s];
            if (end - begin > 1) {
                sort_run(first + begin, first + end, end - begin);
            }
            begin = end;
        }
    }

private:
    static constexpr int kMaxSubBits = 12;
    static constexpr std::size_t kSmallBucket = 48;

    // A run in order: by insertion where it is short (nearly always), else by std::sort.
    static void sort_run(Keyed* first, Keyed* last, std::size_t n) {
        if (n > 64) {
            std::sort(first, last);
            return;
        }
        for (Keyed* i = first + 1; i < last; ++i) {
            const Keyed value = *i;
            Keyed* j = i;
            while (j > first && value < j[-1]) {
                *j = j[-1];
                --j;
            }
            *j = value;
        }
    }

    std::array<std::uint32_t, (std::size_t{1} << kMaxSubBits) + 1> counts_{};
    std::vector<Keyed> scratch_;
};

// Sorts the `n` pairs of `keyed`: a counting sort on the keys' top bits into buckets, on all
// cores, then each bucket sorted on its own (in cache, on the whole pair, so the order is the
// one a comparison sort gives). tbb::parallel_sort of the whole array moved every pair through
// memory about log n times: a tenth of the normals' estimate for 10 M points.
void sort_keyed(std::unique_ptr<Keyed[]>& keyed, std::size_t n) {
    constexpr int kBucketBits = 16;
    constexpr std::size_t kBuckets = std::size_t{1} << kBucketBits;
    constexpr int kShift = 3 * kBitsPerAxis - kBucketBits;
    if (n < 4 * kBuckets) {
        std::sort(keyed.get(), keyed.get() + n);
        return;
    }
    // Chunks of the input, each counted and scattered by one task into its own share of each
    // bucket (the chunks' shares follow in chunk order).
    constexpr std::size_t kChunks = 16;
    const std::size_t chunk_size = (n + kChunks - 1) / kChunks;
    std::vector<std::uint32_t> offsets(kChunks * kBuckets, 0);
    tbb::parallel_for(std::size_t{0}, kChunks, [&](std::size_t c) {
        std::uint32_t* count = offsets.data() + c * kBuckets;
        const std::size_t end = std::min(n, (c + 1) * chunk_size);
        for (std::size_t i = c * chunk_size; i < end; ++i) {
            ++count[keyed[i].key >> kShift];
        }
    });
    std::vector<std::uint32_t> bucket_start(kBuckets + 1, 0);
    std::uint32_t total = 0;
    for (std::size_t b = 0; b < kBuckets; ++b) {
        bucket_start[b] = total;
        for (std::size_t c = 0; c < kChunks; ++c) {
            const std::uint32_t count = offsets[c * kBuckets + b];
            offsets[c * kBuckets + b] = total;
            total += count;
        }
    }
    bucket_start[kBuckets] = total;
    std::unique_ptr<Keyed[]> out = keyed_buffer(n);
    tbb::parallel_for(std::size_t{0}, kChunks, [&](std::size_t c) {
        std::uint32_t* next = offsets.data() + c * kBuckets;
        const std::size_t end = std::min(n, (c + 1) * chunk_size);
        for (std::size_t i = c * chunk_size; i < end; ++i) {
            out[next[keyed[i].key >> kShift]++] = keyed[i];
        }
    });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, kBuckets, 256),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          BucketSorter sorter;
                          for (std::size_t b = range.begin(); b < range.end(); ++b) {
                              sorter.sort(out.get() + bucket_start[b],
                                          out.get() + bucket_start[b + 1], kShift);
                          }
                      });
    keyed = std::move(out);
}

} // namespace

SortedPoints sort_points(const std::vector<glm::vec3>& positions,
                         const std::vector<std::uint32_t>& earlier_order) {
    const std::size_t n = positions.size();
    if (earlier_order.size() != n || n == 0) {
        return sort_points(positions);
    }
    const KeyFrame frame(positions);
    SortedPoints sorted;
    sorted.origin = frame.origin;
    sorted.cube_size = frame.cube_size;
    sorted.keys.resize(n);
    std::atomic<bool> ascending{true};
    tbb::parallel_for(std::size_t{0}, n, [&](std::size_t j) {
        const std::uint32_t i = earlier_order[j];
        sorted.keys[j] = i < n ? frame.key_of(positions[i]) : 0;
        if (i >= n) {
            ascending.store(false, std::memory_order_relaxed);
        }
    });
    for (std::size_t j = 1; j < n && ascending.load(std::memory_order_relaxed); ++j) {
        // Equal keys keep the index order sort_points gives them.
        if (sorted.keys[j] < sorted.keys[j - 1] ||
            (sorted.keys[j] == sorted.keys[j - 1] && earlier_order[j] < earlier_order[j - 1])) {
            ascending.store(false, std::memory_order_relaxed);
        }
    }
    if (!ascending.load(std::memory_order_relaxed)) {
        return sort_points(positions);
    }
    sorted.order = earlier_order;
    return sorted;
}

SortedPoints sort_points(const std::vector<glm::vec3>& positions) {
    SortedPoints sorted;
    const std::size_t n = positions.size();
    if (n == 0) {
        return sorted;
    }
    const KeyFrame frame(positions);
    sorted.origin = frame.origin;
    sorted.cube_size = frame.cube_size;
    std::unique_ptr<Keyed[]> keyed = keyed_buffer(n);
    tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
        keyed[i] = {frame.key_of(positions[i]), static_cast<std::uint32_t>(i)};
    });
    sort_keyed(keyed, n);
    // Sized side by side: each is zeroed as it is sized (120 MB for 10 M points).
    tbb::parallel_invoke([&] { sorted.keys.resize(n); }, [&] { sorted.order.resize(n); });
    tbb::parallel_for(std::size_t{0}, n, [&](std::size_t j) {
        sorted.keys[j] = keyed[j].key;
        sorted.order[j] = keyed[j].index;
    });
    return sorted;
}

} // namespace lfprobe::morton
