// Primary-ray throughput measured one way for every tracer (DESIGN.md §6): the camera's
// pixel-centre rays made once beforehand, then only the traces timed, fastest of `repeats`, on
// the calling task arena's threads. Ray generation and writing pixels are not in the figure.
#pragma once

#include <cstdint>

namespace lfprobe {

struct ThroughputResult {
    std::uint64_t rays = 0;
    std::uint64_t hits = 0;
    double seconds = 0.0;
    double rays_per_second = 0.0;
    int repeats = 0;
};

} // namespace lfprobe
