/* SPDX-License-Identifier: MIT */
/* The layout of kissm.h's public structs (C11), three ways:
 *
 *  - at compile time, on 64-bit targets: _Static_assert on sizeof, _Alignof and every field's offsetof and
 *    sizeof against layout_table.h, and a check that the listed fields cover every byte (no padding, no
 *    field missing from the table). Built with -Wpadded -Werror, so implicit padding fails the build too;
 *  - at run time: kissm_abi_sizeof() of the library this program is linked with equals the header's
 *    sizeof, and the versions agree;
 *  - `abi_layout --json` prints the compiled layout as JSON and `abi_layout --check FILE` compares it with
 *    the committed tests/abi/layout.json, which the Python and Rust tests read.
 *
 * Usage: abi_layout               run the run-time checks
 *        abi_layout --json        print the layout JSON (regenerates layout.json: see update_baseline.sh)
 *        abi_layout --check FILE  run the checks and compare FILE with the compiled layout
 * Exit status: 0 pass, 1 fail, 77 skipped (not a 64-bit target: layout.json describes 64-bit targets). */
#include "kissm.h"

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "layout_table.h"

#if UINTPTR_MAX == UINT64_MAX
#  define KISSM_LAYOUT_64 1

_Static_assert(sizeof(void *) == 8, "64-bit pointers");
_Static_assert(sizeof(double) == 8 && _Alignof(double) == 8, "8-byte aligned doubles");

#  define LAYOUT_ASSERT_FIELD(s, f, type, off, size)                                                                   \
    _Static_assert(offsetof(s, f) == (off), "offsetof(" #s ", " #f ") is not " #off ": the ABI changed");              \
    _Static_assert(sizeof(((s *)0)->f) == (size), "sizeof " #s "." #f " is not " #size ": the ABI changed");
KISSM_LAYOUT_FIELDS(LAYOUT_ASSERT_FIELD)

#  define LAYOUT_ASSERT_STRUCT(s, id, size)                                                                            \
    _Static_assert(sizeof(s) == (size), "sizeof(" #s ") is not " #size ": the ABI changed");                           \
    _Static_assert(_Alignof(s) == 8, "_Alignof(" #s ") is not 8: the ABI changed");
KISSM_LAYOUT_STRUCTS(LAYOUT_ASSERT_STRUCT)

/* The table lists every byte: the field sizes add up to the struct size. */
#  define LAYOUT_ADD_SIZE(s, f, type, off, size) +(size)
_Static_assert(0 KISSM_LAYOUT_CONFIG(LAYOUT_ADD_SIZE) == sizeof(kissm_config),
               "kissm_config has a field that tests/abi/layout_table.h does not list");
_Static_assert(0 KISSM_LAYOUT_POINTS(LAYOUT_ADD_SIZE) == sizeof(kissm_points),
               "kissm_points has a field that tests/abi/layout_table.h does not list");
_Static_assert(0 KISSM_LAYOUT_RESULT(LAYOUT_ADD_SIZE) == sizeof(kissm_result),
               "kissm_result has a field that tests/abi/layout_table.h does not list");
_Static_assert(0 KISSM_LAYOUT_ALIGN_OPTIONS(LAYOUT_ADD_SIZE) == sizeof(kissm_align_options),
               "kissm_align_options has a field that tests/abi/layout_table.h does not list");
#else
#  define KISSM_LAYOUT_64 0
#endif

/* The compiled layout (offsetof/sizeof, not the table's numbers), whatever the target. */
typedef struct layout_field {
    const char *owner;
    const char *name;
    const char *type;
    size_t offset;
    size_t size;
} layout_field;

typedef struct layout_struct {
    const char *name;
    size_t size;
    size_t align;
    int32_t id;
    int32_t unused; /* explicit padding (this file builds with -Wpadded) */
} layout_struct;

#define LAYOUT_FIELD_ROW(s, f, type, off, size) {#s, #f, #type, offsetof(s, f), sizeof(((s *)0)->f)},
static const layout_field kFields[] = {KISSM_LAYOUT_FIELDS(LAYOUT_FIELD_ROW)};
#define LAYOUT_STRUCT_ROW(s, id, size) {#s, sizeof(s), _Alignof(s), id, 0},
static const layout_struct kStructs[] = {KISSM_LAYOUT_STRUCTS(LAYOUT_STRUCT_ROW)};

#define COUNT_OF(a) (sizeof(a) / sizeof((a)[0]))

/* ---------------------------------------------------------------------------------------------- */
/* Run-time checks                                                                                  */
/* ---------------------------------------------------------------------------------------------- */

static void test_library_agrees_with_header(void) {
    size_t i;
    for (i = 0; i < COUNT_OF(kStructs); ++i)
        CHECK_MSG(kissm_abi_sizeof(kStructs[i].id) == kStructs[i].size, "kissm_abi_sizeof(%s) = %u, header: %zu",
                  kStructs[i].name, (unsigned)kissm_abi_sizeof(kStructs[i].id), kStructs[i].size);
    CHECK_EQ_INT(kissm_abi_sizeof(0), 0);
    CHECK_EQ_INT(kissm_abi_sizeof(KISSM_STRUCT_ALIGN_OPTIONS + 1), 0);
    CHECK_EQ_INT(kissm_abi_sizeof(-1), 0);
    CHECK_EQ_INT(kissm_abi_version(), KISSM_ABI_VERSION);
    CHECK_EQ_INT(kissm_version_number(), KISSM_VERSION_NUMBER);
    CHECK(strcmp(kissm_version_string(), KISSM_VERSION_STRING) == 0);
}

/* Fields in declaration order, each starting where the previous one ended, the last one ending at sizeof:
 * no padding anywhere, on any target. */
static void test_no_padding(void) {
    size_t s, i;
    for (s = 0; s < COUNT_OF(kStructs); ++s) {
        size_t end = 0, listed = 0;
        for (i = 0; i < COUNT_OF(kFields); ++i) {
            if (strcmp(kFields[i].owner, kStructs[s].name) != 0) continue;
            CHECK_MSG(kFields[i].offset == end, "%s.%s at offset %zu, expected %zu (padding or a missing field)",
                      kStructs[s].name, kFields[i].name, kFields[i].offset, end);
            end = kFields[i].offset + kFields[i].size;
            ++listed;
        }
        CHECK_MSG(listed > 0 && end == kStructs[s].size, "%s: fields end at %zu, sizeof is %zu", kStructs[s].name, end,
                  kStructs[s].size);
    }
    /* struct_size comes first in the growable structs. */
    CHECK_EQ_INT(offsetof(kissm_config, struct_size), 0);
    CHECK_EQ_INT(offsetof(kissm_result, struct_size), 0);
    CHECK_EQ_INT(offsetof(kissm_align_options, struct_size), 0);
}

/* ---------------------------------------------------------------------------------------------- */
/* JSON                                                                                             */
/* ---------------------------------------------------------------------------------------------- */

typedef struct text {
    char *data;
    size_t length, capacity;
} text;

#if defined(__GNUC__)
static void text_add(text *t, const char *format, ...) __attribute__((format(printf, 2, 3)));
#endif

static void text_add(text *t, const char *format, ...) {
    va_list args;
    int n;
    va_start(args, format);
    n = vsnprintf(NULL, 0, format, args);
    va_end(args);
    if (n < 0) abort();
    if (t->length + (size_t)n + 1 > t->capacity) {
        size_t capacity = (t->capacity ? t->capacity * 2 : 4096) + (size_t)n;
        char *grown = (char *)realloc(t->data, capacity);
        if (grown == NULL) abort();
        t->data = grown;
        t->capacity = capacity;
    }
    va_start(args, format);
    vsnprintf(t->data + t->length, t->capacity - t->length, format, args);
    va_end(args);
    t->length += (size_t)n;
}

/* One field per line, so that a diff of layout.json names the field that moved. */
static text layout_json(void) {
    text t = {NULL, 0, 0};
    size_t s, i;
    text_add(&t, "{\n");
    text_add(&t, "  \"comment\": \"Layout of the public structs of include/kissm.h on 64-bit targets (x86-64, "
                 "aarch64). Generated by tests/abi/update_baseline.sh (abi_layout --json); checked by the "
                 "abi_layout_json test. Published entries never change; fields are only appended to "
                 "kissm_config and kissm_result (docs/abi-policy.md).\",\n");
    text_add(&t, "  \"abi_version\": %d,\n", KISSM_ABI_VERSION);
    text_add(&t, "  \"pointer_size\": %zu,\n", sizeof(void *));
    text_add(&t, "  \"structs\": {\n");
    for (s = 0; s < COUNT_OF(kStructs); ++s) {
        int first = 1;
        text_add(&t, "    \"%s\": {\n", kStructs[s].name);
        text_add(&t, "      \"id\": %d,\n", (int)kStructs[s].id);
        text_add(&t, "      \"size\": %zu,\n", kStructs[s].size);
        text_add(&t, "      \"align\": %zu,\n", kStructs[s].align);
        text_add(&t, "      \"fields\": [\n");
        for (i = 0; i < COUNT_OF(kFields); ++i) {
            if (strcmp(kFields[i].owner, kStructs[s].name) != 0) continue;
            text_add(&t, "%s        {\"name\": \"%s\", \"type\": \"%s\", \"offset\": %zu, \"size\": %zu}",
                     first ? "" : ",\n", kFields[i].name, kFields[i].type, kFields[i].offset, kFields[i].size);
            first = 0;
        }
        text_add(&t, "\n      ]\n");
        text_add(&t, "    }%s\n", s + 1 < COUNT_OF(kStructs) ? "," : "");
    }
    text_add(&t, "  }\n}\n");
    return t;
}

static char *read_file(const char *path, size_t *length) {
    FILE *f = fopen(path, "rb");
    char *data = NULL;
    size_t capacity = 0, n;
    *length = 0;
    if (f == NULL) return NULL;
    for (;;) {
        if (*length + 4096 > capacity) {
            char *grown = (char *)realloc(data, capacity = capacity * 2 + 8192);
            if (grown == NULL) abort();
            data = grown;
        }
        n = fread(data + *length, 1, capacity - *length - 1, f);
        *length += n;
        if (n == 0) break;
    }
    fclose(f);
    data[*length] = '\0';
    return data;
}

/* Compares line by line (a committed file may have CRLF line ends after a Windows checkout). */
static void check_json_file(const char *path) {
    text expected = layout_json();
    size_t length = 0;
    char *committed = read_file(path, &length);
    const char *a, *b;
    int line = 1;
    CHECK_MSG(committed != NULL, "cannot read %s", path);
    if (committed == NULL) {
        free(expected.data);
        return;
    }
    a = committed;
    b = expected.data;
    for (;;) {
        size_t la = strcspn(a, "\r\n"), lb = strcspn(b, "\n");
        if (la != lb || memcmp(a, b, la) != 0) {
            CHECK_MSG(0,
                      "%s differs from the compiled header at line %d:\n  committed: %.*s\n  compiled:  %.*s\n"
                      "A published layout never changes (docs/abi-policy.md). After appending fields to "
                      "kissm_config or kissm_result, extend tests/abi/layout_table.h and run "
                      "tests/abi/update_baseline.sh.",
                      path, line, (int)la, a, (int)lb, b);
            break;
        }
        if (a[la] == '\0' || b[lb] == '\0') {
            CHECK_MSG(a[la] == '\0' && b[lb] == '\0', "%s and the compiled layout have different lengths", path);
            break;
        }
        a += la + (a[la] == '\r' && a[la + 1] == '\n' ? 2 : 1);
        b += lb + 1;
        ++line;
    }
    free(committed);
    free(expected.data);
}

int main(int argc, char **argv) {
    if (argc == 2 && strcmp(argv[1], "--json") == 0) {
        text t = layout_json();
        fputs(t.data, stdout);
        free(t.data);
        return 0;
    }
    if (!(argc == 1 || (argc == 3 && strcmp(argv[1], "--check") == 0))) {
        fprintf(stderr, "usage: %s [--json | --check layout.json]\n", argv[0]);
        return 2;
    }
    RUN_TEST(test_library_agrees_with_header);
    RUN_TEST(test_no_padding);
    if (argc == 3) {
        if (!KISSM_LAYOUT_64) {
            printf("SKIP: tests/abi/layout.json describes 64-bit targets; this one has %zu-byte pointers\n",
                   sizeof(void *));
            return harness_failed ? 1 : 77;
        }
        check_json_file(argv[2]);
    }
    return TEST_SUMMARY();
}
