// SPDX-License-Identifier: MIT
// Compile-only test of the public header from C++. The abi_header_cxx11 and abi_header_cxx17 tests compile
// this file with -std=c++11 / -std=c++17 -Wall -Wextra -pedantic -Werror -Wpadded -Wold-style-cast (and a
// few more).
//
// Beyond compiling cleanly it checks what a C++ caller relies on:
//  - every function has C linkage: each one is declared again below inside extern "C" with its exact type,
//    which does not compile if the header declared it with C++ linkage or another signature;
//  - the structs are trivial standard-layout types (memcpy-able, usable from C, Python and Rust);
//  - every field has the type listed in layout_table.h (the C test layout.c checks offsets and sizes);
//  - the constants are constant expressions of type int.
#include "kissm.h"
#include "kissm.h" // the include guard works

#include <cstddef>
#include <type_traits>

#include "layout_table.h"

extern "C" {
uint32_t kissm_version_number(void);
const char *kissm_version_string(void);
uint32_t kissm_abi_version(void);
const char *kissm_status_string(int32_t status);
const char *kissm_last_error_message(void);
const char *kissm_reason_string(int32_t reason);
int32_t kissm_config_init(kissm_config *config, uint32_t struct_size);
int32_t kissm_config_validate(const kissm_config *config);
int32_t kissm_create(const kissm_config *config, kissm_matcher **out_matcher);
void kissm_destroy(kissm_matcher *matcher);
int32_t kissm_get_config(const kissm_matcher *matcher, kissm_config *out_config);
int32_t kissm_register(kissm_matcher *matcher, const kissm_points *source, const kissm_points *target,
                       kissm_result *result);
void kissm_cancel(kissm_matcher *matcher);
int32_t kissm_features_compute(kissm_matcher *matcher, const kissm_points *cloud, kissm_features **out_features);
void kissm_features_destroy(kissm_features *features);
uint64_t kissm_features_num_points(const kissm_features *features);
uint64_t kissm_features_num_voxels(const kissm_features *features);
uint64_t kissm_features_num_keypoints(const kissm_features *features);
uint64_t kissm_features_memory_bytes(const kissm_features *features);
int32_t kissm_register_features(kissm_matcher *matcher, const kissm_features *source, const kissm_features *target,
                                kissm_result *result);
int32_t kissm_features_serialize(const kissm_features *features, void *buffer, uint64_t capacity, uint64_t *out_size);
int32_t kissm_features_deserialize(const void *bytes, uint64_t size, kissm_features **out_features);
int32_t kissm_read_points(const char *path, int32_t format, kissm_cloud **out_cloud);
void kissm_cloud_destroy(kissm_cloud *cloud);
uint64_t kissm_cloud_count(const kissm_cloud *cloud);
uint64_t kissm_cloud_num_withheld(const kissm_cloud *cloud);
const double *kissm_cloud_data(const kissm_cloud *cloud);
int32_t kissm_cloud_points(const kissm_cloud *cloud, kissm_points *out_points);
uint32_t kissm_abi_sizeof(int32_t which);
}

// No C++ default arguments, overloads or noexcept sneak into the header: the address of each function has
// the plain C function-pointer type.
static_assert(std::is_same<decltype(&kissm_register), int32_t (*)(kissm_matcher *, const kissm_points *,
                                                                  const kissm_points *, kissm_result *)>::value,
              "kissm_register's type changed");
static_assert(std::is_same<decltype(&kissm_config_init), int32_t (*)(kissm_config *, uint32_t)>::value,
              "kissm_config_init's type changed");

template <typename T>
struct is_c_struct {
    static constexpr bool value = std::is_trivial<T>::value && std::is_standard_layout<T>::value;
};
static_assert(is_c_struct<kissm_config>::value, "kissm_config must be a trivial standard-layout struct");
static_assert(is_c_struct<kissm_points>::value, "kissm_points must be a trivial standard-layout struct");
static_assert(is_c_struct<kissm_result>::value, "kissm_result must be a trivial standard-layout struct");
static_assert(std::is_same<kissm_log_fn, void (*)(void *, int32_t, const char *)>::value, "kissm_log_fn changed");
static_assert(std::is_same<kissm_progress_fn, int32_t (*)(void *, int32_t, double)>::value,
              "kissm_progress_fn changed");

#define LAYOUT_ASSERT_TYPE(s, f, type, off, size)                                                                      \
  static_assert(std::is_same<decltype(s::f), type>::value, "the type of " #s "." #f " is not " #type);
KISSM_LAYOUT_FIELDS(LAYOUT_ASSERT_TYPE)

// Constants are int constant expressions, usable in switch labels and array sizes.
static_assert(std::is_same<decltype(KISSM_ERR_INTERNAL), int>::value, "status codes are int constants");
static_assert(std::is_same<decltype(KISSM_STRUCT_RESULT), int>::value, "struct ids are int constants");
constexpr int kStatusCodes[] = {KISSM_OK, KISSM_ERR_INVALID_ARGUMENT, KISSM_ERR_INTERNAL};
static_assert(sizeof(kStatusCodes) == 3 * sizeof(int), "constants are constant expressions");
static_assert(sizeof(KISSM_VERSION_STRING) > 1, "KISSM_VERSION_STRING is a string literal");

// Used so that -Wunused does not remove the point of the test; never called.
int kissm_header_cxx_status_class(int32_t status);
int kissm_header_cxx_status_class(int32_t status) {
    switch (status) {
    case KISSM_OK: return 0;
    case KISSM_ERR_CANCELLED: return 1;
    default: return 2;
    }
}
