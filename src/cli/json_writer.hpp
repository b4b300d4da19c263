// SPDX-License-Identifier: MIT
// A minimal JSON writer: objects, arrays, strings, numbers, booleans and null, pretty-printed with two-space
// indentation; arrays can be kept on one line. Doubles are printed with the shortest of "%.15g", "%.16g"
// and "%.17g" that reads back to the very same value (0.3, not 0.29999999999999999); NaN and infinities,
// which JSON cannot express, are written as null.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace kissm_cli {

class JsonWriter {
public:
    // one_line: the whole document on one line (a JSON Lines record), every level kept inline.
    explicit JsonWriter(bool one_line = false) : one_line_(one_line) {}

    void begin_object();
    void end_object();
    // inline_array: keep the array (and anything nested in it) on one line.
    void begin_array(bool inline_array = false);
    void end_array();
    void key(const std::string &name);

    void value(const std::string &text);
    void value(const char *text);
    void value(double number);
    void value(int64_t number);
    void value(uint64_t number);
    void value(int32_t number) { value(static_cast<int64_t>(number)); }
    void value(bool flag);
    void null();

    template <typename T>
    void field(const std::string &name, const T &v) {
        key(name);
        value(v);
    }
    // A row-major rows x cols matrix as a list of inline lists.
    void field_matrix(const std::string &name, const double *m, int rows, int cols);
    void field_vector(const std::string &name, const double *v, int n);

    // The document so far; complete (with a final newline) once the top-level value is closed.
    const std::string &str() const { return out_; }

    static std::string escape(const std::string &text); // with the surrounding quotes
    static std::string number(double v);                // round-trip text, or "null" when not finite

private:
    struct Level {
        bool is_object;
        bool is_inline;
        int count;
    };
    void before_value();
    void next_member();
    void newline_indent();

    std::vector<Level> stack_;
    std::string out_;
    bool after_key_ = false;
    bool one_line_ = false;
};

} // namespace kissm_cli
