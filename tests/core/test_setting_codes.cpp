// SPDX-License-Identifier: MIT
// The enumerated settings' code tables (core/setting_codes.hpp): every value has one code, codes are 0..max with no
// gap and no repeat, setting_of inverts setting_code, and an out-of-range code gives the table's first value.
#include <set>

#include "core/setting_codes.hpp"
#include "harness.h"

using namespace kissm::detail;

template <class E>
static void check_table() {
    const std::int32_t max = max_setting_code<E>();
    CHECK(max >= 1);
    std::set<std::int32_t> codes;
    for (std::int32_t c = 0; c <= max; ++c) {
        const E v = setting_of<E>(c);
        CHECK(setting_code(v) == c);
        codes.insert(setting_code(v));
    }
    CHECK(static_cast<std::int32_t>(codes.size()) == max + 1);
    CHECK(setting_of<E>(-1) == SettingCodes<E>::values[0]);
    CHECK(setting_of<E>(max + 1) == SettingCodes<E>::values[0]);
}

static void test_tables() {
    check_table<NonFinitePolicy>();
    check_table<ViewpointMode>();
    check_table<RefineMode>();
    check_table<Suppression>();
}

static void test_pinned_codes() {
    // The numbers are kissm.h's and the features format's: they never change.
    CHECK(setting_code(NonFinitePolicy::Drop) == 1);
    CHECK(setting_code(ViewpointMode::CloudCenter) == 1 && setting_code(ViewpointMode::Local) == 3);
    CHECK(setting_code(RefineMode::Gicp) == 1 && setting_code(RefineMode::PointToPlane) == 2);
    CHECK(setting_code(Suppression::Ground) == 1);
}

int main() {
    RUN_TEST(test_tables);
    RUN_TEST(test_pinned_codes);
    return TEST_SUMMARY();
}
