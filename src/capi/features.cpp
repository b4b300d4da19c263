// SPDX-License-Identifier: MIT
// The features handle: a cloud described once (voxels, descriptors), registered against many.
#include <limits>
#include <memory>
#include <string>

#include "capi/boundary.hpp"
#include "capi/conversions.hpp"
#include "capi/handles.hpp"
#include "core/features_codec.hpp"
#include "core/signature.hpp"

using namespace kissm::detail::capi;
namespace core = kissm::detail;

static_assert(core::kSignatureSize == KISSM_SIGNATURE_SIZE, "kissm.h publishes the signature's size");

extern "C" {

int32_t kissm_features_compute(kissm_matcher *matcher, const kissm_points *cloud, kissm_features **out_features) {
    return guarded("kissm_features_compute", [&] {
        require_non_null(matcher, "matcher");
        require_non_null(out_features, "out_features");
        const core::PointsView v = points_view(cloud, "cloud");
        core::RunContext ctx = matcher->begin_call();
        auto f = std::make_unique<kissm_features>();
        f->data = core::describe_cloud(v, matcher->params, "cloud", ctx);
        *out_features = f.release();
        return ok();
    });
}

void kissm_features_destroy(kissm_features *features) { delete features; }

uint64_t kissm_features_num_points(const kissm_features *f) { return f ? f->data.num_points : 0; }
uint64_t kissm_features_num_voxels(const kissm_features *f) { return f ? f->data.voxels.points.size() : 0; }
uint64_t kissm_features_num_keypoints(const kissm_features *f) { return f ? f->data.descriptors.keypoint.size() : 0; }
uint64_t kissm_features_memory_bytes(const kissm_features *f) {
    return f ? sizeof(*f) + core::features_bytes(f->data) : 0;
}

int32_t kissm_register_features(kissm_matcher *matcher, const kissm_features *source, const kissm_features *target,
                                kissm_result *result) {
    return with_result("kissm_register_features", result, [&] {
        require_non_null(matcher, "matcher");
        require_non_null(source, "source");
        require_non_null(target, "target");
        core::RunContext ctx = matcher->begin_call();
        fill_result(core::register_features(source->data, target->data, matcher->params, ctx), result);
        return ok();
    });
}

int32_t kissm_refine_features(kissm_matcher *matcher, const kissm_features *source, const kissm_features *target,
                              const double initial_transform[16], kissm_result *result) {
    return with_result("kissm_refine_features", result, [&] {
        require_non_null(matcher, "matcher");
        require_non_null(source, "source");
        require_non_null(target, "target");
        Eigen::Matrix3d R;
        Eigen::Vector3d t;
        rigid_transform(initial_transform, "initial_transform", R, t);
        core::RunContext ctx = matcher->begin_call();
        fill_result(core::refine_features(source->data, target->data, R, t, matcher->params, ctx), result);
        return ok();
    });
}

int32_t kissm_features_serialize(const kissm_features *features, void *buffer, uint64_t capacity, uint64_t *out_size) {
    return guarded("kissm_features_serialize", [&] {
        require_non_null(features, "features");
        require_non_null(out_size, "out_size");
        const std::size_t needed = core::encoded_features_size(features->data);
        if (buffer != nullptr && capacity < needed) {
            *out_size = needed; // documented: the caller learns how much to allocate
            core::fail(core::ErrorKind::InvalidArgument, "capacity is " + std::to_string(capacity) +
                                                             " bytes; the features need " + std::to_string(needed));
        }
        if (buffer != nullptr) core::encode_features_to(features->data, static_cast<std::uint8_t *>(buffer));
        *out_size = needed;
        return ok();
    });
}

int32_t kissm_features_deserialize(const void *bytes, uint64_t size, kissm_features **out_features) {
    return guarded("kissm_features_deserialize", [&] {
        require_non_null(bytes, "bytes");
        require_non_null(out_features, "out_features");
        if (size > std::numeric_limits<std::size_t>::max())
            core::fail(core::ErrorKind::Parse, "size " + std::to_string(size) + " does not fit in memory");
        // One thread: the indexes do not depend on the thread count, and callers that load many features
        // parallelise over them.
        core::RunContext ctx(1, nullptr, core::Hooks{});
        auto f = std::make_unique<kissm_features>();
        f->data = core::decode_features(static_cast<const std::uint8_t *>(bytes), static_cast<std::size_t>(size), ctx);
        *out_features = f.release();
        return ok();
    });
}

int32_t kissm_features_signature(const kissm_features *features, double *out_signature) {
    return guarded("kissm_features_signature", [&] {
        require_non_null(features, "features");
        require_non_null(out_signature, "out_signature");
        const core::CloudFeatures &f = features->data;
        core::cloud_signature(f.voxels.points, f.descriptors.keypoint, f.descriptors.values.data(), f.params.voxel_size,
                              out_signature);
        return ok();
    });
}

} // extern "C"
