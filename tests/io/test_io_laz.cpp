// SPDX-License-Identifier: MIT
// LAZ through the LAS reader (built with KISSM_WITH_LAZ=ON): every file that tests/io/make_laz_files.py wrote
// with laspy + lazrs is read as .laz and as its uncompressed .las twin, and both must give the same bits
// (withheld points left out of both); then corrupt, truncated and hostile copies must fail with a Parse error
// naming the file, never crash, and never allocate by a count the file cannot back; and the fuzz target's
// regressions. Usage: io_laz DIR REGRESSIONS (the generator's output, with manifest.tsv; tests/fuzz/regressions/las).
#include "io_test_util.hpp"

#include "core/little_endian.hpp"
#include "io/format_readers.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>

using namespace iotest;
using kissm::detail::load_le;
using kissm::detail::store_le;

namespace {

std::string dir_of_files;

std::string slurp(const std::string &path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

template <typename U>
void poke(std::string &s, std::size_t at, U v) {
    store_le(v, reinterpret_cast<std::uint8_t *>(&s[at]));
}
template <typename U>
U peek(const std::string &s, std::size_t at) {
    return load_le<U>(reinterpret_cast<const std::uint8_t *>(s.data()) + at);
}

std::string file(const std::string &name) { return dir_of_files + "/" + name; }

void test_same_points_as_las() {
    std::ifstream manifest(file("manifest.tsv"));
    std::string name;
    long long kept = 0, withheld = 0;
    int pairs = 0;
    while (manifest >> name >> kept >> withheld) {
        const Outcome las = try_read(file(name + ".las"), FileFormat::Auto);
        CHECK_MSG(las.ok, "%s.las: %s", name.c_str(), las.message.c_str());
        CHECK_EQ_INT(las.points.size(), 3 * kept);
        CHECK(withheld > 0); // the files do exercise the flag
        EXPECT_POINTS(file(name + ".laz"), FileFormat::Auto, las.points);
        std::uint64_t left_out = 0;
        kissm::detail::read_points_file(file(name + ".laz"), FileFormat::Auto, &left_out);
        CHECK_EQ_INT(left_out, withheld);
        EXPECT_POINTS(file(name + ".laz"), FileFormat::Las, las.points);
        ++pairs;
    }
    CHECK_EQ_INT(pairs, 10);
}

// The parser over bytes in memory (no file per variant: thousands of variants are read).
Outcome parse(const std::string &bytes) {
    Outcome o;
    try {
        o.points = kissm::detail::parse_las("variant.laz", bytes);
        o.ok = true;
    } catch (const kissm::detail::Failure &f) {
        o.kind = f.kind();
        o.message = f.what();
    } catch (const std::exception &e) {
        o.message = std::string("unexpected exception: ") + e.what();
    }
    return o;
}

// Prefixes of a small file, every byte from the LASzip VLR to the first records replaced, and bytes
// flipped all over: a Parse error or whole points, nothing else; every proper prefix is an error.
void test_corruption(const std::string &name) {
    const std::string bytes = slurp(file(name));
    REQUIRE(bytes.size() > 1000);
    const std::size_t header = peek<std::uint16_t>(bytes, 94);
    int bad = 0;
    // Each byte up to the first records, then a step (each variant builds a decompressor afresh).
    for (std::size_t cut = 0; cut < bytes.size() && bad < 5; cut += cut < header + 400 ? 1 : 5) {
        const Outcome o = parse(bytes.substr(0, cut));
        if (o.ok || o.kind != ErrorKind::Parse) {
            ++bad;
            record(false, __FILE__, __LINE__, name + " cut at " + std::to_string(cut) + ": " + o.message);
        }
    }
    int variants = 0;
    auto check = [&](const std::string &m, const std::string &what) {
        const Outcome o = parse(m);
        ++variants;
        if ((!o.ok && o.kind != ErrorKind::Parse) || o.points.size() % 3 != 0) {
            ++bad;
            record(false, __FILE__, __LINE__, name + " " + what + ": " + kind_name(o.kind) + ": " + o.message);
        }
    };
    for (std::size_t i = header; i < bytes.size() && i < header + 300 && bad < 5; ++i) {
        for (int r : {0x00, 0xFF, 0x80}) {
            std::string m = bytes;
            m[i] = static_cast<char>(r);
            if (m != bytes) check(m, "byte " + std::to_string(i) + " = " + std::to_string(r));
        }
    }
    std::uint64_t state = 12345;
    for (int k = 0; k < 800 && bad < 5; ++k) {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        std::string m = bytes;
        const std::size_t at = header + static_cast<std::size_t>(state >> 33) % (m.size() - header);
        m[at] = static_cast<char>(m[at] ^ static_cast<char>(1 + (state >> 20) % 255));
        check(m, "byte " + std::to_string(at) + " flipped");
    }
    CHECK_EQ_INT(bad, 0);
    CHECK(variants > 1500);
}

void test_hostile_sizes() {
    TempDir dir;
    // A point count the compressed data does not hold: an error when the data ends, memory by points read.
    std::string v12 = slurp(file("v12_f0.laz"));
    poke<std::uint32_t>(v12, 107, 0xFFFFFFFFu);
    EXPECT_FAILURE(dir.write("count.laz", v12), FileFormat::Auto, ErrorKind::Parse, "corrupt or truncated LAZ data");
    std::string v14 = slurp(file("v14_f7.laz"));
    poke<std::uint64_t>(v14, 247, std::uint64_t{1} << 40);
    EXPECT_FAILURE(dir.write("count14.laz", v14), FileFormat::Auto, ErrorKind::Parse, "truncated LAZ data");

    // A chunk table claiming 4 billion chunks.
    std::string table = slurp(file("v12_f1.laz"));
    const std::uint32_t points_at = peek<std::uint32_t>(table, 96);
    const auto table_at = static_cast<std::size_t>(peek<std::uint64_t>(table, points_at));
    REQUIRE(table_at + 8 <= table.size());
    poke<std::uint32_t>(table, table_at + 4, 0xFFFFFFFFu);
    EXPECT_FAILURE(dir.write("table.laz", table), FileFormat::Auto, ErrorKind::Parse,
                   "the LAZ chunk table lists 4294967295 chunks");

    // A layer of LAS 1.4's layered chunks claiming 4 GB (laz would allocate it before reading).
    std::string layered = slurp(file("v14_f7.laz"));
    const std::uint32_t at = peek<std::uint32_t>(layered, 96);
    const std::uint16_t record = peek<std::uint16_t>(layered, 105);
    poke<std::uint32_t>(layered, at + 8 + record + 4, 0xFFFFFF00u);
    EXPECT_FAILURE(dir.write("layer.laz", layered), FileFormat::Auto, ErrorKind::Parse, "beyond the file's");

    // The header's record length disagreeing with the LASzip items.
    std::string len = slurp(file("v12_f3.laz"));
    poke<std::uint16_t>(len, 105, static_cast<std::uint16_t>(peek<std::uint16_t>(len, 105) + 2));
    EXPECT_FAILURE(dir.write("len.laz", len), FileFormat::Auto, ErrorKind::Parse, "the LASzip VLR describes 34-byte");

    // No LASzip VLR: its user id changed.
    std::string novlr = slurp(file("v12_f0.laz"));
    const std::size_t user = novlr.find("laszip encoded");
    REQUIRE(user != std::string::npos);
    novlr[user] = 'L';
    EXPECT_FAILURE(dir.write("novlr.laz", novlr), FileFormat::Auto, ErrorKind::Parse, "without the LASzip VLR");
}

// The inputs that once crashed the las fuzz target with LAZ built in (tests/fuzz/regressions/las): points or
// a Parse error. laz_gps_time_recursion.laz overflowed the stack in laz's recursive GPS time decoder.
void test_fuzz_regressions(const std::string &dir) {
    int files = 0;
    for (const auto &entry : std::filesystem::directory_iterator(dir)) {
        const Outcome o = parse(slurp(entry.path().string()));
        CHECK_MSG(o.ok || o.kind == ErrorKind::Parse, "%s: %s", entry.path().c_str(), o.message.c_str());
        ++files;
    }
    CHECK(files >= 1);
}

} // namespace

int main(int argc, char **argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: io_laz DIR REGRESSIONS (DIR written by tests/io/make_laz_files.py, REGRESSIONS "
                        "tests/fuzz/regressions/las)\n");
        return 2;
    }
    dir_of_files = argv[1];
    RUN_TEST(test_same_points_as_las);
    RUN_TEST([] { test_corruption("small_f1.laz"); });
    RUN_TEST([] { test_corruption("small_f6.laz"); });
    RUN_TEST(test_hostile_sizes);
    RUN_TEST([&] { test_fuzz_regressions(argv[2]); });
    return TEST_SUMMARY();
}
