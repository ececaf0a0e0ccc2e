// Scan readers (.xyz family, .pts, .ply) and the merge into one cloud: good files of every
// variant, every kind of bad file (the message must say where and what was expected), the real
// scans in the shared data, and the precision of georeferenced coordinates.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "lfprobe/color.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/mapped_file.hpp"
#include "lfprobe/progress.hpp"
#include "lfprobe/scan_reader.hpp"
#include "test_data.hpp"

using namespace lfprobe;
namespace fs = std::filesystem;

namespace {

// Writes `content` byte for byte (no newline translation) into a folder of the running test's
// own, so that tests run as separate processes (ctest -j) never share files.
std::string write_file(const std::string& name, const std::string& content) {
    const ::testing::TestInfo* test = ::testing::UnitTest::GetInstance()->current_test_info();
    const fs::path dir = fs::path(::testing::TempDir()) / "lfprobe_scan_reader" /
                         (std::string(test->test_suite_name()) + "." + test->name());
    fs::create_directories(dir);
    const fs::path path = dir / name;
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
    return path.string();
}

ScanFile read(const std::string& name, const std::string& content,
              const std::string& columns = "") {
    ScanReadOptions options;
    options.columns = columns;
    return read_scan_file(write_file(name, content), options);
}

std::string shared_scan(const std::string& name) {
    return lfprobe::testing::shared_data("scans/" + name);
}

// Expects read() to throw InputError whose message holds every one of `parts`.
void expect_input_error(const std::string& name, const std::string& content,
                        std::initializer_list<std::string> parts, const std::string& columns = "") {
    try {
        (void)read(name, content, columns);
        ADD_FAILURE() << name << ": expected an InputError";
    } catch (const InputError& error) {
        const std::string message = error.what();
        for (const std::string& part : parts) {
            EXPECT_NE(message.find(part), std::string::npos)
                << name << ": '" << part << "' missing from: " << message;
        }
    }
}

glm::dvec3 world(const ScanFile& scan, std::size_t i) {
    return scan.origin + glm::dvec3(scan.positions[i]);
}

void expect_world(const ScanFile& scan, std::size_t i, glm::dvec3 expected,
                  double tolerance = 1e-6) {
    const glm::dvec3 actual = world(scan, i);
    for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(actual[a], expected[a], tolerance) << "point " << i << " axis " << a;
    }
}

float srgb8(int value) {
    return srgb8_to_linear_table()[static_cast<std::size_t>(value)];
}

void expect_colour(const glm::vec3& actual, glm::vec3 expected) {
    for (int c = 0; c < 3; ++c) {
        EXPECT_FLOAT_EQ(actual[c], expected[c]) << "channel " << c;
    }
}

// Little- or big-endian binary PLY bodies.
class BinaryWriter {
public:
    explicit BinaryWriter(bool big_endian) : big_endian_(big_endian) {}
    template <class T>
    BinaryWriter& put(T value) {
        char bytes[sizeof(T)];
        std::memcpy(bytes, &value, sizeof(T));
        if (big_endian_) {
            std::reverse(bytes, bytes + sizeof(T));
        }
        bytes_.append(bytes, sizeof(T));
        return *this;
    }
    [[nodiscard]] const std::string& bytes() const { return bytes_; }

private:
    bool big_endian_;
    std::string bytes_;
};

} // namespace

// ---------------------------------------------------------------------------------------------
// Formats, errors, mapping

TEST(ScanFormat, PicksByExtension) {
    EXPECT_EQ(scan_format_from_path("a/b.xyz"), ScanFormat::Xyz);
    EXPECT_EQ(scan_format_from_path("b.TXT"), ScanFormat::Xyz);
    EXPECT_EQ(scan_format_from_path("b.asc"), ScanFormat::Xyz);
    EXPECT_EQ(scan_format_from_path("b.csv"), ScanFormat::Xyz);
    EXPECT_EQ(scan_format_from_path("b.pts"), ScanFormat::Pts);
    EXPECT_EQ(scan_format_from_path("b.Ply"), ScanFormat::Ply);
    EXPECT_EQ(scan_format_from_path("b.e57"), ScanFormat::Auto);
    EXPECT_THROW((void)read("unknown.e57", "1 2 3\n"), InputError);
    ScanReadOptions options;
    options.format = ScanFormat::Xyz;
    EXPECT_EQ(read_scan_file(write_file("named.dat", "1 2 3\n"), options).positions.size(), 1u);
}

TEST(ScanErrors, LocationFormats) {
    EXPECT_STREQ(input_error_at({"a.xyz", 12, 0, true}, "bad").what(), "a.xyz:12: bad");
    EXPECT_STREQ(input_error_at({"b.ply", 0, 345, false}, "short").what(),
                 "b.ply: byte offset 345: short");
}

TEST(ScanErrors, MissingFileIsIoErrorWithReason) {
    try {
        (void)read_scan_file("/nonexistent/lfprobe/scan.xyz", {});
        FAIL() << "expected IoError";
    } catch (const IoError& error) {
        const std::string message = error.what();
        EXPECT_NE(message.find("/nonexistent/lfprobe/scan.xyz"), std::string::npos);
        EXPECT_NE(message.find("No such file"), std::string::npos) << message;
    }
}

TEST(ScanMappedFile, MapsContentAndEmptyFiles) {
    MappedFile full(write_file("mapped.bin", "hello"));
    EXPECT_EQ(full.view(), "hello");
    const MappedFile empty(write_file("mapped_empty.bin", ""));
    EXPECT_EQ(empty.size(), 0u);
    EXPECT_TRUE(empty.view().empty());
    MappedFile moved = std::move(full);
    EXPECT_EQ(moved.view(), "hello");
    EXPECT_THROW(MappedFile(fs::path(::testing::TempDir()).string()), IoError); // a directory
}

// ---------------------------------------------------------------------------------------------
// .xyz family

TEST(XyzReader, SeparatorsAreSpacesTabsAndCommas) {
    const ScanFile scan = read("separators.xyz", "1 2 3\n4\t5\t6\n7,8,9\n  10 ,\t11,,12  \n");
    ASSERT_EQ(scan.positions.size(), 4u);
    EXPECT_EQ(scan.origin, glm::dvec3(1, 2, 3));
    expect_world(scan, 1, {4, 5, 6});
    expect_world(scan, 2, {7, 8, 9});
    expect_world(scan, 3, {10, 11, 12});
    EXPECT_TRUE(scan.colors.empty());
    EXPECT_TRUE(scan.normals.empty());
    EXPECT_TRUE(scan.intensities.empty());
    EXPECT_FALSE(scan.has_scanner);
}

TEST(XyzReader, CrlfCommentsBlankLinesAndNoFinalNewline) {
    const ScanFile scan = read("crlf.txt", "# exported\r\n// by something\r\n\r\n"
                                           "1.5 2.5 3.5\r\n% mid-file comment\r\n"
                                           "  ; another\r\n   \r\n"
                                           "+4 -5e0 6E-1\r\n7 8 9");
    ASSERT_EQ(scan.positions.size(), 3u);
    EXPECT_EQ(scan.origin, glm::dvec3(2, 3, 4)); // 1.5 2.5 3.5 rounded half away from zero
    expect_world(scan, 0, {1.5, 2.5, 3.5});
    expect_world(scan, 1, {4, -5, 0.6});
    expect_world(scan, 2, {7, 8, 9});

    // A UTF-8 byte order mark does not hide the first point.
    const ScanFile bom = read("bom.csv", "\xEF\xBB\xBF"
                                         "1,2,3\n4,5,6\n");
    ASSERT_EQ(bom.positions.size(), 2u);
    expect_world(bom, 0, {1, 2, 3});
}

TEST(XyzReader, ColumnCountsImplyTheLayout) {
    const ScanFile four = read("four.xyz", "1 2 3 -17.5\n4 5 6 100\n");
    ASSERT_EQ(four.intensities.size(), 2u);
    EXPECT_EQ(four.intensities[0], -17.5f);
    EXPECT_TRUE(four.colors.empty());

    const ScanFile six = read("six.xyz", "1 2 3 255 128 0\n4 5 6 10 20 30\n");
    ASSERT_EQ(six.colors.size(), 2u);
    expect_colour(six.colors[0], {1.0f, srgb8(128), 0.0f});
    expect_colour(six.colors[1], {srgb8(10), srgb8(20), srgb8(30)});
    EXPECT_TRUE(six.intensities.empty());

    const ScanFile seven = read("seven.xyz", "1 2 3 -2048 51 65 49\n4 5 6 2047 0 0 255\n");
    ASSERT_EQ(seven.colors.size(), 2u);
    EXPECT_EQ(seven.intensities[0], -2048.0f);
    EXPECT_EQ(seven.intensities[1], 2047.0f);
    expect_colour(seven.colors[0], {srgb8(51), srgb8(65), srgb8(49)});

    const ScanFile nine = read("nine.xyz", "1 2 3 10 20 30 0 0 2\n4 5 6 1 2 3 0 0 0\n");
    ASSERT_EQ(nine.normals.size(), 2u);
    EXPECT_EQ(nine.normals[0], glm::vec3(0, 0, 1));
    EXPECT_EQ(nine.normals[1], glm::vec3(0, 0, 0)); // unknown normal stays zero
    expect_colour(nine.colors[1], {srgb8(1), srgb8(2), srgb8(3)});

    const ScanFile ten = read("ten.xyz", "1 2 3 0.25 200 100 50 3 4 0\n");
    ASSERT_EQ(ten.normals.size(), 1u);
    EXPECT_FLOAT_EQ(ten.normals[0].x, 0.6f);
    EXPECT_FLOAT_EQ(ten.normals[0].y, 0.8f);
    EXPECT_EQ(ten.intensities[0], 0.25f);
    expect_colour(ten.colors[0], {srgb8(200), srgb8(100), srgb8(50)});
}

TEST(XyzReader, FloatColoursInZeroToOne) {
    const ScanFile scan = read("float_colours.xyz", "0 0 0 0.5 1 0\n1 1 1 0.25 0.75 1.0\n");
    ASSERT_EQ(scan.colors.size(), 2u);
    expect_colour(scan.colors[0], {srgb_to_linear(0.5f), 1.0f, 0.0f});
    expect_colour(scan.colors[1], {srgb_to_linear(0.25f), srgb_to_linear(0.75f), 1.0f});
}

TEST(XyzReader, HeaderLineNamesTheColumns) {
    const ScanFile scan = read("header.csv", "Intensity,X,Y,Z,Red,Green,Blue\n"
                                             "7,1,2,3,255,0,0\n"
                                             "8,4,5,6,0,255,0\n");
    ASSERT_EQ(scan.positions.size(), 2u);
    expect_world(scan, 1, {4, 5, 6});
    EXPECT_EQ(scan.intensities[1], 8.0f);
    expect_colour(scan.colors[0], {1, 0, 0});

    const ScanFile named = read("header_names.xyz", "x y z nx ny nz scalar_intensity\n"
                                                    "1 2 3 0 2 0 5\n");
    EXPECT_EQ(named.normals[0], glm::vec3(0, 1, 0));
    EXPECT_EQ(named.intensities[0], 5.0f);
    EXPECT_TRUE(named.colors.empty());
}

TEST(XyzReader, CloudCompareHeaderCommentAndScanner) {
    const ScanFile scan = read("cloudcompare.txt", "// scanner 10.5 -2 1.75\n"
                                                   "//X,Y,Z,R,G,B,Nx,Ny,Nz\n"
                                                   "1,2,3,0,0,255,0,-3,0\n");
    ASSERT_EQ(scan.positions.size(), 1u);
    EXPECT_TRUE(scan.has_scanner);
    EXPECT_EQ(scan.scanner, glm::dvec3(10.5, -2, 1.75));
    EXPECT_EQ(scan.normals[0], glm::vec3(0, -1, 0));
    expect_colour(scan.colors[0], {0, 0, 1});

    const ScanFile hashed = read("scanner_hash.xyz", "# scanner 1 2 3\n# x y z\n4 5 6\n");
    EXPECT_TRUE(hashed.has_scanner);
    EXPECT_EQ(hashed.scanner, glm::dvec3(1, 2, 3));
    // Prose that mentions x, y and z is not a column map.
    const ScanFile prose = read("prose.xyz", "# the x y z of each point\n1 2 3 4 5 6\n");
    EXPECT_EQ(prose.colors.size(), 1u);
}

TEST(XyzReader, ColumnsOptionOverridesEverything) {
    const ScanFile scan = read("columns.xyz", "x y z r g b i\n1 2 3 9 10 20 30\n", "x y z _ r g b");
    ASSERT_EQ(scan.positions.size(), 1u);
    EXPECT_TRUE(scan.intensities.empty());
    expect_colour(scan.colors[0], {srgb8(10), srgb8(20), srgb8(30)});

    const ScanFile odd = read("columns5.xyz", "7 1 2 3 0.5\n", "i x y z _");
    expect_world(odd, 0, {1, 2, 3});
    EXPECT_EQ(odd.intensities[0], 7.0f);
}

TEST(XyzReader, ManyChunksKeepOrderAndReportTheEarliestError) {
    // About 4 MB: several parallel chunks.
    std::string plain = "# big\n";
    const int count = 150000;
    for (int i = 0; i < count; ++i) {
        plain += std::to_string(i) + ".25 " + std::to_string(-i) + " 0.5 " +
                 std::to_string(i % 256) + " 7 9\n";
    }
    const ScanFile scan = read("big.xyz", plain);
    ASSERT_EQ(scan.positions.size(), static_cast<std::size_t>(count));
    for (int i = 0; i < count; i += 997) {
        const auto index = static_cast<std::size_t>(i);
        expect_world(scan, index, {i + 0.25, -i, 0.5}, 1e-3);
        EXPECT_EQ(scan.colors[index].x, srgb8(i % 256));
    }

    // Two bad lines in different chunks: the first one in the file is reported.
    std::string bad = plain;
    const auto line_start = [&](int line) {
        std::size_t offset = 0;
        for (int l = 1; l < line; ++l) {
            offset = bad.find('\n', offset) + 1;
        }
        return offset;
    };
    bad.replace(line_start(140000), 1, "Q");
    bad.replace(line_start(100001), 1, "W");
    expect_input_error("big_bad.xyz", bad, {"big_bad.xyz:100001:", "'W", "column 1 (x)"});
    const std::size_t short_line = line_start(90000);
    bad.replace(short_line, bad.find('\n', short_line) - short_line, "1 2 3 4 5");
    expect_input_error("big_short.xyz", bad, {"big_short.xyz:90000:", "expected 6 columns"});
}

// Each chunk fills its slice of the file's arrays, sized by its lines; lines that hold no point
// (comments, blank lines, .pts count lines) leave gaps that are closed afterwards. Every point
// must land in file order with its own colour and intensity, whichever chunk held a gap.
TEST(XyzReader, LinesWithoutPointsInEveryChunkLeaveNoGaps) {
    const int count = 150000; // about 4 MB: several parallel chunks
    std::string xyz;
    std::string pts;
    int block = 0;
    for (int i = 0; i < count; ++i) {
        if (i % 7 == 3) {
            xyz += "# a comment\n";
        }
        if (i % 11 == 5) {
            xyz += "\n";
        }
        if (i % 1000 == 0) { // a .pts block of 1000 points
            pts += "1000\n";
            ++block;
        }
        const std::string line = std::to_string(i) + ".5 " + std::to_string(block) + " 0.25 " +
                                 std::to_string(i % 97) + " " + std::to_string(i % 256) + " 3 " +
                                 std::to_string(i % 251) + "\n";
        xyz += line;
        pts += line;
    }
    const ScanFile from_xyz = read("gaps.xyz", xyz, "x y z _ r g b");
    const ScanFile from_pts = read("gaps.pts", pts);
    ASSERT_EQ(from_xyz.positions.size(), static_cast<std::size_t>(count));
    ASSERT_EQ(from_xyz.colors.size(), static_cast<std::size_t>(count));
    ASSERT_EQ(from_pts.positions.size(), static_cast<std::size_t>(count));
    ASSERT_EQ(from_pts.intensities.size(), static_cast<std::size_t>(count));
    for (int i = 0; i < count; ++i) {
        const auto index = static_cast<std::size_t>(i);
        ASSERT_EQ(world(from_xyz, index).x, i + 0.5) << i;
        ASSERT_EQ(from_xyz.colors[index].x, srgb8(i % 256)) << i;
        ASSERT_EQ(world(from_pts, index).x, i + 0.5) << i;
        ASSERT_EQ(world(from_pts, index).y, i / 1000 + 1) << i;
        ASSERT_EQ(from_pts.intensities[index], static_cast<float>(i % 97)) << i;
        ASSERT_EQ(from_pts.colors[index].z, srgb8(i % 251)) << i;
    }
}

// Chunks decode their colours as soon as one of their values says 0-255; a chunk whose values
// are all 0 or 1 waits for the file's largest value, which here says 0-255 too.
TEST(XyzReader, ColoursOfEveryChunkFollowTheWholeFilesRange) {
    std::string text;
    const int count = 150000; // about 4 MB: several parallel chunks
    for (int i = 0; i < count; ++i) {
        const int red = i < count / 2 ? i % 2 : 200;
        text += std::to_string(i) + ".5 1.25 2 " + std::to_string(red) + " 0 1\n";
    }
    const ScanFile scan = read("ranges.xyz", text);
    ASSERT_EQ(scan.colors.size(), static_cast<std::size_t>(count));
    for (int i = 0; i < count; i += 499) {
        const int red = i < count / 2 ? i % 2 : 200;
        expect_colour(scan.colors[static_cast<std::size_t>(i)], {srgb8(red), srgb8(0), srgb8(1)});
    }
    // All values 0 or 1: colours are 0-1 floats, in every chunk.
    std::string unit;
    for (int i = 0; i < count; ++i) {
        unit += std::to_string(i) + ".5 1.25 2 " + std::to_string(i % 2) + " 0 1\n";
    }
    const ScanFile floats = read("unit.xyz", unit);
    for (int i = 0; i < count; i += 499) {
        expect_colour(floats.colors[static_cast<std::size_t>(i)],
                      {static_cast<float>(i % 2), 0.0f, 1.0f});
    }
}

TEST(XyzErrors, EmptyFileOrNoData) {
    expect_input_error("empty.xyz", "", {"empty.xyz:1:", "no data lines", "expected"});
    expect_input_error("comments_only.xyz", "# a\n\n// b\n",
                       {"comments_only.xyz:3:", "no data lines"});
}

TEST(XyzErrors, NonNumericField) {
    expect_input_error("nonnumeric.xyz", "1 2 3\n4 five 6\n",
                       {"nonnumeric.xyz:2:", "'five'", "column 2 (y)", "expected a number"});
    expect_input_error("nonnumeric_first.xyz", "1 2x 3\n",
                       {"nonnumeric_first.xyz:1:", "'2x'", "column 2"});
}

TEST(XyzErrors, WrongColumnCount) {
    expect_input_error("columns_wrong.xyz", "1 2 3 4 5 6\r\n# c\r\n1 2 3 4 5\r\n",
                       {"columns_wrong.xyz:3:", "expected 6 columns, found 5"});
    expect_input_error("columns_unknown.xyz", "1 2 3 4 5\n",
                       {"columns_unknown.xyz:1:", "5 columns", "3 (x y z)", "4 (x y z i)",
                        "6 (x y z r g b)", "7 (x y z i r g b)", "10 (x y z i r g b nx ny nz)",
                        "options.columns"});
    expect_input_error("header_mismatch.xyz", "x y z r g b\n1 2 3\n",
                       {"header_mismatch.xyz:2:", "header on line 1 names 6 columns"});
    expect_input_error("option_mismatch.xyz", "1 2 3 4\n", {"option_mismatch.xyz:1:", "names 3"},
                       "x y z");
}

TEST(XyzErrors, NonFiniteCoordinates) {
    expect_input_error("nan.xyz", "1 2 3\nnan 2 3\n",
                       {"nan.xyz:2:", "NaN or infinite coordinate 'nan'", "column 1 (x)"});
    expect_input_error("inf.xyz", "1 2 3\n1 2 -inf\n", {"inf.xyz:2:", "'-inf'", "column 3 (z)"});
    expect_input_error("overflow.xyz", "1 1e999 3\n", {"overflow.xyz:1:", "'1e999'"});
    expect_input_error("infinity.xyz", "1 2 3\n4 5 6\n7 Infinity 9\n", {"infinity.xyz:3:"});
    expect_input_error("far.xyz", "1 2 3\n1 2 3e40\n", {"far.xyz:2:", "'3e40'", "too far"});
}

TEST(XyzErrors, BadColourValues) {
    expect_input_error("colour_high.xyz", "1 2 3 10 20 30\n1 2 3 300 0 0\n",
                       {"colour_high.xyz:2:", "bad colour value '300'", "column 4 (red)", "0-255"});
    expect_input_error("colour_negative.xyz", "1 2 3 0 -1 0\n",
                       {"colour_negative.xyz:1:", "'-1'", "column 5 (green)"});
    expect_input_error("colour_nan.xyz", "1 2 3 0 0 nan\n", {"colour_nan.xyz:1:", "'nan'"});
}

TEST(XyzErrors, BadColumnsOption) {
    expect_input_error("option_bad.xyz", "1 2 3\n", {"option_bad.xyz", "options.columns", "'q'"},
                       "x y q");
    expect_input_error("option_no_z.xyz", "1 2 3\n", {"options.columns", "no 'z'"}, "x y _");
}

// ---------------------------------------------------------------------------------------------
// .pts

TEST(PtsReader, SingleBlockKeepsIntensityAsStored) {
    const ScanFile scan = read("single.pts", "3\n"
                                             "1 2 3 -178 51 65 49\n"
                                             "4 5 6 2047 255 0 0\n"
                                             "7 8 9 -2048 0 0 0\n");
    ASSERT_EQ(scan.positions.size(), 3u);
    EXPECT_EQ(scan.intensities[0], -178.0f);
    EXPECT_EQ(scan.intensities[1], 2047.0f);
    EXPECT_EQ(scan.intensities[2], -2048.0f);
    expect_colour(scan.colors[0], {srgb8(51), srgb8(65), srgb8(49)});
    expect_world(scan, 2, {7, 8, 9});
}

TEST(PtsReader, SeveralBlocksAndColumnCounts) {
    const ScanFile blocks = read("blocks.pts", "2\r\n1 2 3 5\r\n4 5 6 6\r\n1\r\n7 8 9 7\r\n");
    ASSERT_EQ(blocks.positions.size(), 3u);
    EXPECT_EQ(blocks.intensities[2], 7.0f);
    EXPECT_TRUE(blocks.colors.empty());

    EXPECT_EQ(read("three.pts", "1\n1 2 3\n").positions.size(), 1u);
    const ScanFile six = read("six.pts", "# leading comment\n2\n1 2 3 1 2 3\n4 5 6 4 5 6\n");
    ASSERT_EQ(six.colors.size(), 2u);
    EXPECT_TRUE(six.intensities.empty());
    const ScanFile empty_block = read("empty_block.pts", "0\n2\n1 2 3\n4 5 6\n0\n");
    EXPECT_EQ(empty_block.positions.size(), 2u);
}

TEST(PtsErrors, CountsMustMatchThePoints) {
    expect_input_error("short.pts", "3\n1 2 3\n4 5 6\n",
                       {"short.pts:1:", "declare 3 points", "holds 2"});
    expect_input_error("long_blocks.pts", "1\n1 2 3\n1\n4 5 6\n7 8 9\n",
                       {"long_blocks.pts:1:", "declare 2 points", "holds 3"});
    expect_input_error("no_points.pts", "5\n", {"no_points.pts:1:", "5 points", "holds 0"});
    expect_input_error("zero.pts", "0\n", {"zero.pts:1:", "0 points"});
}

TEST(PtsErrors, MalformedLines) {
    expect_input_error("no_count.pts", "1 2 3\n", {"no_count.pts:1:", "point count"});
    expect_input_error("fraction_count.pts", "2.5\n1 2 3\n",
                       {"fraction_count.pts:1:", "point count", "'2.5'"});
    expect_input_error("columns.pts", "2\n1 2 3 4\n1 2 3\n",
                       {"columns.pts:3:", "expected 4 columns, found 3"});
    expect_input_error("five.pts", "1\n1 2 3 4 5\n", {"five.pts:2:", "5 columns"});
    expect_input_error("empty.pts", "", {"empty.pts:1:", "no data lines"});
    expect_input_error("words.pts", "2\n1 2 3\nhello 2 3\n",
                       {"words.pts:3:", "'hello'", "column 1"});
}

// ---------------------------------------------------------------------------------------------
// .ply

namespace {

const std::string ply_rgb_normal_header = "property double x\n"
                                          "property double y\n"
                                          "property double z\n"
                                          "property uchar red\n"
                                          "property uchar green\n"
                                          "property uchar blue\n"
                                          "property float nx\n"
                                          "property float ny\n"
                                          "property float nz\n"
                                          "property float intensity\n";

std::string binary_ply(bool big_endian, bool with_face_before, bool with_faces_after) {
    std::string header = std::string("ply\nformat ") +
                         (big_endian ? "binary_big_endian" : "binary_little_endian") +
                         " 1.0\ncomment scanner 100 200 300\n";
    BinaryWriter body(big_endian);
    if (with_face_before) {
        header += "element material 2\nproperty list uchar int ids\nproperty float shine\n";
        body.put<std::uint8_t>(3).put<std::int32_t>(1).put<std::int32_t>(2).put<std::int32_t>(3);
        body.put<float>(0.5f);
        body.put<std::uint8_t>(0).put<float>(0.25f);
    }
    header += "element vertex 3\n" + ply_rgb_normal_header;
    if (with_faces_after) {
        header += "element face 1\nproperty list uchar uint vertex_indices\n";
    }
    header += "end_header\n";
    const double coordinates[3][3] = {{637000.25, 849000.5, 411.125}, {1, 2, 3}, {-4, 5, -6}};
    for (int v = 0; v < 3; ++v) {
        body.put(coordinates[v][0]).put(coordinates[v][1]).put(coordinates[v][2]);
        body.put<std::uint8_t>(static_cast<std::uint8_t>(v * 100))
            .put<std::uint8_t>(7)
            .put<std::uint8_t>(255);
        body.put(0.0f).put(v == 2 ? 0.0f : 2.0f).put(0.0f);
        body.put(static_cast<float>(v) - 0.5f);
    }
    if (with_faces_after) {
        body.put<std::uint8_t>(3).put<std::uint32_t>(0).put<std::uint32_t>(1).put<std::uint32_t>(2);
    }
    return header + body.bytes();
}

void expect_binary_ply_content(const ScanFile& scan) {
    ASSERT_EQ(scan.positions.size(), 3u);
    EXPECT_EQ(scan.origin, glm::dvec3(637000, 849001, 411));
    expect_world(scan, 0, {637000.25, 849000.5, 411.125}, 0.0);
    expect_world(scan, 1, {1, 2, 3}, 0.0);
    expect_world(scan, 2, {-4, 5, -6}, 0.0);
    expect_colour(scan.colors[0], {0.0f, srgb8(7), 1.0f});
    expect_colour(scan.colors[2], {srgb8(200), srgb8(7), 1.0f});
    EXPECT_EQ(scan.normals[0], glm::vec3(0, 1, 0));
    EXPECT_EQ(scan.normals[2], glm::vec3(0, 0, 0));
    EXPECT_EQ(scan.intensities[1], 0.5f);
    EXPECT_TRUE(scan.has_scanner);
    EXPECT_EQ(scan.scanner, glm::dvec3(100, 200, 300));
}

} // namespace

TEST(PlyReader, BinaryLittleAndBigEndian) {
    expect_binary_ply_content(read("le.ply", binary_ply(false, false, false)));
    expect_binary_ply_content(read("be.ply", binary_ply(true, false, false)));
}

TEST(PlyReader, BinarySkipsElementsBeforeAndIgnoresElementsAfter) {
    expect_binary_ply_content(read("le_before.ply", binary_ply(false, true, false)));
    expect_binary_ply_content(read("be_before_after.ply", binary_ply(true, true, true)));
    expect_binary_ply_content(read("le_after.ply", binary_ply(false, false, true)));
}

TEST(PlyReader, AsciiWithListsBeforeAndFacesAfter) {
    const std::string text = "ply\r\nformat ascii 1.0\r\ncomment made by hand\r\n"
                             "obj_info nothing\r\n"
                             "element material 2\r\nproperty list uchar int ids\r\n"
                             "property float shine\r\n"
                             "element vertex 2\r\nproperty float x\r\nproperty float y\r\n"
                             "property float z\r\nproperty uchar red\r\nproperty uchar green\r\n"
                             "property uchar blue\r\nproperty float nx\r\nproperty float ny\r\n"
                             "property float nz\r\n"
                             "element face 1\r\nproperty list uchar int vertex_indices\r\n"
                             "end_header\r\n"
                             "3 1 2 3 0.5\r\n0 0.25\r\n"
                             "1.5 2 3 255 0 128 0 0 5\r\n"
                             "4 5 6 0 0 0 0 0 0\r\n"
                             "3 0 1 1\r\n";
    const ScanFile scan = read("ascii.ply", text);
    ASSERT_EQ(scan.positions.size(), 2u);
    expect_world(scan, 0, {1.5, 2, 3});
    expect_world(scan, 1, {4, 5, 6});
    expect_colour(scan.colors[0], {1.0f, 0.0f, srgb8(128)});
    EXPECT_EQ(scan.normals[0], glm::vec3(0, 0, 1));
    EXPECT_FALSE(scan.has_scanner);
}

TEST(PlyReader, ColourTypesAndNames) {
    const ScanFile floats = read("float_colour.ply", "ply\nformat ascii 1.0\nelement vertex 2\n"
                                                     "property float x\nproperty float y\n"
                                                     "property float z\nproperty float r\n"
                                                     "property float g\nproperty float b\n"
                                                     "end_header\n"
                                                     "0 0 0 0.5 1 0\n1 1 1 0.25 0 1\n");
    expect_colour(floats.colors[0], {srgb_to_linear(0.5f), 1.0f, 0.0f});
    expect_colour(floats.colors[1], {srgb_to_linear(0.25f), 0.0f, 1.0f});

    BinaryWriter body(false);
    body.put(1.0f).put(2.0f).put(3.0f);
    body.put<std::uint16_t>(65535).put<std::uint16_t>(0).put<std::uint16_t>(32768);
    body.put<double>(0.5).put<double>(0.5).put<double>(0.5);
    const ScanFile words =
        read("ushort_colour.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 1\n"
                                  "property float32 x\nproperty float32 y\nproperty float32 z\n"
                                  "property uint16 diffuse_red\nproperty uint16 diffuse_green\n"
                                  "property uint16 diffuse_blue\n"
                                  "property float64 r\nproperty float64 g\nproperty float64 b\n"
                                  "end_header\n" +
                                      body.bytes());
    // The first colour properties win; the second set (r g b) is ignored.
    expect_colour(words.colors[0],
                  {1.0f, 0.0f, srgb_to_linear(static_cast<float>(32768.0 / 65535.0))});
}

TEST(PlyReader, IntensityNamesAndListInsideVertex) {
    BinaryWriter body(true);
    for (int v = 0; v < 2; ++v) {
        body.put<std::int16_t>(static_cast<std::int16_t>(-v)).put<std::int32_t>(v);
        body.put<std::uint8_t>(2).put<std::uint16_t>(9).put<std::uint16_t>(9); // a list
        body.put<std::int32_t>(3).put<float>(static_cast<float>(v) * 10.0f);
    }
    const ScanFile scan =
        read("vertex_list.ply", "ply\nformat binary_big_endian 1.0\nelement vertex 2\n"
                                "property short x\nproperty int y\n"
                                "property list uchar ushort tags\n"
                                "property int z\nproperty float scalar_Intensity\n"
                                "end_header\n" +
                                    body.bytes());
    ASSERT_EQ(scan.positions.size(), 2u);
    expect_world(scan, 1, {-1, 1, 3});
    EXPECT_EQ(scan.intensities[1], 10.0f);
    EXPECT_TRUE(scan.colors.empty());
}

TEST(PlyReader, ManyChunksInParallel) {
    const int count = 400000; // 4.8 MB of float xyz: several chunks
    BinaryWriter body(false);
    for (int i = 0; i < count; ++i) {
        body.put(static_cast<float>(i)).put(static_cast<float>(-i)).put(0.5f);
    }
    const ScanFile scan = read("many.ply", "ply\nformat binary_little_endian 1.0\n"
                                           "element vertex " +
                                               std::to_string(count) +
                                               "\nproperty float x\nproperty float y\n"
                                               "property float z\nend_header\n" +
                                               body.bytes());
    ASSERT_EQ(scan.positions.size(), static_cast<std::size_t>(count));
    for (int i = 0; i < count; i += 1009) {
        expect_world(scan, static_cast<std::size_t>(i), {i, -i, 0.5}, 0.0);
    }
}

TEST(PlyReader, SensorOriginComment) {
    const ScanFile scan = read("pcl.ply", "ply\nformat ascii 1.0\n"
                                          "comment PCL: sensor origin at (1.5, -2,3e1) here\n"
                                          "element vertex 1\nproperty float x\nproperty float y\n"
                                          "property float z\nend_header\n1 2 3\n");
    EXPECT_TRUE(scan.has_scanner);
    EXPECT_EQ(scan.scanner, glm::dvec3(1.5, -2, 30));
}

namespace {

const std::string xyz_float_header = "property float x\nproperty float y\nproperty float z\n";

std::string binary_xyz_ply(int declared, int written, const std::string& after = "") {
    BinaryWriter body(false);
    for (int i = 0; i < written; ++i) {
        body.put(1.0f).put(2.0f).put(3.0f);
    }
    return "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(declared) +
           "\n" + xyz_float_header + after + "end_header\n" + body.bytes();
}

} // namespace

TEST(PlyErrors, HeaderProblems) {
    expect_input_error("magic.ply", "plyx\nformat ascii 1.0\n", {"magic.ply:1:", "'ply'"});
    expect_input_error("empty.ply", "", {"empty.ply:1:", "'ply'"});
    expect_input_error("format.ply", "ply\nformat binary_middle_endian 1.0\n",
                       {"format.ply:2:", "unknown format 'binary_middle_endian'", "ascii"});
    expect_input_error("type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\n",
                       {"type.ply:4:", "unknown property type 'float128'", "uchar"});
    expect_input_error("no_vertex.ply",
                       "ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int v\n"
                       "end_header\n",
                       {"no_vertex.ply:5:", "no 'vertex' element"});
    expect_input_error("no_z.ply",
                       "ply\nformat ascii 1.0\ncomment c\nelement vertex 1\nproperty float x\n"
                       "property float y\nend_header\n1 2\n",
                       {"no_z.ply:4:", "no 'z'"});
    expect_input_error("no_end.ply",
                       "ply\nformat ascii 1.0\nelement vertex 1\n" + xyz_float_header + "1 2 3\n",
                       {"no_end.ply:7:", "end_header"});
    expect_input_error("no_end_at_eof.ply",
                       "ply\nformat ascii 1.0\nelement vertex 1\n" + xyz_float_header,
                       {"no_end_at_eof.ply:", "end_header"});
    expect_input_error("property_first.ply", "ply\nformat ascii 1.0\nproperty float x\n",
                       {"property_first.ply:3:", "element"});
}

TEST(PlyErrors, BinaryDataThatDoesNotMatchTheHeader) {
    const std::string truncated = binary_xyz_ply(10, 8);
    const std::size_t offset = truncated.size() - 8 * 12;
    expect_input_error("truncated.ply", truncated,
                       {"truncated.ply: byte offset " + std::to_string(offset),
                        "header declares 10 vertices of 12 bytes each (120 bytes) after byte "
                        "offset " +
                            std::to_string(offset) + ", but the file has only 96 bytes there"});
    expect_input_error(
        "too_long.ply", binary_xyz_ply(8, 10),
        {"too_long.ply: byte offset", "8 vertices", "24 more bytes", "header does not match"});
    // More data than declared is fine when another element follows.
    EXPECT_EQ(read("face_follows.ply",
                   binary_xyz_ply(8, 10, "element face 1\nproperty list uchar int v\n"))
                  .positions.size(),
              8u);
    expect_input_error("huge.ply", binary_xyz_ply(2000000000, 1),
                       {"huge.ply: byte offset", "2000000000 vertices"});
    // A list element before the vertices that runs past the end of the file.
    BinaryWriter body(false);
    body.put<std::uint8_t>(200).put<std::int32_t>(1);
    expect_input_error("list_truncated.ply",
                       "ply\nformat binary_little_endian 1.0\nelement material 1\n"
                       "property list uchar int ids\nelement vertex 1\n" +
                           xyz_float_header + "end_header\n" + body.bytes(),
                       {"list_truncated.ply: byte offset", "material 0", "past the end"});
}

TEST(PlyErrors, AsciiDataThatDoesNotMatchTheHeader) {
    const std::string header =
        "ply\nformat ascii 1.0\nelement vertex 3\n" + xyz_float_header + "end_header\n";
    expect_input_error("ascii_short.ply", header + "1 2 3\n4 5 6\n",
                       {"ascii_short.ply:", "declares 3 vertices", "ends after 2"});
    expect_input_error("ascii_values.ply", header + "1 2 3\n4 5\n7 8 9\n",
                       {"ascii_values.ply:9:", "vertex 1", "expected 3 values, found 2"});
    expect_input_error("ascii_extra.ply", header + "1 2 3\n4 5 6 7\n7 8 9\n",
                       {"ascii_extra.ply:9:", "found 4"});
    expect_input_error("ascii_more.ply", header + "1 2 3\n4 5 6\n7 8 9\n1 1 1\n",
                       {"ascii_more.ply:11:", "data after the last vertex"});
    expect_input_error("ascii_word.ply", header + "1 2 3\n4 five 6\n7 8 9\n",
                       {"ascii_word.ply:9:", "'five'", "'y'"});
}

TEST(PlyErrors, NonFiniteCoordinatesAndBadColours) {
    BinaryWriter body(false);
    body.put(1.0f).put(2.0f).put(3.0f);
    body.put(1.0f).put(std::nanf("")).put(3.0f);
    const std::string header = "ply\nformat binary_little_endian 1.0\nelement vertex 2\n" +
                               xyz_float_header + "end_header\n";
    expect_input_error("nan.ply", header + body.bytes(),
                       {"nan.ply: byte offset " + std::to_string(header.size() + 12), "vertex 1",
                        "NaN or infinite", "y = nan"});
    const std::string ascii = "ply\nformat ascii 1.0\nelement vertex 2\n" + xyz_float_header +
                              "property float red\nproperty float green\nproperty float blue\n"
                              "end_header\n";
    expect_input_error("inf_ascii.ply", ascii + "1 2 3 0 0 0\n1 inf 3 0 0 0\n",
                       {"inf_ascii.ply:12:", "vertex 1", "y = inf"});
    expect_input_error("colour_ascii.ply", ascii + "1 2 3 0 0 0\n1 2 3 0 -0.5 0\n",
                       {"colour_ascii.ply:12:", "green", "-0.5"});
}

// ---------------------------------------------------------------------------------------------
// The real scans in the shared data

TEST(ScanSharedData, PumpXyzAndPtsAgreePointForPoint) {
    const ScanFile xyz = read_scan_file(shared_scan("pumpA_xyzrgb.xyz"), {});
    const ScanFile pts = read_scan_file(shared_scan("pumpA.pts"), {});
    ASSERT_EQ(xyz.positions.size(), 155201u);
    ASSERT_EQ(pts.positions.size(), 155201u);
    ASSERT_EQ(xyz.colors.size(), 155201u);
    ASSERT_EQ(pts.colors.size(), 155201u);
    EXPECT_TRUE(xyz.intensities.empty());
    ASSERT_EQ(pts.intensities.size(), 155201u);
    EXPECT_EQ(xyz.origin, pts.origin);
    std::size_t differences = 0;
    for (std::size_t i = 0; i < xyz.positions.size(); ++i) {
        differences += xyz.positions[i] != pts.positions[i] || xyz.colors[i] != pts.colors[i];
    }
    EXPECT_EQ(differences, 0u);
    const auto [low, high] = std::minmax_element(pts.intensities.begin(), pts.intensities.end());
    EXPECT_GE(*low, -2048.0f);
    EXPECT_LE(*high, 2047.0f);
    EXPECT_LT(*low, 0.0f); // kept as stored, not rescaled
    expect_colour(xyz.colors[0], {srgb8(51), srgb8(65), srgb8(49)});
}

TEST(ScanSharedData, Office1HasItsSensorOrigin) {
    const ScanFile scan = read_scan_file(shared_scan("office1.ply"), {});
    EXPECT_EQ(scan.positions.size(), 254456u);
    EXPECT_EQ(scan.colors.size(), 254456u);
    EXPECT_TRUE(scan.has_scanner);
    EXPECT_EQ(scan.scanner, glm::dvec3(0.0));
}

TEST(ScanSharedData, AutzenKeepsSubMillimetrePrecision) {
    const std::string path = shared_scan("autzen_trim_xyzrgb.xyz");
    const ScanFile scan = read_scan_file(path, {});
    ASSERT_EQ(scan.positions.size(), 110000u);
    EXPECT_GT(scan.origin.x, 6e5);

    // An independent parse of the text with strtod.
    std::ifstream in(path);
    std::string line;
    std::size_t index = 0;
    double worst = 0.0;
    while (std::getline(in, line)) {
        const char* cursor = line.c_str();
        char* end = nullptr;
        glm::dvec3 expected;
        for (int a = 0; a < 3; ++a) {
            expected[a] = std::strtod(cursor, &end);
            ASSERT_NE(end, cursor) << "line " << index + 1;
            cursor = end;
        }
        ASSERT_LT(index, scan.positions.size());
        const glm::dvec3 actual = world(scan, index);
        for (int a = 0; a < 3; ++a) {
            worst = std::max(worst, std::abs(actual[a] - expected[a]));
        }
        ++index;
    }
    EXPECT_EQ(index, scan.positions.size());
    EXPECT_LE(worst, 1e-3);
}

TEST(ScanProgress, ReportsBytesAndStopsWhenCancelled) {
    const std::string path = shared_scan("pumpA_xyzrgb.xyz");
    Progress progress;
    const ScanFile scan = read_scan_file(path, {}, &progress);
    EXPECT_EQ(scan.positions.size(), 155201u);
    EXPECT_EQ(progress.fraction(), 1.0);
    EXPECT_NE(progress.stage().find("parsing"), std::string::npos);
    EXPECT_NE(progress.stage().find(path), std::string::npos);

    Progress cancelled;
    cancelled.request_cancel();
    EXPECT_THROW((void)read_scan_file(path, {}, &cancelled), Cancelled);
    EXPECT_THROW((void)read_scan_file(shared_scan("office1.ply"), {}, &cancelled), Cancelled);
}

// ---------------------------------------------------------------------------------------------
// merge_scans

namespace {

ScanFile make_scan(const std::string& path, glm::dvec3 origin, std::vector<glm::vec3> positions) {
    ScanFile scan;
    scan.path = path;
    scan.origin = origin;
    scan.positions = std::move(positions);
    return scan;
}

} // namespace

TEST(MergeScans, NearOriginKeepsWorldCoordinates) {
    std::vector<ScanFile> files;
    files.push_back(make_scan("a", {2, -3, 0}, {{0.5f, 0.25f, 1}, {-1, 0, 0}}));
    files.push_back(make_scan("b", {-1000, 0, 0}, {{-24, 0, 0}})); // at -1024: still near
    const PointCloud cloud = merge_scans(std::move(files), {});
    EXPECT_EQ(cloud.world_offset, glm::dvec3(0.0));
    ASSERT_EQ(cloud.size(), 3u);
    EXPECT_EQ(cloud.positions[0], glm::vec3(2.5f, -2.75f, 1.0f));
    EXPECT_EQ(cloud.positions[2], glm::vec3(-1024.0f, 0.0f, 0.0f));
    EXPECT_EQ(cloud.scan_index, (std::vector<std::uint32_t>{0, 0, 1}));
    ASSERT_EQ(cloud.scans.size(), 2u);
    EXPECT_EQ(cloud.scans[0].path, "a");
    EXPECT_EQ(cloud.scans[0].point_count, 2u);
    EXPECT_EQ(cloud.scans[1].point_count, 1u);
    EXPECT_FALSE(cloud.scans[0].has_scanner);
    EXPECT_FALSE(cloud.has_colors());
    EXPECT_FALSE(cloud.has_normals());
    EXPECT_TRUE(cloud.intensities.empty());
}

TEST(MergeScans, GeoreferencedCloudsMoveToTheirRoundedCentre) {
    std::vector<ScanFile> files;
    files.push_back(make_scan("a", {637000, 849000, 400}, {{0.25f, 0, 0}, {10, 20, 11}}));
    ScanFile with_scanner = make_scan("b", {637001, 849001, 401}, {{0.5f, 0.5f, 0.5f}});
    with_scanner.scanner = glm::dvec3(637005, 849010, 402);
    with_scanner.has_scanner = true;
    files.push_back(std::move(with_scanner));
    const PointCloud cloud = merge_scans(std::move(files), {});
    // Bounds x [637000.25, 637010], y [849000, 849020], z [400, 411] -> centre rounded.
    EXPECT_EQ(cloud.world_offset, glm::dvec3(637005, 849010, 406));
    EXPECT_EQ(cloud.positions[0], glm::vec3(-4.75f, -10.0f, -6.0f));
    EXPECT_EQ(cloud.positions[2], glm::vec3(-3.5f, -8.5f, -4.5f));
    EXPECT_TRUE(cloud.scans[1].has_scanner);
    EXPECT_EQ(cloud.scans[1].scanner, glm::dvec3(0, 0, -4)); // local frame

    std::vector<ScanFile> forced_files;
    forced_files.push_back(make_scan("c", {1e6, 0, 0}, {{1, 2, 3}}));
    MergeOptions forced;
    forced.world_offset = glm::dvec3(1e6 - 10, 0, 0);
    forced.force_world_offset = true;
    const PointCloud forced_cloud = merge_scans(std::move(forced_files), forced);
    EXPECT_EQ(forced_cloud.world_offset, forced.world_offset);
    EXPECT_EQ(forced_cloud.positions[0], glm::vec3(11, 2, 3));
}

TEST(MergeScans, ScannersOptionOverridesTheFiles) {
    std::vector<ScanFile> files;
    ScanFile own = make_scan("a", {5000, 0, 0}, {{0, 0, 0}});
    own.scanner = glm::dvec3(1, 1, 1);
    own.has_scanner = true;
    files.push_back(std::move(own));
    files.push_back(make_scan("b", {5000, 0, 0}, {{2, 0, 0}}));
    MergeOptions options;
    options.scanners = {glm::dvec3(5001, 1, 2), glm::dvec3(5003, 0, 0)};
    const PointCloud cloud = merge_scans(std::move(files), options);
    EXPECT_EQ(cloud.world_offset, glm::dvec3(5001, 0, 0));
    EXPECT_EQ(cloud.scans[0].scanner, glm::dvec3(0, 1, 2));
    EXPECT_EQ(cloud.scans[1].scanner, glm::dvec3(2, 0, 0));
    EXPECT_TRUE(cloud.scans[1].has_scanner);

    std::vector<ScanFile> two;
    two.push_back(make_scan("a", {}, {{0, 0, 0}}));
    two.push_back(make_scan("b", {}, {{0, 0, 0}}));
    MergeOptions wrong;
    wrong.scanners = {glm::dvec3(0.0)};
    EXPECT_THROW((void)merge_scans(std::move(two), wrong), InputError);
}

TEST(MergeScans, ChannelsOfSomeFilesAreFilledForAll) {
    std::vector<ScanFile> files;
    ScanFile coloured = make_scan("coloured", {}, {{0, 0, 0}});
    coloured.colors = {glm::vec3(1, 0, 0)};
    files.push_back(std::move(coloured));
    ScanFile with_normals = make_scan("normals", {}, {{1, 0, 0}, {2, 0, 0}});
    with_normals.normals = {glm::vec3(0, 0, 1), glm::vec3(0, 1, 0)};
    with_normals.intensities = {5.0f, 6.0f};
    files.push_back(std::move(with_normals));
    const PointCloud cloud = merge_scans(std::move(files), {});
    ASSERT_EQ(cloud.colors.size(), 3u);
    ASSERT_EQ(cloud.normals.size(), 3u);
    ASSERT_EQ(cloud.intensities.size(), 3u);
    EXPECT_EQ(cloud.colors[0], glm::vec3(1, 0, 0));
    EXPECT_NEAR(cloud.colors[1].x, 0.214, 1e-3); // mid grey, linear
    EXPECT_EQ(cloud.colors[2], cloud.colors[1]);
    EXPECT_EQ(cloud.normals[0], glm::vec3(0.0f));
    EXPECT_EQ(cloud.normals[2], glm::vec3(0, 1, 0));
    EXPECT_EQ(cloud.intensities[0], 0.0f);
    EXPECT_EQ(cloud.intensities[1], 5.0f);
}

TEST(MergeScans, RealFilesTogether) {
    std::vector<ScanFile> files;
    files.push_back(read_scan_file(shared_scan("pumpA.pts"), {}));
    files.push_back(read_scan_file(shared_scan("office1.ply"), {}));
    const PointCloud cloud = merge_scans(std::move(files), {});
    EXPECT_EQ(cloud.size(), 155201u + 254456u);
    EXPECT_EQ(cloud.world_offset, glm::dvec3(0.0));
    EXPECT_EQ(cloud.intensities.size(), cloud.size());
    EXPECT_EQ(cloud.intensities[155201], 0.0f);
    EXPECT_TRUE(cloud.scans[1].has_scanner);
    EXPECT_EQ(cloud.scan_index.back(), 1u);

    std::vector<ScanFile> autzen;
    autzen.push_back(read_scan_file(shared_scan("autzen_trim_xyzrgb.xyz"), {}));
    const glm::dvec3 first = world(autzen[0], 0);
    const PointCloud geo = merge_scans(std::move(autzen), {});
    EXPECT_NE(geo.world_offset, glm::dvec3(0.0));
    EXPECT_NEAR(geo.world_offset.x + geo.positions[0].x, first.x, 1e-3);
    EXPECT_NEAR(geo.world_offset.y + geo.positions[0].y, first.y, 1e-3);
}
