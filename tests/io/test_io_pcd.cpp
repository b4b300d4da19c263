// SPDX-License-Identifier: MIT
// PCD reader: ascii and binary data, extra fields with COUNT > 1, F4 / F8 / integer coordinates, optional
// header lines, truncation at every byte, malformed headers.
#include "io_test_util.hpp"

#include <limits>

using namespace iotest;

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

const char *kAscii = "# .PCD v0.7 - Point Cloud Data file format\n"
                     "VERSION 0.7\n"
                     "FIELDS x y z rgb normal hist\n"
                     "SIZE 4 4 4 4 4 4\n"
                     "TYPE F F F U F F\n"
                     "COUNT 1 1 1 1 3 2\n"
                     "WIDTH 3\n"
                     "HEIGHT 1\n"
                     "VIEWPOINT 0 0 0 1 0 0 0\n"
                     "POINTS 3\n"
                     "DATA ascii\n"
                     "1.5 -2.25 3 4278190080 0 0 1 0.5 0.5\n"
                     "nan nan nan 0 0 0 0 0 0\n"
                     "-1e-3 2e5 +7 1 1 1 1 1 1\n";
const std::vector<double> kAsciiPoints = {1.5, -2.25, 3, kNaN, kNaN, kNaN, -0.001, 200000, 7};

std::string crlf(const std::string &s) {
    std::string out;
    for (char c : s) {
        if (c == '\n') out += '\r';
        out += c;
    }
    return out;
}

void test_ascii() {
    TempDir dir;
    EXPECT_POINTS(dir.write("a.pcd", kAscii), FileFormat::Pcd, kAsciiPoints);
    EXPECT_POINTS(dir.write("a.pcd", crlf(kAscii)), FileFormat::Auto, kAsciiPoints);
    // x not first, a padding field, blank lines, no COUNT, no POINTS (WIDTH * HEIGHT), no "# .PCD" comment.
    EXPECT_POINTS(dir.write("b.pcd", "VERSION .7\nFIELDS normal_x z _ y x\nSIZE 4 8 4 4 8\nTYPE F F F F F\n"
                                     "WIDTH 2\nHEIGHT 1\nDATA ascii\n\n0 3 0 2 1\n\n9 6 0 5 4\n"),
                  FileFormat::Pcd, {1, 2, 3, 4, 5, 6});
    // Very old files have no TYPE line: every field is a float.
    EXPECT_POINTS(dir.write("c.pcd", "FIELDS x y z\nSIZE 4 4 4\nPOINTS 1\nDATA ascii\n1 2 3\n"), FileFormat::Pcd,
                  {1, 2, 3});
}

// Fields: intensity F4, x F4, padding U1 x3, y F8, z F4, ring U2 -> 25-byte records.
const char *kBinaryHeader = "# .PCD v0.7\n"
                            "VERSION .7\n"
                            "FIELDS intensity x _ y z ring\n"
                            "SIZE 4 4 1 8 4 2\n"
                            "TYPE F F U F F U\n"
                            "COUNT 1 1 3 1 1 1\n"
                            "WIDTH 2\n"
                            "HEIGHT 2\n"
                            "VIEWPOINT 0 0 0 1 0 0 0\n"
                            "POINTS 4\n"
                            "DATA binary\n";
const std::vector<double> kBinaryPoints = {1.5, 0.1, -2, -1e20f, 1e-300, 0.25, 0, 0, 0, 7, -8, 9};

std::string binary_pcd() {
    Bytes b;
    b.text(kBinaryHeader);
    for (std::size_t i = 0; i < 4; ++i) {
        b.put<float>(100.0f).put<float>(static_cast<float>(kBinaryPoints[3 * i]));
        b.put<std::uint8_t>(1).put<std::uint8_t>(2).put<std::uint8_t>(3);
        b.put<double>(kBinaryPoints[3 * i + 1]).put<float>(static_cast<float>(kBinaryPoints[3 * i + 2]));
        b.put<std::uint16_t>(static_cast<std::uint16_t>(i));
    }
    return b.s;
}

void test_binary() {
    TempDir dir;
    EXPECT_POINTS(dir.write("b.pcd", binary_pcd()), FileFormat::Pcd, kBinaryPoints);
    // Trailing bytes after the declared points are ignored.
    EXPECT_POINTS(dir.write("b.pcd", binary_pcd() + "pad"), FileFormat::Pcd, kBinaryPoints);
    // Integer coordinates: I2, U1, I8.
    Bytes b;
    b.text("FIELDS x y z\nSIZE 2 1 8\nTYPE I U I\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA binary\n");
    b.put<std::int16_t>(-32768).put<std::uint8_t>(255).put<std::int64_t>(-5);
    b.put<std::int16_t>(12).put<std::uint8_t>(0).put<std::int64_t>(1LL << 40);
    EXPECT_POINTS(dir.write("i.pcd", b.s), FileFormat::Pcd, {-32768, 255, -5, 12, 0, 1099511627776.0});
    EXPECT_POINTS(dir.write("i.pcd", "FIELDS x y z\nSIZE 2 1 8\nTYPE I U I\nPOINTS 2\nDATA ascii\n-32768 255 -5\n"
                                     "12 0 1099511627776\n"),
                  FileFormat::Pcd, {-32768, 255, -5, 12, 0, 1099511627776.0});
    // The other unsigned / signed sizes.
    Bytes u;
    u.text("FIELDS x y z\nSIZE 2 4 8\nTYPE U U U\nPOINTS 1\nDATA binary\n");
    u.put<std::uint16_t>(65535).put<std::uint32_t>(4294967295u).put<std::uint64_t>(1ULL << 63);
    EXPECT_POINTS(dir.write("u.pcd", u.s), FileFormat::Pcd, {65535, 4294967295.0, 9223372036854775808.0});
    Bytes s;
    s.text("FIELDS x y z\nSIZE 1 4 4\nTYPE I I F\nPOINTS 1\nDATA binary\n");
    s.put<std::int8_t>(-128).put<std::int32_t>(-2147483647 - 1).put<float>(0.5f);
    EXPECT_POINTS(dir.write("s.pcd", s.s), FileFormat::Pcd, {-128, -2147483648.0, 0.5});
}

void test_zero_points() {
    TempDir dir;
    const std::string h = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 0\nHEIGHT 1\nPOINTS 0\n";
    EXPECT_POINTS(dir.write("z.pcd", h + "DATA ascii\n"), FileFormat::Pcd, {});
    EXPECT_POINTS(dir.write("z.pcd", h + "DATA binary\n"), FileFormat::Pcd, {});
}

void test_truncation() {
    TempDir dir;
    CHECK_EVERY_CUT(dir, "cut.pcd", std::string(kAscii), FileFormat::Pcd, kAsciiPoints, CutRule::ParseOrTextPrefix);
    CHECK_EVERY_CUT(dir, "cut.pcd", binary_pcd(), FileFormat::Pcd, kBinaryPoints, CutRule::ParseError);
    const std::string b = binary_pcd();
    EXPECT_FAILURE(dir.write("short.pcd", b.substr(0, b.size() - 1)), FileFormat::Pcd, ErrorKind::Parse,
                   "truncated: expected 100 bytes of point data, found 99");
    const std::string a = kAscii;
    EXPECT_FAILURE(dir.write("short.pcd", a.substr(0, a.rfind("-1e-3"))), FileFormat::Pcd, ErrorKind::Parse,
                   "truncated: expected 3 points, found 2");
}

void test_malformed() {
    TempDir dir;
    auto parse_error = [&](const std::string &bytes, const char *needle, int line) {
        iotest::expect_failure(__FILE__, line, dir.write("bad.pcd", bytes), FileFormat::Pcd, ErrorKind::Parse, needle);
    };
    const std::string xyz = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";
    parse_error(xyz + "WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA binary_compressed\n" + std::string(20, '\0'),
                "binary_compressed PCD is not supported", __LINE__);
    parse_error(xyz + "POINTS 1\nDATA sideways\n", "unknown DATA encoding 'sideways'", __LINE__);
    parse_error(xyz + "POINTS 1\nDATA\n", "expected 'DATA ascii'", __LINE__);
    parse_error(xyz + "POINTS 1\n", "no DATA line", __LINE__);
    parse_error(xyz + "POINTS 1\nCOLOUR 1\nDATA ascii\n1 2 3\n", "unknown keyword 'COLOUR'", __LINE__);
    parse_error("FIELDS x y w\nSIZE 4 4 4\nPOINTS 1\nDATA ascii\n1 2 3\n", "no 'z' field", __LINE__);
    parse_error("FIELDS x y z x\nSIZE 4 4 4 4\nPOINTS 1\nDATA ascii\n1 2 3 4\n", "two 'x' fields", __LINE__);
    parse_error("FIELDS x y z\nSIZE 4 4 4\nCOUNT 3 1 1\nPOINTS 1\nDATA ascii\n1 1 1 2 3\n", "has COUNT 3", __LINE__);
    parse_error("FIELDS x y z\nSIZE 2 4 4\nTYPE F F F\nPOINTS 1\nDATA ascii\n1 2 3\n", "unsupported TYPE/SIZE F2",
                __LINE__);
    parse_error("FIELDS x y z\nSIZE 4 4 3\nTYPE F F I\nPOINTS 1\nDATA ascii\n1 2 3\n", "unsupported TYPE/SIZE I3",
                __LINE__);
    parse_error("FIELDS x y z\nSIZE 4 4 4\nTYPE F F Q\nPOINTS 1\nDATA ascii\n1 2 3\n", "unknown TYPE 'Q'", __LINE__);
    parse_error("FIELDS x y z\nSIZE 4 4 4\nTYPE F F FF\nPOINTS 1\nDATA ascii\n1 2 3\n", "unknown TYPE 'FF'", __LINE__);
    parse_error("FIELDS x y z\nSIZE 4 4\nPOINTS 1\nDATA ascii\n1 2 3\n", "SIZE has 2 entries but FIELDS has 3",
                __LINE__);
    parse_error("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F F\nPOINTS 1\nDATA ascii\n1 2 3\n", "TYPE has 4 entries",
                __LINE__);
    parse_error("FIELDS x y z\nSIZE 4 4 4\nCOUNT 1 1\nPOINTS 1\nDATA ascii\n1 2 3\n", "COUNT has 2 entries", __LINE__);
    parse_error("FIELDS x y z\nSIZE 4 0 4\nPOINTS 1\nDATA ascii\n1 2 3\n", "bad SIZE '0'", __LINE__);
    parse_error("FIELDS x y z\nSIZE 4 -4 4\nPOINTS 1\nDATA ascii\n1 2 3\n", "bad SIZE '-4'", __LINE__);
    parse_error("FIELDS x y z\nSIZE 4 4 4\nCOUNT 1 1 0\nPOINTS 1\nDATA ascii\n1 2 3\n", "bad COUNT '0'", __LINE__);
    parse_error("FIELDS x y z w\nSIZE 4 4 4 4\nCOUNT 1 1 1 18446744073709551615\nPOINTS 1\nDATA binary\n", "too large",
                __LINE__);
    parse_error("SIZE 4 4 4\nPOINTS 1\nDATA ascii\n1 2 3\n", "no FIELDS line", __LINE__);
    parse_error("FIELDS x y z\nPOINTS 1\nDATA ascii\n1 2 3\n", "no SIZE line", __LINE__);
    parse_error("FIELDS x y z\nFIELDS x y z\nSIZE 4 4 4\nPOINTS 1\nDATA ascii\n1 2 3\n", "a second FIELDS line",
                __LINE__);
    parse_error("FIELDS\nSIZE\nPOINTS 1\nDATA ascii\n1 2 3\n", "FIELDS lists nothing", __LINE__);
    parse_error(xyz + "POINTS -1\nDATA ascii\n", "expected 'POINTS <count>'", __LINE__);
    parse_error(xyz + "POINTS 1 2\nDATA ascii\n", "expected 'POINTS <count>'", __LINE__);
    parse_error(xyz + "POINTS 99999999999999999999\nDATA ascii\n", "expected 'POINTS <count>'", __LINE__);
    parse_error(xyz + "WIDTH 2\nHEIGHT 2\nPOINTS 3\nDATA ascii\n", "disagrees with WIDTH * HEIGHT = 4", __LINE__);
    parse_error(xyz + "WIDTH 4294967296\nHEIGHT 4294967296\nDATA ascii\n", "overflows", __LINE__);
    parse_error(xyz + "HEIGHT 1\nDATA ascii\n1 2 3\n", "neither POINTS nor WIDTH", __LINE__);
    // Counts the data cannot hold.
    parse_error(xyz + "POINTS 1000000000000000000\nDATA binary\n" + std::string(24, '\0'),
                "truncated: expected 12000000000000000000 bytes of point data, found 24", __LINE__);
    parse_error("FIELDS x y z w\nSIZE 8 8 8 8\nPOINTS 1000000000000000000\nDATA binary\n" + std::string(24, '\0'),
                "far more than the 24 bytes", __LINE__);
    parse_error(xyz + "POINTS 1000000000000000000\nDATA ascii\n1 2 3\n", "truncated: the PCD header declares",
                __LINE__);
    // Ascii data problems.
    parse_error(xyz + "POINTS 2\nDATA ascii\n1.0 2.0 3.0\n4.0 5.0\n", "line 8: expected 3 values, found 2", __LINE__);
    parse_error(xyz + "POINTS 2\nDATA ascii\n1 2 3\n4 5 6 7\n", "line 8: expected 3 values, found 4", __LINE__);
    parse_error(xyz + "POINTS 1\nDATA ascii\n1 2 3\n4 5 6\n", "line 8: more data than the header's 1 points", __LINE__);
    parse_error(xyz + "POINTS 1\nDATA ascii\n1 2,5 3\n", "line 7: bad value '2,5' for field 'y'", __LINE__);
    parse_error("# .PCD\nVERSION 0.7\n\x01\xfe\n", "unknown keyword", __LINE__);
}

void test_io_errors() {
    TempDir dir;
    EXPECT_FAILURE(dir.file("missing.pcd"), FileFormat::Pcd, ErrorKind::Io, "No such file or directory");
    std::filesystem::create_directory(dir.file("adir.pcd"));
    EXPECT_FAILURE(dir.file("adir.pcd"), FileFormat::Pcd, ErrorKind::Io, "Is a directory");
    EXPECT_FAILURE(dir.write("empty.pcd", ""), FileFormat::Pcd, ErrorKind::Parse, "empty");
}

void test_mutations() {
    TempDir dir;
    const std::string a = kAscii;
    int n = CHECK_MUTATIONS(dir, "m.pcd", a, FileFormat::Pcd, a.size());
    n += CHECK_MUTATIONS(dir, "m.pcd", binary_pcd(), FileFormat::Pcd, binary_pcd().size());
    CHECK(n > 3000);
}

} // namespace

int main() {
    RUN_TEST(test_ascii);
    RUN_TEST(test_binary);
    RUN_TEST(test_zero_points);
    RUN_TEST(test_truncation);
    RUN_TEST(test_malformed);
    RUN_TEST(test_io_errors);
    RUN_TEST(test_mutations);
    return TEST_SUMMARY();
}
