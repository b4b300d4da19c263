/* SPDX-License-Identifier: MIT */
/* Struct versioning (C99): the struct_size rules of kissm_config and kissm_result that let a program built
 * against one kissm header run with a later library (docs/abi-policy.md, "Growable structs").
 *
 *  - the exact size works;
 *  - a larger struct (a caller built against a newer header) works when its unknown tail is zero, and the
 *    library zeroes the unknown tail of what it writes (kissm_config_init, kissm_get_config, results);
 *  - a larger struct whose unknown tail is not zero is refused with KISSM_ERR_STRUCT_SIZE and a message
 *    saying so: a newer caller asked for something this library cannot do;
 *  - a size below the first published layout, or above 65536, is refused with KISSM_ERR_STRUCT_SIZE;
 *  - every published size keeps working, the fields it lacks taking their defaults (kPublished* below;
 *    0.1.0 is the first release, so today the only published size is the current one).
 * On every refusal nothing is written to the caller's struct or output pointer. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "kissm.h"

/* sizeof(kissm_config) and sizeof(kissm_result) of every released header, oldest first. A release that
 * appends fields appends its new size here; no entry is ever removed (the library must keep accepting
 * all of them). */
static const uint32_t kPublishedConfigSizes[] = {152 /* 0.1.0 */};
static const uint32_t kPublishedResultSizes[] = {440 /* 0.1.0 */};
#define COUNT_OF(a) (sizeof(a) / sizeof((a)[0]))

#define TAIL 64     /* bytes a hypothetical newer header appended */
#define POISON 0xA5 /* a byte value the library never writes */
#define MAX_STRUCT_SIZE 65536u

/* Storage for a struct of up to MAX_STRUCT_SIZE + 8 bytes, aligned for any kissm struct. */
typedef union big_buffer {
    kissm_config config;
    kissm_result result;
    unsigned char bytes[MAX_STRUCT_SIZE + 8];
} big_buffer;

static big_buffer *new_buffer(void) {
    big_buffer *b = (big_buffer *)malloc(sizeof(big_buffer));
    if (b == NULL) abort();
    memset(b, POISON, sizeof(*b));
    return b;
}

static int all_bytes(const unsigned char *p, size_t n, unsigned char value) {
    size_t i;
    for (i = 0; i < n; ++i)
        if (p[i] != value) return 0;
    return 1;
}

static int message_contains(const char *needle) { return strstr(kissm_last_error_message(), needle) != NULL; }

static kissm_config defaults(void) {
    kissm_config c;
    memset(&c, 0, sizeof c);
    if (kissm_config_init(&c, (uint32_t)sizeof c) != KISSM_OK) abort();
    return c;
}

/* Two small clouds (three orthogonal planes of points; the second one shifted) for registration calls. */
#define CLOUD_POINTS 300
static double g_source[CLOUD_POINTS * 3], g_target[CLOUD_POINTS * 3];

static void make_clouds(void) {
    int i;
    for (i = 0; i < CLOUD_POINTS; ++i) {
        const double u = (double)(i % 10) * 0.5, v = (double)((i / 10) % 10) * 0.5;
        double *p = &g_source[3 * i], *q = &g_target[3 * i];
        switch (i / 100) {
        case 0: p[0] = u, p[1] = v, p[2] = 0.0; break;
        case 1: p[0] = u, p[1] = 0.0, p[2] = v; break;
        default: p[0] = 0.0, p[1] = u, p[2] = v; break;
        }
        q[0] = p[0] + 0.25, q[1] = p[1] - 0.5, q[2] = p[2] + 0.125;
    }
}

static kissm_points view(const double *xyz) {
    kissm_points p;
    p.data = xyz;
    p.count = CLOUD_POINTS;
    p.stride_bytes = 0;
    p.scalar_type = KISSM_SCALAR_FLOAT64;
    p.reserved = 0;
    return p;
}

/* ---------------------------------------------------------------------------------------------- */
/* kissm_config_init                                                                                */
/* ---------------------------------------------------------------------------------------------- */

static void test_config_init_exact_size(void) {
    big_buffer *b = new_buffer();
    const kissm_config d = defaults();
    CHECK_EQ_INT(kissm_config_init(&b->config, (uint32_t)sizeof(kissm_config)), KISSM_OK);
    CHECK_EQ_INT(b->config.struct_size, sizeof(kissm_config));
    CHECK(memcmp(&b->config, &d, sizeof d) == 0);
    CHECK_MSG(all_bytes(b->bytes + sizeof(kissm_config), 8, POISON), "config_init wrote beyond struct_size");
    free(b);
}

static void test_config_init_larger_zeroes_the_tail(void) {
    big_buffer *b = new_buffer();
    kissm_config d = defaults();
    const uint32_t size = (uint32_t)sizeof(kissm_config) + TAIL;
    CHECK_EQ_INT(kissm_config_init(&b->config, size), KISSM_OK);
    CHECK_EQ_INT(b->config.struct_size, size);
    d.struct_size = size;
    CHECK_MSG(memcmp(&b->config, &d, sizeof d) == 0, "the known part is not the defaults");
    CHECK_MSG(all_bytes(b->bytes + sizeof(kissm_config), TAIL, 0), "the unknown tail is not zeroed");
    CHECK_MSG(all_bytes(b->bytes + size, 8, POISON), "config_init wrote beyond struct_size");
    /* The largest accepted size. */
    memset(b, POISON, sizeof(*b));
    CHECK_EQ_INT(kissm_config_init(&b->config, MAX_STRUCT_SIZE), KISSM_OK);
    CHECK(all_bytes(b->bytes + sizeof(kissm_config), MAX_STRUCT_SIZE - sizeof(kissm_config), 0));
    CHECK(all_bytes(b->bytes + MAX_STRUCT_SIZE, 8, POISON));
    free(b);
}

static void test_config_init_refuses_bad_sizes(void) {
    const uint32_t sizes[] = {
        0,         4, 8, (uint32_t)sizeof(kissm_config) - 8, (uint32_t)sizeof(kissm_config) - 1, MAX_STRUCT_SIZE + 1,
        UINT32_MAX};
    size_t i;
    big_buffer *b = new_buffer();
    for (i = 0; i < COUNT_OF(sizes); ++i) {
        CHECK_MSG(kissm_config_init(&b->config, sizes[i]) == KISSM_ERR_STRUCT_SIZE, "size %u accepted",
                  (unsigned)sizes[i]);
        CHECK(kissm_last_error_message()[0] != '\0');
        CHECK_MSG(all_bytes(b->bytes, sizeof(*b), POISON), "a refused config_init(%u) wrote to the struct",
                  (unsigned)sizes[i]);
    }
    free(b);
}

/* ---------------------------------------------------------------------------------------------- */
/* A config passed in: kissm_config_validate and kissm_create                                        */
/* ---------------------------------------------------------------------------------------------- */

static void test_config_larger_with_zero_tail_is_accepted(void) {
    big_buffer *b = new_buffer();
    kissm_matcher *m = NULL;
    kissm_config back;
    const uint32_t size = (uint32_t)sizeof(kissm_config) + TAIL;
    REQUIRE(kissm_config_init(&b->config, size) == KISSM_OK);
    b->config.voxel_size = 0.5;
    CHECK_EQ_INT(kissm_config_validate(&b->config), KISSM_OK);
    REQUIRE(kissm_create(&b->config, &m) == KISSM_OK);
    back.struct_size = (uint32_t)sizeof back;
    CHECK_EQ_INT(kissm_get_config(m, &back), KISSM_OK);
    CHECK_EQ_INT(back.struct_size, sizeof back);
    CHECK(back.voxel_size == 0.5);
    kissm_destroy(m);
    free(b);
}

static void test_config_larger_with_nonzero_tail_is_refused(void) {
    const size_t positions[] = {0, 7, TAIL - 1}; /* first, some, last byte of the unknown tail */
    size_t i;
    big_buffer *b = new_buffer();
    for (i = 0; i < COUNT_OF(positions); ++i) {
        kissm_matcher *m = (kissm_matcher *)&positions; /* a sentinel: must stay as it is */
        REQUIRE(kissm_config_init(&b->config, (uint32_t)sizeof(kissm_config) + TAIL) == KISSM_OK);
        b->bytes[sizeof(kissm_config) + positions[i]] = 1;
        CHECK_EQ_INT(kissm_config_validate(&b->config), KISSM_ERR_STRUCT_SIZE);
        CHECK_MSG(message_contains("non-zero"), "message: %s", kissm_last_error_message());
        CHECK_EQ_INT(kissm_create(&b->config, &m), KISSM_ERR_STRUCT_SIZE);
        CHECK_MSG(message_contains("non-zero"), "message: %s", kissm_last_error_message());
        CHECK(m == (kissm_matcher *)&positions);
    }
    free(b);
}

static void test_config_smaller_or_huge_is_refused(void) {
    const uint32_t sizes[] = {0, 4, (uint32_t)sizeof(kissm_config) - 8, MAX_STRUCT_SIZE + 1, UINT32_MAX};
    size_t i;
    big_buffer *b = new_buffer();
    for (i = 0; i < COUNT_OF(sizes); ++i) {
        kissm_matcher *m = (kissm_matcher *)&sizes;
        REQUIRE(kissm_config_init(&b->config, (uint32_t)sizeof(kissm_config)) == KISSM_OK);
        b->config.struct_size = sizes[i];
        CHECK_EQ_INT(kissm_config_validate(&b->config), KISSM_ERR_STRUCT_SIZE);
        CHECK_MSG(message_contains("struct_size"), "message: %s", kissm_last_error_message());
        CHECK_EQ_INT(kissm_create(&b->config, &m), KISSM_ERR_STRUCT_SIZE);
        CHECK(m == (kissm_matcher *)&sizes);
    }
    free(b);
}

/* ---------------------------------------------------------------------------------------------- */
/* Structs the library writes: kissm_get_config and kissm_result                                    */
/* ---------------------------------------------------------------------------------------------- */

static void test_get_config_sizes(void) {
    big_buffer *b = new_buffer();
    kissm_matcher *m = NULL;
    kissm_config d = defaults();
    const uint32_t size = (uint32_t)sizeof(kissm_config) + TAIL;
    REQUIRE(kissm_create(NULL, &m) == KISSM_OK);
    b->config.struct_size = size;
    CHECK_EQ_INT(kissm_get_config(m, &b->config), KISSM_OK);
    CHECK_EQ_INT(b->config.struct_size, size);
    d.struct_size = size;
    CHECK(memcmp(&b->config, &d, sizeof d) == 0);
    CHECK_MSG(all_bytes(b->bytes + sizeof(kissm_config), TAIL, 0), "get_config left the unknown tail as it was");
    CHECK(all_bytes(b->bytes + size, 8, POISON));

    memset(b, POISON, sizeof(*b));
    b->config.struct_size = (uint32_t)sizeof(kissm_config) - 8;
    CHECK_EQ_INT(kissm_get_config(m, &b->config), KISSM_ERR_STRUCT_SIZE);
    CHECK(all_bytes(b->bytes + sizeof(uint32_t), sizeof(*b) - sizeof(uint32_t), POISON));
    kissm_destroy(m);
    free(b);
}

static void test_result_sizes(void) {
    big_buffer *b = new_buffer();
    kissm_matcher *m = NULL;
    const kissm_points source = view(g_source), target = view(g_target);
    const uint32_t size = (uint32_t)sizeof(kissm_result) + TAIL;
    REQUIRE(kissm_create(NULL, &m) == KISSM_OK);

    /* Larger: accepted whatever its tail holds (the library writes it, it does not read it). */
    b->result.struct_size = size;
    CHECK_EQ_INT(kissm_register(m, &source, &target, &b->result), KISSM_OK);
    CHECK_EQ_INT(b->result.struct_size, size);
    CHECK_MSG(all_bytes(b->bytes + sizeof(kissm_result), TAIL, 0), "the result's unknown tail is not zeroed");
    CHECK_MSG(all_bytes(b->bytes + size, 8, POISON), "kissm_register wrote beyond struct_size");

    /* Smaller or huge: refused, and nothing beyond the struct_size field is written. */
    {
        const uint32_t sizes[] = {0, 8, (uint32_t)sizeof(kissm_result) - 8, MAX_STRUCT_SIZE + 1};
        size_t i;
        for (i = 0; i < COUNT_OF(sizes); ++i) {
            memset(b, POISON, sizeof(*b));
            b->result.struct_size = sizes[i];
            CHECK_EQ_INT(kissm_register(m, &source, &target, &b->result), KISSM_ERR_STRUCT_SIZE);
            CHECK_MSG(message_contains("result->struct_size"), "message: %s", kissm_last_error_message());
            CHECK_MSG(all_bytes(b->bytes + sizeof(uint32_t), sizeof(*b) - sizeof(uint32_t), POISON),
                      "a refused result of struct_size %u was written to", (unsigned)sizes[i]);
        }
    }
    kissm_destroy(m);
    free(b);
}

/* ---------------------------------------------------------------------------------------------- */
/* Every published layout keeps working                                                             */
/* ---------------------------------------------------------------------------------------------- */

static void test_published_sizes(void) {
    const kissm_config d = defaults();
    const kissm_points source = view(g_source), target = view(g_target);
    size_t i;
    /* The current header's sizes are the newest published ones (or a later, unreleased layout). */
    CHECK(sizeof(kissm_config) >= kPublishedConfigSizes[COUNT_OF(kPublishedConfigSizes) - 1]);
    CHECK(sizeof(kissm_result) >= kPublishedResultSizes[COUNT_OF(kPublishedResultSizes) - 1]);

    for (i = 0; i < COUNT_OF(kPublishedConfigSizes); ++i) {
        const uint32_t size = kPublishedConfigSizes[i];
        big_buffer *b = new_buffer();
        kissm_matcher *m = NULL;
        kissm_config back;
        CHECK_EQ_INT(kissm_config_init(&b->config, size), KISSM_OK);
        CHECK_EQ_INT(b->config.struct_size, size);
        CHECK(all_bytes(b->bytes + size, 8, POISON));
        /* A field every published layout has, set by an older caller... */
        b->config.voxel_size = 0.5;
        CHECK_EQ_INT(kissm_create(&b->config, &m), KISSM_OK);
        if (m != NULL) {
            /* ...is kept, and the fields its layout lacks take their defaults. */
            back.struct_size = (uint32_t)sizeof back;
            CHECK_EQ_INT(kissm_get_config(m, &back), KISSM_OK);
            CHECK(back.voxel_size == 0.5);
            CHECK(size >= sizeof back || memcmp((const unsigned char *)&back + size, (const unsigned char *)&d + size,
                                                sizeof back - size) == 0);
            kissm_destroy(m);
        }
        free(b);
    }
    /* Below the first published layout: refused. */
    {
        kissm_config c;
        CHECK_EQ_INT(kissm_config_init(&c, kPublishedConfigSizes[0] - 1), KISSM_ERR_STRUCT_SIZE);
    }

    for (i = 0; i < COUNT_OF(kPublishedResultSizes); ++i) {
        big_buffer *b = new_buffer();
        kissm_matcher *m = NULL;
        const uint32_t size = kPublishedResultSizes[i];
        REQUIRE(kissm_create(NULL, &m) == KISSM_OK);
        b->result.struct_size = size;
        CHECK_EQ_INT(kissm_register(m, &source, &target, &b->result), KISSM_OK);
        CHECK_EQ_INT(b->result.struct_size, size);
        CHECK_MSG(all_bytes(b->bytes + size, 8, POISON), "kissm_register wrote beyond a published struct_size");
        kissm_destroy(m);
        free(b);
    }
}

int main(void) {
    make_clouds();
    RUN_TEST(test_config_init_exact_size);
    RUN_TEST(test_config_init_larger_zeroes_the_tail);
    RUN_TEST(test_config_init_refuses_bad_sizes);
    RUN_TEST(test_config_larger_with_zero_tail_is_accepted);
    RUN_TEST(test_config_larger_with_nonzero_tail_is_refused);
    RUN_TEST(test_config_smaller_or_huge_is_refused);
    RUN_TEST(test_get_config_sizes);
    RUN_TEST(test_result_sizes);
    RUN_TEST(test_published_sizes);
    return TEST_SUMMARY();
}
