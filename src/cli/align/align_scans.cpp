// SPDX-License-Identifier: MIT
#include "align_scans.hpp"

#include <fstream>
#include <iterator>
#include <map>

#include "batch/batch_pairs.hpp"
#include "cli_args.hpp"

namespace kissm_cli {

std::vector<Scan> parse_scans(const std::string &text, const std::string &name, const std::string &scans_file,
                              int32_t default_format) {
    std::vector<Scan> scans;
    std::map<std::string, size_t> line_of_name;
    std::vector<std::string> header;
    int scan_col = -1, file_col = -1, format_col = -1;
    size_t line_no = 0, start = 0;
    while (start < text.size()) {
        size_t end = text.find('\n', start);
        if (end == std::string::npos) end = text.size();
        std::string line = text.substr(start, end - start);
        start = end + 1;
        ++line_no;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (is_blank_or_comment_line(line)) continue;
        const std::string where = name + " line " + std::to_string(line_no);
        const std::vector<std::string> fields = split_tab_fields(line);
        if (header.empty()) {
            header = fields;
            scan_col = header_column(header, "scan", where);
            file_col = header_column(header, "file", where);
            format_col = header_column(header, "format", where);
            if (scan_col < 0 || file_col < 0) {
                throw UsageError(where + ": the header has no '" + (scan_col < 0 ? "scan" : "file") +
                                 "' column (expected tab-separated column names: scan, file and optionally format)");
            }
            continue;
        }
        if (fields.size() != header.size()) {
            throw UsageError(where + ": " + std::to_string(fields.size()) + " tab-separated fields, the header has " +
                             std::to_string(header.size()));
        }
        Scan scan;
        scan.line = line_no;
        scan.name = fields[static_cast<size_t>(scan_col)];
        const std::string &file = fields[static_cast<size_t>(file_col)];
        if (scan.name.empty() || file.empty()) {
            throw UsageError(where + ": empty " + (scan.name.empty() ? "scan name" : "file"));
        }
        const auto first = line_of_name.emplace(scan.name, line_no);
        if (!first.second) {
            throw UsageError(where + ": the scan '" + one_line(scan.name) + "' is named twice (line " +
                             std::to_string(first.first->second) + " too)");
        }
        scan.file = resolve_pair_path(scans_file, file);
        const std::string format = format_col >= 0 ? fields[static_cast<size_t>(format_col)] : std::string();
        scan.format = format.empty() ? default_format : parse_format(where + ": format", format);
        scans.push_back(scan);
    }
    if (header.empty()) {
        throw UsageError(name + ": no header line (expected tab-separated column names: scan, file and optionally "
                                "format)");
    }
    if (scans.empty()) throw UsageError(name + ": no scans (one line per scan after the header)");
    return scans;
}

std::vector<Scan> read_scans_file(const std::string &path, int32_t default_format) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw UsageError("cannot read the scans file '" + one_line(path) + "'");
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) throw UsageError("cannot read the scans file '" + one_line(path) + "'");
    return parse_scans(text, one_line(path), path, default_format);
}

} // namespace kissm_cli
