// What the CPU the core runs on can do, asked once when the library loads: the AVX2 paths
// (local_geometry.cpp's candidate comparison, few_keys_sort.cpp's sort) run only where it has
// them. Internal to the core.
#pragma once

namespace lfprobe {

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
// After the CPU's features are read (__builtin_cpu_init): a static initialiser may run before
// the compiler's own.
inline const bool kCpuHasAvx2 = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") != 0;
}();
#else
inline constexpr bool kCpuHasAvx2 = false;
#endif

} // namespace lfprobe
