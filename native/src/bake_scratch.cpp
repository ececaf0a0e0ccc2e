#include "lfprobe/bake_scratch.hpp"

#include <algorithm>
#include <mutex>
#include <utility>
#include <vector>

namespace lfprobe {

class BakeScratchPool {
public:
    // The smallest kept block of at least `bytes`, or none. Where none is large enough, the
    // largest kept block is freed: it is too small for this bake's arrays, so keeping it
    // would only add to the set's memory.
    std::pair<std::unique_ptr<std::byte[]>, std::size_t> take(std::size_t bytes) {
        const std::lock_guard<std::mutex> lock(mutex_);
        auto best = blocks_.end();
        auto largest = blocks_.end();
        for (auto it = blocks_.begin(); it != blocks_.end(); ++it) {
            if (it->second >= bytes && (best == blocks_.end() || it->second < best->second)) {
                best = it;
            }
            if (largest == blocks_.end() || it->second > largest->second) {
                largest = it;
            }
        }
        if (best == blocks_.end()) {
            if (largest != blocks_.end()) {
                blocks_.erase(largest);
            }
            return {nullptr, 0};
        }
        auto block = std::move(*best);
        blocks_.erase(best);
        return block;
    }

    void give(std::unique_ptr<std::byte[]> block, std::size_t size) {
        const std::lock_guard<std::mutex> lock(mutex_);
        blocks_.emplace_back(std::move(block), size);
    }

private:
    std::mutex mutex_;
    std::vector<std::pair<std::unique_ptr<std::byte[]>, std::size_t>> blocks_;
};

namespace {

thread_local BakeScratchScope* innermost = nullptr;

} // namespace

BakeScratchScope::BakeScratchScope()
    : pool_(std::make_shared<BakeScratchPool>()), outer_(innermost) {
    innermost = this;
}

BakeScratchScope::~BakeScratchScope() {
    innermost = outer_;
}

std::shared_ptr<BakeScratchPool> BakeScratchScope::current() {
    return innermost != nullptr ? innermost->pool_ : nullptr;
}

ScratchBytes::ScratchBytes(std::size_t bytes) {
    if (bytes == 0) {
        return;
    }
    if (std::shared_ptr<BakeScratchPool> pool = BakeScratchScope::current()) {
        auto [block, size] = pool->take(bytes);
        block_ = std::move(block);
        size_ = size;
        pool_ = pool;
    }
    if (!block_) {
        block_ = std::make_unique_for_overwrite<std::byte[]>(bytes);
        size_ = bytes;
    }
}

ScratchBytes::~ScratchBytes() {
    if (block_) {
        if (std::shared_ptr<BakeScratchPool> pool = pool_.lock()) {
            pool->give(std::move(block_), size_);
        }
    }
}

} // namespace lfprobe
