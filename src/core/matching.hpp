// SPDX-License-Identifier: MIT
// Stage 3: correspondences by nearest neighbours in descriptor space (33-D L2).
#pragma once

#include "cloud.hpp"
#include "detail_namespace.hpp"
#include "run_context.hpp"

KISSM_DETAIL_BEGIN

struct MatchParams {
    double ratio_test;       // on squared distances; >= 1 disables the test
    int max_correspondences; // keep at most this many, most distinctive (lowest ratio) first
};

// Mutual nearest neighbours that pass the ratio test, capped. Candidates come from a kd-tree over the
// descriptors projected on their 6 leading principal components and are ranked by exact 33-D distance. The cloud with
// fewer keypoints is queried against the other (ties: source queries target); the result is sorted by (source, target)
// keypoint index, so it depends only on the descriptors, never on threads or input order.
std::vector<Correspondence> match_descriptors(const Descriptors &source, const Descriptors &target,
                                              const MatchParams &params, RunContext &ctx);

KISSM_DETAIL_END
