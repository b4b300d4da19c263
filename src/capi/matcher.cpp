// SPDX-License-Identifier: MIT
// The matcher handle: create, inspect, cancel, register two clouds.
#include <cstring>

#include "capi/boundary.hpp"
#include "capi/conversions.hpp"
#include "capi/handles.hpp"

using namespace kissm::detail::capi;
namespace core = kissm::detail;

extern "C" {

int32_t kissm_create(const kissm_config *config, kissm_matcher **out_matcher) {
    return guarded("kissm_create", [&] {
        require_non_null(out_matcher, "out_matcher");
        const kissm_config c = validated_config(config);
        auto *m = new kissm_matcher();
        m->config = c;
        m->params = to_params(c);
        *out_matcher = m;
        return ok();
    });
}

void kissm_destroy(kissm_matcher *matcher) { delete matcher; }

int32_t kissm_get_config(const kissm_matcher *matcher, kissm_config *out_config) {
    return guarded("kissm_get_config", [&] {
        require_non_null(matcher, "matcher");
        require_non_null(out_config, "out_config");
        const uint32_t size = out_config->struct_size;
        check_struct_size("out_config->struct_size", size, kConfigSizes);
        store_struct(out_config, size, &matcher->config, sizeof(kissm_config));
        return ok();
    });
}

void kissm_cancel(kissm_matcher *matcher) {
    if (matcher != nullptr) matcher->cancel_requested.store(1);
}

int32_t kissm_register(kissm_matcher *matcher, const kissm_points *source, const kissm_points *target,
                       kissm_result *result) {
    return with_result("kissm_register", result, [&] {
        require_non_null(matcher, "matcher");
        const core::PointsView sv = points_view(source, "source");
        const core::PointsView tv = points_view(target, "target");
        core::RunContext ctx = matcher->begin_call();
        fill_result(core::register_points(sv, tv, matcher->params, ctx), result);
        return ok();
    });
}

int32_t kissm_refine(kissm_matcher *matcher, const kissm_points *source, const kissm_points *target,
                     const double initial_transform[16], kissm_result *result) {
    return with_result("kissm_refine", result, [&] {
        require_non_null(matcher, "matcher");
        const core::PointsView sv = points_view(source, "source");
        const core::PointsView tv = points_view(target, "target");
        Eigen::Matrix3d R;
        Eigen::Vector3d t;
        rigid_transform(initial_transform, "initial_transform", R, t);
        core::RunContext ctx = matcher->begin_call();
        fill_result(core::refine_points(sv, tv, R, t, matcher->params, ctx), result);
        return ok();
    });
}

} // extern "C"
