// SPDX-License-Identifier: MIT
#include "block_ldlt.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#if defined(__SSE2__)
#  include <immintrin.h>
#endif

#include <Eigen/OrderingMethods>
#include <Eigen/SparseCore>

#include "simd_level.hpp"

KISSM_DETAIL_BEGIN

namespace {

// The factorisation's arrays, for the loop that both kernel widths share.
struct Columns {
    long n;
    const long *order, *col_start, *rows, *row_start, *row_column, *row_slot, *slot_source;
    long *where;
    const Matrix6d *diagonal, *off;
    Matrix6d *factor, *inverse;
};

// The inverse of a symmetric 6x6 block through its unpivoted LDL^T (its lower triangle is read): the pivots are the
// ones a scalar LDL^T meets on these six columns, and it fails where that would (a pivot of 0), or on a pivot that
// is not finite, whose step could only be rejected. (Gauss-Jordan on columns, tried instead, took 1.7 times as long:
// its six steps wait on each other.)
bool invert_pivot(const Matrix6d &a, Matrix6d &inverse) {
    // Only the entries each loop reads are written (no arrays cleared first), and each term m_ki d_k^-1 m_kj of the
    // last sums takes its first product from md, formed once per (k, i) rather than once per (k, i, j): the same
    // operations in the same order as before, so the same bits, in 0.7 of the time.
    double l[6][6], ld[6][6]; // l[i][k] and ld[i][k] = l[i][k] d[k], for k < i
    double inv_d[6];
    for (int j = 0; j < 6; ++j) {
        double dj = a(j, j);
        for (int k = 0; k < j; ++k) dj -= ld[j][k] * l[j][k];
        if (dj == 0.0 || !std::isfinite(dj)) return false;
        inv_d[j] = 1.0 / dj;
        for (int i = j + 1; i < 6; ++i) {
            double v = a(i, j);
            for (int k = 0; k < j; ++k) v -= ld[i][k] * l[j][k];
            ld[i][j] = v;
            l[i][j] = v * inv_d[j];
        }
    }
    // m = L^-1 (unit lower triangular, its lower triangle), then A^-1 = m^T D^-1 m.
    double m[6][6];
    for (int j = 0; j < 6; ++j) {
        m[j][j] = 1.0;
        for (int i = j + 1; i < 6; ++i) {
            double v = -l[i][j];
            for (int k = j + 1; k < i; ++k) v -= l[i][k] * m[k][j];
            m[i][j] = v;
        }
    }
    double md[6][6]; // md[k][i] = m[k][i] d_k^-1, for i <= k
    for (int k = 0; k < 6; ++k)
        for (int i = 0; i <= k; ++i) md[k][i] = m[k][i] * inv_d[k];
    for (int j = 0; j < 6; ++j)
        for (int i = j; i < 6; ++i) {
            double v = 0.0;
            for (int k = i; k < 6; ++k) v += md[k][i] * m[k][j];
            inverse(i, j) = v;
            inverse(j, i) = v;
        }
    return true;
}

// A block copied or cleared through vector registers, written out (a fold, not a loop): the compiler turns a loop of
// these back into memcpy and memset, whose rep movs and rep stos have a start-up cost that showed as 5% of a
// factorisation's time (one diagonal block and a few fill blocks per column).
#if defined(__SSE2__)
template <std::size_t... K>
KISSM_ALWAYS_INLINE void copy_pairs(double *to, const double *from, std::index_sequence<K...>) {
    (_mm_storeu_pd(to + 2 * K, _mm_loadu_pd(from + 2 * K)), ...);
}
template <std::size_t... K>
KISSM_ALWAYS_INLINE void clear_pairs(double *to, std::index_sequence<K...>) {
    (_mm_storeu_pd(to + 2 * K, _mm_setzero_pd()), ...);
}
#endif

KISSM_ALWAYS_INLINE void copy_block(Matrix6d &to, const Matrix6d &from) {
#if defined(__SSE2__)
    copy_pairs(to.data(), from.data(), std::make_index_sequence<18>());
#else
    to = from;
#endif
}

KISSM_ALWAYS_INLINE void clear_block(Matrix6d &block) {
#if defined(__SSE2__)
    clear_pairs(block.data(), std::make_index_sequence<18>());
#else
    block.setZero();
#endif
}

// Column k's update of column j, shared by both widths (each kernel struct instantiates it with its own
// operations): from slot at, which holds S_jk, to the end of column k, with v = L_jk = S_jk D_k^-1 (D_k^-1 is
// exactly symmetric, so v = S_jk (D_k^-1)^T; and L_ik D_k L_jk^T = S_ik v^T): D_j -= S_jk v^T and S_ij -= S_ik v^T
// for the rows i below j.
#define KISSM_BLOCK_LDLT_UPDATE(target)                                                                                \
  target static void update(Matrix6d &dj, const Columns &m, long k, long at) {                                         \
    Matrix6d v;                                                                                                        \
    product<false>(v, m.factor[at], m.inverse[k]);                                                                     \
    product<true>(dj, m.factor[at], v);                                                                                \
    for (long s = at + 1; s < m.col_start[k + 1]; ++s) product<true>(m.factor[m.where[m.rows[s]]], m.factor[s], v);    \
  }

// product<true>: c -= a u^T, each coefficient c - a_0 u_0 - a_1 u_1 - ... in that order; product<false>: c = a u^T,
// each coefficient ((a_0 u_0 + a_1 u_1) + ...) in that order. No fused multiply-adds, so both widths give the same
// bits. Almost all of a factorisation's time is here.
struct Sse2Kernel {
    template <bool Subtract>
    static KISSM_ALWAYS_INLINE void product(Matrix6d &c, const Matrix6d &a, const Matrix6d &u) {
        const double *ad = a.data(), *ud = u.data();
        double *cd = c.data();
#if defined(__SSE2__)
        for (int j = 0; j < 6; ++j) {
            __m128d c0 = _mm_setzero_pd(), c1 = c0, c2 = c0;
            if constexpr (Subtract) {
                c0 = _mm_loadu_pd(cd + 6 * j);
                c1 = _mm_loadu_pd(cd + 6 * j + 2);
                c2 = _mm_loadu_pd(cd + 6 * j + 4);
            }
            for (int k = 0; k < 6; ++k) {
                const __m128d b = _mm_set1_pd(ud[6 * k + j]);
                const __m128d p0 = _mm_mul_pd(_mm_loadu_pd(ad + 6 * k), b);
                const __m128d p1 = _mm_mul_pd(_mm_loadu_pd(ad + 6 * k + 2), b);
                const __m128d p2 = _mm_mul_pd(_mm_loadu_pd(ad + 6 * k + 4), b);
                if constexpr (Subtract) {
                    c0 = _mm_sub_pd(c0, p0), c1 = _mm_sub_pd(c1, p1), c2 = _mm_sub_pd(c2, p2);
                } else if (k == 0) {
                    c0 = p0, c1 = p1, c2 = p2;
                } else {
                    c0 = _mm_add_pd(c0, p0), c1 = _mm_add_pd(c1, p1), c2 = _mm_add_pd(c2, p2);
                }
            }
            _mm_storeu_pd(cd + 6 * j, c0);
            _mm_storeu_pd(cd + 6 * j + 2, c1);
            _mm_storeu_pd(cd + 6 * j + 4, c2);
        }
#else
        for (int j = 0; j < 6; ++j)
            for (int r = 0; r < 6; ++r) {
                double v = Subtract ? cd[6 * j + r] : ad[r] * ud[j];
                for (int k = Subtract ? 0 : 1; k < 6; ++k) {
                    if (Subtract)
                        v -= ad[6 * k + r] * ud[6 * k + j];
                    else
                        v += ad[6 * k + r] * ud[6 * k + j];
                }
                cd[6 * j + r] = v;
            }
#endif
    }
    KISSM_BLOCK_LDLT_UPDATE()
};

#if KISSM_HAVE_AVX2_KERNELS
// The same operations four rows at a time (rows 0-3 in one register, 4-5 in another): a's six columns stay in
// twelve registers for the whole block.
struct Avx2Kernel {
    template <bool Subtract>
    KISSM_TARGET_AVX2 static KISSM_ALWAYS_INLINE void product(Matrix6d &c, const Matrix6d &a, const Matrix6d &u) {
        const double *ad = a.data(), *ud = u.data();
        double *cd = c.data();
        __m256d top[6];
        __m128d bottom[6];
        for (int k = 0; k < 6; ++k) {
            top[k] = _mm256_loadu_pd(ad + 6 * k);
            bottom[k] = _mm_loadu_pd(ad + 6 * k + 4);
        }
        for (int j = 0; j < 6; ++j) {
            __m256d c0 = _mm256_setzero_pd();
            __m128d c1 = _mm_setzero_pd();
            if constexpr (Subtract) {
                c0 = _mm256_loadu_pd(cd + 6 * j);
                c1 = _mm_loadu_pd(cd + 6 * j + 4);
            }
            for (int k = 0; k < 6; ++k) {
                const double b = ud[6 * k + j];
                const __m256d p0 = _mm256_mul_pd(top[k], _mm256_set1_pd(b));
                const __m128d p1 = _mm_mul_pd(bottom[k], _mm_set1_pd(b));
                if constexpr (Subtract) {
                    c0 = _mm256_sub_pd(c0, p0), c1 = _mm_sub_pd(c1, p1);
                } else if (k == 0) {
                    c0 = p0, c1 = p1;
                } else {
                    c0 = _mm256_add_pd(c0, p0), c1 = _mm_add_pd(c1, p1);
                }
            }
            _mm256_storeu_pd(cd + 6 * j, c0);
            _mm_storeu_pd(cd + 6 * j + 4, c1);
        }
    }
    KISSM_BLOCK_LDLT_UPDATE(KISSM_TARGET_AVX2)
};
#endif

#undef KISSM_BLOCK_LDLT_UPDATE

// Left-looking by block column: column j is loaded from A when its turn comes (so that it is in cache for its
// updates) and takes the updates of every earlier column k that reaches row j, S_ij = L_ij D_j = A_ij - sum_k
// L_ik D_k L_jk^T, in increasing k. Only S is stored: L_jk = S_jk D_k^-1 is formed once per (j, k) where it is needed,
// which costs the product that dividing every block by its D would, and halves the memory the updates go through.
template <typename Kernel>
bool eliminate(const Columns &m) {
    for (long j = 0; j < m.n; ++j) {
        Matrix6d dj;
        copy_block(dj, m.diagonal[m.order[j]]);
        for (long s = m.col_start[j]; s < m.col_start[j + 1]; ++s) {
            m.where[m.rows[s]] = s;
            const long source = m.slot_source[s];
            if (source < 0)
                clear_block(m.factor[s]);
            else if (source % 2 != 0)
                m.factor[s] = m.off[source / 2].transpose();
            else
                copy_block(m.factor[s], m.off[source / 2]);
        }
        for (long r = m.row_start[j]; r < m.row_start[j + 1]; ++r)
            Kernel::update(dj, m, m.row_column[r], m.row_slot[r]);
        if (!invert_pivot(dj, m.inverse[j])) return false;
    }
    return true;
}

} // namespace

void BlockLdlt::analyse(long n, const std::vector<std::pair<long, long>> &pairs) {
    n_ = n;
    // The fill-reducing order of the node graph: one block per node, so the ordering works on n nodes, not 6 n
    // scalars. Eigen's approximate minimum degree (Amestoy, Davis and Duff), on the symmetric pattern.
    {
        std::vector<Eigen::Triplet<double, int>> entries;
        entries.reserve(2 * pairs.size() + static_cast<std::size_t>(n));
        for (long i = 0; i < n; ++i) entries.emplace_back(static_cast<int>(i), static_cast<int>(i), 1.0);
        for (const auto &p : pairs) {
            entries.emplace_back(static_cast<int>(p.first), static_cast<int>(p.second), 1.0);
            entries.emplace_back(static_cast<int>(p.second), static_cast<int>(p.first), 1.0);
        }
        Eigen::SparseMatrix<double, Eigen::ColMajor, int> pattern(n, n);
        pattern.setFromTriplets(entries.begin(), entries.end());
        Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> permutation;
        Eigen::AMDOrdering<int> amd;
        amd(pattern, permutation); // indices()[k]: the node eliminated k-th
        order_.assign(static_cast<std::size_t>(n), 0);
        position_.assign(static_cast<std::size_t>(n), 0);
        for (long k = 0; k < n; ++k) {
            order_[k] = permutation.indices()[k];
            position_[order_[k]] = k;
        }
    }
    // The pattern of A below the diagonal, by column of the elimination order.
    std::vector<long> a_start(static_cast<std::size_t>(n) + 1, 0), a_rows(pairs.size());
    for (const auto &p : pairs) ++a_start[std::min(position_[p.first], position_[p.second]) + 1];
    for (long j = 0; j < n; ++j) a_start[j + 1] += a_start[j];
    {
        std::vector<long> fill(a_start.begin(), a_start.end() - 1);
        for (const auto &p : pairs) {
            const long i = position_[p.first], j = position_[p.second];
            a_rows[fill[std::min(i, j)]++] = std::max(i, j);
        }
    }
    // L's column j is A's column j joined with the columns of its children in the elimination tree (less j); its
    // first row is its parent. Columns are built in order, so a child is complete before its parent needs it.
    col_start_.assign(static_cast<std::size_t>(n) + 1, 0);
    rows_.clear();
    std::vector<long> mark(static_cast<std::size_t>(n), -1), child_head(static_cast<std::size_t>(n), -1),
        child_next(static_cast<std::size_t>(n), -1), column;
    for (long j = 0; j < n; ++j) {
        column.clear();
        mark[j] = j;
        for (long s = a_start[j]; s < a_start[j + 1]; ++s)
            if (mark[a_rows[s]] != j) mark[a_rows[s]] = j, column.push_back(a_rows[s]);
        for (long c = child_head[j]; c >= 0; c = child_next[c])
            for (long s = col_start_[c]; s < col_start_[c + 1]; ++s)
                if (mark[rows_[s]] != j) mark[rows_[s]] = j, column.push_back(rows_[s]);
        std::sort(column.begin(), column.end());
        rows_.insert(rows_.end(), column.begin(), column.end());
        col_start_[j + 1] = static_cast<long>(rows_.size());
        if (!column.empty()) {
            const long parent = column.front();
            child_next[j] = child_head[parent];
            child_head[parent] = j;
        }
    }
    // The same pattern by row: for row j, the columns k < j that reach it, in increasing k.
    row_start_.assign(static_cast<std::size_t>(n) + 1, 0);
    for (const long r : rows_) ++row_start_[r + 1];
    for (long j = 0; j < n; ++j) row_start_[j + 1] += row_start_[j];
    row_column_.assign(rows_.size(), 0);
    row_slot_.assign(rows_.size(), 0);
    {
        std::vector<long> fill(row_start_.begin(), row_start_.end() - 1);
        for (long k = 0; k < n; ++k)
            for (long s = col_start_[k]; s < col_start_[k + 1]; ++s) {
                const long at = fill[rows_[s]]++;
                row_column_[at] = k;
                row_slot_[at] = s;
            }
    }
    // Where A's blocks land: slot_source_ is 2 p (+1 when the pair's first block is the column, so that its transpose
    // is stored) for the slot of pair p, and -1 for the fill.
    slot_source_.assign(rows_.size(), -1);
    for (std::size_t p = 0; p < pairs.size(); ++p) {
        const long i = position_[pairs[p].first], j = position_[pairs[p].second];
        const long col = std::min(i, j), row = std::max(i, j);
        const auto begin = rows_.begin() + col_start_[col], end = rows_.begin() + col_start_[col + 1];
        slot_source_[std::lower_bound(begin, end, row) - rows_.begin()] = 2 * static_cast<long>(p) + (i < j ? 1 : 0);
    }
    factor_.assign(rows_.size(), Matrix6d::Zero());
    inverse_.assign(static_cast<std::size_t>(n), Matrix6d::Zero());
    where_.assign(static_cast<std::size_t>(n), -1);
}

bool BlockLdlt::factorize(const std::vector<Matrix6d> &diagonal, const std::vector<Matrix6d> &off) {
    const Columns columns{n_,
                          order_.data(),
                          col_start_.data(),
                          rows_.data(),
                          row_start_.data(),
                          row_column_.data(),
                          row_slot_.data(),
                          slot_source_.data(),
                          where_.data(),
                          diagonal.data(),
                          off.data(),
                          factor_.data(),
                          inverse_.data()};
#if KISSM_HAVE_AVX2_KERNELS
    if (use_avx2()) return eliminate<Avx2Kernel>(columns);
#endif
    return eliminate<Sse2Kernel>(columns);
}

// With L_ij = S_ij D_j^-1: forward L y = b, where column j's share is S_ij (D_j^-1 y_j) and D_j^-1 y_j is the
// diagonal solve's result for block j; then back L^T x = z, x_j = z_j - D_j^-1 sum_i S_ij^T x_i.
void BlockLdlt::solve(Eigen::VectorXd &x) {
    Eigen::VectorXd &y = permuted_;
    y.resize(6 * n_);
    for (long k = 0; k < n_; ++k) y.segment<6>(6 * k) = x.segment<6>(6 * order_[k]);
    for (long j = 0; j < n_; ++j) {
        const Vector6d z = inverse_[j] * y.segment<6>(6 * j);
        for (long s = col_start_[j]; s < col_start_[j + 1]; ++s) y.segment<6>(6 * rows_[s]).noalias() -= factor_[s] * z;
        y.segment<6>(6 * j) = z;
    }
    for (long j = n_ - 1; j >= 0; --j) {
        Vector6d sum = Vector6d::Zero();
        for (long s = col_start_[j]; s < col_start_[j + 1]; ++s)
            sum.noalias() += factor_[s].transpose() * y.segment<6>(6 * rows_[s]);
        y.segment<6>(6 * j).noalias() -= inverse_[j] * sum;
    }
    for (long k = 0; k < n_; ++k) x.segment<6>(6 * order_[k]) = y.segment<6>(6 * k);
}

KISSM_DETAIL_END
