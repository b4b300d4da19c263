// SPDX-License-Identifier: MIT
// `kissm batch`'s files: the pairs file it reads (a tab-separated table) and the results file it appends to
// (JSON Lines), scanned again by --resume. Kept apart from the run so that the unit tests reach them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace kissm_cli {

// One pair of the pairs file, its paths as written there.
struct PairRow {
    int64_t index = 0; // 1-based among the data rows: the results' "pair" field
    size_t line = 0;   // line number in the file, for messages
    std::string source, target;
    std::string gt; // the ground-truth transform file; empty when the row (or the file) has none
    // `kissm align`'s rows name scans, not files: source and target are the scans' names (what the results
    // record), and these their files (already resolved) and KISSM_FORMAT_* formats. Empty for `kissm batch`,
    // whose source and target are the paths, resolved against the pairs file and read with the run's formats.
    std::string source_file, target_file;
    int32_t source_file_format = 0, target_file_format = 0;
    // `kissm batch`: the row's `format` column (a KISSM_FORMAT_* for both clouds, over the run's --format), or -1
    // when the file has no such column or the row leaves it empty.
    int32_t format = -1;
};

struct PairsTable {
    bool has_gt_column = false;
    std::vector<PairRow> rows;
};

// Parses a pairs file's text; `name` names it in messages. The first line that is neither blank nor a '#'
// comment is the header: tab-separated column names, among which `source` and `target` (required), `gt` and
// `format` (optional: a --format name for both clouds of the row); other columns are ignored. Every later line that is
// neither blank nor a comment is a pair with exactly as many tab-separated fields as the header; a trailing '\r' is
// ignored. Throws UsageError naming the line on any problem.
PairsTable parse_pairs(const std::string &text, const std::string &name);
// The same from a file (a UsageError when it cannot be read).
PairsTable read_pairs_file(const std::string &path);
// The table pieces parse_pairs uses, shared with `kissm align`'s scans file: a line's tab-separated fields; a
// blank or '#' comment line; a column's position in the header (-1 when absent; a UsageError at `where` when
// it is named twice).
std::vector<std::string> split_tab_fields(const std::string &line);
bool is_blank_or_comment_line(const std::string &line);
int header_column(const std::vector<std::string> &header, const char *column, const std::string &where);
// A whole table: blank and '#' lines skipped, the first other line the header (empty when there is none), every
// later line a row with exactly as many fields as the header (else a UsageError naming the line), a trailing '\r'
// ignored. `name` names the text in each row's `where` ("NAME line N").
struct TextTable {
    struct Row {
        size_t line = 0;
        std::string where;
        std::vector<std::string> fields;
    };
    std::vector<std::string> header;
    std::string header_where;
    std::vector<Row> rows;
};
TextTable parse_text_table(const std::string &text, const std::string &name);
// A file's bytes; a UsageError "cannot read the WHAT 'PATH'" when it cannot be read.
std::string read_table_text(const std::string &path, const std::string &what);
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
    // Read only with scan_results(..., with_poses = true) (`kissm align` builds its pose graph from them):
    // "transform" (16 row-major numbers) and "information" (36), empty when the member is absent, null or not
    // such a matrix (a null entry reads as NaN); "rotation_uncertainty" and "noise_bound", NaN when absent or
    // null.
    std::vector<double> transform, information;
    double rotation_uncertainty = std::numeric_limits<double>::quiet_NaN();
    double noise_bound = std::numeric_limits<double>::quiet_NaN();
};

struct ResultsScan {
    std::vector<DoneRecord> done;
    uint64_t keep_bytes = 0;      // the complete records' bytes; what follows is a killed run's partial line
    bool dropped_partial = false; // there was such a line
};

// Scans a results file's text. A record is one line holding a JSON object with at least "pair" (an integer),
// "source", "target" and "status" (strings) and "valid" (a boolean). The last line is dropped (a run killed
// while writing it) when it has no newline or is not such a record; any other line that is not is a
// UsageError naming it (a file that is not batch results is never truncated). with_poses: also read the
// records' pose members (DoneRecord); a member that is not the expected shape is skipped as any other.
ResultsScan scan_results(const std::string &text, const std::string &name, bool with_poses = false);

} // namespace kissm_cli
