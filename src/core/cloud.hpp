// Data passed between pipeline stages.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace kissm {
// Versioned so that two kissm versions linked statically into one program never share a symbol.
inline namespace v0_1 {
namespace detail {

// A borrowed view of the caller's xyz array (float or double, any byte stride).
struct PointsView {
    const void *data = nullptr;
    std::uint64_t count = 0;
    std::uint64_t stride_bytes = 0; // already resolved: never 0 here
    bool is_double = false;
};

using Vec3f = Eigen::Vector3f;
using Vec3d = Eigen::Vector3d;

// The finite points of one input cloud, still in the caller's frame (double).
struct InputCloud {
    std::vector<Vec3d> points;
    std::uint64_t num_given = 0;
    std::uint64_t num_nonfinite = 0;
    Vec3d min = Vec3d::Zero(), max = Vec3d::Zero();
};

// Voxel centroids in a local frame: p_local = p_input - origin. Single precision is safe after recentring.
struct VoxelCloud {
    Vec3d origin = Vec3d::Zero();
    std::vector<Vec3f> points;
};

// Neighbours within the FPFH radius, CSR: neighbours of i are index[offsets[i] .. offsets[i+1]). The point
// itself is among them. Distances are not stored: users recompute them from the points they read anyway,
// which halves the largest allocation of the pipeline (4 bytes per neighbour instead of 8).
struct Neighborhoods {
    std::vector<std::uint64_t> offsets;
    std::vector<std::uint32_t> index;
};

// Unit normal per point; valid[i] = 0 where no reliable normal exists.
struct Normals {
    std::vector<Vec3f> normal;
    std::vector<std::uint8_t> valid;
};

constexpr int kDescriptorDim = 33;

// A cloud's keypoints (indices into the voxel cloud) and their FPFH descriptors, row-major.
struct Descriptors {
    std::vector<std::uint32_t> keypoint;
    std::vector<float> values; // keypoint.size() * kDescriptorDim
};

struct Correspondence {
    std::uint32_t source; // keypoint index in the source descriptors
    std::uint32_t target;
    float score;          // ratio d0^2 / d1^2 (lower is more distinctive)
};

} // namespace detail
} // namespace v0_1
} // namespace kissm
