// SPDX-License-Identifier: MIT
// Long run: 10,000 sequential registrations of small clouds on one reused matcher (and every 100th on a
// fresh one, plus features) must not grow memory: the live allocation count returns to the same value
// after every call, and the resident set does not creep. Every result equals the first.
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "alloc_hook.hpp"
#include "capi/scenes.h"
#include "harness.h"
#include "kissm.h"

namespace {

// KISSM_LONG_RUN_COUNT overrides the count (the sanitizer presets use fewer: each call is ~10x slower).
int runs() {
    const char *env = std::getenv("KISSM_LONG_RUN_COUNT");
    const int n = env != nullptr ? std::atoi(env) : 0;
    return n >= 1000 ? n : 10000;
}

long resident_kib() {
    std::FILE *f = std::fopen("/proc/self/statm", "r");
    if (f == nullptr) return -1;
    long pages = 0, resident = 0;
    const int got = std::fscanf(f, "%ld %ld", &pages, &resident);
    std::fclose(f);
    return got == 2 ? resident * 4 : -1; // 4 KiB pages on the platforms this test runs on
}

void test_ten_thousand_registrations() {
    scn_pair pair;
    scn_make_pair(&pair, 17, 1.0, 0.01); // ~600 + ~600 points: a couple of milliseconds per call
    kissm_config c = scn_config(1.0);
    c.num_threads = 1;
    kissm_config c2 = c; // the occasional fresh handle runs a thread pool
    c2.num_threads = 2;
    kissm_matcher *m = nullptr;
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    const kissm_points s = scn_points(&pair.source), t = scn_points(&pair.target);
    kissm_result first, r;
    scn_result_poison(&first);
    REQUIRE(kissm_register(m, &s, &t, &first) == KISSM_OK);
    CHECK(first.num_initial_correspondences > 0); // the pipeline runs to the end, not an early exit
    const long live_before = alloc_hook::live();
    long rss_at_1000 = 0;
    int changed = 0, leaked = 0, failed = 0;
    const int count = runs();
    for (int i = 1; i <= count; ++i) {
        int32_t st;
        scn_result_poison(&r);
        if (i % 100 == 0) { // a fresh handle and the features path now and then
            kissm_matcher *fresh = nullptr;
            kissm_features *fs = nullptr, *ft = nullptr;
            st = kissm_create(&c2, &fresh);
            if (st == KISSM_OK) st = kissm_features_compute(fresh, &s, &fs);
            if (st == KISSM_OK) st = kissm_features_compute(fresh, &t, &ft);
            if (st == KISSM_OK) st = kissm_register_features(fresh, fs, ft, &r);
            kissm_features_destroy(fs);
            kissm_features_destroy(ft);
            kissm_destroy(fresh);
        } else {
            st = kissm_register(m, &s, &t, &r);
        }
        failed += st != KISSM_OK;
        changed += st == KISSM_OK && !scn_result_equal(&first, &r);
        leaked += alloc_hook::live() != live_before;
        if (i == 1000) rss_at_1000 = resident_kib();
    }
    const long rss_end = resident_kib();
    std::fprintf(stderr, "  %d registrations: resident %ld KiB after 1000, %ld KiB after %d\n", count, rss_at_1000,
                 rss_end, count);
    CHECK_EQ_INT(failed, 0);
    CHECK_EQ_INT(changed, 0);
    CHECK_EQ_INT(leaked, 0);
    // Allocator noise only: no steady growth (a leak of 1 KiB per call would add ~9 MiB).
    CHECK_MSG(rss_end - rss_at_1000 < 2048, "resident set grew by %ld KiB", rss_end - rss_at_1000);
    kissm_destroy(m);
    scn_pair_free(&pair);
}

} // namespace

int main() {
    RUN_TEST(test_ten_thousand_registrations);
    return TEST_SUMMARY();
}
