// SPDX-License-Identifier: MIT
// kissm_ground_mask: the ground model of KISSM_SUPPRESS_GROUND, per point, for users and tests.
#include <cstring>
#include <vector>

#include "capi/boundary.hpp"
#include "capi/conversions.hpp"
#include "capi/handles.hpp"

using namespace kissm::detail::capi;
namespace core = kissm::detail;

extern "C" {

int32_t kissm_ground_mask(kissm_matcher *matcher, const kissm_points *points, uint8_t *out_mask) {
    return guarded("kissm_ground_mask", [&] {
        require_non_null(matcher, "matcher");
        require_non_null(out_mask, "out_mask");
        const core::PointsView v = points_view(points, "points");
        core::RunContext ctx = matcher->begin_call();
        const std::vector<std::uint8_t> mask = core::ground_mask(v, matcher->params, ctx);
        // Written only once the whole call has succeeded: on error the caller's buffer is unchanged.
        if (!mask.empty()) std::memcpy(out_mask, mask.data(), mask.size());
        return ok();
    });
}

} // extern "C"
