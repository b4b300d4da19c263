// SPDX-License-Identifier: MIT
// What every exported function shares. Each one is: argument checks, one call into the core, status mapping,
// all inside guarded(), which turns every way a call can fail into a status code and the thread-local
// message. Exported definitions are noexcept, so no C++ exception can unwind into a C, Python or Rust frame.
#pragma once

#include <cstddef>
#include <cstdint>
#include <new>
#include <stdexcept>
#include <string>

#include "core/detail_namespace.hpp"
#include "core/failure.hpp"
#include "kissm.h"

KISSM_DETAIL_BEGIN
namespace capi {

// The status code of each failure kind. No default: a new ErrorKind without a status fails the build (-Wswitch
// is an error).
constexpr int32_t status_of(ErrorKind kind) {
    switch (kind) {
    case ErrorKind::InvalidArgument: return KISSM_ERR_INVALID_ARGUMENT;
    case ErrorKind::NullArgument: return KISSM_ERR_NULL_ARGUMENT;
    case ErrorKind::EmptyInput: return KISSM_ERR_EMPTY_INPUT;
    case ErrorKind::TooFewPoints: return KISSM_ERR_TOO_FEW_POINTS;
    case ErrorKind::NonFinite: return KISSM_ERR_NONFINITE;
    case ErrorKind::VoxelRange: return KISSM_ERR_VOXEL_RANGE;
    case ErrorKind::StructSize: return KISSM_ERR_STRUCT_SIZE;
    case ErrorKind::Cancelled: return KISSM_ERR_CANCELLED;
    case ErrorKind::FeaturesMismatch: return KISSM_ERR_FEATURES_MISMATCH;
    case ErrorKind::Io: return KISSM_ERR_IO;
    case ErrorKind::Parse: return KISSM_ERR_PARSE;
    case ErrorKind::UnsupportedFormat: return KISSM_ERR_UNSUPPORTED_FORMAT;
    case ErrorKind::Internal: return KISSM_ERR_INTERNAL;
    }
    return KISSM_ERR_INTERNAL;
}

// Records "function: what[detail]" as this thread's last error and returns status. Never throws: when memory
// has run out the message may be lost, the status is not.
int32_t set_error(int32_t status, const char *function, const char *what, const char *detail = nullptr) noexcept;
// Clears this thread's last error; returns KISSM_OK.
int32_t ok() noexcept;

// Runs body() (which returns a status) and maps every way it can fail to one.
template <class Body>
int32_t guarded(const char *function, Body &&body) noexcept {
    try {
        return body();
    } catch (const Failure &f) {
        return set_error(status_of(f.kind()), function, f.what());
    } catch (const std::bad_alloc &) {
        return set_error(KISSM_ERR_OUT_OF_MEMORY, function, "out of memory");
    } catch (const std::length_error &) {
        return set_error(KISSM_ERR_OUT_OF_MEMORY, function, "out of memory (allocation too large)");
    } catch (const std::exception &e) {
        return set_error(KISSM_ERR_INTERNAL, function, "internal error: ", e.what());
    } catch (...) {
        return set_error(KISSM_ERR_INTERNAL, function, "internal error (unknown exception)");
    }
}

// Throws Failure(NullArgument, "<name> is NULL") when p is null.
void require_non_null(const void *p, const char *name);

// The sizes of a growable struct: its name, the sizes of its earlier published layouts (an older caller's,
// ascending) and this kissm's.
struct StructSizes {
    const char *type;
    const uint32_t *published;
    std::size_t num_published;
    std::size_t known;
};
// Published layouts: 0.1.0's kissm_config of 152 bytes and kissm_result of 440 (docs/abi-policy.md; the same
// list as tests/abi/test_struct_versioning.c). A release that grows a struct appends its size here.
constexpr uint32_t kPublishedConfigSizes[] = {152};
constexpr uint32_t kPublishedResultSizes[] = {440};
constexpr StructSizes kConfigSizes{"kissm_config", kPublishedConfigSizes, 1, sizeof(kissm_config)};
constexpr StructSizes kResultSizes{"kissm_result", kPublishedResultSizes, 1, sizeof(kissm_result)};

// The one struct_size rule, for every versioned struct (docs/abi-policy.md). `label` names the size as the
// caller wrote it ("config->struct_size", or "struct_size" for an argument). A size above 65536 (an
// uninitialised field) is refused; so is one below this kissm's struct unless it is a published layout's (an
// older caller's, whose missing fields take their defaults in configs and are left unwritten in results). For a struct
// the library reads (`given_struct` non-null), bytes beyond the known size must be zero: they are fields of a newer
// kissm that this one would silently ignore. Structs the library writes take any larger size (the tail is zeroed).
void check_struct_size(const char *label, uint32_t given, const StructSizes &sizes, const void *given_struct = nullptr);

// Writes a full struct of this kissm (`known` bytes) into a caller's struct of `size` bytes: the first
// min(size, known) bytes, then zeros up to `size`; never a byte beyond it. The caller's struct_size stays.
void store_struct(void *dst, uint32_t size, const void *full, std::size_t known) noexcept;

// A double as the messages print it (6 significant digits).
std::string number(double v);

} // namespace capi
KISSM_DETAIL_END
