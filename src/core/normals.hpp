// SPDX-License-Identifier: MIT
// Stage 2b: normals and linearity from the neighbours within the normal radius (a subset of the one
// radius search), then the keypoint filter of Faster-PFH.
// Paper: Sec. III-C (\label{subsec:fpfh}) and Algorithm 1 of its appendix (\label{alg:faster_pfh}).
// estimate_normals is its step 1 (lines \label{line:skip}, \label{line:cond_num}, \label{line:cond_lin}):
// at least tau_num neighbours within r_FPFH and within r_normal, linearity p_lin = (l1 - l2) / l1 from the
// PCA's eigenvalues l1 >= l2 >= l3. Deviation: a point is kept when p_lin <= tau_lin (the paper: p_lin <
// tau_lin), which differs only at exact equality. select_keypoints is its step 2 (\label{line:second_condition_start}
// to \label{line:second_condition_end}): at least tau_num neighbours with a normal, the point itself among
// them as in the paper's I. The paper numbers no equation for either.
#pragma once

#include "detail_namespace.hpp"
#include "run_context.hpp"
#include "stage_types.hpp"

KISSM_DETAIL_BEGIN

// How a normal's sign is chosen. TowardViewpoint: n . (viewpoint - p) >= 0. AwayFromNeighbours: n . (c - p) <= 0,
// c the centroid of all of p's neighbours (the FPFH radius, the point itself included): outward on convex
// shapes, a rule of the local shape alone, so it does not depend on the cloud's frame (when c - p is
// perpendicular to n to the last bit the eigenvector's sign stays); where the neighbours' mean offset along n is
// below NormalParams::open_sign_offset (flat or evenly curved surfaces, where the rule reads noise) the sign is
// left open (Normals::open_sign). Unoriented: the eigenvector's sign as the
// solver gives it, for sign-free descriptors.
enum class NormalOrientation { TowardViewpoint, AwayFromNeighbours, Unoriented };

struct NormalParams {
    float normal_radius;
    int min_neighbors;    // tau_num
    double max_linearity; // tau_lin
    Vec3f viewpoint;      // in the cloud's local frame
    NormalOrientation orientation = NormalOrientation::TowardViewpoint;
    // AwayFromNeighbours only: |n . (c - p)| below this leaves the sign open; 0 = every sign decided.
    float open_sign_offset = 0.0f;
};

// A point gets a normal when it has at least tau_num neighbours within the FPFH radius and within the normal
// radius (itself included) and its linearity (l1 - l2) / l1 is at most tau_lin. Normals are oriented as
// params.orientation says.
Normals estimate_normals(const std::vector<Vec3f> &points, const Neighborhoods &nb, const NormalParams &params,
                         RunContext &ctx);

// The normals of estimate_normals and, in the same pass over the neighbours, the normals refinement aligns
// planes with (stage 6): from the neighbours within plane_radius (<= the normal radius, so a subset of the
// same neighbours), at least max(kPlaneMinNeighbors, tau_num) of them, linearity at most tau_lin; unoriented
// (refinement reads n n^T only). The first are bitwise those of estimate_normals.
constexpr int kPlaneMinNeighbors = 5;
struct NormalSets {
    Normals normals;
    Normals planes;
};
NormalSets estimate_normal_sets(const std::vector<Vec3f> &points, const Neighborhoods &nb, const NormalParams &params,
                                float plane_radius, RunContext &ctx);

// The planes of estimate_normal_sets alone (plane_radius > 0), bitwise the same from the same neighbours: for
// features described without refinement, which leave them out (the default path never pays for them).
Normals estimate_planes(const std::vector<Vec3f> &points, const Neighborhoods &nb, const NormalParams &params,
                        float plane_radius, RunContext &ctx);

// Keypoints: points with a normal and at least tau_num neighbours (itself included) that have a normal.
// Ascending indices.
std::vector<std::uint32_t> select_keypoints(const Neighborhoods &nb, const Normals &normals, int min_neighbors);

// Smallest-eigenvalue eigenvector of a symmetric 3x3 covariance and the eigenvalues in descending order
// (closed form; no iterative or dynamic-size solver). Exposed for tests.
void symmetric_eigen3(const Eigen::Matrix3d &cov, Eigen::Vector3d &eigenvalues_desc, Eigen::Vector3d &smallest_vec);

KISSM_DETAIL_END
