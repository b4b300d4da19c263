// SPDX-License-Identifier: MIT
#include "matching.hpp"

#include <algorithm>
#include <limits>
#include <utility>

KISSM_DETAIL_BEGIN

namespace {

constexpr int kProjDim = DescriptorProjection::kDim;
// The kCandidates nearest in a projected space are re-ranked by exact 33-D distance, which keeps the exact
// search's success rate (docs/parameters.md, "Descriptor matching": instructions and successes per projection
// size).
constexpr int kCandidates = 16;
static_assert(kCandidates <= ProjectedKdTree::kMaxK, "the tree returns at most kMaxK neighbours");

// The k nearest by exact 33-D distance among the projected search's candidates, ties by the lower index
// so that the answer is a function of the data alone.
class NearestK {
public:
    explicit NearestK(int k) : k_(k) {}
    void add(float dist, std::uint32_t index) {
        int i = count_;
        while (i > 0 && (dist < dist_[i - 1] || (dist == dist_[i - 1] && index < index_[i - 1]))) {
            if (i < k_) {
                dist_[i] = dist_[i - 1];
                index_[i] = index_[i - 1];
            }
            --i;
        }
        if (i >= k_) return;
        dist_[i] = dist;
        index_[i] = index;
        if (count_ < k_) ++count_;
    }
    int found() const { return count_; }
    std::uint32_t index(int i) const { return index_[i]; }
    float dist(int i) const { return dist_[i]; }

private:
    static constexpr int kCap = 2;
    int k_, count_ = 0;
    std::uint32_t index_[kCap] = {};
    float dist_[kCap] = {};
};

float exact_dist2(const float *a, const float *b) {
    float s = 0.0f;
    for (int c = 0; c < kDescriptorDim; ++c) {
        const float d = a[c] - b[c];
        s += d * d;
    }
    return s;
}

// The k exact nearest of `query` (33 floats, from the other cloud) in `index`, among the candidates of a
// search in that index's own projection; ties by index.
NearestK nearest(const DescriptorIndex &index, const float *query, int k) {
    float projected[kProjDim];
    index.projection().apply(query, projected);
    std::uint32_t cand[kCandidates], cand_slot[kCandidates];
    float cand_dist[kCandidates];
    const int found = index.tree().nearest(projected, kCandidates, cand, cand_dist, cand_slot);
    NearestK best(k);
    for (int i = 0; i < found; ++i) best.add(exact_dist2(query, index.slot_descriptor(cand_slot[i])), cand[i]);
    return best;
}

} // namespace

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
    constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
    std::vector<std::uint32_t> forward(nq, kNone);
    std::vector<float> ratio(nq, 0.0f);
    const ProjectedKdTree &qtree = Q.index->tree();
    ctx.parallel_for(qtree.num_slots(), 256, [&](std::size_t b, std::size_t e) {
        for (std::size_t s = b; s < e; ++s) {
            const std::uint32_t q = qtree.slot_index(s);
            if (q == ProjectedKdTree::kNoPoint) continue;
            const NearestK r = nearest(*R.index, Q.index->slot_descriptor(s), use_ratio ? 2 : 1);
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
            const NearestK n = nearest(*Q.index, &rvalues[static_cast<std::size_t>(picked[k]) * kDescriptorDim], 1);
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

    const std::size_t cap = static_cast<std::size_t>(params.max_correspondences);
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

KISSM_DETAIL_END
