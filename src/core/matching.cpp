// SPDX-License-Identifier: MIT
#include "matching.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <utility>

#include "kdtree.hpp"

KISSM_DETAIL_BEGIN

namespace {

// Search space: descriptors projected on their kProjDim leading principal components. A kd-tree in 33-D
// backtracks into near brute force; in a few dimensions it does not. The kCandidates nearest found there are
// re-ranked by exact 33-D distances, which keeps the exact search's success rate (docs/parameters.md,
// "Descriptor matching": instructions and successes per projection size).
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
                for (int c = 0; c < kDescriptorDim; ++c)
                    xs[r * kPad + c] = static_cast<double>(rows[r0 + r][c]) - mean[c];
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
    Eigen::Matrix<double, kDescriptorDim, kDescriptorDim> cov =
        Eigen::Matrix<double, kDescriptorDim, kDescriptorDim>::Zero();
    for (int i = 0; i < kDescriptorDim; ++i)
        for (int j = 0; j <= i; ++j) cov(i, j) = tri[i * kPad + j];
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, kDescriptorDim, kDescriptorDim>> es(cov);
    Projection p;
    p.mean = mean.cast<float>();
    for (int k = 0; k < kProjDim; ++k)
        p.basis.row(k) = es.eigenvectors().col(kDescriptorDim - 1 - k).transpose().cast<float>();
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

// A cloud's descriptors laid out by its tree's slots. A search's candidates sit in a few neighbouring
// leaves, and the searches run in slot order, so the exact re-ranking reads neighbouring memory instead of
// 16 scattered rows per search (at a million descriptors per cloud the rows are far out of cache).
UninitVector<float> by_slot(const Descriptors &d, const ProjectedKdTree &tree, RunContext &ctx) {
    UninitVector<float> out;
    out.resize(tree.num_slots() * kDescriptorDim);
    ctx.parallel_for(tree.num_slots(), 4096, [&](std::size_t b, std::size_t e) {
        for (std::size_t s = b; s < e; ++s) {
            const std::uint32_t i = tree.slot_index(s);
            if (i == ProjectedKdTree::kNoPoint)
                std::fill_n(&out[s * kDescriptorDim], kDescriptorDim, 0.0f); // padding: never read
            else
                std::copy_n(&d.values[static_cast<std::size_t>(i) * kDescriptorDim], kDescriptorDim,
                            &out[s * kDescriptorDim]);
        }
    });
    return out;
}

// The two exact nearest among the projected search's candidates, ties by index. `ref` is the searched
// cloud's descriptors by slot.
NearestK nearest(const ProjectedKdTree &tree, const float *projected_query, const float *query,
                 const UninitVector<float> &ref, int k) {
    std::uint32_t cand[kCandidates], cand_slot[kCandidates];
    float cand_dist[kCandidates];
    const int found = tree.nearest(projected_query, kCandidates, cand, cand_dist, cand_slot);
    NearestK best(k);
    for (int i = 0; i < found; ++i)
        best.add(exact_dist2(query, &ref[static_cast<std::size_t>(cand_slot[i]) * kDescriptorDim]), cand[i]);
    return best;
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
    // The two trees are independent: built side by side when there are threads. They keep their own copy
    // of the projections, so those go as soon as the trees stand.
    std::unique_ptr<ProjectedKdTree> trees[2];
    {
        const std::vector<float> qproj = project(Q, pca, ctx), rproj = project(R, pca, ctx);
        ctx.parallel_for(2, 1, [&](std::size_t b, std::size_t e) {
            for (std::size_t t = b; t < e; ++t)
                trees[t] = t == 0 ? std::make_unique<ProjectedKdTree>(rproj.data(), R.keypoint.size())
                                  : std::make_unique<ProjectedKdTree>(qproj.data(), Q.keypoint.size());
        });
    }
    const ProjectedKdTree &rtree = *trees[0], &qtree = *trees[1];
    const UninitVector<float> rdesc = by_slot(R, rtree, ctx), qdesc = by_slot(Q, qtree, ctx);

    // Every search is independent and writes only its own query's entries, so the order (slot order:
    // consecutive searches start in neighbouring leaves of the other tree, which stay cached) changes
    // nothing in the results. A query left out of its tree (a non-finite projection) could never find a
    // neighbour: its distances are never finite.
    const std::size_t nq = Q.keypoint.size(), nr = R.keypoint.size();
    constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
    std::vector<std::uint32_t> forward(nq, kNone);
    std::vector<float> ratio(nq, 0.0f);
    ctx.parallel_for(qtree.num_slots(), 256, [&](std::size_t b, std::size_t e) {
        float projected[kProjDim];
        for (std::size_t s = b; s < e; ++s) {
            const std::uint32_t q = qtree.slot_index(s);
            if (q == ProjectedKdTree::kNoPoint) continue;
            qtree.slot_point(s, projected);
            const NearestK r = nearest(rtree, projected, &qdesc[s * kDescriptorDim], rdesc, use_ratio ? 2 : 1);
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

    // Backward searches only from the reference points some query picked.
    std::vector<std::uint8_t> picked(nr, 0);
    for (std::size_t q = 0; q < nq; ++q)
        if (forward[q] != kNone) picked[forward[q]] = 1;
    std::vector<std::uint32_t> backward(nr, kNone);
    ctx.parallel_for(rtree.num_slots(), 256, [&](std::size_t b, std::size_t e) {
        float projected[kProjDim];
        for (std::size_t s = b; s < e; ++s) {
            const std::uint32_t r = rtree.slot_index(s);
            if (r == ProjectedKdTree::kNoPoint || !picked[r]) continue;
            rtree.slot_point(s, projected);
            const NearestK n = nearest(qtree, projected, &rdesc[s * kDescriptorDim], qdesc, 1);
            if (n.found() >= 1) backward[r] = n.index(0);
        }
    });

    for (std::size_t q = 0; q < nq; ++q) {
        if (forward[q] == kNone || backward[forward[q]] != q) continue;
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
