// SPDX-License-Identifier: MIT
// Bounded scanning of text in a byte buffer that is not NUL-terminated: lines, tokens, numbers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/detail_namespace.hpp"

KISSM_DETAIL_BEGIN

inline bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f'; }

// All of [b, e) as a number: decimal or exponent forms with an optional sign, "nan" and "inf"/"infinity" in
// any case. Magnitudes beyond double's range give +-inf or +-0 (as strtod does, but independent of the
// C locale, which a host application may have set to use ',' as the decimal point).
bool parse_double(const char *b, const char *e, double &out);

// All of [b, e) as a non-negative decimal integer that fits in 64 bits (no sign, no spaces).
bool parse_u64(const char *b, const char *e, std::uint64_t &out);
inline bool parse_u64(std::string_view s, std::uint64_t &out) { return parse_u64(s.data(), s.data() + s.size(), out); }

// A token for an error message: quoted, at most ~40 characters, control and non-ASCII bytes escaped, so that
// messages stay on one line whatever garbage the file holds.
std::string quote_token(const char *b, const char *e);
inline std::string quote_token(std::string_view s) { return quote_token(s.data(), s.data() + s.size()); }

// The whitespace-separated words of [b, e).
std::vector<std::string_view> split_words(const char *b, const char *e);

// Line by line over [pos, end). A line ends at '\n' (or at the end of the buffer); a '\r' before the '\n'
// is dropped so CRLF files read like LF ones.
struct LineCursor {
    const char *pos;
    const char *end;
    std::size_t line_no = 0; // 1-based number of the line last returned

    LineCursor(const char *b, const char *e) : pos(b), end(e) {}
    bool next(const char *&line_begin, const char *&line_end);
};

// Whitespace-separated tokens over [pos, end), whatever the line structure, counting lines for messages.
struct TokenCursor {
    const char *pos;
    const char *end;
    std::size_t line_no; // line of the token last returned

    TokenCursor(const char *b, const char *e, std::size_t first_line) : pos(b), end(e), line_no(first_line) {}
    bool next(const char *&token_begin, const char *&token_end);
};

KISSM_DETAIL_END
