// SPDX-License-Identifier: MIT
#include "align_pairs.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

#include "cli_args.hpp"

namespace kissm_cli {

std::vector<ScanPair> all_pairs(size_t scans) {
    std::vector<ScanPair> pairs;
    for (size_t i = 0; i < scans; ++i) {
        for (size_t j = i + 1; j < scans; ++j) pairs.push_back({j, i});
    }
    return pairs;
}

std::vector<ScanPair> sequence_candidates(size_t scans, const SequenceOptions &opt) {
    std::vector<ScanPair> pairs;
    const size_t window = opt.window > 0 ? static_cast<size_t>(opt.window) : 0;
    for (size_t i = 0; i < scans; ++i) {
        for (size_t k = 1; k <= window && i + k < scans; ++k) pairs.push_back({i + k, i});
    }
    return pairs;
}

namespace {

// a @ b for row-major 4x4s as numpy's matmul computes it here (OpenBLAS's dgemm kernel: each entry a fused
// multiply-add chain over the inner index, starting from 0).
void matmul_like_numpy(const double a[16], const double b[16], double out[16]) {
    double c[16];
    for (int r = 0; r < 4; ++r) {
        for (int col = 0; col < 4; ++col) {
            double s = 0.0;
            for (int m = 0; m < 4; ++m) s = std::fma(a[4 * r + m], b[4 * m + col], s);
            c[4 * r + col] = s;
        }
    }
    std::copy(c, c + 16, out);
}

void set_identity(double pose[16]) {
    for (int i = 0; i < 16; ++i) pose[i] = i % 5 == 0 ? 1.0 : 0.0;
}

} // namespace

DeadReckoning dead_reckoned(const std::vector<const double *> &steps, size_t scans) {
    DeadReckoning d;
    d.positions.assign(3 * scans, 0.0);
    d.path.assign(scans, 0.0);
    d.piece.assign(scans, 0);
    double pose[16];
    set_identity(pose);
    for (size_t k = 0; k + 1 < scans; ++k) {
        const double *step = k < steps.size() ? steps[k] : nullptr;
        if (step) {
            matmul_like_numpy(pose, step, pose);
            const double x = step[3], y = step[7], z = step[11];
            const double length = std::sqrt(x * x + y * y + z * z);
            d.path[k + 1] = d.path[k] + length;
            d.piece[k + 1] = d.piece[k];
        } else {
            set_identity(pose);
            d.piece[k + 1] = d.piece[k] + 1;
        }
        for (int i = 0; i < 3; ++i) d.positions[3 * (k + 1) + static_cast<size_t>(i)] = pose[4 * i + 3];
    }
    return d;
}

std::vector<ScanPair> loop_candidates(const DeadReckoning &where, double radius, size_t gap, size_t per_scan,
                                      double drift) {
    const size_t n = where.path.size();
    std::vector<bool> known(n);
    for (size_t k = 0; k < n; ++k) {
        const double *p = &where.positions[3 * k];
        known[k] = std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
    }
    std::vector<ScanPair> out;
    if (gap == 0 || per_scan == 0) return out;
    for (size_t j = gap; j < n; ++j) {
        if (!known[j]) continue;
        const double *pj = &where.positions[3 * j];
        std::vector<std::pair<double, size_t>> near;
        for (size_t i = 0; i + gap <= j; ++i) {
            const double *pi = &where.positions[3 * i];
            const double dx = pi[0] - pj[0], dy = pi[1] - pj[1], dz = pi[2] - pj[2];
            const double distance = std::sqrt(dx * dx + dy * dy + dz * dz);
            const double allowed = radius + drift * std::fabs(where.path[j] - where.path[i]);
            if (known[i] && where.piece[i] == where.piece[j] && distance <= allowed) near.push_back({distance, i});
        }
        std::sort(near.begin(), near.end());
        if (near.size() > per_scan) near.resize(per_scan);
        std::vector<size_t> chosen;
        for (const auto &c : near) chosen.push_back(c.second);
        std::sort(chosen.begin(), chosen.end());
        for (const size_t i : chosen) out.push_back({j, i});
    }
    return out;
}

std::vector<ScanPair> sequence_loops(size_t scans, const std::vector<ScanPair> &round1,
                                     const std::vector<DoneRecord> &records, const SequenceOptions &opt) {
    if (scans < 2 || opt.loops_per_scan <= 0 || opt.loop_gap <= 0) return {};
    std::vector<const DoneRecord *> by_pair(round1.size(), nullptr);
    for (const DoneRecord &record : records) {
        if (record.pair >= 1 && record.pair <= static_cast<int64_t>(round1.size())) {
            by_pair[static_cast<size_t>(record.pair - 1)] = &record;
        }
    }
    std::vector<std::vector<double>> matrices(scans - 1);
    std::vector<const double *> steps(scans - 1, nullptr);
    for (size_t k = 0; k < round1.size(); ++k) {
        const ScanPair &pair = round1[k];
        const DoneRecord *record = by_pair[k];
        if (pair.source != pair.target + 1 || !record || record->error || !record->valid) continue;
        // A valid record without a transform chains NaN, as a valid result's NaN transform in Python would.
        std::vector<double> &m = matrices[pair.target];
        m = record->transform;
        if (m.size() != 16) m.assign(16, std::numeric_limits<double>::quiet_NaN());
        steps[pair.target] = m.data();
    }
    return loop_candidates(dead_reckoned(steps, scans), opt.loop_radius, static_cast<size_t>(opt.loop_gap),
                           static_cast<size_t>(opt.loops_per_scan), kLoopDrift);
}

std::vector<ScanPair> pairs_from_file(const std::string &path, const std::vector<Scan> &scans) {
    std::map<std::string, size_t> position;
    for (size_t k = 0; k < scans.size(); ++k) position[scans[k].name] = k;
    const PairsTable table = read_pairs_file(path);
    std::vector<ScanPair> pairs;
    for (const PairRow &row : table.rows) {
        const std::string where = one_line(path) + " line " + std::to_string(row.line);
        ScanPair pair;
        for (const bool is_source : {true, false}) {
            const std::string &name = is_source ? row.source : row.target;
            const auto found = position.find(name);
            if (found == position.end()) {
                throw UsageError(where + ": unknown scan '" + one_line(name) + "' (the " +
                                 (is_source ? "source" : "target") + " names no scan of the scans file)");
            }
            (is_source ? pair.source : pair.target) = found->second;
        }
        if (pair.source == pair.target) {
            throw UsageError(where + ": the scan '" + one_line(row.source) + "' is paired with itself");
        }
        pairs.push_back(pair);
    }
    return pairs;
}

std::vector<PairRow> pair_rows(const std::vector<ScanPair> &pairs, const std::vector<Scan> &scans) {
    std::vector<PairRow> rows;
    rows.reserve(pairs.size());
    for (const ScanPair &pair : pairs) {
        const Scan &source = scans[pair.source], &target = scans[pair.target];
        PairRow row;
        row.index = static_cast<int64_t>(rows.size()) + 1;
        row.source = source.name;
        row.target = target.name;
        row.source_file = source.file;
        row.target_file = target.file;
        row.source_file_format = source.format;
        row.target_file_format = target.format;
        rows.push_back(row);
    }
    return rows;
}

} // namespace kissm_cli
