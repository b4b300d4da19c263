// SPDX-License-Identifier: MIT
// The data the pipeline stages pass to each other: the caller's points, the input, the voxels, the
// neighbourhoods, normals, descriptors and correspondences.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "detail_namespace.hpp"
#include "uninitialized.hpp"

KISSM_DETAIL_BEGIN

// A borrowed view of the caller's xyz array (float or double, any byte stride).
struct PointsView {
    const void *data = nullptr;
    std::uint64_t count = 0;
    std::uint64_t stride_bytes = 0; // already resolved: never 0 here
    bool is_double = false;
};

using Vec3f = Eigen::Vector3f;
using Vec3d = Eigen::Vector3d;

// One input cloud, still in the caller's array and frame: what the voxel stage must know before it reads
// the points. Nothing is copied: a copy in double cost 24 bytes per point and, being fresh memory every
// call, its page faults (docs/design/performance.md, "Input scan").
struct InputCloud {
    PointsView view;
    bool skip_nonfinite = false; // some points are not finite and the policy drops them: readers skip them
    std::uint64_t num_given = 0;
    std::uint64_t num_nonfinite = 0;
    Vec3d min = Vec3d::Zero(), max = Vec3d::Zero(); // of the finite points

    std::uint64_t num_finite() const { return num_given - num_nonfinite; }
    // Calls f(i, point i converted to double) for the points [begin, end) of the caller's array, finite or
    // not. The scalar type is chosen once per call, not per point (a test per point slowed voxelisation
    // down; docs/design/performance.md, "Input scan"); strides need not be aligned.
    template <class F>
    void for_each_point(std::size_t begin, std::size_t end, F &&f) const {
        if (view.is_double)
            for_each_point_as<double>(begin, end, f);
        else
            for_each_point_as<float>(begin, end, f);
    }
    static bool finite(const Vec3d &v) { return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z()); }

private:
    template <class T, class F>
    void for_each_point_as(std::size_t begin, std::size_t end, F &f) const {
        const unsigned char *base = static_cast<const unsigned char *>(view.data);
        const std::size_t stride = static_cast<std::size_t>(view.stride_bytes);
        for (std::size_t i = begin; i < end; ++i) {
            T xyz[3];
            std::memcpy(xyz, base + i * stride, sizeof xyz);
            f(i, Vec3d(static_cast<double>(xyz[0]), static_cast<double>(xyz[1]), static_cast<double>(xyz[2])));
        }
    }
};

// Voxel centroids in a local frame: p_local = p_input - origin. Single precision is safe after recentring.
struct VoxelCloud {
    Vec3d origin = Vec3d::Zero();
    std::vector<Vec3f> points;
};

// Neighbours within the FPFH radius: the neighbours of i are row(i)[0 .. count(i)), the point itself among
// them. Entry t of row i has the number offsets[i] + t, by which stages keep per-entry data. Distances are
// not stored: users recompute them from the points they read anyway, which halves the largest structure of
// the pipeline (4 bytes per neighbour instead of 8, about 100 neighbours per voxel). Rows are kept in
// blocks of kBlockRows consecutive rows, each allocated at its exact size when the search finishes it:
// one flat array had to be filled by a second copy of everything, with its page faults and twice the
// memory while copying (docs/design/performance.md, "What the profiles showed").
struct Neighborhoods {
    static constexpr std::size_t kBlockRows = 1024;
    std::vector<std::uint64_t> offsets;
    std::vector<std::vector<std::uint32_t>> blocks;

    std::size_t count(std::size_t i) const { return static_cast<std::size_t>(offsets[i + 1] - offsets[i]); }
    const std::uint32_t *row(std::size_t i) const {
        const std::size_t b = i / kBlockRows;
        return blocks[b].data() + (offsets[i] - offsets[b * kBlockRows]);
    }
    std::uint64_t num_entries() const { return offsets.empty() ? 0 : offsets.back(); }
};

// Unit normal per point; valid[i] = 0 where no reliable normal exists.
struct Normals {
    std::vector<Vec3f> normal;
    std::vector<std::uint8_t> valid;
    // 1 where the orientation rule left the sign open (NormalParams::open_sign_offset): the pair features then
    // ignore that normal's sign. Empty when every sign is decided. Only the descriptors read it.
    std::vector<std::uint8_t> open_sign;
};

constexpr int kDescriptorDim = 33;

// A cloud's keypoints (indices into the voxel cloud) and their FPFH descriptors, row-major.
struct Descriptors {
    std::vector<std::uint32_t> keypoint;
    UninitVector<float> values; // keypoint.size() * kDescriptorDim
};

struct Correspondence {
    std::uint32_t source; // keypoint index in the source descriptors
    std::uint32_t target;
    float score; // ratio d0^2 / d1^2 (lower is more distinctive)
};

KISSM_DETAIL_END
