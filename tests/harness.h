/* SPDX-License-Identifier: MIT */
/* A tiny test harness usable from C99 and C++: CHECK(...) records a failure and carries on, REQUIRE(...)
 * stops the current test function. Each test binary ends with `return TEST_SUMMARY();`, which prints
 * "N passed, N failed" and returns 1 when anything failed. Return 77 from main to mark a skip. */
#ifndef KISSM_TEST_HARNESS_H
#define KISSM_TEST_HARNESS_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static int harness_passed = 0;
static int harness_failed = 0;

#define CHECK(cond)                                                                                                    \
  do {                                                                                                                 \
    if (cond) {                                                                                                        \
      harness_passed++;                                                                                                \
    } else {                                                                                                           \
      harness_failed++;                                                                                                \
      fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond);                                         \
    }                                                                                                                  \
  } while (0)

#define CHECK_MSG(cond, ...)                                                                                           \
  do {                                                                                                                 \
    if (cond) {                                                                                                        \
      harness_passed++;                                                                                                \
    } else {                                                                                                           \
      harness_failed++;                                                                                                \
      fprintf(stderr, "%s:%d: CHECK failed: %s: ", __FILE__, __LINE__, #cond);                                         \
      fprintf(stderr, __VA_ARGS__);                                                                                    \
      fprintf(stderr, "\n");                                                                                           \
    }                                                                                                                  \
  } while (0)

#define REQUIRE(cond)                                                                                                  \
  do {                                                                                                                 \
    if (!(cond)) {                                                                                                     \
      harness_failed++;                                                                                                \
      fprintf(stderr, "%s:%d: REQUIRE failed: %s\n", __FILE__, __LINE__, #cond);                                       \
      return;                                                                                                          \
    }                                                                                                                  \
    harness_passed++;                                                                                                  \
  } while (0)

#define CHECK_EQ_INT(a, b)                                                                                             \
  do {                                                                                                                 \
    long long harness_a = (long long)(a), harness_b = (long long)(b);                                                  \
    if (harness_a == harness_b) {                                                                                      \
      harness_passed++;                                                                                                \
    } else {                                                                                                           \
      harness_failed++;                                                                                                \
      fprintf(stderr, "%s:%d: CHECK_EQ failed: %s == %s (%lld vs %lld)\n", __FILE__, __LINE__, #a, #b, harness_a,      \
              harness_b);                                                                                              \
    }                                                                                                                  \
  } while (0)

#define CHECK_NEAR(a, b, tol)                                                                                          \
  do {                                                                                                                 \
    double harness_a = (double)(a), harness_b = (double)(b);                                                           \
    if (fabs(harness_a - harness_b) <= (tol)) {                                                                        \
      harness_passed++;                                                                                                \
    } else {                                                                                                           \
      harness_failed++;                                                                                                \
      fprintf(stderr, "%s:%d: CHECK_NEAR failed: %s ~ %s (%.17g vs %.17g, tol %g)\n", __FILE__, __LINE__, #a, #b,      \
              harness_a, harness_b, (double)(tol));                                                                    \
    }                                                                                                                  \
  } while (0)

#define RUN_TEST(fn)                                                                                                   \
  do {                                                                                                                 \
    int harness_before = harness_failed;                                                                               \
    fn();                                                                                                              \
    fprintf(stderr, "%s %s\n", harness_failed == harness_before ? "[ ok ]" : "[FAIL]", #fn);                           \
  } while (0)

#define TEST_SUMMARY() (printf("%d passed, %d failed\n", harness_passed, harness_failed), harness_failed ? 1 : 0)

#endif
