// The byte steps of an EXR ZIP block (OpenEXR's file layout) around its deflate: the block's
// even bytes, then its odd bytes, stored as differences of consecutive bytes, each + 128.
// Reading sums them back and interleaves the halves (a fifth of reading a probe when made byte
// by byte: a running sum is a chain of dependent additions); writing splits and differences.
// Both sixteen bytes at a time here, with the byte-by-byte forms they must equal.
#pragma once

#include <cstddef>
#include <cstdint>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace lfprobe {

// Byte by byte, as the format describes it: what unpack_zip_bytes must give.
inline void unpack_zip_bytes_serially(std::uint8_t* bytes, std::size_t n, std::uint8_t* out) {
    for (std::size_t i = 1; i < n; ++i) {
        bytes[i] = static_cast<std::uint8_t>(bytes[i - 1] + bytes[i] - 128);
    }
    const std::uint8_t* first = bytes;
    const std::uint8_t* second = bytes + (n + 1) / 2;
    for (std::size_t i = 0; i + 1 < n; i += 2) {
        out[i] = *first++;
        out[i + 1] = *second++;
    }
    if (n % 2 == 1) {
        out[n - 1] = *first;
    }
}

#if defined(__SSE2__)
namespace zip_bytes_detail {

constexpr std::size_t kLanes = 16;

// Whether a block of n bytes has a run of kLanes pairs to take at a time: the even (first) half
// holds (n + 1) / 2 bytes, the odd half n / 2.
constexpr bool has_lanes_of_pairs(std::size_t n) {
    return n / 2 >= kLanes;
}

// The running sums (mod 256) of sixteen differences, from `carry` (every lane the sum before).
inline __m128i running_sums(__m128i differences, __m128i carry) {
    __m128i x = differences;
    x = _mm_add_epi8(x, _mm_slli_si128(x, 1));
    x = _mm_add_epi8(x, _mm_slli_si128(x, 2));
    x = _mm_add_epi8(x, _mm_slli_si128(x, 4));
    x = _mm_add_epi8(x, _mm_slli_si128(x, 8));
    return _mm_add_epi8(x, carry);
}

// Every lane the last byte of x.
inline __m128i last_byte_everywhere(__m128i x) {
    const __m128i high = _mm_unpackhi_epi8(x, x);         // bytes 8..15, each twice
    const __m128i words = _mm_unpackhi_epi16(high, high); // bytes 12..15, each four times
    return _mm_shuffle_epi32(words, 0xff);                // byte 15 sixteen times
}

} // namespace zip_bytes_detail
#endif

// Out: the n bytes the block holds (the same bytes as unpack_zip_bytes_serially). `bytes` (the
// inflated block) may be overwritten.
inline void unpack_zip_bytes(std::uint8_t* bytes, std::size_t n, std::uint8_t* out) {
#if defined(__SSE2__)
    using namespace zip_bytes_detail;
    if (!has_lanes_of_pairs(n)) {
        unpack_zip_bytes_serially(bytes, n, out);
        return;
    }
    const std::size_t second_start = (n + 1) / 2;
    const std::size_t pairs = n / 2;
    // The sum of the first half's bytes (mod 256) gives the value the second half starts from:
    // its first byte's sum continues the first half's last, as if the two ran one after the
    // other. The first byte is stored as is: its difference is counted from 128.
    std::uint64_t first_sum = 0;
    std::size_t i = 0;
    const __m128i zero = _mm_setzero_si128();
    for (; i + kLanes <= second_start; i += kLanes) {
        const __m128i sums =
            _mm_sad_epu8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(bytes + i)), zero);
        first_sum += static_cast<std::uint64_t>(_mm_cvtsi128_si32(sums)) +
                     static_cast<std::uint64_t>(_mm_cvtsi128_si32(_mm_srli_si128(sums, 8)));
    }
    for (; i < second_start; ++i) {
        first_sum += bytes[i];
    }
    // 128 + Σ (b - 128) over the first half, the first byte's difference counted from 128.
    const auto second_carry_in =
        static_cast<std::uint8_t>(128 + first_sum - 128 * static_cast<std::uint64_t>(second_start));
    const __m128i bias = _mm_set1_epi8(static_cast<char>(-128));
    __m128i carry_first = _mm_set1_epi8(static_cast<char>(-128)); // 128: b[0] - 128 + 128
    __m128i carry_second = _mm_set1_epi8(static_cast<char>(second_carry_in));
    const std::uint8_t* first = bytes;
    const std::uint8_t* second = bytes + second_start;
    std::size_t k = 0;
    for (; k + kLanes <= pairs; k += kLanes) {
        const __m128i a = running_sums(
            _mm_add_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(first + k)), bias),
            carry_first);
        const __m128i b = running_sums(
            _mm_add_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(second + k)), bias),
            carry_second);
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out + 2 * k), _mm_unpacklo_epi8(a, b));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out + 2 * k + kLanes), _mm_unpackhi_epi8(a, b));
        carry_first = last_byte_everywhere(a);
        carry_second = last_byte_everywhere(b);
    }
    auto running_first = static_cast<std::uint8_t>(_mm_cvtsi128_si32(carry_first));
    auto running_second = static_cast<std::uint8_t>(_mm_cvtsi128_si32(carry_second));
    for (; k < pairs; ++k) {
        running_first = static_cast<std::uint8_t>(running_first + first[k] - 128);
        running_second = static_cast<std::uint8_t>(running_second + second[k] - 128);
        out[2 * k] = running_first;
        out[2 * k + 1] = running_second;
    }
    if (n % 2 == 1) {
        out[n - 1] = static_cast<std::uint8_t>(running_first + first[pairs] - 128);
    }
#else
    unpack_zip_bytes_serially(bytes, n, out);
#endif
}

// The block's `n` bytes `raw` split into even and odd bytes and differenced, byte by byte, as the
// format describes it: what pack_zip_bytes must give.
inline void pack_zip_bytes_serially(const std::uint8_t* raw, std::size_t n, std::uint8_t* out) {
    const std::size_t half = (n + 1) / 2;
    for (std::size_t k = 0; k < n / 2; ++k) {
        out[k] = raw[2 * k];
        out[half + k] = raw[2 * k + 1];
    }
    if (n % 2 == 1) {
        out[half - 1] = raw[n - 1];
    }
    std::uint8_t previous = n == 0 ? 0 : out[0];
    for (std::size_t i = 1; i < n; ++i) {
        const std::uint8_t value = out[i];
        out[i] = static_cast<std::uint8_t>(value - previous + 128);
        previous = value;
    }
}

// Out: what a ZIP block deflates (the same bytes as pack_zip_bytes_serially).
inline void pack_zip_bytes(const std::uint8_t* raw, std::size_t n, std::uint8_t* out) {
#if defined(__SSE2__)
    using namespace zip_bytes_detail;
    if (!has_lanes_of_pairs(n)) {
        pack_zip_bytes_serially(raw, n, out);
        return;
    }
    const std::size_t half = (n + 1) / 2;
    const std::size_t pairs = n / 2;
    const __m128i low_bytes = _mm_set1_epi16(0x00ff);
    const __m128i bias = _mm_set1_epi8(static_cast<char>(-128));
    // The byte before each half's first, in lane 15: the first byte is stored as is (as if 128
    // came before it), and the odd half follows the even half's last byte.
    __m128i before_even = _mm_slli_si128(_mm_set1_epi8(static_cast<char>(-128)), 15);
    __m128i before_odd = _mm_slli_si128(_mm_cvtsi32_si128(raw[2 * (half - 1)]), 15);
    std::size_t k = 0;
    for (; k + kLanes <= pairs; k += kLanes) {
        const __m128i a = _mm_loadu_si128(reinterpret_cast<const __m128i*>(raw + 2 * k));
        const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i*>(raw + 2 * k + kLanes));
        const __m128i even =
            _mm_packus_epi16(_mm_and_si128(a, low_bytes), _mm_and_si128(b, low_bytes));
        const __m128i odd = _mm_packus_epi16(_mm_srli_epi16(a, 8), _mm_srli_epi16(b, 8));
        const __m128i previous_even =
            _mm_or_si128(_mm_slli_si128(even, 1), _mm_srli_si128(before_even, 15));
        const __m128i previous_odd =
            _mm_or_si128(_mm_slli_si128(odd, 1), _mm_srli_si128(before_odd, 15));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out + k),
                         _mm_add_epi8(_mm_sub_epi8(even, previous_even), bias));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out + half + k),
                         _mm_add_epi8(_mm_sub_epi8(odd, previous_odd), bias));
        before_even = even;
        before_odd = odd;
    }
    auto last_even = static_cast<std::uint8_t>(_mm_cvtsi128_si32(_mm_srli_si128(before_even, 15)));
    auto last_odd = static_cast<std::uint8_t>(_mm_cvtsi128_si32(_mm_srli_si128(before_odd, 15)));
    for (; k < pairs; ++k) {
        out[k] = static_cast<std::uint8_t>(raw[2 * k] - last_even + 128);
        out[half + k] = static_cast<std::uint8_t>(raw[2 * k + 1] - last_odd + 128);
        last_even = raw[2 * k];
        last_odd = raw[2 * k + 1];
    }
    if (n % 2 == 1) {
        out[half - 1] = static_cast<std::uint8_t>(raw[n - 1] - last_even + 128);
    }
#else
    pack_zip_bytes_serially(raw, n, out);
#endif
}

} // namespace lfprobe
