// SPDX-License-Identifier: MIT
// kissm_points: the caller's coordinates as a checked, zero-copy view.
#include <string>

#include "capi/boundary.hpp"
#include "capi/conversions.hpp"

KISSM_DETAIL_BEGIN
namespace capi {

PointsView points_view(const kissm_points *p, const char *name) {
    require_non_null(p, name);
    const std::string n(name);
    if (p->scalar_type != KISSM_SCALAR_FLOAT32 && p->scalar_type != KISSM_SCALAR_FLOAT64)
        fail(ErrorKind::InvalidArgument, n + "->scalar_type is " + std::to_string(p->scalar_type) +
                                             "; use KISSM_SCALAR_FLOAT32 or KISSM_SCALAR_FLOAT64");
    if (p->reserved != 0) fail(ErrorKind::InvalidArgument, n + "->reserved must be 0");
    if (p->count == 0) fail(ErrorKind::EmptyInput, n + " has no points (count is 0)");
    if (p->data == nullptr) fail(ErrorKind::NullArgument, n + "->data is NULL");
    if (p->count < KISSM_MIN_POINTS)
        fail(ErrorKind::TooFewPoints, n + " has " + std::to_string(p->count) + " points; at least " +
                                          std::to_string(KISSM_MIN_POINTS) + " are needed");
    if (p->count > 0xFFFFFFFFull)
        fail(ErrorKind::InvalidArgument,
             n + "->count is " + std::to_string(p->count) + "; at most 4294967295 points per cloud are supported");
    const uint64_t scalar = p->scalar_type == KISSM_SCALAR_FLOAT64 ? 8 : 4;
    const uint64_t stride = p->stride_bytes == 0 ? 3 * scalar : p->stride_bytes;
    if (stride < 3 * scalar)
        fail(ErrorKind::InvalidArgument, n + "->stride_bytes is " + std::to_string(p->stride_bytes) +
                                             "; it must be 0 (packed) or at least " + std::to_string(3 * scalar));
    if (stride > (UINT64_MAX / p->count)) fail(ErrorKind::InvalidArgument, n + ": count * stride_bytes overflows");
    PointsView v;
    v.data = p->data;
    v.count = p->count;
    v.stride_bytes = stride;
    v.is_double = p->scalar_type == KISSM_SCALAR_FLOAT64;
    return v;
}

} // namespace capi
KISSM_DETAIL_END
