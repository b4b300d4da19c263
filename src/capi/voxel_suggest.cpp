// SPDX-License-Identifier: MIT
// kissm_suggest_voxel_size: the automatic voxel size of src/core/voxel_suggest.hpp for the caller's clouds.
#include <string>
#include <vector>

#include "capi/boundary.hpp"
#include "capi/conversions.hpp"
#include "core/failure.hpp"
#include "core/voxel_suggest.hpp"

using namespace kissm::detail::capi;
namespace core = kissm::detail;

namespace {

// More clouds than a set of scans plausibly holds is a caller's mistake (e.g. a point count passed as num_clouds).
constexpr uint64_t kMaxSuggestClouds = 65536;

} // namespace

extern "C" {

int32_t kissm_suggest_voxel_size(const kissm_points *clouds, uint64_t num_clouds, double *out_voxel_size) {
    return guarded("kissm_suggest_voxel_size", [&] {
        require_non_null(clouds, "clouds");
        require_non_null(out_voxel_size, "out_voxel_size");
        if (num_clouds == 0 || num_clouds > kMaxSuggestClouds)
            core::fail(core::ErrorKind::InvalidArgument, "num_clouds is " + std::to_string(num_clouds) +
                                                             "; it must be 1 to " + std::to_string(kMaxSuggestClouds));
        std::vector<std::string> names;
        std::vector<core::PointsView> views;
        for (uint64_t c = 0; c < num_clouds; ++c) {
            names.push_back("clouds[" + std::to_string(c) + "]");
            views.push_back(points_view(&clouds[c], names.back().c_str()));
        }
        std::vector<const char *> name_ptrs;
        for (const std::string &n : names) name_ptrs.push_back(n.c_str());
        *out_voxel_size = core::suggest_voxel_size(views, name_ptrs);
        return ok();
    });
}

} // extern "C"
