// SPDX-License-Identifier: MIT
#include "matching.hpp"

#include "setting_limits.hpp"

#include <algorithm>
#include <limits>
#include <utility>

KISSM_DETAIL_BEGIN

std::size_t correspondence_cap(int max_correspondences, std::size_t smaller_keypoints) {
    if (max_correspondences > 0) return static_cast<std::size_t>(max_correspondences);
    const auto ceiling = static_cast<std::size_t>(limits::max_correspondences.hi);
    return std::min(ceiling, std::max(kAutoCapFloor, smaller_keypoints / kAutoKeypointsPerMatch));
}

std::vector<Correspondence> match_descriptors(const IndexedDescriptors &source, const IndexedDescriptors &target,
                                              const MatchParams &params, RunContext &ctx) {
    std::vector<Correspondence> out;
    if (source.descriptors->keypoint.empty() || target.descriptors->keypoint.empty()) return out;
    const bool source_queries = source.descriptors->keypoint.size() <= target.descriptors->keypoint.size();
    const IndexedDescriptors &Q = source_queries ? source : target;
    const IndexedDescriptors &R = source_queries ? target : source;
    const bool use_ratio = params.ratio_test < 1.0;

    // Forward: every query against the reference's index. Every search is independent and writes only its
    // own query's entries, so the order (the query's tree slots: consecutive searches then start in
    // neighbouring leaves of the other tree, which stay cached) changes nothing in the results. A query whose
    // projection is not finite never finds a neighbour: its distances are never finite.
    const std::size_t nq = Q.descriptors->keypoint.size();
    // Against a much larger cloud (a map), the part of it the queries' own votes single out, when they do.
    const PlaceRegion region = PlaceRegion::find(Q, R, ctx);
    constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
    std::vector<std::uint32_t> forward(nq, kNone);
    std::vector<float> ratio(nq, 0.0f);
    const ProjectedKdTree &qtree = Q.index->tree();
    ctx.parallel_for(qtree.num_slots(), 256, [&](std::size_t b, std::size_t e) {
        for (std::size_t s = b; s < e; ++s) {
            const std::uint32_t q = qtree.slot_index(s);
            if (q == ProjectedKdTree::kNoPoint) continue;
            const float *query = Q.index->slot_descriptor(s);
            const int k = use_ratio ? 2 : 1;
            const RankedNeighbours r = region.empty() ? R.index->nearest(query, k) : region.nearest(query, k);
            if (r.found() < 1) continue;
            if (use_ratio) {
                if (r.found() < 2 || !(r.dist(1) > 0.0f)) continue; // ambiguous: two identical candidates
                const float score = r.dist(0) / r.dist(1);
                if (!(static_cast<double>(score) <= params.ratio_test)) continue;
                ratio[q] = score;
            }
            forward[q] = r.index(0);
        }
    });

    // Backward searches only from the reference keypoints some query reached, so the reference side costs
    // in proportion to the queries however large it is (a map described once and matched by many scans).
    std::vector<std::uint32_t> picked;
    picked.reserve(nq);
    for (std::size_t q = 0; q < nq; ++q)
        if (forward[q] != kNone) picked.push_back(forward[q]);
    std::sort(picked.begin(), picked.end());
    picked.erase(std::unique(picked.begin(), picked.end()), picked.end());
    std::vector<std::uint32_t> backward(picked.size(), kNone);
    const float *rvalues = R.descriptors->values.data();
    ctx.parallel_for(picked.size(), 256, [&](std::size_t b, std::size_t e) {
        for (std::size_t k = b; k < e; ++k) {
            const RankedNeighbours n =
                Q.index->nearest(&rvalues[static_cast<std::size_t>(picked[k]) * kDescriptorDim], 1);
            if (n.found() >= 1) backward[k] = n.index(0);
        }
    });

    for (std::size_t q = 0; q < nq; ++q) {
        if (forward[q] == kNone) continue;
        const std::size_t k =
            static_cast<std::size_t>(std::lower_bound(picked.begin(), picked.end(), forward[q]) - picked.begin());
        if (backward[k] != q) continue;
        Correspondence c;
        c.source = source_queries ? static_cast<std::uint32_t>(q) : forward[q];
        c.target = source_queries ? forward[q] : static_cast<std::uint32_t>(q);
        c.score = ratio[q];
        out.push_back(c);
    }

    const std::size_t cap = correspondence_cap(params.max_correspondences, nq);
    if (out.size() > cap) {
        std::stable_sort(out.begin(), out.end(), [](const Correspondence &a, const Correspondence &b) {
            if (a.score != b.score) return a.score < b.score;
            return a.source != b.source ? a.source < b.source : a.target < b.target;
        });
        out.resize(cap);
    }
    std::sort(out.begin(), out.end(), [](const Correspondence &a, const Correspondence &b) {
        return a.source != b.source ? a.source < b.source : a.target < b.target;
    });
    return out;
}

MatchedPoints matched_points(const IndexedDescriptors &source, const IndexedDescriptors &target,
                             const std::vector<Correspondence> &matches) {
    MatchedPoints out;
    out.source.resize(matches.size());
    out.target.resize(matches.size());
    for (std::size_t k = 0; k < matches.size(); ++k) {
        out.source[k] = (*source.points)[source.descriptors->keypoint[matches[k].source]];
        out.target[k] = (*target.points)[target.descriptors->keypoint[matches[k].target]];
    }
    return out;
}

KISSM_DETAIL_END
