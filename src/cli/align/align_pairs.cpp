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
    std::vector<const DoneRecord *> by_pair(round1.size(), nullptr);
    for (const DoneRecord &record : records) {
        if (record.pair >= 1 && record.pair <= static_cast<int64_t>(round1.size())) {
            by_pair[static_cast<size_t>(record.pair - 1)] = &record;
        }
    }
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
    std::vector<double> steps(16 * (scans - 1), 0.0);
    std::vector<uint8_t> valid(scans - 1, 0);
    for (size_t k = 0; k < round1.size(); ++k) {
        const ScanPair &pair = round1[k];
        const DoneRecord *record = by_pair[k];
        if (pair.source != pair.target + 1 || !record || record->error || !record->valid) continue;
        double *step = &steps[16 * pair.target];
        if (record->transform.size() == 16)
            std::copy(record->transform.begin(), record->transform.end(), step);
        else
            std::fill(step, step + 16, std::numeric_limits<double>::quiet_NaN());
        valid[pair.target] = 1;
    }
    return candidates(steps.data(), valid.data(), nullptr);
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
