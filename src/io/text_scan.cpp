// SPDX-License-Identifier: MIT
#include "io/text_scan.hpp"

#include <charconv>
#include <cstring>
#include <limits>
#include <system_error>

KISSM_DETAIL_BEGIN

namespace {

inline bool is_digit(char c) { return c >= '0' && c <= '9'; }

// from_chars reports out-of-range magnitudes without a value. [b, e) already parsed as a number, so it is
// [-]digits[.digits][e[+-]digits]; decide from the decimal exponent whether it overflowed or underflowed.
double out_of_range_value(const char *b, const char *e) {
    const bool negative = b < e && *b == '-';
    if (negative) ++b;
    long long int_digits = 0;    // significant digits before the point
    long long leading_zeros = 0; // zeros after the point before the first significant digit
    bool significant = false;
    while (b < e && is_digit(*b)) {
        if (*b != '0' || significant) {
            significant = true;
            ++int_digits;
        }
        ++b;
    }
    if (b < e && *b == '.') {
        ++b;
        while (b < e && is_digit(*b)) {
            if (!significant) {
                if (*b == '0')
                    ++leading_zeros;
                else
                    significant = true;
            }
            ++b;
        }
    }
    long long exponent = 0;
    if (b < e && (*b == 'e' || *b == 'E')) {
        ++b;
        bool exp_negative = false;
        if (b < e && (*b == '+' || *b == '-')) exp_negative = *b++ == '-';
        while (b < e && is_digit(*b)) {
            if (exponent < 1000000000LL) exponent = exponent * 10 + (*b - '0');
            ++b;
        }
        if (exp_negative) exponent = -exponent;
    }
    // Decimal exponent of the leading significant digit.
    const long long magnitude = (int_digits > 0 ? int_digits - 1 : -(leading_zeros + 1)) + exponent;
    const double value = significant && magnitude > 0 ? std::numeric_limits<double>::infinity() : 0.0;
    return negative ? -value : value;
}

} // namespace

bool parse_double(const char *b, const char *e, double &out) {
    // from_chars takes no leading '+'; strtod does, and writers emit it ("+1.5e+02").
    if (b < e && *b == '+') {
        ++b;
        if (b < e && (*b == '+' || *b == '-')) return false;
    }
    if (b >= e) return false;
    double value = 0.0;
    const std::from_chars_result r = std::from_chars(b, e, value);
    if (r.ptr != e) return false;
    if (r.ec == std::errc::result_out_of_range) {
        out = out_of_range_value(b, e);
        return true;
    }
    if (r.ec != std::errc()) return false;
    out = value;
    return true;
}

bool parse_u64(const char *b, const char *e, std::uint64_t &out) {
    if (b >= e || !is_digit(*b)) return false;
    std::uint64_t value = 0;
    const std::from_chars_result r = std::from_chars(b, e, value);
    if (r.ec != std::errc() || r.ptr != e) return false;
    out = value;
    return true;
}

std::string quote_token(const char *b, const char *e) {
    constexpr std::size_t kMax = 40;
    std::string s = "'";
    static const char hex[] = "0123456789abcdef";
    for (const char *p = b; p < e; ++p) {
        if (s.size() > kMax) {
            s += "...";
            break;
        }
        const unsigned char c = static_cast<unsigned char>(*p);
        if (c < 0x20 || c >= 0x7f || c == '\'' || c == '\\') {
            s += "\\x";
            s += hex[c >> 4];
            s += hex[c & 15];
        } else {
            s += static_cast<char>(c);
        }
    }
    s += "'";
    return s;
}

std::vector<std::string_view> split_words(const char *b, const char *e) {
    std::vector<std::string_view> words;
    const char *p = b;
    while (p < e) {
        while (p < e && is_space(*p)) ++p;
        const char *w = p;
        while (p < e && !is_space(*p)) ++p;
        if (p > w) words.emplace_back(w, static_cast<std::size_t>(p - w));
    }
    return words;
}

bool LineCursor::next(const char *&line_begin, const char *&line_end) {
    if (pos >= end) return false;
    const void *nl = std::memchr(pos, '\n', static_cast<std::size_t>(end - pos));
    const char *stop = nl ? static_cast<const char *>(nl) : end;
    line_begin = pos;
    line_end = stop;
    if (line_end > line_begin && line_end[-1] == '\r') --line_end;
    pos = nl ? stop + 1 : end;
    ++line_no;
    return true;
}

bool TokenCursor::next(const char *&token_begin, const char *&token_end) {
    const char *p = pos;
    while (p < end && is_space(*p)) {
        if (*p == '\n') ++line_no;
        ++p;
    }
    if (p >= end) {
        pos = p;
        return false;
    }
    token_begin = p;
    while (p < end && !is_space(*p)) ++p;
    token_end = p;
    pos = p;
    return true;
}

KISSM_DETAIL_END
