// SPDX-License-Identifier: MIT
// A sparse LDL^T of a symmetric matrix made of 6x6 blocks (the pose graph's normal equations: one block row per
// node, one off-diagonal block per pair of nodes an edge joins). analyse() computes the ordering (approximate minimum
// degree on the node graph, n nodes rather than 6 n scalars) and the pattern of L once; factorize() then runs per
// step on dense 6x6 blocks, where a scalar sparse LDL^T spends its time on indices: 5.5 ms per factorisation of the
// 10,000-node drive against Eigen's simplicial LDL^T's 75 ms (docs/pose-graph.md). The block products have an AVX2
// twin (simd_level.hpp) that performs the SSE2 kernel's operations lane by lane: the same bits on every x86-64 CPU.
//
// The factorisation is A = L D L^T with L unit lower triangular by blocks and D block diagonal; each D block is
// inverted through its own unpivoted LDL^T, so a pivot fails exactly where a scalar LDL^T in the same order would:
// when it is 0 (a negative one is taken, as Eigen's simplicial LDL^T takes it). Single-threaded, every sum in a
// fixed order: the same input gives the same bits.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "detail_namespace.hpp"
#include "se3.hpp"

KISSM_DETAIL_BEGIN

class BlockLdlt {
public:
    // n block rows and columns; pairs are the off-diagonal blocks that may be non-zero, (i, j) with i != j, each
    // unordered pair at most once. Throws std::bad_alloc.
    void analyse(long n, const std::vector<std::pair<long, long>> &pairs);

    // diagonal[i] is the block A_ii (its lower triangle is read), off[p] the block A_{pairs[p].first,
    // pairs[p].second} (its transpose is A_{second,first}). Returns false when a pivot is 0 or not finite.
    bool factorize(const std::vector<Matrix6d> &diagonal, const std::vector<Matrix6d> &off);

    // x <- A^-1 x, after a successful factorize(); x has 6 n entries.
    void solve(Eigen::VectorXd &x);

    long size() const { return n_; }
    // The number of 6x6 blocks below L's diagonal (the fill, for tests and measurements).
    long lower_blocks() const { return static_cast<long>(rows_.size()); }
    // The number of 6x6 block products a factorisation does (its work, for measurements).
    long block_products() const {
        long products = 0;
        for (long j = 0; j < n_; ++j) {
            const long c = col_start_[j + 1] - col_start_[j];
            products += c * (c + 3) / 2;
        }
        return products;
    }

private:
    long n_ = 0;
    std::vector<long> order_;    // order_[k] = the block eliminated k-th
    std::vector<long> position_; // position_[block] = k
    // L's strictly lower blocks by column (in elimination order): rows_[col_start_[j] .. col_start_[j+1]) sorted.
    std::vector<long> col_start_, rows_;
    // For each row j, the columns k < j with L_jk != 0, in increasing k, and the slot of L_jk in rows_.
    std::vector<long> row_start_, row_column_, row_slot_;
    std::vector<long> slot_source_; // per slot: 2 p (+1: transposed) for the slot of pair p, -1 for the fill
    std::vector<Matrix6d> factor_;  // S_ij = L_ij D_j by slot (L itself is not stored)
    std::vector<Matrix6d> inverse_; // D's blocks inverted
    std::vector<long> where_;       // scratch: the slot of each row in the column being factorised
    Eigen::VectorXd permuted_;      // scratch: the right-hand side in elimination order
};

KISSM_DETAIL_END
