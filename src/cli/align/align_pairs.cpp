// SPDX-License-Identifier: MIT
#include "align_pairs.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

#include <kissm.h>

#include "cli_args.hpp"
#include "report.hpp"

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

std::vector<ScanPair> sequence_loops(size_t scans, const std::vector<ScanPair> &round1,
                                     const std::vector<DoneRecord> &records, const SequenceOptions &opt) {
    if (scans < 2 || opt.loops_per_scan <= 0 || opt.loop_gap <= 0) return {};
    const auto gap = static_cast<uint64_t>(opt.loop_gap), per_scan = static_cast<uint64_t>(opt.loops_per_scan);
    const auto candidates = [&](const double *steps, const uint8_t *valid, const double *priors) {
        uint64_t count = 0;
        int32_t status =
            kissm_sequence_loops(scans, steps, valid, priors, opt.loop_radius, gap, per_scan, nullptr, 0, &count);
        std::vector<uint64_t> found(2 * count);
        if (status == KISSM_OK)
            status = kissm_sequence_loops(scans, steps, valid, priors, opt.loop_radius, gap, per_scan, found.data(),
                                          count, &count);
        if (status != KISSM_OK) throw UsageError("cannot choose the loop candidates: " + library_error(status));
        std::vector<ScanPair> pairs(count);
        for (size_t k = 0; k < count; ++k)
            pairs[k] = {static_cast<size_t>(found[2 * k]), static_cast<size_t>(found[2 * k + 1])};
        return pairs;
    };
    if (!opt.priors.empty()) return candidates(nullptr, nullptr, opt.priors.data());
    const SequenceChain chain = sequence_chain(scans, round1, records);
    return candidates(chain.steps.data(), chain.valid.data(), nullptr);
}

SequenceChain sequence_chain(size_t scans, const std::vector<ScanPair> &round1,
                             const std::vector<DoneRecord> &records) {
    SequenceChain chain;
    if (scans < 2) return chain;
    std::vector<const DoneRecord *> by_pair(round1.size(), nullptr);
    for (const DoneRecord &record : records) {
        if (record.pair >= 1 && record.pair <= static_cast<int64_t>(round1.size())) {
            by_pair[static_cast<size_t>(record.pair - 1)] = &record;
        }
    }
    chain.steps.assign(16 * (scans - 1), 0.0);
    chain.valid.assign(scans - 1, 0);
    for (size_t k = 0; k < round1.size(); ++k) {
        const ScanPair &pair = round1[k];
        const DoneRecord *record = by_pair[k];
        if (pair.source != pair.target + 1 || !record || record->error || !record->valid) continue;
        double *step = &chain.steps[16 * pair.target];
        if (record->transform.size() == 16)
            std::copy(record->transform.begin(), record->transform.end(), step);
        else
            std::fill(step, step + 16, std::numeric_limits<double>::quiet_NaN());
        chain.valid[pair.target] = 1;
    }
    return chain;
}

std::vector<size_t> session_starts(const std::vector<Scan> &scans) {
    std::vector<size_t> starts;
    std::map<std::string, size_t> first_line;
    for (size_t k = 0; k < scans.size(); ++k) {
        if (k > 0 && scans[k].session == scans[k - 1].session) continue;
        const auto seen = first_line.emplace(scans[k].session, scans[k].line);
        if (!seen.second) {
            throw UsageError("scans file line " + std::to_string(scans[k].line) + ": session '" +
                             one_line(scans[k].session) + "' began at line " + std::to_string(seen.first->second) +
                             " and another came between; list each session's scans together, in acquisition order");
        }
        starts.push_back(k);
    }
    starts.push_back(scans.size());
    return starts;
}

std::vector<ScanPair> session_odometry(const std::vector<size_t> &starts) {
    std::vector<ScanPair> pairs;
    for (size_t s = 0; s + 1 < starts.size(); ++s)
        for (size_t k = starts[s]; k + 1 < starts[s + 1]; ++k) pairs.push_back({k + 1, k, true});
    return pairs;
}

std::vector<ScanPair> session_loops_and_grid(const std::vector<size_t> &starts, const std::vector<ScanPair> &round1,
                                             const std::vector<DoneRecord> &records, const SequenceOptions &opt,
                                             size_t stride) {
    // The whole list dead-reckoned: no odometry joins two sessions, so each starts a piece of its own, as Python
    // chains each session alone.
    const size_t n = starts.back();
    const std::vector<ScanPair> loops = sequence_loops(n, round1, records, opt);
    std::vector<ScanPair> pairs;
    size_t next = 0;
    for (size_t s = 0; s + 1 < starts.size(); ++s) {
        for (; next < loops.size() && loops[next].source < starts[s + 1]; ++next) pairs.push_back(loops[next]);
        for (size_t t = 0; t < s; ++t)
            for (size_t j = starts[s]; j < starts[s + 1]; j += stride)
                for (size_t i = starts[t]; i < starts[t + 1]; i += stride) pairs.push_back({j, i});
    }
    return pairs;
}

std::vector<ScanPair> sessions_across(const std::vector<size_t> &starts, const std::vector<ScanPair> &so_far,
                                      const std::vector<double> &poses, const std::vector<uint8_t> &placed,
                                      const SequenceOptions &opt) {
    const size_t n = starts.back();
    std::vector<size_t> session(n);
    for (size_t s = 0; s + 1 < starts.size(); ++s)
        for (size_t k = starts[s]; k < starts[s + 1]; ++k) session[k] = s;
    std::vector<std::pair<size_t, size_t>> done;
    for (const ScanPair &p : so_far) done.push_back({p.source, p.target});
    std::sort(done.begin(), done.end());
    std::vector<ScanPair> pairs;
    std::vector<std::pair<double, size_t>> near;
    for (size_t k = 0; k < n; ++k) {
        if (!placed[k]) continue;
        near.clear();
        for (size_t e = 0; e < n; ++e) {
            if (!placed[e] || session[e] >= session[k]) continue;
            const double dx = poses[16 * e + 3] - poses[16 * k + 3], dy = poses[16 * e + 7] - poses[16 * k + 7],
                         dz = poses[16 * e + 11] - poses[16 * k + 11];
            const double d = std::sqrt(dx * dx + dy * dy + dz * dz);
            if (d <= opt.loop_radius) near.push_back({d, e});
        }
        std::sort(near.begin(), near.end());
        const size_t keep = std::min(near.size(), static_cast<size_t>(std::max(opt.loops_per_scan, 0)));
        for (size_t c = 0; c < keep; ++c) {
            if (!std::binary_search(done.begin(), done.end(), std::make_pair(k, near[c].second)))
                pairs.push_back({k, near[c].second});
        }
    }
    return pairs;
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
