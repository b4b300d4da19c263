// SPDX-License-Identifier: MIT
#include "batch_resume.hpp"

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>

#include "cli_args.hpp"

namespace kissm_cli {

std::vector<DoneRecord> resume_results(const std::string &path, const std::vector<PairRow> &rows,
                                       const std::string &table, bool quiet) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return {};
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    in.close();
    const std::string name = "'" + one_line(path) + "'";
    const ResultsScan scan = scan_results(text, name);
    std::set<int64_t> seen;
    for (const DoneRecord &d : scan.done) {
        const std::string where = name + " line " + std::to_string(d.line);
        if (d.pair < 1 || d.pair > static_cast<int64_t>(rows.size())) {
            throw UsageError(where + " is pair " + std::to_string(d.pair) + ", but the " + table + " has " +
                             std::to_string(rows.size()) + " (results of another " + table + "?)");
        }
        const PairRow &row = rows[static_cast<size_t>(d.pair - 1)];
        if (d.source != row.source || d.target != row.target) {
            throw UsageError(where + ": pair " + std::to_string(d.pair) + " is '" + one_line(d.source) + "' to '" +
                             one_line(d.target) + "', but the " + table + "'s is '" + one_line(row.source) + "' to '" +
                             one_line(row.target) + "' (results of another " + table + "?)");
        }
        if (!seen.insert(d.pair).second) throw UsageError(where + " repeats pair " + std::to_string(d.pair));
    }
    if (scan.dropped_partial) {
        std::error_code ec;
        std::filesystem::resize_file(path, scan.keep_bytes, ec);
        if (ec) throw UsageError("cannot cut the partial last line off " + name + ": " + ec.message());
        if (!quiet)
            std::fprintf(stderr, "kissm: dropped the partial last line of %s (a run stopped while writing it)\n",
                         name.c_str());
    }
    return scan.done;
}

} // namespace kissm_cli
