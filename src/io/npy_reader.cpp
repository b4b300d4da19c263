// SPDX-License-Identifier: MIT
// NumPy .npy (format versions 1.0, 2.0, 3.0): a 2-D array of shape (N, k >= 3), C or Fortran order; the
// first three columns are x, y, z.
#include "core/detail_namespace.hpp"
#include "core/little_endian.hpp"
#include "io/binary_scalar.hpp"
#include "io/file_bytes.hpp"
#include "io/format_readers.hpp"
#include "io/text_scan.hpp"

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

KISSM_DETAIL_BEGIN

namespace {

struct NpyHeader {
    std::string descr;
    bool have_descr = false;
    bool fortran_order = false;
    std::vector<std::uint64_t> shape;
    bool have_shape = false;
};

// The header is a Python dict literal such as {'descr': '<f8', 'fortran_order': False, 'shape': (18977, 3), }.
// Only the few value forms numpy writes for plain arrays are accepted.
class DictParser {
public:
    DictParser(const std::string &path, const char *b, const char *e) : path_(path), p_(b), end_(e) {}

    NpyHeader parse() {
        NpyHeader h;
        expect('{');
        for (;;) {
            skip_space();
            if (peek() == '}') break;
            const std::string key = string_literal();
            expect(':');
            skip_space();
            if (key == "descr") {
                if (peek() != '\'' && peek() != '"')
                    fail_parse(path_, "structured .npy dtypes are not supported (descr is not a plain type string)");
                h.descr = string_literal();
                h.have_descr = true;
            } else if (key == "fortran_order") {
                h.fortran_order = boolean();
            } else if (key == "shape") {
                h.shape = int_tuple();
                h.have_shape = true;
            } else {
                fail_parse(path_, ".npy header has an unexpected key " + quote_token(key));
            }
            skip_space();
            if (peek() == ',') {
                ++p_;
                continue;
            }
            if (peek() != '}') bad("expected ',' or '}'");
        }
        return h;
    }

private:
    [[noreturn]] void bad(const std::string &what) {
        fail_parse(path_, "malformed .npy header: " + what + " at " + quote_token(p_, end_));
    }
    char peek() const { return p_ < end_ ? *p_ : '\0'; }
    void skip_space() {
        while (p_ < end_ && is_space(*p_)) ++p_;
    }
    void expect(char c) {
        skip_space();
        if (peek() != c) bad(std::string("expected '") + c + "'");
        ++p_;
    }
    std::string string_literal() {
        skip_space();
        const char quote = peek();
        if (quote != '\'' && quote != '"') bad("expected a quoted string");
        const char *b = ++p_;
        while (p_ < end_ && *p_ != quote && *p_ != '\\') ++p_;
        if (p_ >= end_ || *p_ != quote) bad("unterminated or escaped string");
        return std::string(b, p_++);
    }
    bool word(const char *w) {
        const std::size_t n = std::strlen(w);
        if (static_cast<std::size_t>(end_ - p_) < n || std::memcmp(p_, w, n) != 0) return false;
        p_ += n;
        return true;
    }
    bool boolean() {
        if (word("True")) return true;
        if (word("False")) return false;
        bad("expected True or False");
    }
    std::vector<std::uint64_t> int_tuple() {
        expect('(');
        std::vector<std::uint64_t> dims;
        for (;;) {
            skip_space();
            if (peek() == ')') break;
            const char *b = p_;
            while (p_ < end_ && *p_ >= '0' && *p_ <= '9') ++p_;
            std::uint64_t d = 0;
            if (!parse_u64(b, p_, d)) bad("expected a non-negative dimension");
            if (peek() == 'L') ++p_; // Python 2 long literal
            dims.push_back(d);
            skip_space();
            if (peek() == ',') {
                ++p_;
                continue;
            }
            if (peek() != ')') bad("expected ',' or ')'");
        }
        ++p_;
        return dims;
    }

    const std::string &path_;
    const char *p_;
    const char *end_;
};

std::string shape_text(const std::vector<std::uint64_t> &shape) {
    std::string s = "(";
    for (std::size_t i = 0; i < shape.size(); ++i) s += (i ? ", " : "") + std::to_string(shape[i]);
    return s + (shape.size() == 1 ? ",)" : ")");
}

// descr is <byte order><kind><bytes>, e.g. '<f8'. Returns the scalar type and whether to byte-swap.
void parse_descr(const std::string &path, const std::string &descr, Scalar &type, bool &swap) {
    std::string body = descr;
    char order = '=';
    if (!body.empty() && (body[0] == '<' || body[0] == '>' || body[0] == '|' || body[0] == '=')) {
        order = body[0];
        body.erase(0, 1);
    }
    static const struct {
        const char *code;
        Scalar type;
    } table[] = {{"f4", Scalar::F32}, {"f8", Scalar::F64}, {"i1", Scalar::I8},  {"u1", Scalar::U8},
                 {"i2", Scalar::I16}, {"u2", Scalar::U16}, {"i4", Scalar::I32}, {"u4", Scalar::U32},
                 {"i8", Scalar::I64}, {"u8", Scalar::U64}};
    bool known = false;
    for (const auto &e : table) {
        if (body == e.code) {
            type = e.type;
            known = true;
        }
    }
    if (!known) fail_parse(path, ".npy dtype " + quote_token(descr) + " is not supported (use float32 or float64)");
    // '|' means "byte order not applicable", which is only true of single-byte types.
    if (order == '|' && scalar_size(type) != 1)
        fail_parse(path, ".npy dtype " + quote_token(descr) + " has no byte order");
    const bool little = order == '<' || ((order == '=' || order == '|') && host_is_little_endian());
    swap = little != host_is_little_endian();
}

const std::uint8_t *as_bytes(const char *p) { return reinterpret_cast<const std::uint8_t *>(p); }

} // namespace

std::vector<double> parse_npy(const std::string &path, std::string_view bytes) {
    static const char magic[] = "\x93NUMPY";
    if (bytes.size() < 6 || std::memcmp(bytes.data(), magic, 6) != 0)
        fail_parse(path, "not a .npy file (missing the \\x93NUMPY magic)");
    if (bytes.size() < 10) fail_parse(path, "truncated: the .npy preamble is incomplete");
    const int major = static_cast<unsigned char>(bytes[6]);
    const int minor = static_cast<unsigned char>(bytes[7]);
    std::size_t header_begin = 0;
    std::size_t header_len = 0;
    if (major == 1) {
        header_begin = 10;
        header_len = load_le<std::uint16_t>(as_bytes(bytes.data() + 8));
    } else if (major == 2 || major == 3) {
        if (bytes.size() < 12) fail_parse(path, "truncated: the .npy preamble is incomplete");
        header_begin = 12;
        header_len = load_le<std::uint32_t>(as_bytes(bytes.data() + 8));
    } else {
        fail_parse(path, "unsupported .npy format version " + std::to_string(major) + "." + std::to_string(minor));
    }
    if (header_len > bytes.size() - header_begin)
        fail_parse(path, "truncated: the .npy header needs " + std::to_string(header_len) + " bytes, found " +
                             std::to_string(bytes.size() - header_begin));
    const char *hb = bytes.data() + header_begin;
    const NpyHeader h = DictParser(path, hb, hb + header_len).parse();
    if (!h.have_descr) fail_parse(path, "the .npy header has no 'descr'");
    if (!h.have_shape) fail_parse(path, "the .npy header has no 'shape'");
    Scalar type = Scalar::F64;
    bool swap = false;
    parse_descr(path, h.descr, type, swap);
    if (h.shape.size() != 2 || h.shape[1] < 3)
        fail_parse(path, ".npy shape " + shape_text(h.shape) + " is not (N, 3) or (N, k >= 3)");

    const std::uint64_t rows = h.shape[0];
    const std::uint64_t cols = h.shape[1];
    const std::size_t data_begin = header_begin + header_len;
    const std::size_t left = bytes.size() - data_begin;
    std::uint64_t need = 0;
    if (!checked_mul(rows, cols, need) || !checked_mul(need, scalar_size(type), need))
        fail_parse(path, "truncated: .npy shape " + shape_text(h.shape) + " is far larger than the " +
                             std::to_string(left) + " bytes that follow");
    if (need > left)
        fail_parse(path, "truncated: expected " + std::to_string(need) + " bytes of array data, found " +
                             std::to_string(left));

    const std::size_t n = static_cast<std::size_t>(rows);
    const std::size_t k = static_cast<std::size_t>(cols);
    const std::size_t item = scalar_size(type);
    const char *data = bytes.data() + data_begin;
    std::vector<double> xyz(n * 3);
    if (type == Scalar::F64 && !swap && k == 3 && !h.fortran_order) {
        if (n > 0) std::memcpy(xyz.data(), data, n * 3 * sizeof(double));
        return xyz;
    }
    // Element (i, j) lives at i * k + j in C order and at j * n + i in Fortran (column-major) order.
    const std::size_t row_step = h.fortran_order ? 1 : k;
    const std::size_t col_step = h.fortran_order ? n : 1;
    for (std::size_t i = 0; i < n; ++i) {
        for (std::size_t j = 0; j < 3; ++j)
            xyz[3 * i + j] = load_scalar(data + (i * row_step + j * col_step) * item, type, swap);
    }
    return xyz;
}

KISSM_DETAIL_END
