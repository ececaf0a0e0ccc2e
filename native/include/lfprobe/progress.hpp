// Progress reporting and cancellation shared by every long native job. Workers only touch
// atomics, so a UI thread (Blender's timer, the CLI's poll loop) can read progress and ask
// for cancellation without locks and without holding the GIL in the workers.
#pragma once

#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include "lfprobe/error.hpp"

namespace lfprobe {

class Progress {
public:
    // Starts a new stage of `total` work units (points, probes, texels: the stage decides).
    void begin_stage(const std::string& name, std::uint64_t total) {
        {
            std::lock_guard lock(stage_mutex_);
            stage_ = name;
        }
        total_.store(total == 0 ? 1 : total, std::memory_order_relaxed);
        done_.store(0, std::memory_order_relaxed);
    }
    void advance(std::uint64_t units) { done_.fetch_add(units, std::memory_order_relaxed); }

    // Fraction of the current stage in [0, 1].
    [[nodiscard]] double fraction() const {
        const double total = static_cast<double>(total_.load(std::memory_order_relaxed));
        const double done = static_cast<double>(done_.load(std::memory_order_relaxed));
        return done >= total ? 1.0 : done / total;
    }
    [[nodiscard]] std::string stage() const {
        std::lock_guard lock(stage_mutex_);
        return stage_;
    }

    // Something the user should hear about that did not stop the work (a cache that could not
    // be written): kept, and raised as a Python warning when the job's result is taken.
    void warn(const std::string& message) {
        std::lock_guard lock(stage_mutex_);
        warnings_.push_back(message);
    }
    [[nodiscard]] std::vector<std::string> warnings() const {
        std::lock_guard lock(stage_mutex_);
        return warnings_;
    }
    void request_cancel() { cancel_.store(true, std::memory_order_relaxed); }
    [[nodiscard]] bool cancel_requested() const { return cancel_.load(std::memory_order_relaxed); }
    // Called by workers between units of work.
    void throw_if_cancelled() const {
        if (cancel_requested()) {
            throw Cancelled();
        }
    }

private:
    mutable std::mutex stage_mutex_;
    std::string stage_;
    std::vector<std::string> warnings_;
    std::atomic<std::uint64_t> total_{1};
    std::atomic<std::uint64_t> done_{0};
    std::atomic<bool> cancel_{false};
};

} // namespace lfprobe
