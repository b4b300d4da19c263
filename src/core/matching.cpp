#include "matching.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include <nanoflann.hpp>

namespace kissm {
namespace detail {

namespace {

// nanoflann dataset adaptor over a row-major descriptor array.
struct DescriptorSet {
    const Descriptors *d;
    std::size_t kdtree_get_point_count() const { return d->keypoint.size(); }
    float kdtree_get_pt(std::size_t i, std::size_t dim) const { return d->values[i * kDescriptorDim + dim]; }
    template <class BBox>
    bool kdtree_get_bbox(BBox &) const {
        return false;
    }
};

using Metric = nanoflann::L2_Simple_Adaptor<float, DescriptorSet, float, std::uint32_t>;
using Tree = nanoflann::KDTreeSingleIndexAdaptor<Metric, DescriptorSet, kDescriptorDim, std::uint32_t>;

// The k (<= 2) nearest descriptors, ties broken by the lower index so that the answer is a function of the
// data alone. nanoflann only offers a candidate when it is strictly closer than worstDist(), hence the
// nextafter: equal distances still reach addPoint().
class Nearest2 {
public:
    explicit Nearest2(int k) : k_(k) {}
    bool addPoint(float dist, std::uint32_t index) {
        int i = count_;
        while (i > 0 && (dist < dist_[i - 1] || (dist == dist_[i - 1] && index < index_[i - 1]))) {
            if (i < k_) {
                dist_[i] = dist_[i - 1];
                index_[i] = index_[i - 1];
            }
            --i;
        }
        if (i < k_) {
            dist_[i] = dist;
            index_[i] = index;
            if (count_ < k_) ++count_;
        }
        return true;
    }
    float worstDist() const {
        return count_ < k_ ? std::numeric_limits<float>::max()
                           : std::nextafter(dist_[k_ - 1], std::numeric_limits<float>::max());
    }
    bool full() const { return count_ == k_; }
    int found() const { return count_; }
    std::uint32_t index(int i) const { return index_[i]; }
    float dist2(int i) const { return dist_[i]; }

private:
    int k_, count_ = 0;
    std::uint32_t index_[2] = {0, 0};
    float dist_[2] = {0.0f, 0.0f};
};

Nearest2 knn(const Tree &tree, const float *query, int k) {
    Nearest2 r(k);
    tree.findNeighbors(r, query, nanoflann::SearchParams(0, 0.0f, false));
    return r;
}

} // namespace

std::vector<Correspondence> match_descriptors(const Descriptors &source, const Descriptors &target,
                                              const MatchParams &params, RunContext &ctx) {
    std::vector<Correspondence> out;
    if (source.keypoint.empty() || target.keypoint.empty()) return out;
    const bool source_queries = source.keypoint.size() <= target.keypoint.size();
    const Descriptors &Q = source_queries ? source : target;
    const Descriptors &R = source_queries ? target : source;
    const bool use_ratio = params.ratio_test < 1.0;

    DescriptorSet qset{&Q}, rset{&R};
    const nanoflann::KDTreeSingleIndexAdaptorParams tree_params(12);
    Tree rtree(kDescriptorDim, rset, tree_params);
    Tree qtree(kDescriptorDim, qset, tree_params);

    // Forward: each query's nearest (and second nearest) reference descriptor.
    const std::size_t nq = Q.keypoint.size();
    constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
    std::vector<std::uint32_t> forward(nq, kNone);
    std::vector<float> ratio(nq, 0.0f);
    ctx.parallel_for(nq, 256, [&](std::size_t b, std::size_t e) {
        for (std::size_t q = b; q < e; ++q) {
            const Nearest2 r = knn(rtree, &Q.values[q * kDescriptorDim], use_ratio ? 2 : 1);
            if (r.found() < 1) continue;
            if (use_ratio) {
                if (r.found() < 2 || !(r.dist2(1) > 0.0f)) continue; // ambiguous: two identical candidates
                const float score = r.dist2(0) / r.dist2(1);
                if (!(static_cast<double>(score) <= params.ratio_test)) continue;
                ratio[q] = score;
            }
            forward[q] = r.index(0);
        }
    });

    // Backward, only for reference descriptors that some query picked.
    std::vector<std::uint32_t> picked;
    picked.reserve(nq);
    for (std::size_t q = 0; q < nq; ++q)
        if (forward[q] != kNone) picked.push_back(forward[q]);
    std::sort(picked.begin(), picked.end());
    picked.erase(std::unique(picked.begin(), picked.end()), picked.end());
    std::vector<std::uint32_t> backward(picked.size(), kNone);
    ctx.parallel_for(picked.size(), 256, [&](std::size_t b, std::size_t e) {
        for (std::size_t k = b; k < e; ++k) {
            const Nearest2 r = knn(qtree, &R.values[static_cast<std::size_t>(picked[k]) * kDescriptorDim], 1);
            if (r.found() >= 1) backward[k] = r.index(0);
        }
    });

    for (std::size_t q = 0; q < nq; ++q) {
        if (forward[q] == kNone) continue;
        const std::size_t k = static_cast<std::size_t>(std::lower_bound(picked.begin(), picked.end(), forward[q]) - picked.begin());
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

} // namespace detail
} // namespace kissm
