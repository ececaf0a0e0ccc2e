// What the bit-for-bit bake tests share: settings at a resolution, and two probes compared bit
// for bit.
#pragma once

#include <gtest/gtest.h>

#include "lfprobe/probe_bake.hpp"
#include "lfprobe/probe_map.hpp"
#include "wall_cloud.hpp"

namespace lfprobe::testing {

// The default bake settings at `resolution`.
inline BakeSettings at(int resolution) {
    BakeSettings settings;
    settings.resolution = resolution;
    return settings;
}

inline void expect_same_probe(const ProbeMap& a, const ProbeMap& b) {
    EXPECT_TRUE(same_bits(a.distance, b.distance));
    EXPECT_TRUE(same_bits(a.rgba, b.rgba));
    EXPECT_TRUE(same_bits(a.normal, b.normal));
}

} // namespace lfprobe::testing
