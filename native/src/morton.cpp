#include "lfprobe/morton.hpp"

#include <algorithm>
#include <atomic>
#include <limits>
#include <utility>

#include <glm/common.hpp>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

namespace lfprobe::morton {

namespace {

// The bounding cube of `positions` and the function giving a position's key in it.
struct KeyFrame {
    glm::vec3 origin{0.0f};
    float cube_size = 0.0f;

    explicit KeyFrame(const std::vector<glm::vec3>& positions) {
        glm::vec3 lo(std::numeric_limits<float>::max());
        glm::vec3 hi(std::numeric_limits<float>::lowest());
        for (const glm::vec3& p : positions) {
            lo = glm::min(lo, p);
            hi = glm::max(hi, p);
        }
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
    std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(n);
    tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
        keyed[i] = {frame.key_of(positions[i]), static_cast<std::uint32_t>(i)};
    });
    tbb::parallel_sort(keyed.begin(), keyed.end());
    sorted.keys.resize(n);
    sorted.order.resize(n);
    tbb::parallel_for(std::size_t{0}, n, [&](std::size_t j) {
        sorted.keys[j] = keyed[j].first;
        sorted.order[j] = keyed[j].second;
    });
    return sorted;
}

} // namespace lfprobe::morton
