// The neighbour search's sort of up to 32 keys (few_keys_sort.hpp): both its AVX2 and its one-at-
// a-time network must give exactly std::sort's smallest keys, for every count and number kept.
#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "few_keys_sort.hpp"

using namespace lfprobe;

namespace {

// `count` distinct keys drawn by `draw`, followed by junk up to kMaxKeys (read and ignored).
template <class Draw>
std::vector<std::uint64_t> distinct_keys(std::size_t count, std::mt19937_64& random, Draw draw) {
    std::vector<std::uint64_t> keys;
    while (keys.size() < count) {
        const std::uint64_t key = draw(random);
        if (std::find(keys.begin(), keys.end(), key) == keys.end()) {
            keys.push_back(key);
        }
    }
    while (keys.size() < few_keys_sort::kMaxKeys) {
        keys.push_back(random() % 7); // small: sorts before most keys if it were not ignored
    }
    return keys;
}

void expect_smallest_sorted(const std::vector<std::uint64_t>& keys, std::size_t count,
                            const char* what) {
    std::vector<std::uint64_t> expected(keys.begin(), keys.begin() + static_cast<long>(count));
    std::sort(expected.begin(), expected.end());
    for (std::size_t keep = 0; keep <= count; ++keep) {
        for (const bool vectors : {true, false}) {
            std::vector<std::uint64_t> out(few_keys_sort::kMaxKeys, 12345);
            few_keys_sort::smallest_sorted(keys.data(), count, keep, out.data(), vectors);
            ASSERT_TRUE(
                std::equal(out.begin(), out.begin() + static_cast<long>(keep), expected.begin()))
                << what << ": " << count << " keys, " << keep << " kept, vectors " << vectors;
        }
    }
}

} // namespace

// The neighbour search's keys: a non-negative float's bits above a point index. Every count
// from 0 to 32 (one register's worth, sixteen, and the merge of two sixteens) and every number
// kept, many draws each.
TEST(FewKeysSort, EveryCountAndKeepGivesStdSortsSmallestKeys) {
    std::mt19937_64 random(7);
    std::uniform_real_distribution<float> distance2(0.0f, 4.0f);
    for (std::size_t count = 0; count <= few_keys_sort::kMaxKeys; ++count) {
        for (int draw = 0; draw < 40; ++draw) {
            const auto keys = distinct_keys(count, random, [&](std::mt19937_64& r) {
                const float d2 = draw % 4 == 0 ? 0.0f : distance2(r); // ties broken by index
                return (std::uint64_t{std::bit_cast<std::uint32_t>(d2)} << 32) | (r() % 64);
            });
            expect_smallest_sorted(keys, count, "distance keys");
        }
    }
}

// AVX2 compares 64-bit lanes as signed: keys with the top bit set, and the largest keys (next
// to the padding), must still sort as unsigned integers.
TEST(FewKeysSort, KeysSortAsUnsignedIntegersUpToTheLargest) {
    std::mt19937_64 random(9);
    for (std::size_t count = 1; count <= few_keys_sort::kMaxKeys; ++count) {
        for (int draw = 0; draw < 40; ++draw) {
            const auto keys = distinct_keys(count, random, [&](std::mt19937_64& r) {
                switch (r() % 4) {
                case 0:
                    return ~std::uint64_t{0} - r() % 4; // the largest keys, padding's value too
                case 1:
                    return (std::uint64_t{1} << 63) + r() % 4; // either side of the top bit
                case 2:
                    return (std::uint64_t{1} << 63) - 1 - r() % 4;
                default:
                    return r();
                }
            });
            expect_smallest_sorted(keys, count, "unsigned keys");
        }
    }
}
