// Lower bounds on the angle between the centres of two neighbouring texels of an N×N octahedral
// map, for turning a splat's angular radius into a texel search radius (probe_bake.cpp). The
// map's texels shrink to about half the mean angle near its corners and are near the mean
// elsewhere, so one bound for the whole map would make most searches four times the area they
// need: the bound is kept per block of texels (the block and the blocks around it), and the
// whole map's is used where a search reaches beyond the blocks around. Internal to the core.
#pragma once

#include <vector>

#include "lfprobe/octahedral.hpp"

namespace lfprobe {

class TexelAngleBounds {
public:
    static constexpr int kBlock = 16;

    explicit TexelAngleBounds(int n);

    // The search radius in texels around `home` that holds every texel within `alpha` radians
    // of a direction in `home`: a texel k steps away lies at least (k - 0.5) bounds away.
    [[nodiscard]] int search_radius(oct::Texel home, float alpha, int max_radius) const;

    // The bound that holds around texel `t` (its block and the blocks around), and the whole
    // map's.
    [[nodiscard]] float around(oct::Texel t) const {
        return around_[static_cast<std::size_t>(t.y / kBlock) * static_cast<std::size_t>(blocks_) +
                       static_cast<std::size_t>(t.x / kBlock)];
    }
    [[nodiscard]] float global() const { return global_; }

    // One bound set per resolution, made once (from any thread).
    [[nodiscard]] static const TexelAngleBounds& of(int n);

private:
    int blocks_;
    float global_ = 0.0f;
    std::vector<float> around_;
};

} // namespace lfprobe
