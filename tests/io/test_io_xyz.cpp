// SPDX-License-Identifier: MIT
// xyz text reader: separators, comments, extra columns, CRLF, non-finite tokens, .pts count lines, and
// errors that name the line.
#include "io_test_util.hpp"

#include <limits>

using namespace iotest;

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

const char *kText = "# x y z intensity\n"
                    "1 2 3\n"
                    "\n"
                    "  4,5,6\n"
                    "7\t8\t9 10 11 label\r\n"
                    "   # an indented comment\n"
                    "+1.5e2, -2.5E-1 ,nan,\n"
                    "inf -inf -0.0 # trailing columns are ignored\n"
                    "1e400 -1e400 1e-400\n"
                    ".5 5. 0.000001";
const std::vector<double> kPoints = {1,    2,    3,     4,    5,    6,     7, 8,   9, 150, -0.25,
                                     kNaN, kInf, -kInf, -0.0, kInf, -kInf, 0, 0.5, 5, 1e-6};

void test_exact() {
    TempDir dir;
    EXPECT_POINTS(dir.write("a.xyz", kText), FileFormat::Xyz, kPoints);
    EXPECT_POINTS(dir.write("a.txt", kText), FileFormat::Auto, kPoints);
    // Leica .pts: a first line holding only the point count, then x y z intensity r g b.
    EXPECT_POINTS(dir.write("a.pts", "2\n1.25 2 3 -1200 255 0 0\n4 5 6 300 0 255 0\n"), FileFormat::Auto,
                  {1.25, 2, 3, 4, 5, 6});
    // Comments and blank lines only: a well-formed file with no points.
    EXPECT_POINTS(dir.write("none.xyz", "# nothing here\n\n   \r\n"), FileFormat::Xyz, {});
    // Values written with full precision read back exactly.
    const double v[3] = {0.1, -123456.789012345678, 6.02214076e23};
    char line[128];
    snprintf(line, sizeof line, "%.17g %.17g %.17g\n", v[0], v[1], v[2]);
    EXPECT_POINTS(dir.write("exact.xyz", line), FileFormat::Xyz, {v[0], v[1], v[2]});
}

void test_errors() {
    TempDir dir;
    auto parse_error = [&](const std::string &bytes, const char *needle, int line) {
        iotest::expect_failure(__FILE__, line, dir.write("bad.xyz", bytes), FileFormat::Xyz, ErrorKind::Parse, needle);
    };
    parse_error("1 2\n", "line 1: expected at least 3 numbers (x y z), found 2", __LINE__);
    parse_error("# c\n1 2 3\n\n4 5\n", "line 4: expected at least 3 numbers (x y z), found 2", __LINE__);
    parse_error("1 2 x\n", "line 1: not a number: 'x'", __LINE__);
    parse_error("x,y,z\n1,2,3\n", "line 1: not a number: 'x'", __LINE__);
    parse_error("1 2 3\n5\n", "line 2: expected at least 3 numbers (x y z), found 1", __LINE__);
    parse_error("1 2 3\n1..2 3 4\n", "line 2: not a number: '1..2'", __LINE__);
    parse_error("1 2 # comment\n", "line 1: not a number: '#'", __LINE__);
    parse_error("1;2;3\n", "not a number: '1;2;3'", __LINE__);
    parse_error("1 2 3\n4 5 0x10\n", "line 2: not a number: '0x10'", __LINE__);
    parse_error("1 2 ++3\n", "not a number", __LINE__);
    parse_error("1 2 3\n\x01\x02\x03\n", "line 2: not a number: '\\x01\\x02\\x03'", __LINE__);
    parse_error(std::string("1 2 3\0", 6), "not a number", __LINE__);
    // Only the first data line may be a bare count.
    parse_error("2\n1 2 3\n7\n", "line 3: expected at least 3 numbers", __LINE__);
    parse_error("-2\n1 2 3\n", "line 1: expected at least 3 numbers", __LINE__);
}

void test_truncation() {
    TempDir dir;
    CHECK_EVERY_CUT(dir, "cut.xyz", std::string(kText), FileFormat::Xyz, kPoints, CutRule::ParseOrTextPrefix);
}

void test_io_errors() {
    TempDir dir;
    EXPECT_FAILURE(dir.file("missing.xyz"), FileFormat::Xyz, ErrorKind::Io, "No such file or directory");
    std::filesystem::create_directory(dir.file("adir.xyz"));
    EXPECT_FAILURE(dir.file("adir.xyz"), FileFormat::Xyz, ErrorKind::Io, "Is a directory");
    EXPECT_FAILURE(dir.write("empty.xyz", ""), FileFormat::Xyz, ErrorKind::Parse, "empty");
}

void test_mutations() {
    TempDir dir;
    const std::string t = kText;
    CHECK(CHECK_MUTATIONS(dir, "m.xyz", t, FileFormat::Xyz, t.size()) > 1000);
}

} // namespace

int main() {
    RUN_TEST(test_exact);
    RUN_TEST(test_errors);
    RUN_TEST(test_truncation);
    RUN_TEST(test_io_errors);
    RUN_TEST(test_mutations);
    return TEST_SUMMARY();
}
