/* SPDX-License-Identifier: MIT */
/* src/common/splitmix64.h, the generator behind the C test scenes, the stage tests and the CLI demo:
 * known values (the reference splitmix64 outputs for state 0, and the derived functions as every user
 * computed them before they shared this header), so that no user's numbers change unnoticed.
 *
 *   test_splitmix64                 the checks
 *   test_splitmix64 --print SEED N  N lines "next uniform range(-2, 3) gauss", drawn in that order from
 *                                   state SEED; tools/make_roundtrip_data.py --selftest compares its own
 *                                   generator with them (the test splitmix64_python). */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "splitmix64.h"

static void test_reference_outputs(void) {
    uint64_t state = 0;
    CHECK(splitmix64_next(&state) == UINT64_C(0xe220a8397b1dcdaf));
    CHECK(splitmix64_next(&state) == UINT64_C(0x6e789e6aa1b965f4));
    CHECK(splitmix64_next(&state) == UINT64_C(0x06c45d188009454f));
    CHECK(state == 3 * UINT64_C(0x9E3779B97F4A7C15));
}

static void test_derived_values(void) {
    uint64_t state = 20261122; /* the seed of tests/data/roundtrip_* */
    CHECK(splitmix64_uniform(&state) == 0x1.1f52d476c30ep-5);
    CHECK(splitmix64_range(&state, -2.0, 3.0) == -0x1.639948e729b8bp+0);
    CHECK(splitmix64_gauss(&state) == -0x1.a5a28d9ec97dbp-1);
    CHECK(splitmix64_gauss(&state) == 0x1.e7a419f842c6ep-2);
    CHECK(state == 20261122 + 6 * UINT64_C(0x9E3779B97F4A7C15));
}

static void test_unit_bounds(void) {
    CHECK(splitmix64_unit(0) == 0.0);
    CHECK(splitmix64_unit(UINT64_C(0x7FF)) == 0.0); /* the low 11 bits are dropped */
    CHECK(splitmix64_unit(UINT64_C(0x800)) == 0x1p-53);
    CHECK(splitmix64_unit(UINT64_MAX) == 1.0 - 0x1p-53);
}

static int print_values(const char *seed_text, const char *count_text) {
    uint64_t state = strtoull(seed_text, NULL, 10);
    const long count = strtol(count_text, NULL, 10);
    long i;
    for (i = 0; i < count; ++i) {
        const uint64_t bits = splitmix64_next(&state);
        const double u = splitmix64_uniform(&state);
        const double r = splitmix64_range(&state, -2.0, 3.0);
        const double g = splitmix64_gauss(&state);
        printf("%" PRIu64 " %.17g %.17g %.17g\n", bits, u, r, g);
    }
    return 0;
}

int main(int argc, char **argv) {
    if (argc == 4 && strcmp(argv[1], "--print") == 0) return print_values(argv[2], argv[3]);
    test_reference_outputs();
    test_derived_values();
    test_unit_bounds();
    return TEST_SUMMARY();
}
