// SPDX-License-Identifier: MIT
// The nearest voxel of a cloud to a 3-D query within a distance bound: refinement's correspondence search and
// the aligned overlap (stage 6). Built once per target cloud; features built for refinement keep it, so a map
// is indexed once and matched against many scans.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "detail_namespace.hpp"
#include "stage_types.hpp"

KISSM_DETAIL_BEGIN

// A 3-D kd-tree over a cloud's voxel points (local frame), for one-nearest queries within a radius, with a
// hash of cells for the common case of a query that already knows a close point. Exact and a function of the
// data alone: the nearest point, ties broken by the lower index, whatever the search path; so results never
// depend on threads or on the hint. Leaves hold up to kLeafPoints points contiguously (x, y, z as separate
// rows); nodes are a flat array in depth-first order.
class RefineIndex {
public:
    static constexpr std::uint32_t kNone = 0xFFFFFFFFu;

    RefineIndex() = default;
    // `cell` is the side of the hash's cells (the voxel size: a cell then holds a few points); <= 0: no hash.
    RefineIndex(const std::vector<Vec3f> &points, double cell);

    bool empty() const { return index_.empty(); }
    std::size_t size() const { return index_.size(); }

    // The index of the point nearest to q with squared distance <= max_dist2 (ties: the lower index), or kNone.
    // *dist2 receives its squared distance (float, computed as (x-qx)^2 + (y-qy)^2 + (z-qz)^2 in that order).
    // `hint`, when not kNone, is a point to try first (the previous answer for a query that moved a little): its
    // distance bounds the search from the start; when that bound is within one cell, the cells it reaches are
    // searched instead of the tree. The answer is the same either way.
    std::uint32_t nearest(const Vec3f &q, float max_dist2, float *dist2, std::uint32_t hint = kNone) const;

    // Bytes held.
    std::size_t bytes() const;

private:
    static constexpr int kLeafPoints = 8;
    struct Node {
        float split;        // internal: the splitting coordinate (low child <= split <= high child)
        std::uint32_t link; // internal: index of the high child (the low child follows its parent); leaf: first slot
        std::uint32_t info; // internal: dim; leaf: kLeafBit | number of points
    };
    static constexpr std::uint32_t kLeafBit = 0x80000000u;
    struct Cell {
        std::uint64_t key;          // kNoCell when the table slot is free
        std::uint32_t first, count; // into cell_slots_
    };
    static constexpr std::uint64_t kNoCell = ~std::uint64_t{0};

    std::uint32_t build(std::uint32_t *begin, std::uint32_t *end, const std::vector<Vec3f> &points);
    void build_cells(double cell);
    const Cell *find_cell(std::uint64_t key) const;
    void scan(std::size_t slot, float qx, float qy, float qz, float &best_d2, std::uint32_t &best) const;
    std::uint32_t search_tree(float qx, float qy, float qz, float &best_d2, std::uint32_t best) const;
    bool search_cells(float qx, float qy, float qz, float &best_d2, std::uint32_t &best) const;

    std::vector<Node> nodes_;
    std::vector<float> xs_, ys_, zs_;  // by slot
    std::vector<std::uint32_t> index_; // by slot: the point's original index
    std::vector<std::uint32_t> slot_;  // by original index: its slot
    // The hash of cells: side cell_, anchored at cell_origin_, 21 bits per axis in the key.
    double cell_ = 0.0;
    double cell_origin_[3] = {0.0, 0.0, 0.0};
    std::vector<Cell> cells_; // open addressing, power-of-two size
    std::vector<std::uint32_t> cell_slots_;
};

KISSM_DETAIL_END
