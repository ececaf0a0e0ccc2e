// The text scan parser's numbers (scan_parsing.hpp): the fast path for plain decimals gives
// fast_float's value bit for bit, and leaves everything else to it.
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <fast_float/fast_float.h>
#include <gtest/gtest.h>

#include "scan_parsing.hpp"

using lfprobe::detail::parse_double;
using lfprobe::detail::parse_plain_decimal;
using lfprobe::detail::RangeEnd;

namespace {

std::uint64_t bits(double v) {
    std::uint64_t b = 0;
    std::memcpy(&b, &v, sizeof(b));
    return b;
}

// fast_float's value and end for `text`, as parse_double had them before the fast path.
std::pair<double, std::size_t> reference(const std::string& text) {
    double value = 0.0;
    const auto r = fast_float::from_chars(text.data(), text.data() + text.size(), value);
    return {value, static_cast<std::size_t>(r.ptr - text.data())};
}

void expect_same(const std::string& text) {
    double value = 0.0;
    const char* end = parse_double(text.data(), text.data() + text.size(), value);
    const auto [expected, expected_end] = reference(text);
    ASSERT_NE(end, nullptr) << text;
    EXPECT_EQ(bits(value), bits(expected)) << text;
    EXPECT_EQ(static_cast<std::size_t>(end - text.data()), expected_end) << text;
}

// A text of a number (or not) as a scan's column has it: sign, digits, point, digits.
std::string random_number(std::mt19937_64& random) {
    const int integer_digits = static_cast<int>(random() % 12);
    const int fraction_digits = static_cast<int>(random() % 25);
    std::string text = random() % 3 == 0 ? "-" : "";
    for (int d = 0; d < integer_digits + 1; ++d) {
        text += static_cast<char>('0' + random() % 10);
    }
    if (fraction_digits > 0) {
        text += '.';
        for (int d = 0; d < fraction_digits; ++d) {
            text += static_cast<char>('0' + random() % 10);
        }
    }
    return text;
}

} // namespace

TEST(NumberParsing, PlainDecimalsAreFastFloatsValueBitForBit) {
    std::mt19937_64 random(11);
    for (int i = 0; i < 400000; ++i) {
        // 1 to 20 digits around a point anywhere, signs, leading zeros: a scan's columns and
        // the edges of the fast path (2^53, 19 and 20 digits, 22 decimals and more).
        std::string text = random_number(random);
        text += random() % 2 == 0 ? " " : "\n";
        expect_same(text);
    }
    for (const std::string text :
         {"0", "-0", "-0.000", "0.0", "9007199254740992", "9007199254740993", "9007199254740993.0",
          "0.0000000000000000000001", "0.00000000000000000000001", "12345678901234567890",
          "1234567890123456789", "1.5e3", "1.5E-3", "2.", ".5", "007.25", "255", "-1.25,3"}) {
        expect_same(text);
    }
}

TEST(NumberParsing, TheFastPathLeavesWhatIsNotAPlainDecimalToFastFloat) {
    double value = 0.0;
    for (const std::string text : {"1e5", "2.5E-3", "12345678901234567890", "1.", ".5", "inf",
                                   "nan", "+1.5", "-", "", "9007199254740993"}) {
        EXPECT_EQ(parse_plain_decimal(text.data(), text.data() + text.size(), value), nullptr)
            << text;
    }
}

// The chunk parser reads ranges that end with a newline without comparing with their end: the
// newline stops every run of digits. It must read the same numbers, to the same ends, and turn
// away the same texts as the bounded parse.
TEST(NumberParsing, ARangeEndingInANewlineReadsWhatABoundedOneReads) {
    std::mt19937_64 random(12);
    std::vector<std::string> texts = {"0",
                                      "-0",
                                      "1e5",
                                      "2.5E-3",
                                      "12345678901234567890",
                                      "1.",
                                      ".5",
                                      "inf",
                                      "nan",
                                      "+1.5",
                                      "-",
                                      "",
                                      "-.",
                                      "255",
                                      "9007199254740993",
                                      "1.5x",
                                      "7,8",
                                      "3 ",
                                      "\t",
                                      "0.0000000000000000001",
                                      "00000000000000000001",
                                      "1234567890123456789.5"};
    for (int i = 0; i < 200000; ++i) {
        texts.push_back(random_number(random));
    }
    for (const std::string& number : texts) {
        const std::string text = number + "\n";
        const char* first = text.data();
        const char* last = first + text.size();
        double bounded = -1.0;
        double newline = -2.0;
        const char* bounded_end = parse_double<RangeEnd::Bounded>(first, last, bounded);
        const char* newline_end = parse_double<RangeEnd::Newline>(first, last, newline);
        ASSERT_EQ(newline_end, bounded_end) << number;
        if (bounded_end != nullptr) {
            EXPECT_EQ(bits(newline), bits(bounded)) << number;
        }
        double plain_bounded = 0.0;
        double plain_newline = 0.0;
        EXPECT_EQ(parse_plain_decimal<RangeEnd::Newline>(first, last, plain_newline),
                  parse_plain_decimal<RangeEnd::Bounded>(first, last, plain_bounded))
            << number;
    }
}
