// Large arrays in transparent huge pages. Filling a freshly allocated array of tens of millions
// of points costs a page fault per 4 KiB page (a fifth of a 10 M-point scan's parse went to the
// kernel); backed by 2 MiB pages it costs one per 512 of them. Debian's kernels give huge
// pages only where asked for (madvise), so the arrays that readers fill are asked for.
#pragma once

#include <cstddef>
#include <vector>

namespace lfprobe {

// Advises the kernel to back the whole 2 MiB pages within [data, data + bytes) with huge
// pages; best effort, and nothing for regions smaller than a huge page.
void advise_huge_pages(const void* data, std::size_t bytes);

// `values` resized to `count` elements, its storage advised for huge pages before the
// resize first touches it (when the vector had no room for them yet).
template <class T>
void resize_in_huge_pages(std::vector<T>& values, std::size_t count) {
    if (values.capacity() < count) {
        values.reserve(count);
        advise_huge_pages(values.data(), count * sizeof(T));
    }
    values.resize(count);
}

} // namespace lfprobe
