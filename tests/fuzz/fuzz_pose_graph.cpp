// SPDX-License-Identifier: MIT
// libFuzzer target for one pose graph used for a sequence of calls: edges with decoded transforms (rigid or
// refused ones, fuzz_input.hpp) and informations (diagonal, coupled, singular, asymmetric, non-finite), robust
// flags in and out of range, optimisations from any anchor with any bound, cancel requests, reads of the solution.
// Invariants: a refused call changes nothing (the edge count, the last solution); an optimisation places the anchor
// at exactly the identity, gives every placed node a finite rigid pose and every other one NaN, reports residuals
// exactly where both nodes are placed, keeps trusted edges of the anchor's component, and repeated gives the same
// bits.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <vector>

#include "fuzz_input.hpp"

namespace {

void require(bool ok) {
    if (!ok) std::abort();
}

// An information: a diagonal of decoded scales, sometimes coupled, sometimes spoilt.
bool make_information(kissm_fuzz::Bytes &in, double I[36]) {
    std::memset(I, 0, 36 * sizeof(double));
    const std::uint8_t kind = in.u8() % 8;
    double largest = 0.0;
    for (int k = 0; k < 6; ++k) { // two statements: the order of a call's arguments is the compiler's
        const double mantissa = 1.0 + in.u8() / 64.0;
        I[7 * k] = std::ldexp(mantissa, static_cast<int>(in.u8() % 40) - 10);
        largest = std::max(largest, I[7 * k]);
    }
    const int at = in.u8() % 36;
    switch (kind) {
    case 1: I[1] = I[6] = 0.5 * std::sqrt(I[0] * I[7]); return true; // coupled, still positive definite
    case 2: I[at] = std::numeric_limits<double>::quiet_NaN(); return false;
    case 3: I[at] = std::numeric_limits<double>::infinity(); return false;
    case 4: I[7 * (at % 6)] = 0.0; return false;  // singular
    case 5: I[7 * (at % 6)] = -1.0; return false; // indefinite
    case 6: I[6] = 1e-6 * largest; return false;  // asymmetric beyond 1e-9 of the largest entry
    default: return true;
    }
}

bool rigid_pose(const double *m) {
    for (int k = 0; k < 16; ++k)
        if (!std::isfinite(m[k])) return false;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            double dot = 0.0;
            for (int k = 0; k < 3; ++k) dot += m[4 * k + i] * m[4 * k + j];
            if (std::abs(dot - (i == j ? 1.0 : 0.0)) > 1e-6) return false;
        }
    return m[12] == 0.0 && m[13] == 0.0 && m[14] == 0.0 && m[15] == 1.0;
}

struct Solution {
    std::vector<double> poses, residuals;
    std::vector<std::uint8_t> placed, accepted;
    std::vector<std::uint64_t> components;
};

Solution read(const kissm_pose_graph *g) {
    const std::size_t n = kissm_pose_graph_num_nodes(g), m = kissm_pose_graph_num_edges(g);
    Solution s{std::vector<double>(16 * n), std::vector<double>(m), std::vector<std::uint8_t>(n),
               std::vector<std::uint8_t>(m), std::vector<std::uint64_t>(n)};
    require(kissm_pose_graph_poses(g, s.poses.data(), s.placed.data(), s.components.data()) == KISSM_OK);
    require(kissm_pose_graph_edges(g, s.accepted.data(), s.residuals.data()) == KISSM_OK);
    return s;
}

// Bit for bit (NaN poses compare equal to themselves); memcmp of empty vectors would pass it null pointers.
bool same_doubles(const std::vector<double> &a, const std::vector<double> &b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

bool same_bits(const Solution &a, const Solution &b) {
    return same_doubles(a.poses, b.poses) && same_doubles(a.residuals, b.residuals) && a.placed == b.placed &&
           a.accepted == b.accepted && a.components == b.components;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
    kissm_fuzz::Bytes in(data, size);
    const std::uint64_t n = in.u8() % 12; // 0 is refused
    kissm_pose_graph *g = nullptr;
    const int32_t created = kissm_pose_graph_create(n, &g);
    require((n == 0) == (created == KISSM_ERR_INVALID_ARGUMENT) && (created == KISSM_OK) == (g != nullptr));
    if (g == nullptr) return 0;
    std::vector<std::uint8_t> robust_of; // per edge
    std::vector<std::uint64_t> source_of, target_of;
    bool solved = false;
    Solution last;
    static const double bounds[] = {
        KISSM_POSE_GRAPH_DEFAULT_BOUND,         1.0, 1e-9, 1e9, 0.0, -1.0, std::numeric_limits<double>::quiet_NaN(),
        std::numeric_limits<double>::infinity()};
    for (int step = 0; step < 40 && in.left() > 0; ++step) {
        const std::uint8_t op = in.u8();
        switch (op % 4) {
        case 0:
        case 1: {                                                             // an edge
            const std::uint64_t s = in.u8() % (n + 2), t = in.u8() % (n + 2); // sometimes out of range
            double T[16], I[36];
            const bool rigid = kissm_fuzz::make_transform(in, T);
            const bool spd = make_information(in, I);
            const int32_t robust = static_cast<int32_t>(in.u8() % 4) - 1; // -1 and 2 are refused
            const std::uint64_t before = kissm_pose_graph_num_edges(g);
            std::uint64_t id = 12345;
            const int32_t st = kissm_pose_graph_add_edge(g, s, t, T, I, robust, &id);
            const bool ok = s < n && t < n && s != t && rigid && spd && (robust == 0 || robust == 1);
            // The decoded kinds are refused where they say; a rigid decode may still be refused (a translation
            // beyond the library's bound), a "positive definite" diagonal may underflow: never the other way.
            require(st == KISSM_OK || st == KISSM_ERR_INVALID_ARGUMENT || st == KISSM_ERR_OUT_OF_MEMORY);
            if (!ok) require(st != KISSM_OK);
            if (st == KISSM_OK) {
                require(id == before && kissm_pose_graph_num_edges(g) == before + 1);
                robust_of.push_back(static_cast<std::uint8_t>(robust));
                source_of.push_back(s);
                target_of.push_back(t);
                solved = false;
            } else {
                require(id == 12345 && kissm_pose_graph_num_edges(g) == before);
                if (solved) require(same_bits(read(g), last)); // the solution kept
            }
            break;
        }
        case 2: { // optimise, and again: the same bits
            const std::uint64_t anchor = in.u8() % (n + 1);
            const double bound = bounds[in.u8() % 8];
            const int32_t st = kissm_pose_graph_optimize(g, anchor, bound);
            const bool ok = anchor < n && bound > 0.0 && std::isfinite(bound);
            require(st == (ok ? KISSM_OK : KISSM_ERR_INVALID_ARGUMENT) || st == KISSM_ERR_OUT_OF_MEMORY);
            if (st != KISSM_OK) { // refused arguments change nothing; running out of memory loses the solution
                if (st == KISSM_ERR_INVALID_ARGUMENT && solved) require(same_bits(read(g), last));
                if (st != KISSM_ERR_INVALID_ARGUMENT) solved = false;
                break;
            }
            const Solution s = read(g);
            require(s.placed[anchor] == 1);
            for (int k = 0; k < 16; ++k) require(s.poses[16 * anchor + k] == (k % 5 == 0 ? 1.0 : 0.0));
            for (std::size_t i = 0; i < n; ++i) {
                if (s.placed[i]) {
                    require(rigid_pose(&s.poses[16 * i]) && s.components[i] == s.components[anchor]);
                } else {
                    for (int k = 0; k < 16; ++k) require(std::isnan(s.poses[16 * i + k]));
                    require(s.components[i] != s.components[anchor]);
                }
                require(s.components[i] <= i && s.components[s.components[i]] == s.components[i]);
            }
            for (std::size_t e = 0; e < robust_of.size(); ++e) {
                const bool both = s.placed[source_of[e]] && s.placed[target_of[e]];
                require(both ? s.residuals[e] >= 0.0 : std::isnan(s.residuals[e]));
                if (!both) require(s.accepted[e] == 0);
                if (both && robust_of[e] == 0) require(s.accepted[e] == 1);
                if (robust_of[e] == 0) require(s.components[source_of[e]] == s.components[target_of[e]]);
            }
            require(kissm_pose_graph_optimize(g, anchor, bound) == KISSM_OK);
            require(same_bits(read(g), s));
            last = s;
            solved = true;
            break;
        }
        default: // a cancel request while no call runs: dropped when the next call starts
            kissm_pose_graph_cancel(g);
            break;
        }
    }
    if (!solved) {
        std::vector<std::uint8_t> flags(n, 7);
        require(kissm_pose_graph_poses(g, nullptr, flags.data(), nullptr) == KISSM_ERR_INVALID_ARGUMENT &&
                flags[0] == 7);
    }
    kissm_pose_graph_destroy(g);
    return 0;
}
