#include "lfprobe/huge_pages.hpp"

#include <cstdint>

#include <sys/mman.h>

namespace lfprobe {

void advise_huge_pages(const void* data, std::size_t bytes) {
#ifdef MADV_HUGEPAGE
    constexpr std::uintptr_t kHugePage = std::uintptr_t{2} << 20;
    const auto begin = reinterpret_cast<std::uintptr_t>(data);
    const std::uintptr_t from = (begin + kHugePage - 1) & ~(kHugePage - 1);
    const std::uintptr_t to = (begin + bytes) & ~(kHugePage - 1);
    if (data != nullptr && to > from) {
        // Best effort: a kernel without transparent huge pages refuses, and 4 KiB pages serve.
        (void)::madvise(reinterpret_cast<void*>(from), to - from, MADV_HUGEPAGE);
    }
#else
    (void)data;
    (void)bytes;
#endif
}

} // namespace lfprobe
