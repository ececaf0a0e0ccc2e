// Seconds since a steady-clock time point: the stage times a bake's summary reports
// (cloud_bake.cpp, probe_set.cpp). Internal to the core.
#pragma once

#include <chrono>

namespace lfprobe {

[[nodiscard]] inline double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

} // namespace lfprobe
