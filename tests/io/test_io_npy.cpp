// SPDX-License-Identifier: MIT
// .npy reader: format versions 1/2/3, float32/float64 in both byte orders, integer dtypes, C and Fortran
// order, (N, k >= 3) shapes, and every way a header can be wrong.
#include "io_test_util.hpp"

using namespace iotest;

namespace {

// A .npy file as numpy writes it: the dict padded with spaces and a newline to a 64-byte boundary.
std::string npy(int major, const std::string &dict, const std::string &data) {
    std::string header = dict;
    const std::size_t preamble = major == 1 ? 10 : 12;
    while ((preamble + header.size() + 1) % 64 != 0) header += ' ';
    header += '\n';
    Bytes b;
    b.text("\x93NUMPY").put<std::uint8_t>(static_cast<std::uint8_t>(major)).put<std::uint8_t>(0);
    if (major == 1)
        b.put<std::uint16_t>(static_cast<std::uint16_t>(header.size()));
    else
        b.put<std::uint32_t>(static_cast<std::uint32_t>(header.size()));
    return b.s + header + data;
}

std::string dict(const char *descr, bool fortran, const std::string &shape) {
    return std::string("{'descr': '") + descr + "', 'fortran_order': " + (fortran ? "True" : "False") +
           ", 'shape': " + shape + ", }";
}

// Row-major values of a rows x cols matrix stored as T, in C or Fortran order.
template <typename T>
std::string matrix(const std::vector<double> &m, std::size_t cols, bool fortran, bool big = false) {
    const std::size_t rows = m.size() / cols;
    Bytes b;
    for (std::size_t k = 0; k < m.size(); ++k) {
        const std::size_t i = fortran ? k % rows : k / cols;
        const std::size_t j = fortran ? k / rows : k % cols;
        b.put<T>(static_cast<T>(m[i * cols + j]), big);
    }
    return b.s;
}

const std::vector<double> k3 = {1.5, -2.25, 3, 0.1, 1e300, -7, 8, 9, 10, 11, 12, 13};
const std::vector<double> k4 = {1.5, -2.25, 3, 99, 0.1, 1e30, -7, 99, 8, 9, 10, 99}; // third row: 8 9 10
const std::vector<double> k4_xyz = {1.5, -2.25, 3, 0.1, 1e30, -7, 8, 9, 10};

std::vector<double> as_float(const std::vector<double> &v) {
    std::vector<double> out;
    for (double d : v) out.push_back(static_cast<float>(d));
    return out;
}

void test_exact() {
    TempDir dir;
    EXPECT_POINTS(dir.write("f8.npy", npy(1, dict("<f8", false, "(4, 3)"), matrix<double>(k3, 3, false))),
                  FileFormat::Npy, k3);
    EXPECT_POINTS(dir.write("f4.npy", npy(1, dict("<f4", false, "(4, 3)"), matrix<float>(k3, 3, false))),
                  FileFormat::Auto, as_float(k3));
    EXPECT_POINTS(dir.write("bf8.npy", npy(1, dict(">f8", false, "(4, 3)"), matrix<double>(k3, 3, false, true))),
                  FileFormat::Npy, k3);
    EXPECT_POINTS(dir.write("bf4.npy", npy(1, dict(">f4", false, "(4, 3)"), matrix<float>(k3, 3, false, true))),
                  FileFormat::Npy, as_float(k3));
    EXPECT_POINTS(dir.write("ff8.npy", npy(1, dict("<f8", true, "(4, 3)"), matrix<double>(k3, 3, true))),
                  FileFormat::Npy, k3);
    EXPECT_POINTS(dir.write("c4.npy", npy(1, dict("<f8", false, "(3, 4)"), matrix<double>(k4, 4, false))),
                  FileFormat::Npy, k4_xyz);
    EXPECT_POINTS(dir.write("fc4.npy", npy(1, dict("<f4", true, "(3, 4)"), matrix<float>(k4, 4, true))),
                  FileFormat::Npy, as_float(k4_xyz));
    EXPECT_POINTS(dir.write("v2.npy", npy(2, dict("<f8", false, "(4, 3)"), matrix<double>(k3, 3, false))),
                  FileFormat::Npy, k3);
    EXPECT_POINTS(dir.write("v3.npy", npy(3, dict("<f8", false, "(4, 3)"), matrix<double>(k3, 3, false))),
                  FileFormat::Npy, k3);
    // Keys in another order, double quotes, no trailing comma, Python 2 long dimensions.
    EXPECT_POINTS(dir.write("order.npy", npy(1, "{\"shape\": (4L, 3L), \"fortran_order\": False, \"descr\": \"<f8\"}",
                                             matrix<double>(k3, 3, false))),
                  FileFormat::Npy, k3);
    const std::vector<double> ints = {-1, 2, -3, 4, 5, 6};
    EXPECT_POINTS(dir.write("i4.npy", npy(1, dict("<i4", false, "(2, 3)"), matrix<std::int32_t>(ints, 3, false))),
                  FileFormat::Npy, ints);
    EXPECT_POINTS(dir.write("i8.npy", npy(1, dict(">i8", false, "(2, 3)"), matrix<std::int64_t>(ints, 3, false, true))),
                  FileFormat::Npy, ints);
    EXPECT_POINTS(
        dir.write("u1.npy", npy(1, dict("|u1", false, "(2, 3)"), matrix<std::uint8_t>({1, 2, 3, 4, 5, 255}, 3, false))),
        FileFormat::Npy, {1, 2, 3, 4, 5, 255});
    EXPECT_POINTS(dir.write("i1.npy", npy(1, dict("|i1", false, "(2, 3)"), matrix<std::int8_t>(ints, 3, false))),
                  FileFormat::Npy, ints);
    EXPECT_POINTS(dir.write("u2.npy", npy(1, dict("<u2", false, "(2, 3)"),
                                          matrix<std::uint16_t>({1, 2, 3, 4, 5, 65535}, 3, false))),
                  FileFormat::Npy, {1, 2, 3, 4, 5, 65535});
    EXPECT_POINTS(dir.write("nat.npy", npy(1, dict("=f8", false, "(4, 3)"), matrix<double>(k3, 3, false))),
                  FileFormat::Npy, k3);
    EXPECT_POINTS(dir.write("empty.npy", npy(1, dict("<f8", false, "(0, 3)"), "")), FileFormat::Npy, {});
    EXPECT_POINTS(dir.write("emptyf.npy", npy(1, dict("<f4", true, "(0, 5)"), "")), FileFormat::Npy, {});
    // Trailing bytes after the array are ignored.
    EXPECT_POINTS(dir.write("trail.npy", npy(1, dict("<f8", false, "(4, 3)"), matrix<double>(k3, 3, false) + "xx")),
                  FileFormat::Npy, k3);
}

void test_truncation() {
    TempDir dir;
    const std::string f8 = npy(1, dict("<f8", false, "(4, 3)"), matrix<double>(k3, 3, false));
    CHECK_EVERY_CUT(dir, "cut.npy", f8, FileFormat::Npy, k3, CutRule::ParseError);
    const std::string v2 = npy(2, dict(">f4", true, "(3, 4)"), matrix<float>(k4, 4, true, true));
    CHECK_EVERY_CUT(dir, "cut.npy", v2, FileFormat::Npy, as_float(k4_xyz), CutRule::ParseError);
    EXPECT_FAILURE(dir.write("short.npy", f8.substr(0, f8.size() - 1)), FileFormat::Npy, ErrorKind::Parse,
                   "truncated: expected 96 bytes of array data, found 95");
}

void test_malformed() {
    TempDir dir;
    const std::string data = matrix<double>(k3, 3, false);
    auto parse_error = [&](const std::string &bytes, const char *needle, int line) {
        iotest::expect_failure(__FILE__, line, dir.write("bad.npy", bytes), FileFormat::Npy, ErrorKind::Parse, needle);
    };
    parse_error(npy(1, dict("<f8", false, "(12,)"), data), "shape (12,) is not (N, 3)", __LINE__);
    parse_error(npy(1, dict("<f8", false, "(6, 2)"), data), "shape (6, 2) is not", __LINE__);
    parse_error(npy(1, dict("<f8", false, "(2, 3, 2)"), data), "shape (2, 3, 2) is not", __LINE__);
    parse_error(npy(1, dict("<f8", false, "()"), data), "shape () is not", __LINE__);
    parse_error(npy(1, dict("<f2", false, "(4, 3)"), data), "dtype '<f2' is not supported", __LINE__);
    parse_error(npy(1, dict("<c16", false, "(4, 3)"), data), "is not supported", __LINE__);
    parse_error(npy(1, dict("|f8", false, "(4, 3)"), data), "has no byte order", __LINE__);
    parse_error(npy(1, dict("<U8", false, "(4, 3)"), data), "is not supported", __LINE__);
    parse_error(
        npy(1, "{'descr': [('x', '<f8'), ('y', '<f8'), ('z', '<f8')], 'fortran_order': False, 'shape': (4,), }", data),
        "structured .npy dtypes are not supported", __LINE__);
    parse_error(npy(1, "{'descr': '<f8', 'fortran_order': Maybe, 'shape': (4, 3), }", data), "expected True or False",
                __LINE__);
    parse_error(npy(1, "{'descr': '<f8', 'fortran_order': False, 'shape': (-4, 3), }", data),
                "expected a non-negative dimension", __LINE__);
    parse_error(npy(1, "{'descr': '<f8', 'fortran_order': False, 'shape': (4; 3), }", data), "expected ',' or ')'",
                __LINE__);
    parse_error(npy(1, "{'descr': '<f8', 'fortran_order': False, 'shape': (4, 3) 'x' }", data), "expected ',' or '}'",
                __LINE__);
    parse_error(npy(1, "{'descr': '<f8, 'fortran_order': False, 'shape': (4, 3), }", data), "malformed .npy header",
                __LINE__);
    parse_error(npy(1, "{'descr': '<f8', 'fortran_order': False, 'shape': (4, 3), 'extra': 1}", data),
                "unexpected key 'extra'", __LINE__);
    parse_error(npy(1, "{'fortran_order': False, 'shape': (4, 3), }", data), "no 'descr'", __LINE__);
    parse_error(npy(1, "{'descr': '<f8', 'fortran_order': False, }", data), "no 'shape'", __LINE__);
    parse_error(npy(1, "garbage", data), "expected '{'", __LINE__);
    parse_error(npy(1, "{'descr': '<f8'", data), "malformed .npy header", __LINE__);
    parse_error(npy(1, dict("<f8", false, "(100000000000000000, 3)"), data),
                "truncated: expected 2400000000000000000 bytes of array data, found 96", __LINE__);
    parse_error(npy(1, dict("<f8", false, "(1000000000000000000, 3)"), data), "far larger than the 96 bytes", __LINE__);
    parse_error(npy(1, dict("<f8", false, "(18446744073709551616, 3)"), data), "expected a non-negative dimension",
                __LINE__);
    // Preamble problems.
    std::string v4 = npy(1, dict("<f8", false, "(4, 3)"), data);
    v4[6] = 4;
    parse_error(v4, "unsupported .npy format version 4.0", __LINE__);
    std::string long_header = npy(1, dict("<f8", false, "(4, 3)"), data);
    long_header[8] = '\xff';
    long_header[9] = '\xff';
    parse_error(long_header, "truncated: the .npy header needs 65535 bytes", __LINE__);
    std::string v2_long = npy(2, dict("<f8", false, "(4, 3)"), data);
    v2_long[11] = '\x7f';
    parse_error(v2_long, "truncated: the .npy header needs", __LINE__);
    parse_error("\x93NUMPY\x01", "truncated: the .npy preamble is incomplete", __LINE__);
    parse_error(std::string("\x93NUMPY\x02\x00\x10\x00", 10), "truncated: the .npy preamble is incomplete", __LINE__);
    parse_error("\x93NUMPX\x01\x00\x10\x00", "not a .npy file", __LINE__);
    parse_error("PK\x03\x04 a zip, say", "not a .npy file", __LINE__);
}

void test_io_errors() {
    TempDir dir;
    EXPECT_FAILURE(dir.file("missing.npy"), FileFormat::Npy, ErrorKind::Io, "No such file or directory");
    std::filesystem::create_directory(dir.file("adir.npy"));
    EXPECT_FAILURE(dir.file("adir.npy"), FileFormat::Npy, ErrorKind::Io, "Is a directory");
    EXPECT_FAILURE(dir.write("empty.npy", ""), FileFormat::Npy, ErrorKind::Parse, "empty");
}

void test_mutations() {
    TempDir dir;
    const std::string f8 = npy(1, dict("<f8", false, "(4, 3)"), matrix<double>(k3, 3, false));
    int n = CHECK_MUTATIONS(dir, "m.npy", f8, FileFormat::Npy, f8.size());
    const std::string v3 = npy(3, dict(">f4", true, "(3, 4)"), matrix<float>(k4, 4, true, true));
    n += CHECK_MUTATIONS(dir, "m.npy", v3, FileFormat::Npy, v3.size());
    CHECK(n > 1000);
}

} // namespace

int main() {
    RUN_TEST(test_exact);
    RUN_TEST(test_truncation);
    RUN_TEST(test_malformed);
    RUN_TEST(test_io_errors);
    RUN_TEST(test_mutations);
    return TEST_SUMMARY();
}
