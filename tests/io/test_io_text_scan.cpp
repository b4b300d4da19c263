// SPDX-License-Identifier: MIT
// The bounded number parsers and message quoting every text reader relies on.
#include "harness.h"

#include "io/text_scan.hpp"

#include <cmath>
#include <cstring>
#include <limits>
#include <string>

using kissm::detail::parse_double;
using kissm::detail::parse_u64;
using kissm::detail::quote_token;

namespace {

bool d(const char *s, double &v) { return parse_double(s, s + std::strlen(s), v); }
bool u(const char *s, std::uint64_t &v) { return parse_u64(s, s + std::strlen(s), v); }

void test_parse_double() {
    double v = 0;
    CHECK(d("1", v) && v == 1);
    CHECK(d("-2.5", v) && v == -2.5);
    CHECK(d("+2.5", v) && v == 2.5);
    CHECK(d(".5", v) && v == 0.5);
    CHECK(d("5.", v) && v == 5);
    CHECK(d("1e3", v) && v == 1000);
    CHECK(d("1.5E-2", v) && v == 0.015);
    CHECK(d("+1.5e+02", v) && v == 150);
    CHECK(d("0.1", v) && v == 0.1);
    CHECK(d("nan", v) && std::isnan(v));
    CHECK(d("NaN", v) && std::isnan(v));
    CHECK(d("-nan", v) && std::isnan(v));
    CHECK(d("inf", v) && v == std::numeric_limits<double>::infinity());
    CHECK(d("-Infinity", v) && v == -std::numeric_limits<double>::infinity());
    CHECK(d("+inf", v) && v == std::numeric_limits<double>::infinity());
    // Out of range behaves like strtod: overflow to +-inf, underflow to +-0.
    CHECK(d("1e400", v) && v == std::numeric_limits<double>::infinity());
    CHECK(d("-1e400", v) && v == -std::numeric_limits<double>::infinity());
    CHECK(d("123456789e301", v) && std::isinf(v));
    CHECK(d("0.000001e-400", v) && v == 0);
    CHECK(d("1e-400", v) && v == 0 && !std::signbit(v));
    CHECK(d("-1e-400", v) && v == 0 && std::signbit(v));
    CHECK(d("1e-99999999999999999999", v) && v == 0);
    CHECK(d("1e99999999999999999999", v) && std::isinf(v));
    CHECK(d("4e-320", v) && v > 0 && v < 1e-300); // subnormal, in range
    const char *bad[] = {"",   "+",  "-",   ".",   "e5",  "1e",  "1e+", "1..2", "1.2.3", "0x10",
                         " 1", "1 ", "1,5", "++1", "+-1", "-+1", "abc", "1f",   "nanx",  "in"};
    for (const char *s : bad) CHECK_MSG(!d(s, v), "'%s' parsed", s);
    // Bounds are respected: the parser must not read past e.
    const char buf[] = "12345";
    CHECK(parse_double(buf, buf + 2, v) && v == 12);
}

void test_parse_u64() {
    std::uint64_t v = 0;
    CHECK(u("0", v) && v == 0);
    CHECK(u("40256", v) && v == 40256);
    CHECK(u("18446744073709551615", v) && v == UINT64_MAX);
    const char *bad[] = {"",   "-1",  "+1", "18446744073709551616", "99999999999999999999999", "1.0", "1e3",
                         " 1", "0x1", "1 "};
    for (const char *s : bad) CHECK_MSG(!u(s, v), "'%s' parsed", s);
}

void test_quote_token() {
    const char raw[] = "a\nb'\\\x01\xff";
    const std::string q = quote_token(raw, raw + sizeof raw - 1);
    CHECK(q == "'a\\x0ab\\x27\\x5c\\x01\\xff'");
    const std::string longer(200, 'z');
    const std::string ql = quote_token(longer.data(), longer.data() + longer.size());
    CHECK(ql.size() < 60);
    CHECK(ql.find("...") != std::string::npos);
}

} // namespace

int main() {
    RUN_TEST(test_parse_double);
    RUN_TEST(test_parse_u64);
    RUN_TEST(test_quote_token);
    return TEST_SUMMARY();
}
