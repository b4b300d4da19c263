// SPDX-License-Identifier: MIT
#include "descriptor_index.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <utility>

#include "simd_level.hpp"

KISSM_DETAIL_BEGIN

namespace {

constexpr int kProjDim = DescriptorProjection::kDim;
using DescVec = Eigen::Matrix<double, kDescriptorDim, 1>;

constexpr int kPad = 36; // covariance columns (and rows) padded with zeros to whole 4 x 4 tiles
constexpr std::size_t kChunk = 64;

// The covariance's lower triangle as 4 x 4 tiles (i0, j0), summed over rows in row order.
struct TileSums {
    const float *const *rows;
    std::size_t num_rows;
    const double *mean;
    const std::pair<int, int> *tiles;
    double *tri; // kPad x kPad
};

// Tiles [t0, t1) of `job`: rows by chunks of kChunk centred into xs (kChunk x kPad, its padding zero), then each
// tile's 16 accumulators (kept in registers) add x_j * x_i row by row. Both widths' clones (simd_level.hpp) do the
// same multiplications and additions in the same order, so the same bits.
KISSM_ALWAYS_INLINE void sum_tiles_body(const TileSums &job, std::size_t t0, std::size_t t1, double *xs) {
    for (std::size_t r0 = 0; r0 < job.num_rows; r0 += kChunk) {
        const std::size_t nr = std::min(kChunk, job.num_rows - r0);
        for (std::size_t r = 0; r < nr; ++r)
            for (int c = 0; c < kDescriptorDim; ++c)
                xs[r * kPad + c] = static_cast<double>(job.rows[r0 + r][c]) - job.mean[c];
        for (std::size_t t = t0; t < t1; ++t) {
            const int i0 = job.tiles[t].first, j0 = job.tiles[t].second;
            double acc[4][4];
            for (int i = 0; i < 4; ++i)
                for (int j = 0; j < 4; ++j) acc[i][j] = job.tri[(i0 + i) * kPad + j0 + j];
            for (std::size_t r = 0; r < nr; ++r) {
                const double *xr = &xs[r * kPad];
                for (int i = 0; i < 4; ++i)
                    for (int j = 0; j < 4; ++j) acc[i][j] += xr[j0 + j] * xr[i0 + i];
            }
            for (int i = 0; i < 4; ++i)
                for (int j = 0; j < 4; ++j) job.tri[(i0 + i) * kPad + j0 + j] = acc[i][j];
        }
    }
}

void sum_tiles_sse2(const TileSums &job, std::size_t t0, std::size_t t1, double *xs) {
    sum_tiles_body(job, t0, t1, xs);
}
#if KISSM_HAVE_AVX2_KERNELS
KISSM_TARGET_AVX2 void sum_tiles_avx2(const TileSums &job, std::size_t t0, std::size_t t1, double *xs) {
    sum_tiles_body(job, t0, t1, xs);
}
#endif

// Principal axes of the descriptors, from a fixed subsample (cost independent of cloud size; a function of
// the data alone, so the same for every thread count).
DescriptorProjection principal_axes(const Descriptors &d, RunContext &ctx) {
    constexpr std::size_t kSample = 8192;
    std::vector<const float *> rows;
    const std::size_t n = d.keypoint.size();
    const std::size_t step = std::max<std::size_t>(1, n / kSample);
    for (std::size_t i = 0; i < n; i += step) rows.push_back(&d.values[i * kDescriptorDim]);
    DescVec mean = DescVec::Zero();
    for (const float *r : rows)
        for (int c = 0; c < kDescriptorDim; ++c) mean[c] += static_cast<double>(r[c]);
    mean /= static_cast<double>(rows.size());
    // Only the lower triangle: the eigen solver reads nothing else. Every element is still the sum over
    // rows, in row order, of x_j * x_i, so the axes are bit for bit those of per-row outer products. The
    // rows go by chunks through 4 x 4 tiles of accumulators that the compiler keeps in vector registers (an
    // AVX2 clone where the CPU has it: docs/design/performance.md, "Descriptor index build"); threads share out
    // tiles (disjoint elements, each summed whole by one thread), never rows.
    std::vector<std::pair<int, int>> tiles;
    for (int i0 = 0; i0 < kDescriptorDim; i0 += 4)
        for (int j0 = 0; j0 <= i0; j0 += 4) tiles.emplace_back(i0, j0);
    std::vector<double> tri(kPad * kPad, 0.0);
#if KISSM_HAVE_AVX2_KERNELS
    const auto sum_tiles = use_avx2() ? sum_tiles_avx2 : sum_tiles_sse2;
#else
    const auto sum_tiles = sum_tiles_sse2;
#endif
    const TileSums job{rows.data(), rows.size(), mean.data(), tiles.data(), tri.data()};
    ctx.parallel_for(tiles.size(), (tiles.size() + 1) / 2, [&](std::size_t t0, std::size_t t1) {
        std::vector<double> xs(kChunk * kPad, 0.0);
        sum_tiles(job, t0, t1, xs.data());
    });
    Eigen::Matrix<double, kDescriptorDim, kDescriptorDim> cov =
        Eigen::Matrix<double, kDescriptorDim, kDescriptorDim>::Zero();
    for (int i = 0; i < kDescriptorDim; ++i)
        for (int j = 0; j <= i; ++j) cov(i, j) = tri[i * kPad + j];
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, kDescriptorDim, kDescriptorDim>> es(cov);
    DescriptorProjection p;
    p.mean = mean.cast<float>();
    for (int k = 0; k < kProjDim; ++k)
        p.basis.row(k) = es.eigenvectors().col(kDescriptorDim - 1 - k).transpose().cast<float>();
    return p;
}

std::vector<float> project(const Descriptors &d, const DescriptorProjection &p, RunContext &ctx) {
    const std::size_t n = d.keypoint.size();
    std::vector<float> out(n * kProjDim);
    ctx.parallel_for(n, 1024, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) p.apply(&d.values[i * kDescriptorDim], &out[i * kProjDim]);
    });
    return out;
}

} // namespace

void RankedNeighbours::add(float dist, std::uint32_t index) {
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

float descriptor_dist2(const float *a, const float *b) {
    float s = 0.0f;
    for (int c = 0; c < kDescriptorDim; ++c) {
        const float d = a[c] - b[c];
        s += d * d;
    }
    return s;
}

RankedNeighbours DescriptorIndex::nearest(const float *query, int k) const {
    static_assert(kCandidates <= ProjectedKdTree::kMaxK, "the tree returns at most kMaxK neighbours");
    float projected[kProjDim];
    projection_.apply(query, projected);
    std::uint32_t cand[kCandidates], cand_slot[kCandidates];
    float cand_dist[kCandidates];
    const int found = tree_->nearest(projected, kCandidates, cand, cand_dist, cand_slot);
    RankedNeighbours best(k);
    for (int i = 0; i < found; ++i) best.add(descriptor_dist2(query, slot_descriptor(cand_slot[i])), cand[i]);
    return best;
}

void DescriptorProjection::apply(const float *descriptor, float *out) const {
    const Eigen::Map<const Eigen::Matrix<float, kDescriptorDim, 1>> x(descriptor);
    const Eigen::Matrix<float, kDim, 1> y = basis * (x - mean);
    for (int c = 0; c < kDim; ++c) out[c] = y[c];
}

std::size_t DescriptorIndex::bytes() const {
    return (tree_ ? tree_->bytes() : 0) + by_slot_.capacity() * sizeof(float);
}

std::vector<DescriptorIndex> DescriptorIndex::build(const std::vector<const Descriptors *> &clouds, RunContext &ctx) {
    const std::size_t n = clouds.size();
    std::vector<DescriptorIndex> out(n);
    std::vector<std::vector<float>> projected(n);
    for (std::size_t c = 0; c < n; ++c) {
        if (clouds[c]->keypoint.empty()) continue;
        out[c].projection_ = principal_axes(*clouds[c], ctx);
        projected[c] = project(*clouds[c], out[c].projection_, ctx);
    }
    // The trees are independent: side by side when there are threads. Each keeps its own copy of the
    // projections, which go as soon as it stands.
    ctx.parallel_for(n, 1, [&](std::size_t b, std::size_t e) {
        for (std::size_t c = b; c < e; ++c) {
            if (clouds[c]->keypoint.empty()) continue;
            out[c].tree_ = std::make_unique<const ProjectedKdTree>(projected[c].data(), clouds[c]->keypoint.size());
            std::vector<float>().swap(projected[c]);
        }
    });
    for (std::size_t c = 0; c < n; ++c) {
        if (!out[c].tree_) continue;
        const ProjectedKdTree &tree = *out[c].tree_;
        const Descriptors &d = *clouds[c];
        UninitVector<float> &by_slot = out[c].by_slot_;
        by_slot.resize(tree.num_slots() * kDescriptorDim);
        ctx.parallel_for(tree.num_slots(), 4096, [&](std::size_t b, std::size_t e) {
            for (std::size_t s = b; s < e; ++s) {
                const std::uint32_t i = tree.slot_index(s);
                if (i == ProjectedKdTree::kNoPoint)
                    std::fill_n(&by_slot[s * kDescriptorDim], kDescriptorDim, 0.0f); // padding: never read
                else
                    std::copy_n(&d.values[static_cast<std::size_t>(i) * kDescriptorDim], kDescriptorDim,
                                &by_slot[s * kDescriptorDim]);
            }
        });
    }
    return out;
}

KISSM_DETAIL_END
