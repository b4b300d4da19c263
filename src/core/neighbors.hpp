// SPDX-License-Identifier: MIT
// Stage 2a: the one radius search per point (Faster-PFH): every neighbour within the FPFH radius.
// Normals use the subset within the normal radius, so no second search is ever made.
#pragma once

#include "cloud.hpp"
#include "detail_namespace.hpp"
#include "run_context.hpp"

KISSM_DETAIL_BEGIN

// Neighbours strictly closer than `radius`, the point itself included. Uses a uniform grid of cell size
// `radius` (the input is voxelised, so cells hold a bounded number of points): 27 cells per query.
// Deterministic order: by cell, then by point index.
Neighborhoods radius_neighbors(const std::vector<Vec3f> &points, float radius, RunContext &ctx);

KISSM_DETAIL_END
