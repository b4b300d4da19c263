// SPDX-License-Identifier: MIT
// Point files: kissm_read_points and the library-owned cloud it returns.
#include <memory>
#include <string>

#include "capi/boundary.hpp"
#include "capi/handles.hpp"
#include "io/read_points.hpp"

using namespace kissm::detail::capi;
namespace core = kissm::detail;

namespace {
// The reader of each KISSM_FORMAT_* value (the caller has checked the range).
core::FileFormat file_format_of(int32_t format) {
    switch (format) {
    case KISSM_FORMAT_PLY: return core::FileFormat::Ply;
    case KISSM_FORMAT_PCD: return core::FileFormat::Pcd;
    case KISSM_FORMAT_KITTI_BIN: return core::FileFormat::KittiBin;
    case KISSM_FORMAT_NPY: return core::FileFormat::Npy;
    case KISSM_FORMAT_XYZ: return core::FileFormat::Xyz;
    case KISSM_FORMAT_BIN_XYZ: return core::FileFormat::BinXyz;
    case KISSM_FORMAT_LAS: return core::FileFormat::Las;
    default: return core::FileFormat::Auto;
    }
}
} // namespace

extern "C" {

int32_t kissm_read_points(const char *path, int32_t format, kissm_cloud **out_cloud) {
    return guarded("kissm_read_points", [&] {
        require_non_null(path, "path");
        require_non_null(out_cloud, "out_cloud");
        if (format < KISSM_FORMAT_AUTO || format > KISSM_FORMAT_LAS)
            core::fail(core::ErrorKind::InvalidArgument,
                       "format is " + std::to_string(format) + "; use a KISSM_FORMAT_* value");
        auto c = std::make_unique<kissm_cloud>();
        c->xyz = core::read_points_file(path, file_format_of(format), &c->withheld);
        *out_cloud = c.release();
        return ok();
    });
}

void kissm_cloud_destroy(kissm_cloud *cloud) { delete cloud; }
uint64_t kissm_cloud_count(const kissm_cloud *cloud) { return cloud ? cloud->xyz.size() / 3 : 0; }
uint64_t kissm_cloud_num_withheld(const kissm_cloud *cloud) { return cloud ? cloud->withheld : 0; }
const double *kissm_cloud_data(const kissm_cloud *cloud) {
    return (cloud && !cloud->xyz.empty()) ? cloud->xyz.data() : nullptr;
}

int32_t kissm_cloud_points(const kissm_cloud *cloud, kissm_points *out_points) {
    return guarded("kissm_cloud_points", [&] {
        require_non_null(cloud, "cloud");
        require_non_null(out_points, "out_points");
        out_points->data = cloud->xyz.empty() ? nullptr : cloud->xyz.data();
        out_points->count = cloud->xyz.size() / 3;
        out_points->stride_bytes = 3 * sizeof(double);
        out_points->scalar_type = KISSM_SCALAR_FLOAT64;
        out_points->reserved = 0;
        return ok();
    });
}

} // extern "C"
