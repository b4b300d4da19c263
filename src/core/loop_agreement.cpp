// SPDX-License-Identifier: MIT
#include "loop_agreement.hpp"

#include <cmath>
#include <map>
#include <utility>

KISSM_DETAIL_BEGIN

namespace {

// A rigid transform: rotation (row-major) and translation.
struct Frame {
    double r[9];
    double t[3];
};

Frame frame_of(const double *m) {
    Frame f{};
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) f.r[3 * i + j] = m[4 * i + j];
        f.t[i] = m[4 * i + 3];
    }
    return f;
}

// a o b: first b, then a.
Frame compose(const Frame &a, const Frame &b) {
    Frame c{};
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j)
            c.r[3 * i + j] = a.r[3 * i] * b.r[j] + a.r[3 * i + 1] * b.r[3 + j] + a.r[3 * i + 2] * b.r[6 + j];
        c.t[i] = a.r[3 * i] * b.t[0] + a.r[3 * i + 1] * b.t[1] + a.r[3 * i + 2] * b.t[2] + a.t[i];
    }
    return c;
}

// The inverse of a rigid transform, written out (R^T, -R^T t): exact transposition, no general inverse.
Frame inverse(const Frame &a) {
    Frame c{};
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) c.r[3 * i + j] = a.r[3 * j + i];
        c.t[i] = -(a.r[i] * a.t[0] + a.r[3 + i] * a.t[1] + a.r[6 + i] * a.t[2]);
    }
    return c;
}

void apply(const Frame &a, const double p[3], double out[3]) {
    for (int i = 0; i < 3; ++i) out[i] = a.r[3 * i] * p[0] + a.r[3 * i + 1] * p[1] + a.r[3 * i + 2] * p[2] + a.t[i];
}

} // namespace

std::vector<std::uint8_t> corroborated(const std::vector<PieceLink> &links, const ScanPlaces &reckoned, double radius,
                                       double drift) {
    std::vector<std::uint8_t> out(links.size(), 0);
    // The links between two pieces, grouped by their pieces (a group's members in link order).
    std::map<std::pair<std::int64_t, std::int64_t>, std::vector<std::size_t>> groups;
    for (std::size_t k = 0; k < links.size(); ++k) {
        const std::int64_t first = reckoned.piece[links[k].earlier], second = reckoned.piece[links[k].later];
        if (first == second)
            out[k] = 1;
        else
            groups[{first, second}].push_back(k);
    }
    std::vector<Frame> placed;
    std::vector<std::uint8_t> agree, best_row;
    for (const auto &group : groups) {
        const std::vector<std::size_t> &members = group.second;
        const std::size_t m = members.size();
        // Each link's own placing of its later scan in the earlier piece's frame.
        placed.clear();
        for (const std::size_t k : members) {
            const PieceLink &l = links[k];
            placed.push_back(compose(frame_of(&reckoned.poses[16 * l.earlier]), frame_of(l.transform)));
        }
        std::size_t best = 0, best_count = 0;
        for (std::size_t a = 0; a < m; ++a) {
            const PieceLink &la = links[members[a]];
            // Link a's placing of every later scan of the group: through the later piece's odometry.
            const Frame relay = compose(placed[a], inverse(frame_of(&reckoned.poses[16 * la.later])));
            agree.assign(m, 0);
            std::size_t count = 0;
            for (std::size_t b = 0; b < m; ++b) {
                const PieceLink &lb = links[members[b]];
                if (lb.later == la.later) continue;
                const double *pb = &reckoned.poses[16 * lb.later];
                const double where[3] = {pb[3], pb[7], pb[11]};
                double predicted[3];
                apply(relay, where, predicted);
                const double dx = predicted[0] - placed[b].t[0], dy = predicted[1] - placed[b].t[1],
                             dz = predicted[2] - placed[b].t[2];
                const double error = std::sqrt(dx * dx + dy * dy + dz * dz);
                const double allowed =
                    radius + drift * (std::fabs(reckoned.path[lb.earlier] - reckoned.path[la.earlier]) +
                                      std::fabs(reckoned.path[lb.later] - reckoned.path[la.later]));
                if (error <= allowed) {
                    agree[b] = 1;
                    ++count;
                }
            }
            if (count > best_count) {
                best = a;
                best_count = count;
                best_row = agree;
            }
        }
        if (best_count == 0) continue;
        out[members[best]] = 1;
        for (std::size_t b = 0; b < m; ++b)
            if (best_row[b]) out[members[b]] = 1;
    }
    return out;
}

KISSM_DETAIL_END
