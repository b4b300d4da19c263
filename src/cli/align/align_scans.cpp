// SPDX-License-Identifier: MIT
#include "align_scans.hpp"

#include <map>

#include "batch/batch_pairs.hpp"
#include "cli_args.hpp"

namespace kissm_cli {

std::vector<Scan> parse_scans(const std::string &text, const std::string &name, const std::string &scans_file,
                              int32_t default_format) {
    const TextTable t = parse_text_table(text, name);
    if (t.header_where.empty()) {
        throw UsageError(name + ": no header line (expected tab-separated column names: scan, file and optionally "
                                "format)");
    }
    const int scan_col = header_column(t.header, "scan", t.header_where);
    const int file_col = header_column(t.header, "file", t.header_where);
    const int format_col = header_column(t.header, "format", t.header_where);
    const int session_col = header_column(t.header, "session", t.header_where);
    if (scan_col < 0 || file_col < 0) {
        throw UsageError(t.header_where + ": the header has no '" + (scan_col < 0 ? "scan" : "file") +
                         "' column (expected tab-separated column names: scan, file and optionally format)");
    }
    std::vector<Scan> scans;
    std::map<std::string, size_t> line_of_name;
    for (const TextTable::Row &r : t.rows) {
        Scan scan;
        scan.line = r.line;
        scan.name = r.fields[static_cast<size_t>(scan_col)];
        const std::string &file = r.fields[static_cast<size_t>(file_col)];
        if (scan.name.empty() || file.empty()) {
            throw UsageError(r.where + ": empty " + (scan.name.empty() ? "scan name" : "file"));
        }
        const auto first = line_of_name.emplace(scan.name, r.line);
        if (!first.second) {
            throw UsageError(r.where + ": the scan '" + one_line(scan.name) + "' is named twice (line " +
                             std::to_string(first.first->second) + " too)");
        }
        scan.file = resolve_pair_path(scans_file, file);
        const std::string format = format_col >= 0 ? r.fields[static_cast<size_t>(format_col)] : std::string();
        scan.format = format.empty() ? default_format : parse_format(r.where + ": format", format);
        if (session_col >= 0) scan.session = r.fields[static_cast<size_t>(session_col)];
        scans.push_back(scan);
    }
    if (scans.empty()) throw UsageError(name + ": no scans (one line per scan after the header)");
    return scans;
}

std::vector<Scan> read_scans_file(const std::string &path, int32_t default_format) {
    return parse_scans(read_table_text(path, "scans file"), one_line(path), path, default_format);
}

} // namespace kissm_cli
