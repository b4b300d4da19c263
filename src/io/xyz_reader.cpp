// SPDX-License-Identifier: MIT
// Plain-text point lists (.xyz, .txt, .pts, .asc): one point per line, the first three of any number of
// whitespace- or comma-separated columns are x, y, z; '#' starts a comment line.
#include "core/detail_namespace.hpp"
#include "io/file_bytes.hpp"
#include "io/format_readers.hpp"
#include "io/text_scan.hpp"

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

KISSM_DETAIL_BEGIN

namespace {

inline bool is_separator(char c) { return c == ',' || is_space(c); }

} // namespace

std::vector<double> parse_xyz_text(const std::string &path, std::string_view bytes) {
    const char *begin = bytes.data();
    const char *end = begin + bytes.size();
    std::vector<double> xyz;
    // Reserve for the point lines the file could hold ("1 2 3\n" is the shortest): growth copies are
    // avoided for typical files without letting a file of blank lines reserve much.
    const std::size_t lines_in_file = static_cast<std::size_t>(std::count(begin, end, '\n')) + 1;
    xyz.reserve(3 * std::min(lines_in_file, bytes.size() / 6 + 1));

    LineCursor lines(begin, end);
    const char *lb = nullptr;
    const char *le = nullptr;
    bool first_data_line = true;
    while (lines.next(lb, le)) {
        const char *p = lb;
        while (p < le && is_separator(*p)) ++p;
        if (p >= le || *p == '#') continue;

        // Only the first three columns are looked at; the rest (intensity, colour, ...) may hold anything.
        const char *token_begin[3] = {nullptr, nullptr, nullptr};
        const char *token_end[3] = {nullptr, nullptr, nullptr};
        int tokens = 0;
        while (p < le && tokens < 3) {
            token_begin[tokens] = p;
            while (p < le && !is_separator(*p)) ++p;
            token_end[tokens++] = p;
            while (p < le && is_separator(*p)) ++p;
        }
        // Leica .pts files start with a line holding only the point count.
        std::uint64_t declared = 0;
        const bool pts_count_line = first_data_line && tokens == 1 && parse_u64(token_begin[0], token_end[0], declared);
        first_data_line = false;
        if (pts_count_line) continue;

        double v[3] = {0, 0, 0};
        for (int t = 0; t < tokens; ++t) {
            if (!parse_double(token_begin[t], token_end[t], v[t]))
                fail_parse(path, "line " + std::to_string(lines.line_no) +
                                     ": not a number: " + quote_token(token_begin[t], token_end[t]));
        }
        if (tokens < 3)
            fail_parse(path, "line " + std::to_string(lines.line_no) + ": expected at least 3 numbers (x y z), found " +
                                 std::to_string(tokens));
        xyz.insert(xyz.end(), v, v + 3);
    }
    return xyz;
}

KISSM_DETAIL_END
