#include "matching.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <utility>

#include "kdtree.hpp"
#include "radix_sort.hpp"

namespace kissm {
// Versioned so that two kissm versions linked statically into one program never share a symbol.
inline namespace v0_1 {
namespace detail {

namespace {

// Search space: descriptors projected on their kProjDim leading principal components. A kd-tree in 33-D
// backtracks into near brute force (full KITTI scan pair: 13.3 G instructions of matching); in 8-D it
// takes 1.5 G and in 6-D 0.8 G (callgrind). The kCandidates nearest found there are re-ranked by exact
// 33-D distances; success on ../shared/data is the same as the exact search's (docs/parameters.md).
constexpr int kProjDim = ProjectedKdTree::kDim;
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

using DescVec = Eigen::Matrix<double, kDescriptorDim, 1>;
using ProjBasis = Eigen::Matrix<float, kProjDim, kDescriptorDim>;

struct Projection {
    Eigen::Matrix<float, kDescriptorDim, 1> mean;
    ProjBasis basis; // rows: principal axes, largest variance first
};

// Principal axes of both clouds' descriptors, from a fixed subsample (cost independent of cloud size; a
// function of the data alone, so the same for every thread count).
Projection principal_axes(const Descriptors &a, const Descriptors &b, RunContext &ctx) {
    constexpr std::size_t kSample = 4096;
    std::vector<const float *> rows;
    for (const Descriptors *d : {&a, &b}) {
        const std::size_t n = d->keypoint.size();
        const std::size_t step = std::max<std::size_t>(1, n / kSample);
        for (std::size_t i = 0; i < n; i += step) rows.push_back(&d->values[i * kDescriptorDim]);
    }
    DescVec mean = DescVec::Zero();
    for (const float *r : rows)
        for (int c = 0; c < kDescriptorDim; ++c) mean[c] += static_cast<double>(r[c]);
    mean /= static_cast<double>(rows.size());
    // Only the lower triangle: the eigen solver reads nothing else. Every element is still the sum over
    // rows, in row order, of x_j * x_i, so the axes are bit for bit those of per-row outer products. The
    // rows go by chunks through 4 x 4 tiles of accumulators that the compiler keeps in SSE2 registers;
    // threads share out tiles (disjoint elements, each summed whole by one thread), never rows.
    constexpr int kPad = 36; // columns (and rows) padded with zeros to whole tiles
    constexpr std::size_t kChunk = 64;
    std::vector<std::pair<int, int>> tiles;
    for (int i0 = 0; i0 < kDescriptorDim; i0 += 4)
        for (int j0 = 0; j0 <= i0; j0 += 4) tiles.emplace_back(i0, j0);
    std::vector<double> tri(kPad * kPad, 0.0);
    ctx.parallel_for(tiles.size(), (tiles.size() + 1) / 2, [&](std::size_t t0, std::size_t t1) {
        std::vector<double> xs(kChunk * kPad, 0.0);
        for (std::size_t r0 = 0; r0 < rows.size(); r0 += kChunk) {
            const std::size_t nr = std::min(kChunk, rows.size() - r0);
            for (std::size_t r = 0; r < nr; ++r)
                for (int c = 0; c < kDescriptorDim; ++c) xs[r * kPad + c] = static_cast<double>(rows[r0 + r][c]) - mean[c];
            for (std::size_t t = t0; t < t1; ++t) {
                const int i0 = tiles[t].first, j0 = tiles[t].second;
                double acc[4][4];
                for (int i = 0; i < 4; ++i)
                    for (int j = 0; j < 4; ++j) acc[i][j] = tri[(i0 + i) * kPad + j0 + j];
                for (std::size_t r = 0; r < nr; ++r) {
                    const double *xr = &xs[r * kPad];
                    for (int i = 0; i < 4; ++i)
                        for (int j = 0; j < 4; ++j) acc[i][j] += xr[j0 + j] * xr[i0 + i];
                }
                for (int i = 0; i < 4; ++i)
                    for (int j = 0; j < 4; ++j) tri[(i0 + i) * kPad + j0 + j] = acc[i][j];
            }
        }
    });
    Eigen::Matrix<double, kDescriptorDim, kDescriptorDim> cov = Eigen::Matrix<double, kDescriptorDim, kDescriptorDim>::Zero();
    for (int i = 0; i < kDescriptorDim; ++i)
        for (int j = 0; j <= i; ++j) cov(i, j) = tri[i * kPad + j];
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, kDescriptorDim, kDescriptorDim>> es(cov);
    Projection p;
    p.mean = mean.cast<float>();
    for (int k = 0; k < kProjDim; ++k) p.basis.row(k) = es.eigenvectors().col(kDescriptorDim - 1 - k).transpose().cast<float>();
    return p;
}

std::vector<float> project(const Descriptors &d, const Projection &p, RunContext &ctx) {
    const std::size_t n = d.keypoint.size();
    std::vector<float> out(n * kProjDim);
    ctx.parallel_for(n, 1024, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
            const Eigen::Map<const Eigen::Matrix<float, kDescriptorDim, 1>> x(&d.values[i * kDescriptorDim]);
            const Eigen::Matrix<float, kProjDim, 1> y = p.basis * (x - p.mean);
            for (int c = 0; c < kProjDim; ++c) out[i * kProjDim + c] = y[c];
        }
    });
    return out;
}

// The two exact nearest among the projected search's candidates, ties by index.
NearestK nearest(const ProjectedKdTree &tree, const std::vector<float> &proj_q, std::size_t q, const float *query,
                 const Descriptors &ref, int k) {
    std::uint32_t cand[kCandidates];
    float cand_dist[kCandidates];
    const int found = tree.nearest(&proj_q[q * kProjDim], kCandidates, cand, cand_dist);
    NearestK best(k);
    for (int i = 0; i < found; ++i)
        best.add(exact_dist2(query, &ref.values[static_cast<std::size_t>(cand[i]) * kDescriptorDim]), cand[i]);
    return best;
}

// Visiting order for a batch of searches: by a Morton code of the first three projected coordinates, so
// that consecutive searches land in the same part of the other cloud's tree and find it in cache. Only the
// order changes; every search is independent, so the results are the same.
// point(k) gives the projection of search k (k < n); the result lists the positions 0..n-1 in visiting order.
template <class Point>
std::vector<std::uint32_t> search_order(std::size_t n, const Point &point) {
    float lo[3], hi[3];
    for (int d = 0; d < 3; ++d) lo[d] = std::numeric_limits<float>::max(), hi[d] = -std::numeric_limits<float>::max();
    for (std::size_t k = 0; k < n; ++k)
        for (int d = 0; d < 3; ++d) {
            const float v = point(k)[d];
            if (std::isfinite(v)) lo[d] = std::min(lo[d], v), hi[d] = std::max(hi[d], v);
        }
    std::vector<KeyIndex> keyed(n);
    for (std::size_t k = 0; k < n; ++k) {
        std::uint64_t code = 0;
        for (int d = 0; d < 3; ++d) {
            const float v = point(k)[d];
            const float span = hi[d] > lo[d] ? hi[d] - lo[d] : 1.0f;
            const float t = std::isfinite(v) ? (v - lo[d]) / span : 0.0f;
            const std::uint64_t cell = static_cast<std::uint64_t>(std::min(1023.0f, std::max(0.0f, t * 1024.0f)));
            for (int b = 0; b < 10; ++b) code |= ((cell >> b) & 1u) << (3 * b + d);
        }
        keyed[k] = {code, static_cast<std::uint32_t>(k)};
    }
    radix_sort_by_key(keyed);
    std::vector<std::uint32_t> order(n);
    for (std::size_t k = 0; k < n; ++k) order[k] = keyed[k].index;
    return order;
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

    const Projection pca = principal_axes(Q, R, ctx);
    const std::vector<float> qproj = project(Q, pca, ctx), rproj = project(R, pca, ctx);
    // The two trees are independent: built side by side when there are threads.
    std::unique_ptr<ProjectedKdTree> trees[2];
    ctx.parallel_for(2, 1, [&](std::size_t b, std::size_t e) {
        for (std::size_t t = b; t < e; ++t)
            trees[t] = t == 0 ? std::make_unique<ProjectedKdTree>(rproj.data(), R.keypoint.size())
                              : std::make_unique<ProjectedKdTree>(qproj.data(), Q.keypoint.size());
    });
    const ProjectedKdTree &rtree = *trees[0], &qtree = *trees[1];

    const std::size_t nq = Q.keypoint.size();
    constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
    std::vector<std::uint32_t> forward(nq, kNone);
    std::vector<float> ratio(nq, 0.0f);
    const std::vector<std::uint32_t> query_order = search_order(nq, [&](std::size_t q) { return &qproj[q * kProjDim]; });
    ctx.parallel_for(nq, 256, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
            const std::size_t q = query_order[i];
            const NearestK r = nearest(rtree, qproj, q, &Q.values[q * kDescriptorDim], R, use_ratio ? 2 : 1);
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

    std::vector<std::uint32_t> picked;
    picked.reserve(nq);
    for (std::size_t q = 0; q < nq; ++q)
        if (forward[q] != kNone) picked.push_back(forward[q]);
    std::sort(picked.begin(), picked.end());
    picked.erase(std::unique(picked.begin(), picked.end()), picked.end());
    std::vector<std::uint32_t> backward(picked.size(), kNone);
    const std::vector<std::uint32_t> picked_proj_order = search_order(
        picked.size(), [&](std::size_t k) { return &rproj[static_cast<std::size_t>(picked[k]) * kProjDim]; });
    ctx.parallel_for(picked.size(), 256, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
            const std::size_t k = picked_proj_order[i];
            const std::size_t r = picked[k];
            const NearestK n = nearest(qtree, rproj, r, &R.values[r * kDescriptorDim], Q, 1);
            if (n.found() >= 1) backward[k] = n.index(0);
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
} // namespace v0_1
} // namespace kissm
