// SPDX-License-Identifier: MIT
#include "json_writer.hpp"

#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace kissm_cli {

std::string JsonWriter::escape(const std::string &text) {
    std::string out;
    out.reserve(text.size() + 2);
    out.push_back('"');
    for (char ch : text) {
        const unsigned char c = static_cast<unsigned char>(ch);
        switch (c) {
        case '"': out += "\\\""; break;
        case '\\': out += "\\\\"; break;
        case '\b': out += "\\b"; break;
        case '\f': out += "\\f"; break;
        case '\n': out += "\\n"; break;
        case '\r': out += "\\r"; break;
        case '\t': out += "\\t"; break;
        default:
            if (c < 0x20 || c == 0x7F) {
                char buf[8];
                std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(c));
                out += buf;
            } else {
                out.push_back(ch);
            }
        }
    }
    out.push_back('"');
    return out;
}

std::string JsonWriter::number(double v) {
    if (!std::isfinite(v)) return "null";
    // The shortest of %.15g, %.16g and %.17g that reads back to the same double (%.17g always does).
    char buf[32];
    for (int precision = 15; precision < 17; ++precision) {
        std::snprintf(buf, sizeof buf, "%.*g", precision, v);
        if (std::strtod(buf, nullptr) == v) return buf;
    }
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

void JsonWriter::newline_indent() {
    out_.push_back('\n');
    out_.append(2 * stack_.size(), ' ');
}

// The separator before the next member of the innermost object or array: a comma after the first, then a
// space (inline levels) or a new indented line.
void JsonWriter::next_member() {
    Level &level = stack_.back();
    if (level.count > 0) out_.push_back(',');
    if (level.is_inline) {
        if (level.count > 0) out_.push_back(' ');
    } else {
        newline_indent();
    }
    ++level.count;
}

void JsonWriter::before_value() {
    if (after_key_) {
        after_key_ = false;
        return;
    }
    if (stack_.empty()) return;
    next_member();
}

void JsonWriter::key(const std::string &name) {
    next_member();
    out_ += escape(name);
    out_ += ": ";
    after_key_ = true;
}

void JsonWriter::begin_object() {
    const bool parent_inline = one_line_ || (!stack_.empty() && stack_.back().is_inline);
    before_value();
    out_.push_back('{');
    stack_.push_back({true, parent_inline, 0});
}

void JsonWriter::end_object() {
    const Level level = stack_.back();
    stack_.pop_back();
    if (level.count > 0 && !level.is_inline) newline_indent();
    out_.push_back('}');
    if (stack_.empty()) out_.push_back('\n');
}

void JsonWriter::begin_array(bool inline_array) {
    const bool parent_inline = one_line_ || (!stack_.empty() && stack_.back().is_inline);
    before_value();
    out_.push_back('[');
    stack_.push_back({false, inline_array || parent_inline, 0});
}

void JsonWriter::end_array() {
    const Level level = stack_.back();
    stack_.pop_back();
    if (level.count > 0 && !level.is_inline) newline_indent();
    out_.push_back(']');
    if (stack_.empty()) out_.push_back('\n');
}

void JsonWriter::value(const std::string &text) {
    before_value();
    out_ += escape(text);
}

void JsonWriter::value(const char *text) { value(std::string(text ? text : "")); }

void JsonWriter::value(double number_value) {
    before_value();
    out_ += number(number_value);
}

void JsonWriter::value(int64_t number_value) {
    before_value();
    char buf[32];
    std::snprintf(buf, sizeof buf, "%" PRId64, number_value);
    out_ += buf;
}

void JsonWriter::value(uint64_t number_value) {
    before_value();
    char buf[32];
    std::snprintf(buf, sizeof buf, "%" PRIu64, number_value);
    out_ += buf;
}

void JsonWriter::value(bool flag) {
    before_value();
    out_ += flag ? "true" : "false";
}

void JsonWriter::null() {
    before_value();
    out_ += "null";
}

void JsonWriter::field_matrix(const std::string &name, const double *m, int rows, int cols) {
    key(name);
    begin_array(true);
    for (int r = 0; r < rows; ++r) {
        begin_array(true);
        for (int c = 0; c < cols; ++c) value(m[r * cols + c]);
        end_array();
    }
    end_array();
}

void JsonWriter::field_vector(const std::string &name, const double *v, int n) {
    key(name);
    begin_array(true);
    for (int i = 0; i < n; ++i) value(v[i]);
    end_array();
}

} // namespace kissm_cli
