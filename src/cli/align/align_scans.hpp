// SPDX-License-Identifier: MIT
// `kissm align`'s scans file: one row per scan, its name, its file and optionally its format, in the layout of
// ../shared/data's multi-scan sets (scans.tsv).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace kissm_cli {

struct Scan {
    std::string name;    // the "scan" column: how the results, the pairs file and the outputs name it
    std::string file;    // resolved against the scans file's folder (absolute paths as they are)
    int32_t format = 0;  // KISSM_FORMAT_*
    std::string session; // the optional "session" column (--pairs sessions)
    size_t line = 0;     // in the scans file, for messages
};

// Parses a scans file's text; `name` names it in messages and `scans_file` is its path (relative files are
// resolved against its folder). As `kissm batch`'s pairs file: blank and '#' lines are ignored, the first
// other line is the header (tab-separated: `scan` and `file` required, `format` optional, others ignored),
// every later line one scan with as many fields as the header, a trailing '\r' ignored. An empty or absent
// format is `default_format` (--format). An optional `session` column names each scan's session. Throws UsageError
// naming the line: a missing column, an empty name or file, a name given twice, an unknown format, no scan at all.
std::vector<Scan> parse_scans(const std::string &text, const std::string &name, const std::string &scans_file,
                              int32_t default_format);
// The same from the file (a UsageError when it cannot be read).
std::vector<Scan> read_scans_file(const std::string &path, int32_t default_format);

} // namespace kissm_cli
