// SPDX-License-Identifier: MIT
#include "align_pairs.hpp"

#include <map>

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
