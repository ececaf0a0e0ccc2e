// The directions one probe knows (docs/DESIGN.md §4 "Rays that no probe can answer"), kept in
// the set's known space so that a trace can pass a probe over without reading it: a bit per
// texel, set where the texel's distance is known, and per block of texels (32 blocks a side)
// the farthest known distance in it. From these a probe field tells where the probe's own
// trace would stop UNKNOWN at its first texel (TraceSettings::dismiss_unknown_start) with the
// trace's own rule, each distance replaced by its block's bound: it dismisses only where the
// trace does. On the real pump-room scan most probes a ray would ask are such probes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "lfprobe/probe_map.hpp"
#include "lfprobe/probe_trace.hpp"
#include "lfprobe/ray.hpp"

namespace lfprobe {

class SeenDirections {
public:
    static constexpr int kBlocksPerSide = 32;

    SeenDirections() = default;
    explicit SeenDirections(const ProbeMap& map);

    // Whether trace_probe on the probe would answer `ray` (in the probe's frame) UNKNOWN at its
    // first texel, judged from these directions, every block's distance read `slack` metres
    // farther (a packed probe's distances may load up to a step off): true only where it
    // would; false where the trace would not judge the start so, or the bounds cannot tell.
    [[nodiscard]] bool dismisses(const Ray& ray, const TraceSettings& settings,
                                 double slack = 0.0) const;

    [[nodiscard]] int resolution() const { return resolution_; }
    [[nodiscard]] std::size_t memory_bytes() const {
        return known_.size() * sizeof(std::uint64_t) + farthest_.size() * sizeof(float);
    }

    // Appended to / read from a known-space file's bytes.
    void write_to(std::string& out) const;
    [[nodiscard]] static SeenDirections read_from(const std::string& in, std::size_t& at,
                                                  const std::string& path);
    friend bool operator==(const SeenDirections&, const SeenDirections&) = default;

private:
    [[nodiscard]] std::size_t block_of(int x, int y) const {
        return static_cast<std::size_t>(y / block_) * static_cast<std::size_t>(blocks_) +
               static_cast<std::size_t>(x / block_);
    }

    int resolution_ = 0;
    int block_ = 1;                    // texels per block side
    int blocks_ = 0;                   // blocks per side
    std::vector<std::uint64_t> known_; // bit texel_index: the texel's distance is known
    std::vector<float> farthest_;      // per block: the farthest known distance, -inf for none
};

} // namespace lfprobe
