// SPDX-License-Identifier: MIT
// Stage 3's spatial index of a cloud's keypoints, built once with its features: the place gate (place_gate.hpp)
// takes the keypoints inside a box of a map from it in time proportional to the box's contents, not the map's.
#pragma once

#include <cstdint>
#include <vector>

#include "detail_namespace.hpp"
#include "stage_types.hpp"

KISSM_DETAIL_BEGIN

// Keypoints in vertical columns of a fixed size (x-y squares), columns in (x, y) order, each column's keypoints
// in ascending index order.
class KeypointGrid {
public:
    KeypointGrid() = default;
    // `keypoint` indexes `points`; `column` > 0 is the columns' side. Keypoints whose column does not fit 31 bits
    // (a non-finite position, or one 2^30 columns out) are left out: select() never returns them.
    KeypointGrid(const std::vector<Vec3f> &points, const std::vector<std::uint32_t> &keypoint, double column);

    bool empty() const { return order_.empty(); }
    std::size_t bytes() const {
        return order_.capacity() * sizeof(std::uint32_t) + columns_.capacity() * sizeof(Column);
    }

    // The keypoints k (indexes into `keypoint`) whose position p has lo[d] <= p[d] * scale < hi[d] in every axis,
    // in ascending order. Visits only the columns that overlap the box.
    std::vector<std::uint32_t> select(const std::vector<Vec3f> &points, const std::vector<std::uint32_t> &keypoint,
                                      double scale, const double lo[3], const double hi[3]) const;

private:
    struct Column {
        std::uint64_t key; // (x + bias) << 32 | (y + bias)
        std::uint32_t begin;
    };
    double inverse_ = 0.0;             // 1 / column
    std::vector<std::uint32_t> order_; // keypoint indexes, column after column
    std::vector<Column> columns_;      // sorted by key; a column ends where the next begins (or at order_.size())
};

KISSM_DETAIL_END
