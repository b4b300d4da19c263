// SPDX-License-Identifier: MIT
#include "align_priors.hpp"

#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>

#include "batch/batch_pairs.hpp"
#include "cli_args.hpp"

namespace kissm_cli {

std::vector<double> parse_priors(const std::string &text, const std::string &name, const std::vector<Scan> &scans) {
    const TextTable t = parse_text_table(text, name);
    const std::string expected = " (expected the poses table of --out: scan, then T00 T01 ... T23)";
    if (t.header_where.empty()) throw UsageError(name + ": no header line" + expected);
    const int scan_col = header_column(t.header, "scan", t.header_where);
    if (scan_col < 0) throw UsageError(t.header_where + ": the header has no 'scan' column" + expected);
    int entry_col[12];
    for (int k = 0; k < 12; ++k) {
        const std::string column = "T" + std::to_string(k / 4) + std::to_string(k % 4);
        entry_col[k] = header_column(t.header, column.c_str(), t.header_where);
        if (entry_col[k] < 0)
            throw UsageError(t.header_where + ": the header has no '" + column + "' column" + expected);
    }
    std::map<std::string, size_t> position;
    for (size_t k = 0; k < scans.size(); ++k) position[scans[k].name] = k;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    std::vector<double> priors(16 * scans.size(), nan);
    std::map<size_t, size_t> line_of;
    for (const TextTable::Row &r : t.rows) {
        const std::string &scan = r.fields[static_cast<size_t>(scan_col)];
        const auto found = position.find(scan);
        if (found == position.end()) {
            throw UsageError(r.where + ": unknown scan '" + one_line(scan) + "' (the scans file names no such scan)");
        }
        const auto first = line_of.emplace(found->second, r.line);
        if (!first.second) {
            throw UsageError(r.where + ": the scan '" + one_line(scan) + "' is given twice (line " +
                             std::to_string(first.first->second) + " too)");
        }
        double m[16] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1};
        bool finite = true;
        for (int k = 0; k < 12; ++k) {
            const std::string &field = r.fields[static_cast<size_t>(entry_col[k])];
            char *end = nullptr;
            const double v = std::strtod(field.c_str(), &end);
            if (field.empty() || end != field.c_str() + field.size()) {
                throw UsageError(r.where + ": T" + std::to_string(k / 4) + std::to_string(k % 4) + " is '" +
                                 one_line(field) + "', not a number");
            }
            m[k] = v;
            finite = finite && std::isfinite(v);
        }
        if (finite) std::copy(m, m + 16, priors.begin() + static_cast<std::ptrdiff_t>(16 * found->second));
    }
    return priors;
}

std::vector<double> read_priors(const std::string &path, const std::vector<Scan> &scans) {
    return parse_priors(read_table_text(path, "priors file"), one_line(path), scans);
}

} // namespace kissm_cli
