// SPDX-License-Identifier: MIT
// Status codes and reasons as text, the thread-local last error, versions and the ABI self-check.
#include <cstring>
#include <sstream>
#include <string>

#include "capi/boundary.hpp"

// The core's versioned namespace (core/detail_namespace.hpp) must follow the version of the header.
static_assert(KISSM_DETAIL_VERSION_MAJOR == KISSM_VERSION_MAJOR && KISSM_DETAIL_VERSION_MINOR == KISSM_VERSION_MINOR,
              "core/detail_namespace.hpp and kissm.h disagree on the version");

KISSM_DETAIL_BEGIN
namespace capi {

namespace {
thread_local std::string t_last_error;
} // namespace

int32_t set_error(int32_t status, const char *function, const char *what, const char *detail) noexcept {
    try {
        t_last_error = function;
        t_last_error += ": ";
        t_last_error += what;
        if (detail != nullptr) t_last_error += detail;
    } catch (...) {
        t_last_error.clear(); // clear() never allocates
    }
    return status;
}

int32_t ok() noexcept {
    t_last_error.clear();
    return KISSM_OK;
}

void require_non_null(const void *p, const char *name) {
    if (p == nullptr) fail(ErrorKind::NullArgument, std::string(name) + " is NULL");
}

namespace {
// A size no kissm struct will ever reach: an uninitialised struct_size is refused before any byte beyond the
// known layout is read or written.
constexpr uint32_t kMaxStructSize = 65536;

bool tail_is_zero(const void *p, std::size_t known, std::size_t given) {
    const auto *bytes = static_cast<const unsigned char *>(p);
    for (std::size_t i = known; i < given; ++i)
        if (bytes[i] != 0) return false;
    return true;
}
} // namespace

void check_struct_size(const char *label, uint32_t given, const StructSizes &sizes, const void *given_struct) {
    const std::string head = std::string(label) + " is " + std::to_string(given);
    const std::string set_it = std::string("set it to sizeof(") + sizes.type + ")";
    if (given > kMaxStructSize)
        fail(ErrorKind::StructSize, head + ", larger than any kissm struct (was it initialised? " + set_it + ")");
    if (given < sizes.known) {
        std::string older;
        for (std::size_t i = 0; i < sizes.num_published; ++i) {
            if (given == sizes.published[i]) return; // an older caller's layout
            older += (i ? ", " : "") + std::to_string(sizes.published[i]);
        }
        const std::string earlier = sizes.num_published ? "an earlier release's size (" + older + ") or " : "";
        fail(ErrorKind::StructSize,
             head + "; this kissm takes " + earlier + "at least " + std::to_string(sizes.known) + " (" + set_it + ")");
    }
    if (given_struct != nullptr && given > sizes.known && !tail_is_zero(given_struct, sizes.known, given))
        fail(ErrorKind::StructSize, head + " with non-zero fields beyond the " + std::to_string(sizes.known) +
                                        " bytes this kissm " KISSM_VERSION_STRING " knows; upgrade kissm");
}

void store_struct(void *dst, uint32_t size, const void *full, std::size_t known) noexcept {
    const std::size_t n = size < known ? size : known;
    std::memcpy(dst, full, n);
    if (size > n) std::memset(static_cast<unsigned char *>(dst) + n, 0, size - n);
    std::memcpy(dst, &size, sizeof size); // struct_size is the first field of every growable struct
}

std::string number(double v) {
    std::ostringstream s;
    s.precision(6);
    s << v;
    return s.str();
}

// Every failure kind maps to a distinct, pinned status (status_of has no default, so a missing kind does
// not compile; these check the values).
static_assert(status_of(ErrorKind::InvalidArgument) == -1 && status_of(ErrorKind::Internal) == -14,
              "status codes are pinned forever");

} // namespace capi
KISSM_DETAIL_END

extern "C" {

uint32_t kissm_version_number(void) { return KISSM_VERSION_NUMBER; }
const char *kissm_version_string(void) { return KISSM_VERSION_STRING; }
uint32_t kissm_abi_version(void) { return KISSM_ABI_VERSION; }

const char *kissm_status_string(int32_t status) {
    switch (status) {
    case KISSM_OK: return "success";
    case KISSM_ERR_INVALID_ARGUMENT: return "invalid argument";
    case KISSM_ERR_NULL_ARGUMENT: return "required pointer is NULL";
    case KISSM_ERR_EMPTY_INPUT: return "point cloud is empty";
    case KISSM_ERR_TOO_FEW_POINTS: return "point cloud has too few points";
    case KISSM_ERR_NONFINITE: return "point cloud has a NaN or infinite coordinate";
    case KISSM_ERR_VOXEL_RANGE: return "voxel size too small for the cloud's extent";
    case KISSM_ERR_STRUCT_SIZE: return "unsupported struct size";
    case KISSM_ERR_OUT_OF_MEMORY: return "out of memory";
    case KISSM_ERR_CANCELLED: return "cancelled";
    case KISSM_ERR_FEATURES_MISMATCH: return "features were computed with different settings";
    case KISSM_ERR_IO: return "file could not be read";
    case KISSM_ERR_PARSE: return "file is malformed";
    case KISSM_ERR_UNSUPPORTED_FORMAT: return "file format not supported";
    case KISSM_ERR_INTERNAL: return "internal error";
    default: return "unknown status";
    }
}

const char *kissm_reason_string(int32_t reason) {
    switch (reason) {
    case KISSM_REASON_NONE: return "none";
    case KISSM_REASON_TOO_FEW_VOXELS: return "too few voxels";
    case KISSM_REASON_TOO_FEW_FEATURES: return "too few points with a reliable descriptor";
    case KISSM_REASON_TOO_FEW_CORRESPONDENCES: return "too few correspondences";
    case KISSM_REASON_SOLVER_FAILED: return "no consistent rotation found";
    case KISSM_REASON_TOO_FEW_INLIERS: return "too few inliers";
    case KISSM_REASON_DEGENERATE: return "inliers are collinear or planar";
    case KISSM_REASON_LOW_OVERLAP: return "the refined pose overlaps too little";
    case KISSM_REASON_UNCONSTRAINED: return "the refined pose is not constrained in every direction";
    case KISSM_REASON_UNCERTAIN_ROTATION: return "the inliers leave the rotation uncertain";
    case KISSM_REASON_CLUSTERED_INLIERS: return "the inliers cover too little of the overlap";
    case KISSM_REASON_NOT_CONVERGED: return "refinement did not converge";
    case KISSM_REASON_TILTED: return "the clouds' relative roll or pitch is not zero (rotation_dof = 1)";
    case KISSM_REASON_LOOSE_ALIGNMENT: return "the refined clouds stay apart (a local optimum beside the right pose)";
    case KISSM_REASON_AMBIGUOUS:
        return "a second, distinct pose has nearly as much support (a repetitive or symmetric scene)";
    case KISSM_REASON_LOOSE_AND_WEAK:
        return "the refined clouds stay loosely apart and the pose can slide (a partial match of repeated structure)";
    default: return "unknown reason";
    }
}

const char *kissm_last_error_message(void) { return kissm::detail::capi::t_last_error.c_str(); }

uint32_t kissm_abi_sizeof(int32_t which) {
    switch (which) {
    case KISSM_STRUCT_CONFIG: return sizeof(kissm_config);
    case KISSM_STRUCT_POINTS: return sizeof(kissm_points);
    case KISSM_STRUCT_RESULT: return sizeof(kissm_result);
    case KISSM_STRUCT_ALIGN_OPTIONS: return sizeof(kissm_align_options);
    default: return 0;
    }
}

} // extern "C"
