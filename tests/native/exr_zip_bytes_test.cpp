// An EXR ZIP block's bytes split and differenced for writing, and summed and interleaved for
// reading, sixteen bytes at a time (exr_zip_bytes.hpp): the same bytes as byte by byte, for
// every length around the vector width and its halves, odd and even, and bytes of any value.
#include <cstdint>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "exr_zip_bytes.hpp"

using namespace lfprobe;

TEST(ExrZipBytes, SixteenAtATimeGiveTheBytesOfTheFormat) {
    std::mt19937 rng(11);
    std::uniform_int_distribution<int> byte(0, 255);
    std::vector<std::size_t> lengths;
    for (std::size_t n = 0; n <= 140; ++n) {
        lengths.push_back(n);
    }
    for (const std::size_t n : {255u, 256u, 257u, 1023u, 4096u, 65537u, 1u << 20}) {
        lengths.push_back(n);
    }
    for (const std::size_t n : lengths) {
        for (int trial = 0; trial < 3; ++trial) {
            std::vector<std::uint8_t> inflated(n);
            for (auto& b : inflated) {
                // Mostly small differences (stored near 128), as a smooth map's are, and any.
                b = static_cast<std::uint8_t>(trial == 0 ? 128 + byte(rng) % 5 - 2 : byte(rng));
            }
            std::vector<std::uint8_t> scratch = inflated;
            std::vector<std::uint8_t> expected(n);
            unpack_zip_bytes_serially(scratch.data(), n, expected.data());
            scratch = inflated;
            std::vector<std::uint8_t> got(n, 0xab);
            unpack_zip_bytes(scratch.data(), n, got.data());
            ASSERT_EQ(got, expected) << n << " bytes, trial " << trial;
            // Written: split and differenced as byte by byte, and read back to the same bytes.
            std::vector<std::uint8_t> packed(n, 0xcd);
            std::vector<std::uint8_t> packed_serially(n);
            pack_zip_bytes(inflated.data(), n, packed.data());
            pack_zip_bytes_serially(inflated.data(), n, packed_serially.data());
            ASSERT_EQ(packed, packed_serially) << n << " bytes, trial " << trial;
            std::vector<std::uint8_t> back(n);
            unpack_zip_bytes(packed.data(), n, back.data());
            ASSERT_EQ(back, inflated) << n << " bytes, trial " << trial;
        }
    }
}
