// SPDX-License-Identifier: MIT
// The numeric settings' ranges (core/setting_limits.hpp) are the ones docs/parameters.md's "Ranges" table states:
// every row of the table is rendered from the limits here and compared as text, and every limit has its row; each
// row's default is what kissm_config_init writes. Also the limits' own edges: open and closed ends, non-finite values.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string>

#include "core/setting_limits.hpp"
#include "harness.h"
#include "kissm.h"

using namespace kissm::detail;

static std::string number(double v) {
    if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}
static std::string render(const RealLimits &r) {
    return std::string(r.lo_open ? "(" : "[") + number(r.lo) + ", " + number(r.hi) + (std::isinf(r.hi) ? ")" : "]");
}
static std::string render(const IntLimits &r) { return "[" + std::to_string(r.lo) + ", " + std::to_string(r.hi) + "]"; }

struct Row {
    std::string range, fallback; // the range and default cells
};

// `| `field` | range | default |` rows of the "## Ranges" section.
static std::map<std::string, Row> documented(const std::string &path) {
    std::ifstream in(path);
    std::map<std::string, Row> rows;
    std::string line;
    bool inside = false;
    while (std::getline(in, line)) {
        if (line.rfind("## ", 0) == 0) inside = line == "## Ranges";
        if (!inside || line.rfind("| `", 0) != 0) continue;
        const std::size_t name_end = line.find('`', 3);
        const std::size_t cell = line.find("| ", name_end);
        const std::size_t cell_end = line.find(" |", cell + 2);
        const std::size_t next_end = cell_end == std::string::npos ? cell_end : line.find(" |", cell_end + 3);
        if (name_end == std::string::npos || cell == std::string::npos || next_end == std::string::npos) continue;
        rows[line.substr(3, name_end - 3)] = {line.substr(cell + 2, cell_end - cell - 2),
                                              line.substr(cell_end + 3, next_end - cell_end - 3)};
    }
    return rows;
}

static const char *g_doc = nullptr;

static void test_docs_state_the_limits() {
    REQUIRE(g_doc != nullptr);
    std::map<std::string, Row> rows = documented(g_doc);
    REQUIRE(!rows.empty());
    kissm_config defaults;
    REQUIRE(kissm_config_init(&defaults, sizeof defaults) == KISSM_OK);
#define KISSM_CHECK_ROW(field, ...)                                                                                    \
  CHECK_MSG(rows.count(#field) == 1 && rows[#field].range == render(limits::field), "%s: docs '%s', limits '%s'",      \
            #field, rows.count(#field) ? rows[#field].range.c_str() : "(no row)", render(limits::field).c_str());      \
  CHECK_MSG(rows[#field].fallback == number(static_cast<double>(defaults.field)), "%s: docs default '%s', init %s",    \
            #field, rows[#field].fallback.c_str(), number(static_cast<double>(defaults.field)).c_str());               \
  rows.erase(#field);
    KISSM_SETTING_LIMITS(KISSM_CHECK_ROW, KISSM_CHECK_ROW)
#undef KISSM_CHECK_ROW
    CHECK(rows.count("normal_radius_gain") == 1 && rows["normal_radius_gain"].range == "(0, fpfh_radius_gain]");
    CHECK(rows["normal_radius_gain"].fallback == number(defaults.normal_radius_gain));
    CHECK(render(limits::normal_radius_gain_below(5.0)) == "(0, 5]");
    rows.erase("normal_radius_gain");
    for (const auto &row : rows) CHECK_MSG(false, "docs row '%s' names no limit", row.first.c_str());
}

static void test_edges() {
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = HUGE_VAL;
    CHECK(!limits::max_linearity.contains(0.0) && limits::max_linearity.contains(1.0)); // (0, 1]
    CHECK(limits::min_overlap.contains(0.0) && limits::min_overlap.contains(1.0));      // [0, 1]
    CHECK(!limits::min_overlap.contains(nan) && !limits::voxel_size.contains(inf));     // finite only
    CHECK(limits::voxel_size.contains(1e300) && !limits::voxel_size.contains(0.0));
    CHECK(limits::min_normal_neighbors.contains(3) && !limits::min_normal_neighbors.contains(2));
    CHECK(!limits::min_normal_neighbors.contains(100001));
}

int main(int argc, char **argv) {
    g_doc = argc > 1 ? argv[1] : nullptr;
    RUN_TEST(test_docs_state_the_limits);
    RUN_TEST(test_edges);
    return TEST_SUMMARY();
}
