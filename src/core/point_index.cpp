// SPDX-License-Identifier: MIT
#include "point_index.hpp"

#include <algorithm>
#include <limits>

#include "failure.hpp"

KISSM_DETAIL_BEGIN

PointIndex::PointIndex(const std::vector<Vec3f> &points) {
    if (points.size() >= static_cast<std::size_t>(kLeafBit))
        fail(ErrorKind::InvalidArgument, "too many points for the refinement index");
    std::vector<std::uint32_t> order(points.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<std::uint32_t>(i);
    xs_.reserve(points.size()), ys_.reserve(points.size()), zs_.reserve(points.size());
    index_.reserve(points.size());
    nodes_.reserve(2 * (points.size() / (kLeafPoints / 2) + 1));
    if (!points.empty()) build(order.data(), order.data() + order.size(), points);
}

std::uint32_t PointIndex::build(std::uint32_t *begin, std::uint32_t *end, const std::vector<Vec3f> &points) {
    const auto here = static_cast<std::uint32_t>(nodes_.size());
    nodes_.push_back(Node{0.0f, 0, 0});
    const std::size_t n = static_cast<std::size_t>(end - begin);
    if (n <= static_cast<std::size_t>(kLeafPoints)) {
        nodes_[here].link = static_cast<std::uint32_t>(index_.size());
        nodes_[here].info = kLeafBit | static_cast<std::uint32_t>(n);
        for (const std::uint32_t *p = begin; p != end; ++p) {
            xs_.push_back(points[*p].x()), ys_.push_back(points[*p].y()), zs_.push_back(points[*p].z());
            index_.push_back(*p);
        }
        return here;
    }
    // Split the widest side of the bounding box at the median; (coordinate, index) order makes the split a
    // function of the data alone.
    Vec3f lo = points[*begin], hi = lo;
    for (const std::uint32_t *p = begin; p != end; ++p) lo = lo.cwiseMin(points[*p]), hi = hi.cwiseMax(points[*p]);
    int dim = 0;
    const Vec3f ext = hi - lo;
    if (ext.y() > ext[dim]) dim = 1;
    if (ext.z() > ext[dim]) dim = 2;
    std::uint32_t *mid = begin + n / 2;
    std::nth_element(begin, mid, end, [&](std::uint32_t a, std::uint32_t b) {
        const float ca = points[a][dim], cb = points[b][dim];
        return ca < cb || (ca == cb && a < b);
    });
    nodes_[here].split = points[*mid][dim];
    nodes_[here].info = static_cast<std::uint32_t>(dim);
    build(begin, mid, points);
    const std::uint32_t high = build(mid, end, points);
    nodes_[here].link = high;
    return here;
}

std::uint32_t PointIndex::nearest(const Vec3f &q, float max_dist2, float *dist2) const {
    std::uint32_t best = kNone;
    float best_d2 = max_dist2;
    if (nodes_.empty() || !(max_dist2 >= 0.0f)) {
        if (dist2 != nullptr) *dist2 = std::numeric_limits<float>::infinity();
        return kNone;
    }
    // A far child waits on the stack with the lower bound (q[dim] - split)^2 of its points' squared distance.
    // Rounding is monotone, so no point's computed distance can fall below that bound: pruning on "bound >
    // best" loses no point at the best distance, and ties go to the lower index wherever they are found.
    struct Pending {
        std::uint32_t node;
        float bound;
    };
    Pending stack[64];
    int top = 0;
    std::uint32_t node = 0;
    float bound = 0.0f;
    const float qx = q.x(), qy = q.y(), qz = q.z();
    for (;;) {
        if (bound <= best_d2) {
            for (;;) {
                const Node &nd = nodes_[node];
                if (nd.info & kLeafBit) {
                    const std::size_t first = nd.link, count = nd.info & ~kLeafBit;
                    for (std::size_t s = first; s < first + count; ++s) {
                        const float dx = xs_[s] - qx, dy = ys_[s] - qy, dz = zs_[s] - qz;
                        const float d2 = dx * dx + dy * dy + dz * dz;
                        if (d2 < best_d2 || (d2 == best_d2 && index_[s] < best)) best_d2 = d2, best = index_[s];
                    }
                    break;
                }
                const float diff = (nd.info == 0 ? qx : nd.info == 1 ? qy : qz) - nd.split;
                const std::uint32_t low = node + 1, high = nd.link;
                // Points equal to the split may sit on either side: the far side's bound is then 0. At most one
                // entry per level waits, and fewer than 2^31 points make fewer than 28 levels.
                stack[top++] = Pending{diff <= 0.0f ? high : low, diff * diff};
                node = diff <= 0.0f ? low : high;
            }
        }
        if (top == 0) break;
        --top;
        node = stack[top].node;
        bound = stack[top].bound;
    }
    if (dist2 != nullptr) *dist2 = best == kNone ? std::numeric_limits<float>::infinity() : best_d2;
    return best;
}

std::size_t PointIndex::bytes() const {
    return nodes_.capacity() * sizeof(Node) + (xs_.capacity() + ys_.capacity() + zs_.capacity()) * sizeof(float) +
           index_.capacity() * sizeof(std::uint32_t);
}

KISSM_DETAIL_END
