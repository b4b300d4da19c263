// SPDX-License-Identifier: MIT
#include "batch_pairs.hpp"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>

#include "cli_args.hpp"

namespace kissm_cli {
namespace {

std::string trimmed(const std::string &s) {
    const size_t a = s.find_first_not_of(" \t");
    if (a == std::string::npos) return std::string();
    return s.substr(a, s.find_last_not_of(" \t") - a + 1);
}

// Reads one results record's members. Only the members --resume needs are kept (and with_poses, the ones
// `kissm align` builds its graph from); the others are checked to be JSON and skipped. Every method returns false on
// anything that is not JSON.
class RecordReader {
public:
    RecordReader(const std::string &text, bool with_poses) : s_(text), with_poses_(with_poses) {}

    bool read(DoneRecord *out) {
        bool have_pair = false, have_source = false, have_target = false, have_status = false, have_valid = false;
        if (!consume('{')) return false;
        if (consume('}')) return false; // no members
        do {
            std::string key;
            if (!string_value(&key) || !consume(':')) return false;
            if (key == "pair") {
                if (!integer_value(&out->pair)) return false;
                have_pair = true;
            } else if (key == "source") {
                if (!string_value(&out->source)) return false;
                have_source = true;
            } else if (key == "target") {
                if (!string_value(&out->target)) return false;
                have_target = true;
            } else if (key == "status") {
                std::string status;
                if (!string_value(&status)) return false;
                out->error = status == "error";
                have_status = true;
            } else if (key == "valid") {
                if (!bool_value(&out->valid)) return false;
                have_valid = true;
            } else if (with_poses_ && key == "transform") {
                if (!matrix_or_skip(4, 4, &out->transform)) return false;
            } else if (with_poses_ && key == "information") {
                if (!matrix_or_skip(6, 6, &out->information)) return false;
            } else if (with_poses_ && key == "rotation_uncertainty") {
                if (!number_or_skip(&out->rotation_uncertainty)) return false;
            } else if (with_poses_ && key == "noise_bound") {
                if (!number_or_skip(&out->noise_bound)) return false;
            } else if (!skip_value(0)) {
                return false;
            }
        } while (consume(','));
        if (!consume('}')) return false;
        skip_space();
        return at_ == s_.size() && have_pair && have_source && have_target && have_status && have_valid;
    }

private:
    void skip_space() {
        while (at_ < s_.size() && (s_[at_] == ' ' || s_[at_] == '\t' || s_[at_] == '\r')) ++at_;
    }
    bool consume(char c) {
        skip_space();
        if (at_ >= s_.size() || s_[at_] != c) return false;
        ++at_;
        return true;
    }
    bool literal(const char *word) {
        skip_space();
        const std::string w(word);
        if (s_.compare(at_, w.size(), w) != 0) return false;
        at_ += w.size();
        return true;
    }
    bool bool_value(bool *v) {
        if (literal("true")) {
            *v = true;
        } else if (literal("false")) {
            *v = false;
        } else {
            return false;
        }
        return true;
    }
    bool integer_value(int64_t *v) {
        skip_space();
        const size_t start = at_;
        if (at_ < s_.size() && s_[at_] == '-') ++at_;
        while (at_ < s_.size() && s_[at_] >= '0' && s_[at_] <= '9') ++at_;
        if (at_ == start || at_ - start > 18) return false;
        *v = std::strtoll(s_.c_str() + start, nullptr, 10);
        return true;
    }
    bool number_value(double *v = nullptr) {
        skip_space();
        const char *begin = s_.c_str() + at_;
        char *end = nullptr;
        const double parsed = std::strtod(begin, &end);
        if (end == begin) return false;
        at_ += static_cast<size_t>(end - begin);
        if (v) *v = parsed;
        return true;
    }
    // A number, or null as NaN (the writer's spelling of a non-finite number). The writer prints the shortest
    // text that reads back to the same double, so strtod gives the very bits the run had.
    bool number_or_null(double *v) {
        if (literal("null")) {
            *v = std::numeric_limits<double>::quiet_NaN();
            return true;
        }
        return number_value(v);
    }
    // A rows x cols list of lists of numbers (or nulls) into *out, row-major. Anything else that is JSON
    // (null, another shape) is skipped and leaves *out empty: a record is judged by batch's rules alone.
    bool matrix_or_skip(int rows, int cols, std::vector<double> *out) {
        const size_t start = at_;
        std::vector<double> values;
        bool ok = consume('[');
        for (int r = 0; ok && r < rows; ++r) {
            ok = (r == 0 || consume(',')) && consume('[');
            for (int c = 0; ok && c < cols; ++c) {
                double v = 0.0;
                ok = (c == 0 || consume(',')) && number_or_null(&v);
                values.push_back(v);
            }
            ok = ok && consume(']');
        }
        if (ok && consume(']')) {
            *out = values;
            return true;
        }
        at_ = start;
        out->clear();
        return skip_value(0);
    }
    bool number_or_skip(double *v) {
        const size_t start = at_;
        if (number_or_null(v)) return true;
        at_ = start;
        *v = std::numeric_limits<double>::quiet_NaN();
        return skip_value(0);
    }
    static int hex_digit(char c) {
        if (c >= '0' && c <= '9') return c - '0';
        if (c >= 'a' && c <= 'f') return c - 'a' + 10;
        if (c >= 'A' && c <= 'F') return c - 'A' + 10;
        return -1;
    }
    // A string; \uXXXX escapes are decoded to UTF-8 (surrogate pairs are not needed: the tool writes \u only
    // for control characters).
    bool string_value(std::string *out) {
        if (!consume('"')) return false;
        out->clear();
        while (at_ < s_.size()) {
            const char c = s_[at_++];
            if (c == '"') return true;
            if (static_cast<unsigned char>(c) < 0x20) return false;
            if (c != '\\') {
                out->push_back(c);
                continue;
            }
            if (at_ >= s_.size()) return false;
            const char e = s_[at_++];
            switch (e) {
            case '"': out->push_back('"'); break;
            case '\\': out->push_back('\\'); break;
            case '/': out->push_back('/'); break;
            case 'b': out->push_back('\b'); break;
            case 'f': out->push_back('\f'); break;
            case 'n': out->push_back('\n'); break;
            case 'r': out->push_back('\r'); break;
            case 't': out->push_back('\t'); break;
            case 'u': {
                if (at_ + 4 > s_.size()) return false;
                unsigned code = 0;
                for (int i = 0; i < 4; ++i) {
                    const int d = hex_digit(s_[at_++]);
                    if (d < 0) return false;
                    code = code * 16 + static_cast<unsigned>(d);
                }
                if (code < 0x80) {
                    out->push_back(static_cast<char>(code));
                } else if (code < 0x800) {
                    out->push_back(static_cast<char>(0xC0 | (code >> 6)));
                    out->push_back(static_cast<char>(0x80 | (code & 0x3F)));
                } else {
                    out->push_back(static_cast<char>(0xE0 | (code >> 12)));
                    out->push_back(static_cast<char>(0x80 | ((code >> 6) & 0x3F)));
                    out->push_back(static_cast<char>(0x80 | (code & 0x3F)));
                }
                break;
            }
            default: return false;
            }
        }
        return false; // unterminated
    }
    bool skip_value(int depth) {
        if (depth > 32) return false;
        skip_space();
        if (at_ >= s_.size()) return false;
        const char c = s_[at_];
        if (c == '"') {
            std::string ignored;
            return string_value(&ignored);
        }
        if (c == '{' || c == '[') {
            const char close = c == '{' ? '}' : ']';
            ++at_;
            if (consume(close)) return true;
            do {
                if (c == '{') {
                    std::string ignored;
                    if (!string_value(&ignored) || !consume(':')) return false;
                }
                if (!skip_value(depth + 1)) return false;
            } while (consume(','));
            return consume(close);
        }
        if (literal("true") || literal("false") || literal("null")) return true;
        return number_value();
    }

    const std::string &s_;
    bool with_poses_ = false;
    size_t at_ = 0;
};

} // namespace

std::vector<std::string> split_tab_fields(const std::string &line) {
    std::vector<std::string> fields;
    size_t start = 0;
    for (;;) {
        const size_t tab = line.find('\t', start);
        fields.push_back(line.substr(start, tab == std::string::npos ? std::string::npos : tab - start));
        if (tab == std::string::npos) return fields;
        start = tab + 1;
    }
}

bool is_blank_or_comment_line(const std::string &line) {
    const std::string t = trimmed(line);
    return t.empty() || t[0] == '#';
}

int header_column(const std::vector<std::string> &header, const char *column, const std::string &where) {
    int at = -1;
    for (size_t i = 0; i < header.size(); ++i) {
        if (trimmed(header[i]) != column) continue;
        if (at >= 0) throw UsageError(where + ": the header names the column '" + column + "' twice");
        at = static_cast<int>(i);
    }
    return at;
}

TextTable parse_text_table(const std::string &text, const std::string &name) {
    TextTable table;
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
        std::vector<std::string> fields = split_tab_fields(line);
        if (table.header_where.empty()) {
            table.header = std::move(fields);
            table.header_where = where;
            continue;
        }
        if (fields.size() != table.header.size()) {
            throw UsageError(where + ": " + std::to_string(fields.size()) + " tab-separated fields, the header has " +
                             std::to_string(table.header.size()));
        }
        table.rows.push_back({line_no, where, std::move(fields)});
    }
    return table;
}

std::string read_table_text(const std::string &path, const std::string &what) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw UsageError("cannot read the " + what + " '" + one_line(path) + "'");
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) throw UsageError("cannot read the " + what + " '" + one_line(path) + "'");
    return text;
}

PairsTable parse_pairs(const std::string &text, const std::string &name) {
    const TextTable t = parse_text_table(text, name);
    if (t.header_where.empty()) {
        throw UsageError(name + ": no header line (expected tab-separated column names: source, target and "
                                "optionally gt)");
    }
    const int source_col = header_column(t.header, "source", t.header_where);
    const int target_col = header_column(t.header, "target", t.header_where);
    const int gt_col = header_column(t.header, "gt", t.header_where);
    const int format_col = header_column(t.header, "format", t.header_where);
    if (source_col < 0 || target_col < 0) {
        throw UsageError(t.header_where + ": the header has no '" + (source_col < 0 ? "source" : "target") +
                         "' column (expected tab-separated column names: source, target and optionally gt)");
    }
    PairsTable table;
    table.has_gt_column = gt_col >= 0;
    for (const TextTable::Row &r : t.rows) {
        PairRow row;
        row.index = static_cast<int64_t>(table.rows.size()) + 1;
        row.line = r.line;
        row.source = r.fields[static_cast<size_t>(source_col)];
        row.target = r.fields[static_cast<size_t>(target_col)];
        if (gt_col >= 0) row.gt = r.fields[static_cast<size_t>(gt_col)];
        if (format_col >= 0 && !trimmed(r.fields[static_cast<size_t>(format_col)]).empty())
            row.format = parse_format(r.where + ": format", trimmed(r.fields[static_cast<size_t>(format_col)]));
        if (row.source.empty() || row.target.empty()) {
            throw UsageError(r.where + ": empty " + (row.source.empty() ? "source" : "target") + " path");
        }
        table.rows.push_back(row);
    }
    return table;
}

PairsTable read_pairs_file(const std::string &path) {
    return parse_pairs(read_table_text(path, "pairs file"), one_line(path));
}

std::string resolve_pair_path(const std::string &pairs_file, const std::string &path) {
    const std::filesystem::path p(path);
    if (p.is_absolute()) return path;
    return (std::filesystem::path(pairs_file).parent_path() / p).string();
}

ResultsScan scan_results(const std::string &text, const std::string &name, bool with_poses) {
    ResultsScan scan;
    size_t start = 0, line_no = 0;
    while (start < text.size()) {
        const size_t newline = text.find('\n', start);
        const bool last = newline == std::string::npos || newline + 1 == text.size();
        const size_t end = newline == std::string::npos ? text.size() : newline;
        ++line_no;
        DoneRecord record;
        record.line = line_no;
        const bool ok =
            newline != std::string::npos && RecordReader(text.substr(start, end - start), with_poses).read(&record);
        if (!ok) {
            if (last) {
                scan.dropped_partial = true;
                return scan;
            }
            throw UsageError(name + " line " + std::to_string(line_no) +
                             " is not a kissm batch record (a JSON object with pair, source, target, status and "
                             "valid); not resuming into it");
        }
        scan.done.push_back(record);
        start = end + 1;
        scan.keep_bytes = start;
    }
    return scan;
}

} // namespace kissm_cli
