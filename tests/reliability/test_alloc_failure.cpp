// SPDX-License-Identifier: MIT
// Allocation failure: the k-th allocation of a call fails, for every k the call makes (registration, features,
// refinement, file reading). Each such call must
// return KISSM_ERR_OUT_OF_MEMORY (or KISSM_OK when the library could do without that memory), leave no
// allocation behind, and the next call must give exactly the reference result.
//
// The hook (alloc_hook.cpp) replaces the global operator new; the library is linked statically, so all of
// its C++ allocations come through it. Counting is always on; failing is armed per call.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <initializer_list>

#include "alloc_hook.hpp"
#include "capi/scenes.h"
#include "harness.h"
#include "kissm.h"

namespace {

constexpr double kVoxel = 0.5;
scn_pair g_pair;

struct Sweep {
    long allocations = 0; // allocations the call makes when nothing fails
    int out_of_memory = 0, ok = 0, other = 0, leaks = 0, changed_after = 0;
};

// Runs call() once normally (counting its allocations), then once per k with the k-th allocation failing,
// each followed by a normal call that must equal the first. `every` > 1 samples every every-th k.
// release() frees what a successful call() produced (a no-op for calls that produce nothing).
template <class Call, class Release, class Same>
Sweep sweep(const char *what, long every, Call call, Release release, Same same_as_reference) {
    Sweep s;
    const long before = alloc_hook::count();
    if (call() != KISSM_OK) {
        std::fprintf(stderr, "%s: the reference call failed: %s\n", what, kissm_last_error_message());
        s.other = 1;
        return s;
    }
    s.allocations = alloc_hook::count() - before;
    release();
    for (long k = 1; k <= s.allocations; k += every) {
        const long live = alloc_hook::live();
        alloc_hook::fail_at(alloc_hook::count() + k);
        const int32_t st = call();
        alloc_hook::fail_at(-1);
        release();
        if (st == KISSM_ERR_OUT_OF_MEMORY) {
            ++s.out_of_memory;
        } else if (st == KISSM_OK) {
            ++s.ok;
        } else {
            ++s.other;
            std::fprintf(stderr, "%s: allocation %ld failed -> status %d (%s)\n", what, k, (int)st,
                         kissm_last_error_message());
        }
        if (alloc_hook::live() != live) {
            ++s.leaks;
            std::fprintf(stderr, "%s: allocation %ld failed -> %ld allocations left behind\n", what, k,
                         alloc_hook::live() - live);
        }
        const bool same = call() == KISSM_OK && same_as_reference();
        release();
        if (!same) {
            ++s.changed_after;
            std::fprintf(stderr, "%s: after allocation %ld failed, the next call differs\n", what, k);
        }
    }
    std::fprintf(stderr, "  %s: %ld allocations, %d runs -> out of memory %d, ok %d\n", what, s.allocations,
                 s.out_of_memory + s.ok + s.other, s.out_of_memory, s.ok);
    return s;
}

void check_sweep(const Sweep &s) {
    CHECK(s.allocations > 0);
    CHECK(s.out_of_memory > 0); // the hook really fired
    CHECK_EQ_INT(s.other, 0);
    CHECK_EQ_INT(s.leaks, 0);
    CHECK_EQ_INT(s.changed_after, 0);
}

void test_register(int32_t threads, long every) {
    kissm_config c = scn_config(kVoxel);
    c.num_threads = threads;
    kissm_matcher *m = nullptr;
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    const kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    kissm_result reference, r;
    scn_result_poison(&reference);
    REQUIRE(kissm_register(m, &s, &t, &reference) == KISSM_OK);
    CHECK(reference.valid == 1);
    const Sweep sw = sweep(
        threads == 1 ? "kissm_register, 1 thread" : "kissm_register, 2 threads", every,
        [&] {
            scn_result_poison(&r);
            return kissm_register(m, &s, &t, &r);
        },
        [] {}, [&] { return scn_result_equal(&reference, &r) != 0; });
    check_sweep(sw);
    kissm_destroy(m);
}

// KISSM_ALLOC_SWEEP_STEP > 1 samples every step-th allocation (the sanitizer presets: each call there is
// ~10x slower); by default every allocation of the 1-thread registration fails once.
long sweep_step() {
    const char *env = std::getenv("KISSM_ALLOC_SWEEP_STEP");
    const long step = env != nullptr ? std::atol(env) : 1;
    return step >= 1 ? step : 1;
}

void test_register_one_thread() { test_register(1, sweep_step()); }
void test_register_two_threads() { test_register(2, 3 * sweep_step()); }

void test_create_and_features() {
    kissm_config c = scn_config(kVoxel);
    c.num_threads = 1;
    kissm_matcher *m = nullptr;
    bool created = false;
    check_sweep(sweep(
        "kissm_create", 1, [&] { return kissm_create(&c, &m); },
        [&] {
            created = created || m != nullptr;
            kissm_destroy(m);
            m = nullptr;
        },
        [&] { return m != nullptr; }));
    CHECK(created);
    REQUIRE(kissm_create(&c, &m) == KISSM_OK);
    const kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    kissm_features *fs = nullptr, *ft = nullptr, *f = nullptr;
    REQUIRE(kissm_features_compute(m, &s, &fs) == KISSM_OK);
    REQUIRE(kissm_features_compute(m, &t, &ft) == KISSM_OK);
    check_sweep(sweep(
        "kissm_features_compute", 1, [&] { return kissm_features_compute(m, &s, &f); },
        [&] {
            kissm_features_destroy(f);
            f = nullptr;
        },
        [&] {
            return f != nullptr && kissm_features_num_keypoints(f) == kissm_features_num_keypoints(fs) &&
                   kissm_features_num_voxels(f) == kissm_features_num_voxels(fs);
        }));
    kissm_result reference, r;
    scn_result_poison(&reference);
    const int32_t st = kissm_register_features(m, fs, ft, &reference);
    CHECK_MSG(st == KISSM_OK, "%d %s", (int)st, kissm_last_error_message());
    check_sweep(sweep(
        "kissm_register_features", 1,
        [&] {
            scn_result_poison(&r);
            return kissm_register_features(m, fs, ft, &r);
        },
        [] {}, [&] { return scn_result_equal(&reference, &r) != 0; }));
    kissm_features_destroy(fs);
    kissm_features_destroy(ft);
    kissm_destroy(m);
}

// Refinement: kissm_refine (from the truth, 1 thread, every allocation; 2 threads, every 3rd),
// kissm_features_compute with refinement on (it also builds the point index), kissm_refine_features and
// kissm_register with refinement (every 2nd: two registrations per allocation).
void test_refine() {
    double initial[16];
    scn_pose_to_matrix(&g_pair.truth, initial);
    const kissm_points s = scn_points(&g_pair.source), t = scn_points(&g_pair.target);
    for (const int32_t threads : {1, 2}) {
        kissm_config c = scn_config(kVoxel);
        c.num_threads = threads;
        c.refine_mode = threads == 1 ? KISSM_REFINE_GICP : KISSM_REFINE_POINT_TO_PLANE;
        kissm_matcher *m = nullptr;
        REQUIRE(kissm_create(&c, &m) == KISSM_OK);
        kissm_result reference, r;
        scn_result_poison(&reference);
        REQUIRE(kissm_refine(m, &s, &t, initial, &reference) == KISSM_OK);
        CHECK(reference.valid == 1 && reference.refine_iterations >= 1);
        check_sweep(sweep(
            threads == 1 ? "kissm_refine, GICP, 1 thread" : "kissm_refine, point-to-plane, 2 threads",
            threads == 1 ? sweep_step() : 3 * sweep_step(),
            [&] {
                scn_result_poison(&r);
                return kissm_refine(m, &s, &t, initial, &r);
            },
            [] {}, [&] { return scn_result_equal(&reference, &r) != 0; }));
        if (threads == 1) {
            kissm_features *fs = nullptr, *ft = nullptr, *f = nullptr;
            REQUIRE(kissm_features_compute(m, &s, &fs) == KISSM_OK);
            REQUIRE(kissm_features_compute(m, &t, &ft) == KISSM_OK);
            check_sweep(sweep(
                "kissm_features_compute with refinement", sweep_step(),
                [&] { return kissm_features_compute(m, &t, &f); },
                [&] {
                    kissm_features_destroy(f);
                    f = nullptr;
                },
                [&] { return f != nullptr && kissm_features_num_voxels(f) == kissm_features_num_voxels(ft); }));
            kissm_result via;
            scn_result_poison(&via);
            REQUIRE(kissm_refine_features(m, fs, ft, initial, &via) == KISSM_OK);
            check_sweep(sweep(
                "kissm_refine_features", sweep_step(),
                [&] {
                    scn_result_poison(&r);
                    return kissm_refine_features(m, fs, ft, initial, &r);
                },
                [] {}, [&] { return scn_result_equal(&via, &r) != 0; }));
            scn_result_poison(&via);
            REQUIRE(kissm_register(m, &s, &t, &via) == KISSM_OK);
            CHECK(via.refine_iterations >= 1);
            check_sweep(sweep(
                "kissm_register with refinement", 2 * sweep_step(),
                [&] {
                    scn_result_poison(&r);
                    return kissm_register(m, &s, &t, &r);
                },
                [] {}, [&] { return scn_result_equal(&via, &r) != 0; }));
            kissm_features_destroy(fs);
            kissm_features_destroy(ft);
        }
        kissm_destroy(m);
    }
}

const char *g_file = nullptr;

void test_read_points() {
    REQUIRE(g_file != nullptr);
    kissm_cloud *reference = nullptr, *c = nullptr;
    REQUIRE(kissm_read_points(g_file, KISSM_FORMAT_AUTO, &reference) == KISSM_OK);
    const uint64_t n = kissm_cloud_count(reference);
    CHECK(n > 1000);
    check_sweep(sweep(
        "kissm_read_points", 1, [&] { return kissm_read_points(g_file, KISSM_FORMAT_AUTO, &c); },
        [&] {
            kissm_cloud_destroy(c);
            c = nullptr;
        },
        [&] {
            return c != nullptr && kissm_cloud_count(c) == n &&
                   std::memcmp(kissm_cloud_data(c), kissm_cloud_data(reference), n * 3 * sizeof(double)) == 0;
        }));
    kissm_cloud_destroy(reference);
}

} // namespace

int main(int argc, char **argv) {
    g_file = argc > 1 ? argv[1] : nullptr; // a point file to read (tests/data/roundtrip_source.ply)
    // A small pair keeps the sweep (one registration per allocation) to seconds; one that the default config
    // registers (valid), so that every stage allocates.
    scn_make_pair(&g_pair, 6, 3.0, 0.01);
    // The thread's last-error message keeps its buffer: let it grow once before anything is counted.
    if (kissm_create(nullptr, nullptr) == KISSM_OK) return 1;
    RUN_TEST(test_create_and_features);
    RUN_TEST(test_read_points);
    RUN_TEST(test_register_one_thread);
    RUN_TEST(test_register_two_threads);
    RUN_TEST(test_refine);
    scn_pair_free(&g_pair);
    return TEST_SUMMARY();
}
