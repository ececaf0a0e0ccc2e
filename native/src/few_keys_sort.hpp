// Sorting the few 64-bit keys of one neighbour search (local_geometry.cpp): up to 32 keys, the k
// smallest ascending. A million queries each sort 8 to 31 candidates, so the sort is a fixed
// sequence of compare-exchanges that branches on nothing; with AVX2 it runs four keys at a time
// in registers. Internal to the core.
#pragma once

#include <cstddef>
#include <cstdint>

namespace lfprobe::few_keys_sort {

// The most keys one call sorts.
inline constexpr std::size_t kMaxKeys = 32;

// Writes the `keep` smallest of keys[0, count) to out[0, keep), ascending as unsigned integers
// (count <= kMaxKeys, keep <= count). `keys` must be readable for kMaxKeys keys from its start
// (the keys past `count` are read and ignored, so that whole registers load without a branch),
// and `out` writable for kMaxKeys (whole registers are stored; past `keep` they hold no keys). With
// `vectors` false, or on a CPU without AVX2, the network runs one compare-exchange at a time; both
// give the same keys (a sort's result is unique).
void smallest_sorted(const std::uint64_t* keys, std::size_t count, std::size_t keep,
                     std::uint64_t* out, bool vectors);

} // namespace lfprobe::few_keys_sort
