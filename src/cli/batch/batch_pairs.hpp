// SPDX-License-Identifier: MIT
// `kissm batch`'s files: the pairs file it reads (a tab-separated table) and the results file it appends to
// (JSON Lines), scanned again by --resume. Kept apart from the run so that the unit tests reach them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace kissm_cli {

// One pair of the pairs file, its paths as written there.
struct PairRow {
    int64_t index = 0; // 1-based among the data rows: the results' "pair" field
    size_t line = 0;   // line number in the file, for messages
    std::string source, target;
    std::string gt; // the ground-truth transform file; empty when the row (or the file) has none
};

struct PairsTable {
    bool has_gt_column = false;
    std::vector<PairRow> rows;
};

// Parses a pairs file's text; `name` names it in messages. The first line that is neither blank nor a '#'
// comment is the header: tab-separated column names, among which `source` and `target` (required) and `gt`
// (optional); other columns are ignored. Every later line that is neither blank nor a comment is a pair with
// exactly as many tab-separated fields as the header; a trailing '\r' is ignored. Throws UsageError naming the
// line on any problem.
PairsTable parse_pairs(const std::string &text, const std::string &name);
// The same from a file (a UsageError when it cannot be read).
PairsTable read_pairs_file(const std::string &path);
// `path` as written in the pairs file: absolute as is, relative against the pairs file's folder (so that a
// pairs file and its clouds can move together, and the result does not depend on the working directory).
std::string resolve_pair_path(const std::string &pairs_file, const std::string &path);

// A finished pair's record in a results file: what --resume needs of it.
struct DoneRecord {
    int64_t pair = 0;
    std::string source, target;
    bool error = false; // "status": "error" (a per-pair input error); otherwise it ran
    bool valid = false;
    size_t line = 0; // line number in the results file
};

struct ResultsScan {
    std::vector<DoneRecord> done;
    uint64_t keep_bytes = 0;      // the complete records' bytes; what follows is a killed run's partial line
    bool dropped_partial = false; // there was such a line
};

// Scans a results file's text. A record is one line holding a JSON object with at least "pair" (an integer),
// "source", "target" and "status" (strings) and "valid" (a boolean). The last line is dropped (a run killed
// while writing it) when it has no newline or is not such a record; any other line that is not is a
// UsageError naming it (a file that is not batch results is never truncated).
ResultsScan scan_results(const std::string &text, const std::string &name);

} // namespace kissm_cli
