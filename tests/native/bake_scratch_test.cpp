// Scratch arrays kept from one probe's bake for the next (bake_scratch.hpp): a bake that starts
// from another's leftovers must come out bit for bit as one from fresh memory, and a scope's
// blocks must be handed out again only within it.
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "lfprobe/bake_scratch.hpp"
#include "lfprobe/cloud_bake.hpp"
#include "same_probe.hpp"
#include "wall_cloud.hpp"

using namespace lfprobe;
using lfprobe::testing::expect_same_probe;

TEST(BakeScratch, ABakeFromAnotherBakesLeftoverArraysIsTheSameBitForBit) {
    BakeSettings settings;
    settings.resolution = 128;
    const CloudBakeSource source = prepare_cloud_bake(
        std::make_shared<const PointCloud>(lfprobe::testing::wall_corner(0.01f)), settings, {});
    const std::vector<glm::dvec3> centres = {
        glm::dvec3(-1.0, 0.1, 0.2), glm::dvec3(-0.05, 0.45, 0.0), glm::dvec3(-6.0, -3.0, 2.0)};
    std::vector<ProbeMap> fresh;
    for (const glm::dvec3& centre : centres) {
        fresh.push_back(bake_probe(source, centre));
    }
    // Each bake in the scope starts from the arrays the one before filled: other fronts,
    // winners and colour sums, another cut's points.
    const BakeScratchScope scope;
    for (int round = 0; round < 2; ++round) {
        for (std::size_t i = 0; i < centres.size(); ++i) {
            expect_same_probe(bake_probe(source, centres[i]), fresh[i]);
        }
    }
}

TEST(BakeScratch, AScopeHandsItsBlocksOutAgainOnlyWhileItLives) {
    const void* first = nullptr;
    {
        const BakeScratchScope scope;
        { first = ScratchBytes(1000).data(); }
        {
            const ScratchBytes again(800); // the smallest kept block large enough
            EXPECT_EQ(again.data(), first);
        }
        const void* larger = nullptr;
        { larger = ScratchBytes(5000).data(); } // none large enough: the 1000 block is freed
        {
            const ScratchBytes small(10);
            EXPECT_EQ(small.data(), larger);
            {
                const BakeScratchScope inner; // the innermost scope serves
                const ScratchBytes other(10);
                EXPECT_NE(other.data(), larger);
            }
        }
    }
    // Outside every scope a block is plain memory, freed when done.
    const ScratchBytes outside(16);
    EXPECT_NE(outside.data(), nullptr);
    EXPECT_EQ(ScratchBytes(0).data(), nullptr);
}
