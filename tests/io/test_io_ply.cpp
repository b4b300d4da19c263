// SPDX-License-Identifier: MIT
// PLY reader: ascii / binary little / big endian, every scalar type, skipped properties and list elements
// before and after the vertex element, truncation at every byte, malformed headers.
#include "io_test_util.hpp"

#include <limits>

using namespace iotest;

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

std::string crlf(const std::string &s) {
    std::string out;
    for (char c : s) {
        if (c == '\n') out += '\r';
        out += c;
    }
    return out;
}

const char *kAscii = "ply\n"
                     "format ascii 1.0\n"
                     "comment made by hand\n"
                     "obj_info scanner 1\n"
                     "element vertex 3\n"
                     "property float x\n"
                     "property float nx\n"
                     "property double y\n"
                     "property uchar red\n"
                     "property float z\n"
                     "element face 2\n"
                     "property list uchar int vertex_indices\n"
                     "end_header\n"
                     "1.5 0 -2.25 255 3\n"
                     "-0.125 1 1e3 0 4.5e-2\n"
                     "nan 0 inf 7 -0\n"
                     "3 0 1 2\n"
                     "3 2 1 0\n";
const std::vector<double> kAsciiPoints = {1.5, -2.25, 3, -0.125, 1000, 0.045, kNaN, kInf, -0.0};

void test_ascii() {
    TempDir dir;
    EXPECT_POINTS(dir.write("a.ply", kAscii), FileFormat::Ply, kAsciiPoints);
    EXPECT_POINTS(dir.write("a_crlf.ply", crlf(kAscii)), FileFormat::Ply, kAsciiPoints);
    EXPECT_POINTS(dir.write("a_auto.ply", kAscii), FileFormat::Auto, kAsciiPoints);
}

// Stanford's happyStandRight_{0,48,72,96}.ply end their obj_info block with three "bye" lines before the first
// element (as the origin wrote them); such lines describe no data and are skipped.
void test_keyword_lines_before_the_elements() {
    TempDir dir;
    const std::string text = kAscii;
    const std::size_t at = text.find("element");
    REQUIRE(at != std::string::npos);
    const std::string with_bye = text.substr(0, at) + "obj_info is_mesh 0\nbye\nbye\nbye\n" + text.substr(at);
    EXPECT_POINTS(dir.write("bye.ply", with_bye), FileFormat::Ply, kAsciiPoints);
    EXPECT_POINTS(dir.write("bye_crlf.ply", crlf(with_bye)), FileFormat::Ply, kAsciiPoints);
    const std::string words = text.substr(0, at) + "scanner_name cyberware 3030\n" + text.substr(at);
    EXPECT_POINTS(dir.write("words.ply", words), FileFormat::Ply, kAsciiPoints);
}

// Shaped like the Stanford scans: obj_info lines, CRLF, a trailing space on every vertex line and a
// range_grid list element after the vertices.
void test_bunny_like() {
    TempDir dir;
    const std::string text = crlf("ply\n"
                                  "format ascii 1.0\n"
                                  "obj_info is_cyberware_data 1\n"
                                  "obj_info num_cols 3\n"
                                  "element vertex 4\n"
                                  "property float x\n"
                                  "property float y\n"
                                  "property float z\n"
                                  "element range_grid 6\n"
                                  "property list uchar int vertex_indices\n"
                                  "end_header\n"
                                  "-0.06325 0.0359793 0.0420873 \n"
                                  "-0.06275 0.0360343 0.0425949 \n"
                                  "-0.0645 0.0365101 0.0404362 \n"
                                  "-0.064 0.0366195 0.0414512 \n"
                                  "1 0 \n"
                                  "0 \n"
                                  "1 1 \n"
                                  "2 2 3 \n"
                                  "0 \n"
                                  "0 \n");
    EXPECT_POINTS(dir.write("bun.ply", text), FileFormat::Auto,
                  {-0.06325, 0.0359793, 0.0420873, -0.06275, 0.0360343, 0.0425949, -0.0645, 0.0365101, 0.0404362,
                   -0.064, 0.0366195, 0.0414512});
}

std::string binary_header(bool big) {
    return std::string("ply\n") + (big ? "format binary_big_endian 1.0\n" : "format binary_little_endian 1.0\n") +
           "comment lists before and after the vertices\n"
           "element material 2\n"
           "property list uchar int ids\n"
           "property float shininess\n"
           "element vertex 3\n"
           "property float x\n"
           "property uchar flags\n"
           "property double y\n"
           "property short z\n"
           "property float32 intensity\n"
           "element face 1\n"
           "property list uchar int vertex_indices\n"
           "end_header\n";
}

const std::vector<double> kBinaryPoints = {1.5, 0.1, -7, -3.25, 1e10, 32767, 0, -0.5, -32768};

// Returns the file and, through vertex_end, where its vertex data ends.
std::string binary_ply(bool big, std::size_t *vertex_end = nullptr) {
    Bytes b;
    b.text(binary_header(big));
    b.put<std::uint8_t>(2).put<std::int32_t>(7, big).put<std::int32_t>(8, big).put<float>(0.5f, big);
    b.put<std::uint8_t>(0).put<float>(1.0f, big);
    const double v[3][3] = {{1.5, 0.1, -7}, {-3.25, 1e10, 32767}, {0, -0.5, -32768}};
    for (const auto &p : v) {
        b.put<float>(static_cast<float>(p[0]), big).put<std::uint8_t>(9).put<double>(p[1], big);
        b.put<std::int16_t>(static_cast<std::int16_t>(p[2]), big).put<float>(0.25f, big);
    }
    if (vertex_end) *vertex_end = b.s.size();
    b.put<std::uint8_t>(3).put<std::int32_t>(0, big).put<std::int32_t>(1, big).put<std::int32_t>(2, big);
    return b.s;
}

void test_binary() {
    TempDir dir;
    EXPECT_POINTS(dir.write("le.ply", binary_ply(false)), FileFormat::Ply, kBinaryPoints);
    EXPECT_POINTS(dir.write("be.ply", binary_ply(true)), FileFormat::Ply, kBinaryPoints);
    // CRLF header lines before binary data.
    std::string crlf_header = binary_ply(false);
    const std::size_t header_len = binary_header(false).size();
    crlf_header = crlf(crlf_header.substr(0, header_len)) + crlf_header.substr(header_len);
    EXPECT_POINTS(dir.write("le_crlf.ply", crlf_header), FileFormat::Ply, kBinaryPoints);
}

// Every scalar type name, as x y z, in all three encodings, including each type's extremes.
void test_all_types() {
    TempDir dir;
    struct Type {
        const char *names[2];
        int bytes;
        bool is_signed;
        bool is_float;
    };
    const Type types[] = {{{"char", "int8"}, 1, true, false},    {{"uchar", "uint8"}, 1, false, false},
                          {{"short", "int16"}, 2, true, false},  {{"ushort", "uint16"}, 2, false, false},
                          {{"int", "int32"}, 4, true, false},    {{"uint", "uint32"}, 4, false, false},
                          {{"float", "float32"}, 4, true, true}, {{"double", "float64"}, 8, true, true}};
    for (const Type &t : types) {
        double lo = 0, hi = 0;
        if (t.is_float) {
            lo = -1.25e30;
            hi = 3.5e-3f;
            if (t.bytes == 8) hi = 3.5e-3;
        } else if (t.is_signed) {
            lo = -std::ldexp(1.0, 8 * t.bytes - 1);
            hi = std::ldexp(1.0, 8 * t.bytes - 1) - 1;
        } else {
            hi = std::ldexp(1.0, 8 * t.bytes) - 1;
        }
        if (t.is_float && t.bytes == 4) lo = static_cast<double>(static_cast<float>(lo));
        const std::vector<double> expected = {lo, hi, 1, 2, lo, hi};
        for (const char *name : t.names) {
            const std::string props =
                std::string("property ") + name + " x\nproperty " + name + " y\nproperty " + name + " z\n";
            // ascii
            char line1[200], line2[200];
            snprintf(line1, sizeof line1, "%.17g %.17g 1\n", lo, hi);
            snprintf(line2, sizeof line2, "2 %.17g %.17g\n", lo, hi);
            EXPECT_POINTS(dir.write(std::string("t_") + name + ".ply", "ply\nformat ascii 1.0\nelement vertex 2\n" +
                                                                           props + "end_header\n" + line1 + line2),
                          FileFormat::Ply, expected);
            for (int big = 0; big < 2; ++big) {
                Bytes b;
                b.text(std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
                       " 1.0\nelement vertex 2\n" + props + "end_header\n");
                for (double v : expected) {
                    switch (t.bytes * (t.is_float ? -1 : 1) * (t.is_signed ? 1 : 3)) {
                    case 1: b.put<std::int8_t>(static_cast<std::int8_t>(v), big); break;
                    case 3: b.put<std::uint8_t>(static_cast<std::uint8_t>(v), big); break;
                    case 2: b.put<std::int16_t>(static_cast<std::int16_t>(v), big); break;
                    case 6: b.put<std::uint16_t>(static_cast<std::uint16_t>(v), big); break;
                    case 4: b.put<std::int32_t>(static_cast<std::int32_t>(v), big); break;
                    case 12: b.put<std::uint32_t>(static_cast<std::uint32_t>(v), big); break;
                    case -4: b.put<float>(static_cast<float>(v), big); break;
                    case -8: b.put<double>(v, big); break;
                    }
                }
                EXPECT_POINTS(dir.write(std::string("t_") + name + (big ? "_be" : "_le") + ".ply", b.s),
                              FileFormat::Ply, expected);
            }
        }
    }
}

// List properties inside the vertex element itself, with an int (not uchar) length.
void test_vertex_lists() {
    TempDir dir;
    const std::string props = "element vertex 2\n"
                              "property list uchar float normals\n"
                              "property float x\n"
                              "property list int uchar tags\n"
                              "property float y\n"
                              "property float z\n"
                              "end_header\n";
    EXPECT_POINTS(dir.write("vl.ply", "ply\nformat ascii 1.0\n" + props + "2 0.5 0.25 1 1 7 2 3\n0 4 0 5 6\n"),
                  FileFormat::Ply, {1, 2, 3, 4, 5, 6});
    for (int big = 0; big < 2; ++big) {
        Bytes b;
        b.text(std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") + " 1.0\n" + props);
        b.put<std::uint8_t>(2).put<float>(0.5f, big).put<float>(0.25f, big).put<float>(1, big);
        b.put<std::int32_t>(1, big).put<std::uint8_t>(7).put<float>(2, big).put<float>(3, big);
        b.put<std::uint8_t>(0).put<float>(4, big).put<std::int32_t>(0, big).put<float>(5, big).put<float>(6, big);
        const std::string path = dir.write("vl.ply", b.s);
        EXPECT_POINTS(path, FileFormat::Ply, {1, 2, 3, 4, 5, 6});
        CHECK_EVERY_CUT(dir, "vl_cut.ply", b.s, FileFormat::Ply, {1, 2, 3, 4, 5, 6}, CutRule::ParseError);
    }
}

void test_zero_vertices() {
    TempDir dir;
    const std::string header = "element vertex 0\nproperty float x\nproperty float y\nproperty float z\n"
                               "element face 0\nproperty list uchar int vertex_indices\nend_header\n";
    EXPECT_POINTS(dir.write("z.ply", "ply\nformat ascii 1.0\n" + header), FileFormat::Ply, {});
    EXPECT_POINTS(dir.write("zb.ply", "ply\nformat binary_little_endian 1.0\n" + header), FileFormat::Ply, {});
    // An element with no properties, however large its count, holds no data.
    EXPECT_POINTS(dir.write("np.ply", "ply\nformat ascii 1.0\nelement nothing 1000000000000000000\n" + header),
                  FileFormat::Ply, {});
}

void test_truncation() {
    TempDir dir;
    std::size_t vertex_end = 0;
    const std::string ascii = kAscii;
    CHECK_EVERY_CUT(dir, "cut.ply", ascii, FileFormat::Ply, kAsciiPoints, CutRule::ParseOrTextPrefix,
                    ascii.find("3 0 1 2\n"));
    const std::string ascii_crlf = crlf(kAscii);
    CHECK_EVERY_CUT(dir, "cut.ply", ascii_crlf, FileFormat::Ply, kAsciiPoints, CutRule::ParseOrTextPrefix,
                    ascii_crlf.find("3 0 1 2\r\n"));
    for (int big = 0; big < 2; ++big) {
        const std::string bin = binary_ply(big != 0, &vertex_end);
        CHECK_EVERY_CUT(dir, "cut.ply", bin, FileFormat::Ply, kBinaryPoints, CutRule::ParseError, vertex_end);
    }
    // The exact message for a binary file cut inside its vertex data.
    Bytes b;
    b.text("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
           "property float z\nend_header\n");
    for (int i = 0; i < 9; ++i) b.put<float>(static_cast<float>(i));
    const std::string cut = b.s.substr(0, b.s.size() - 1);
    EXPECT_FAILURE(dir.write("short.ply", cut), FileFormat::Ply, ErrorKind::Parse,
                   "truncated: expected 36 bytes of vertex data, found 35");
    EXPECT_FAILURE(dir.write("short.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                          "property float y\nproperty float z\nend_header\n1.0 2.0 3.0\n4.0 5.0 6.0\n"),
                   FileFormat::Ply, ErrorKind::Parse, "truncated: expected 3 vertices, found 2");
}

std::string ascii_with(const std::string &header_body, const std::string &data = "1 2 3\n") {
    return "ply\nformat ascii 1.0\n" + header_body + "end_header\n" + data;
}

const char *kXyz = "property float x\nproperty float y\nproperty float z\n";

void test_malformed() {
    TempDir dir;
    auto parse_error = [&](const std::string &bytes, const char *needle, int line) {
        iotest::expect_failure(__FILE__, line, dir.write("bad.ply", bytes), FileFormat::Ply, ErrorKind::Parse, needle);
    };
    const std::string v1 = "element vertex 1\n";
    parse_error(ascii_with(v1 + "property float y\nproperty float z\n"), "no 'x' property", __LINE__);
    parse_error(ascii_with(v1 + "property float x\nproperty float y\n"), "no 'z' property", __LINE__);
    parse_error(ascii_with(v1 + "property list uchar float x\nproperty float y\nproperty float z\n"), "is a list",
                __LINE__);
    parse_error(ascii_with(v1 + "property float x\nproperty float x\nproperty float y\nproperty float z\n"),
                "two 'x' properties", __LINE__);
    parse_error(ascii_with(v1 + "property float16 x\nproperty float y\nproperty float z\n"), "unknown property type",
                __LINE__);
    parse_error(ascii_with(v1 + "property list float int ids\n" + kXyz), "not an integer type", __LINE__);
    parse_error(ascii_with(v1 + "property list uchar blob ids\n" + kXyz), "unknown property type", __LINE__);
    parse_error(ascii_with("element vertex -1\n" + std::string(kXyz)), "bad element count", __LINE__);
    parse_error(ascii_with("element vertex 18446744073709551616\n" + std::string(kXyz)), "bad element count", __LINE__);
    parse_error(ascii_with("element vertex 3x\n" + std::string(kXyz)), "bad element count", __LINE__);
    parse_error(ascii_with("element vertex\n" + std::string(kXyz)), "expected 'element <name> <count>'", __LINE__);
    parse_error(ascii_with("element vertex 1000000000000000000\n" + std::string(kXyz)), "truncated", __LINE__);
    parse_error(ascii_with("property float x\n" + v1), "property before any element", __LINE__);
    parse_error(ascii_with(v1 + kXyz + "frobnicate 1\n"), "unknown keyword 'frobnicate'", __LINE__);
    parse_error(ascii_with(v1 + kXyz + "\x01\x02garbage\xff\n"), "unknown keyword", __LINE__);
    // Before the first element an unknown keyword line is skipped only when it reads like a keyword.
    parse_error(ascii_with("\x01\x02garbage\xff\n" + v1 + kXyz), "unknown keyword", __LINE__);
    parse_error(ascii_with("2bye\n" + v1 + kXyz), "unknown keyword '2bye'", __LINE__);
    parse_error(ascii_with("b-ye\n" + v1 + kXyz), "unknown keyword 'b-ye'", __LINE__);
    parse_error(ascii_with(v1 + kXyz + v1 + kXyz), "two 'vertex' elements", __LINE__);
    parse_error(ascii_with("element face 1\nproperty list uchar int idx\n"), "no 'vertex' element", __LINE__);
    parse_error("ply\nformat ascii 1.0\n" + v1 + kXyz, "no end_header", __LINE__);
    parse_error("ply\n" + v1 + kXyz + "end_header\n1 2 3\n", "no format line", __LINE__);
    parse_error("ply\nformat binary_middle_endian 1.0\n" + v1 + kXyz + "end_header\n", "unknown encoding", __LINE__);
    parse_error("ply\nformat ascii 1.0\nformat ascii 1.0\n" + v1 + kXyz + "end_header\n1 2 3\n", "second format",
                __LINE__);
    parse_error("plyx\nformat ascii 1.0\n", "not a PLY file", __LINE__);
    parse_error("PLY\n", "not a PLY file", __LINE__);
    parse_error("\x89PNG\r\n\x1a\n\0\0\0", "not a PLY file", __LINE__);
    parse_error("ply", "no end_header", __LINE__);
    // Ascii data problems.
    parse_error(ascii_with(v1 + kXyz, "1.5 abc 3\n"), "line 8: bad vertex value 'abc'", __LINE__);
    parse_error(ascii_with(v1 + kXyz, "1.5 2 3 4\n"), "does not fill exactly one line", __LINE__);
    parse_error(ascii_with("element vertex 2\n" + std::string(kXyz), "1 2\n3 4\n5 6\n"),
                "does not fill exactly one line", __LINE__);
    parse_error(ascii_with("element face 1\nproperty list uchar int idx\n" + v1 + kXyz, "x 1 2\n1 2 3\n"),
                "bad list length 'x'", __LINE__);
    parse_error(ascii_with("element face 1\nproperty list uchar int idx\n" + v1 + kXyz, "-1 1 2\n1 2 3\n"),
                "bad list length", __LINE__);
    parse_error(ascii_with("element face 1\nproperty list uchar int idx\n" + v1 + kXyz, "1000000000000 1 2\n1 2 3\n"),
                "truncated", __LINE__);
    parse_error(ascii_with("element face 2\nproperty list uchar int idx\n" + v1 + kXyz, "0\n"),
                "truncated: expected 2 records of element 'face', found 1", __LINE__);

    // Binary counts that the file cannot hold.
    auto binary_with = [](const std::string &header_body, const std::string &data) {
        return "ply\nformat binary_little_endian 1.0\n" + header_body + "end_header\n" + data;
    };
    const std::string nine_floats(36, '\0');
    parse_error(binary_with("element vertex 1000000000000000000\n" + std::string(kXyz), nine_floats),
                "truncated: expected 12000000000000000000 bytes of vertex data, found 36", __LINE__);
    parse_error(binary_with("element vertex 1000000000000000000\nproperty double x\nproperty double y\n"
                            "property double z\nproperty double w\nproperty double v\n",
                            nine_floats),
                "far more than the 36 bytes", __LINE__);
    parse_error(binary_with("element vertex 18446744073709551615\n" + std::string(kXyz), nine_floats), "truncated",
                __LINE__);
    parse_error(binary_with("element blob 1000000000000000000\nproperty int a\nelement vertex 3\n" + std::string(kXyz),
                            nine_floats),
                "truncated: expected 4000000000000000000 bytes of element 'blob' data", __LINE__);
    // A negative list length (char -1) and an enormous one (uint 0xffffffff) in an element before the vertices.
    Bytes neg;
    neg.put<std::int8_t>(-1).text(nine_floats);
    parse_error(binary_with("element f 1\nproperty list char int idx\n" + v1 + kXyz, neg.s), "negative list length",
                __LINE__);
    Bytes huge;
    huge.put<std::uint32_t>(0xffffffffu).text(nine_floats);
    parse_error(binary_with("element f 1\nproperty list uint int idx\n" + v1 + kXyz, huge.s), "runs past the end",
                __LINE__);
    Bytes huge_records;
    huge_records.put<std::uint8_t>(0).text(nine_floats);
    parse_error(binary_with("element f 1000000000000000000\nproperty list uchar int idx\n" + v1 + kXyz, huge_records.s),
                "runs past the end", __LINE__);
    // A vertex element with a list and a count its smallest records cannot fit.
    parse_error(binary_with("element vertex 1000\nproperty list uchar float n\n" + std::string(kXyz), nine_floats),
                "truncated: the header declares 1000 vertices", __LINE__);
}

void test_io_errors() {
    TempDir dir;
    EXPECT_FAILURE(dir.file("missing.ply"), FileFormat::Ply, ErrorKind::Io, "No such file or directory");
    std::filesystem::create_directory(dir.file("adir.ply"));
    EXPECT_FAILURE(dir.file("adir.ply"), FileFormat::Ply, ErrorKind::Io, "Is a directory");
    EXPECT_FAILURE(dir.write("empty.ply", ""), FileFormat::Ply, ErrorKind::Parse, "empty");
}

void test_mutations() {
    TempDir dir;
    int n = CHECK_MUTATIONS(dir, "m.ply", std::string(kAscii), FileFormat::Ply, std::string(kAscii).size());
    n += CHECK_MUTATIONS(dir, "m.ply", binary_ply(false), FileFormat::Ply, binary_ply(false).size());
    n += CHECK_MUTATIONS(dir, "m.ply", binary_ply(true), FileFormat::Ply, binary_ply(true).size());
    CHECK(n > 3000);
}

} // namespace

int main() {
    RUN_TEST(test_ascii);
    RUN_TEST(test_keyword_lines_before_the_elements);
    RUN_TEST(test_bunny_like);
    RUN_TEST(test_binary);
    RUN_TEST(test_all_types);
    RUN_TEST(test_vertex_lists);
    RUN_TEST(test_zero_vertices);
    RUN_TEST(test_truncation);
    RUN_TEST(test_malformed);
    RUN_TEST(test_io_errors);
    RUN_TEST(test_mutations);
    return TEST_SUMMARY();
}
