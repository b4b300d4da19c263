// SPDX-License-Identifier: MIT
// Stage 2a: the one radius search per point (Faster-PFH): every neighbour within the FPFH radius.
// Normals use the subset within the normal radius, so no second search is ever made.
// Paper: Sec. III-C (\label{subsec:fpfh}) and Eq. (A1) of its appendix (\label{eqn:radius_neighbor_search}),
// I = {s : |p_s - p_q| < r_FPFH}: strictly closer, the query itself included. The paper searches a K-d tree;
// a uniform grid here finds the same set.
#pragma once

#include "detail_namespace.hpp"
#include "run_context.hpp"
#include "stage_types.hpp"

KISSM_DETAIL_BEGIN

// Neighbours strictly closer than `radius`, the point itself included. Uses a uniform grid of cell size
// `radius` (the input is voxelised, so cells hold a bounded number of points): 27 cells per query.
// Deterministic order: by cell, then by point index.
Neighborhoods radius_neighbors(const std::vector<Vec3f> &points, float radius, RunContext &ctx);

KISSM_DETAIL_END
