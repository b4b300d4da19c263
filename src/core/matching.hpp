// SPDX-License-Identifier: MIT
// Stage 3: correspondences by nearest neighbours in descriptor space (33-D L2).
// Paper: the mutual matching (reciprocity test) of Sec. III-C (\label{subsec:fpfh}) and the top-N_tau
// selection by descriptor distance ratio of Sec. III-D (\label{subsec:robin}); it numbers no equation for
// them. Deviations: candidates come from a 6-D projection and are re-ranked by exact distance (see
// matching.cpp), the ratio is on squared distances and also rejects above ratio_test, and N_tau defaults to
// 5000 (the paper's Sec. IV-B: 3000; docs/parameters.md) growing with very large clouds (correspondence_cap).
#pragma once

#include <cstddef>

#include "descriptor_index.hpp"
#include "detail_namespace.hpp"
#include "place_gate.hpp"
#include "run_context.hpp"
#include "stage_types.hpp"

KISSM_DETAIL_BEGIN

struct MatchParams {
    double ratio_test;       // on squared distances; >= 1 disables the test
    int max_correspondences; // keep at most this many, most distinctive (lowest ratio) first; 0: automatic
};

// The cap on the matches kept: max_correspondences when it is set, else (0, automatic) one match per
// kAutoKeypointsPerMatch keypoints of the smaller cloud, at least kAutoCapFloor (the paper's and the reference's
// order of magnitude: every pair of ordinary scans keeps it) and at most the setting's own upper limit. Very large
// repetitive clouds need more than a fixed cap: among 300,000 keypoints per cloud the 5,000 most distinctive matches
// hold too few right ones (docs/design/frames.md, "Very large clouds under the default").
constexpr std::size_t kAutoCapFloor = 5000;
constexpr std::size_t kAutoKeypointsPerMatch = 20;
std::size_t correspondence_cap(int max_correspondences, std::size_t smaller_keypoints);

// Mutual nearest neighbours that pass the ratio test, capped. A query's candidates come from the other cloud's
// index (its descriptors projected on their own leading principal components) and are ranked by exact 33-D
// distance. The cloud with fewer keypoints queries the other (ties: source queries target), and only the keypoints
// it reaches search back, so the larger side costs little beyond the log of its size. Against a cloud much larger
// than the queries (a map), the queries search only the place their votes single out (place_gate.hpp). The result is
// sorted by (source, target) keypoint index, so it depends only on the descriptors, never on threads or input order.
std::vector<Correspondence> match_descriptors(const IndexedDescriptors &source, const IndexedDescriptors &target,
                                              const MatchParams &params, RunContext &ctx);

// The matches as points: source[k] and target[k] are the voxel positions of match k's keypoints.
struct MatchedPoints {
    std::vector<Vec3f> source, target;
};
MatchedPoints matched_points(const IndexedDescriptors &source, const IndexedDescriptors &target,
                             const std::vector<Correspondence> &matches);

KISSM_DETAIL_END
