// SPDX-License-Identifier: MIT
// Helpers for the command-line tool's tests: file I/O, a JSON parser, a zlib/deflate decoder
// (stored and fixed-Huffman blocks, which is what the tool's PNG encoder emits) and a PNG reader. They are
// written independently of the tool's own encoders so that each checks the other.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace cli_test {

inline bool read_file(const std::string &path, std::string *out) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return false;
    out->assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    return true;
}

inline std::string read_file(const std::string &path) {
    std::string text;
    read_file(path, &text);
    return text;
}

inline bool write_file(const std::string &path, const std::string &bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    return static_cast<bool>(out);
}

inline bool starts_with(const std::string &s, const std::string &prefix) {
    return s.size() >= prefix.size() && s.compare(0, prefix.size(), prefix) == 0;
}

inline bool contains(const std::string &s, const std::string &part) { return s.find(part) != std::string::npos; }

// ---------------------------------------------------------------------------------------------------
// JSON (RFC 8259): a strict parser into a small tree that keeps the members' order and each number's
// literal (strtod of it gives the double the tool meant, exactly).
// ---------------------------------------------------------------------------------------------------
struct Json {
    enum class Type { Null, Bool, Number, String, Array, Object };
    Type type = Type::Null;
    bool boolean = false;
    double number = 0.0;
    std::string text; // a string's value, or a number's literal
    std::vector<Json> items;
    std::vector<std::pair<std::string, Json>> members;

    bool is(Type t) const { return type == t; }
    // The member's value, or nullptr.
    const Json *find(const std::string &key) const {
        for (const auto &m : members) {
            if (m.first == key) return &m.second;
        }
        return nullptr;
    }
    const Json &at(const std::string &key) const {
        static const Json missing;
        const Json *v = find(key);
        return v ? *v : missing;
    }
    std::vector<std::string> keys() const {
        std::vector<std::string> out;
        for (const auto &m : members) out.push_back(m.first);
        return out;
    }
    // A number, or NaN for null (how the tool writes NaN); NaN for anything else too.
    double as_double() const { return type == Type::Number ? number : std::nan(""); }
    // The numbers of a (nested) array in order, NaN for null.
    std::vector<double> flat() const {
        std::vector<double> out;
        for (const Json &item : items) {
            if (item.is(Type::Array)) {
                const std::vector<double> inner = item.flat();
                out.insert(out.end(), inner.begin(), inner.end());
            } else {
                out.push_back(item.as_double());
            }
        }
        return out;
    }
    // A rows x cols array of arrays of numbers (null allowed as an element when nulls is true).
    bool is_matrix(size_t rows, size_t cols, bool nulls) const {
        if (!is(Type::Array) || items.size() != rows) return false;
        for (const Json &row : items) {
            if (!row.is(Type::Array) || row.items.size() != cols) return false;
            for (const Json &v : row.items) {
                if (!v.is(Type::Number) && !(nulls && v.is(Type::Null))) return false;
            }
        }
        return true;
    }
};

class JsonParser {
public:
    explicit JsonParser(const std::string &text) : s_(text) {}

    // Throws std::runtime_error on anything but exactly one JSON value (with optional whitespace around).
    Json parse() {
        ws();
        Json v = value(0);
        ws();
        if (i_ != s_.size()) fail("trailing characters");
        return v;
    }

private:
    [[noreturn]] void fail(const char *what) const {
        throw std::runtime_error(std::string(what) + " at offset " + std::to_string(i_));
    }
    char peek() const { return i_ < s_.size() ? s_[i_] : '\0'; }
    void ws() {
        while (i_ < s_.size() && (s_[i_] == ' ' || s_[i_] == '\t' || s_[i_] == '\n' || s_[i_] == '\r')) ++i_;
    }
    void expect(char c) {
        if (peek() != c) fail("unexpected character");
        ++i_;
    }
    void literal(const char *word) {
        const size_t n = std::strlen(word);
        if (s_.compare(i_, n, word) != 0) fail("bad literal");
        i_ += n;
    }
    bool digit() const { return peek() >= '0' && peek() <= '9'; }
    void digits() {
        if (!digit()) fail("digit expected");
        while (digit()) ++i_;
    }
    Json number() {
        const size_t begin = i_;
        if (peek() == '-') ++i_;
        if (peek() == '0') {
            ++i_;
        } else {
            digits();
        }
        if (peek() == '.') {
            ++i_;
            digits();
        }
        if (peek() == 'e' || peek() == 'E') {
            ++i_;
            if (peek() == '+' || peek() == '-') ++i_;
            digits();
        }
        Json v;
        v.type = Json::Type::Number;
        v.text = s_.substr(begin, i_ - begin);
        v.number = std::strtod(v.text.c_str(), nullptr);
        return v;
    }
    static void append_utf8(std::string &out, unsigned cp) {
        if (cp < 0x80) {
            out.push_back(static_cast<char>(cp));
        } else if (cp < 0x800) {
            out.push_back(static_cast<char>(0xC0 | (cp >> 6)));
            out.push_back(static_cast<char>(0x80 | (cp & 0x3F)));
        } else {
            out.push_back(static_cast<char>(0xE0 | (cp >> 12)));
            out.push_back(static_cast<char>(0x80 | ((cp >> 6) & 0x3F)));
            out.push_back(static_cast<char>(0x80 | (cp & 0x3F)));
        }
    }
    std::string string() {
        expect('"');
        std::string out;
        while (true) {
            if (i_ >= s_.size()) fail("unterminated string");
            const unsigned char c = static_cast<unsigned char>(s_[i_++]);
            if (c == '"') return out;
            if (c < 0x20) fail("control character in string");
            if (c != '\\') {
                out.push_back(static_cast<char>(c));
                continue;
            }
            const char e = peek();
            ++i_;
            if (e == 'u') {
                unsigned cp = 0;
                for (int k = 0; k < 4; ++k) {
                    const char h = peek();
                    if (!((h >= '0' && h <= '9') || (h >= 'a' && h <= 'f') || (h >= 'A' && h <= 'F'))) {
                        fail("bad \\u escape");
                    }
                    cp = cp * 16 + static_cast<unsigned>(h <= '9' ? h - '0' : (h | 0x20) - 'a' + 10);
                    ++i_;
                }
                append_utf8(out, cp);
            } else if (e == '\0' || !std::strchr("\"\\/bfnrt", e)) {
                fail("bad escape");
            } else {
                const char *from = "\"\\/bfnrt", *to = "\"\\/\b\f\n\r\t";
                out.push_back(to[std::strchr(from, e) - from]);
            }
        }
    }
    Json value(int depth) {
        if (depth > 64) fail("nesting too deep");
        Json v;
        const char c = peek();
        if (c == '{') {
            ++i_;
            v.type = Json::Type::Object;
            ws();
            if (peek() == '}') {
                ++i_;
                return v;
            }
            while (true) {
                ws();
                std::string key = string();
                ws();
                expect(':');
                ws();
                v.members.emplace_back(std::move(key), value(depth + 1));
                ws();
                if (peek() == ',') {
                    ++i_;
                    continue;
                }
                expect('}');
                return v;
            }
        } else if (c == '[') {
            ++i_;
            v.type = Json::Type::Array;
            ws();
            if (peek() == ']') {
                ++i_;
                return v;
            }
            while (true) {
                ws();
                v.items.push_back(value(depth + 1));
                ws();
                if (peek() == ',') {
                    ++i_;
                    continue;
                }
                expect(']');
                return v;
            }
        } else if (c == '"') {
            v.type = Json::Type::String;
            v.text = string();
        } else if (c == 't') {
            literal("true");
            v.type = Json::Type::Bool;
            v.boolean = true;
        } else if (c == 'f') {
            literal("false");
            v.type = Json::Type::Bool;
        } else if (c == 'n') {
            literal("null");
        } else if (c == '-' || (c >= '0' && c <= '9')) {
            v = number();
        } else {
            fail("value expected");
        }
        return v;
    }

    const std::string &s_;
    size_t i_ = 0;
};

inline bool json_valid(const std::string &text, std::string *error = nullptr) {
    try {
        JsonParser(text).parse();
        return true;
    } catch (const std::runtime_error &e) {
        if (error) *error = e.what();
        return false;
    }
}

// The parsed document, or a Null value (with *error set) when the text is not JSON.
inline Json json_parse(const std::string &text, std::string *error = nullptr) {
    try {
        return JsonParser(text).parse();
    } catch (const std::runtime_error &e) {
        if (error) *error = e.what();
        return Json();
    }
}

// The raw text of a top-level "key": value on one line (how the tool prints arrays), e.g. the transform.
inline std::string json_line_value(const std::string &json, const std::string &key) {
    const std::string needle = "\"" + key + "\": ";
    const size_t at = json.find(needle);
    if (at == std::string::npos) return std::string();
    const size_t begin = at + needle.size();
    size_t end = json.find('\n', begin);
    if (end == std::string::npos) end = json.size();
    std::string v = json.substr(begin, end - begin);
    if (!v.empty() && v.back() == ',') v.pop_back();
    return v;
}

// All numbers in a text such as "[[1, 2], [3, 4]]", in order.
inline std::vector<double> numbers_in(const std::string &text) {
    std::vector<double> out;
    const char *p = text.c_str();
    while (*p) {
        if ((*p >= '0' && *p <= '9') || *p == '-' || *p == '+' || *p == '.') {
            char *end = nullptr;
            const double v = std::strtod(p, &end);
            if (end == p) {
                ++p;
                continue;
            }
            out.push_back(v);
            p = end;
        } else {
            ++p;
        }
    }
    return out;
}

// ---------------------------------------------------------------------------------------------------
// zlib / deflate decoding: stored and fixed-Huffman blocks only.
// ---------------------------------------------------------------------------------------------------
class BitReader {
public:
    BitReader(const uint8_t *data, size_t size) : data_(data), size_(size) {}
    uint32_t bit() {
        if (pos_ >= size_ * 8) throw std::runtime_error("deflate stream ends early");
        const uint32_t b = (data_[pos_ >> 3] >> (pos_ & 7u)) & 1u;
        ++pos_;
        return b;
    }
    uint32_t bits(int n) { // least significant bit first
        uint32_t v = 0;
        for (int i = 0; i < n; ++i) v |= bit() << i;
        return v;
    }
    void align() { pos_ = (pos_ + 7u) & ~size_t{7}; }
    size_t byte_pos() const { return (pos_ + 7u) >> 3; }

private:
    const uint8_t *data_;
    size_t size_;
    size_t pos_ = 0;
};

inline uint32_t decode_fixed_litlen(BitReader &br) {
    uint32_t code = 0;
    for (int i = 0; i < 7; ++i) code = (code << 1) | br.bit();
    if (code <= 23u) return 256u + code;
    code = (code << 1) | br.bit();
    if (code >= 48u && code <= 191u) return code - 48u;
    if (code >= 192u && code <= 199u) return 280u + (code - 192u);
    code = (code << 1) | br.bit();
    if (code >= 400u && code <= 511u) return 144u + (code - 400u);
    throw std::runtime_error("bad fixed Huffman code");
}

inline void inflate_raw(const uint8_t *data, size_t size, std::vector<uint8_t> *out, size_t *consumed) {
    static const uint16_t kLenBase[29] = {3,  4,  5,  6,  7,  8,  9,  10, 11,  13,  15,  17,  19,  23, 27,
                                          31, 35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258};
    static const uint8_t kLenExtra[29] = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2,
                                          2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};
    static const uint16_t kDistBase[30] = {1,    2,    3,    4,    5,    7,    9,    13,    17,    25,
                                           33,   49,   65,   97,   129,  193,  257,  385,   513,   769,
                                           1025, 1537, 2049, 3073, 4097, 6145, 8193, 12289, 16385, 24577};
    static const uint8_t kDistExtra[30] = {0, 0, 0, 0, 1, 1, 2, 2,  3,  3,  4,  4,  5,  5,  6,
                                           6, 7, 7, 8, 8, 9, 9, 10, 10, 11, 11, 12, 12, 13, 13};
    BitReader br(data, size);
    bool last = false;
    while (!last) {
        last = br.bit() != 0;
        const uint32_t type = br.bits(2);
        if (type == 0) {
            br.align();
            const uint32_t len = br.bits(16), nlen = br.bits(16);
            if ((len ^ 0xFFFFu) != nlen) throw std::runtime_error("stored block length check failed");
            for (uint32_t i = 0; i < len; ++i) out->push_back(static_cast<uint8_t>(br.bits(8)));
        } else if (type == 1) {
            while (true) {
                const uint32_t sym = decode_fixed_litlen(br);
                if (sym < 256u) {
                    out->push_back(static_cast<uint8_t>(sym));
                    continue;
                }
                if (sym == 256u) break;
                const uint32_t li = sym - 257u;
                if (li >= 29u) throw std::runtime_error("bad length symbol");
                const uint32_t length = kLenBase[li] + br.bits(kLenExtra[li]);
                uint32_t dcode = 0;
                for (int i = 0; i < 5; ++i) dcode = (dcode << 1) | br.bit();
                if (dcode >= 30u) throw std::runtime_error("bad distance symbol");
                const uint32_t distance = kDistBase[dcode] + br.bits(kDistExtra[dcode]);
                if (distance > out->size()) throw std::runtime_error("distance beyond the output");
                const size_t from = out->size() - distance;
                for (uint32_t k = 0; k < length; ++k) out->push_back((*out)[from + k]);
            }
        } else {
            throw std::runtime_error("unsupported deflate block type");
        }
    }
    *consumed = br.byte_pos();
}

inline uint32_t test_adler32(const std::vector<uint8_t> &data) {
    uint32_t a = 1, b = 0;
    for (uint8_t c : data) {
        a = (a + c) % 65521u;
        b = (b + a) % 65521u;
    }
    return (b << 16) | a;
}

inline uint32_t test_crc32(const uint8_t *data, size_t size) { // bit by bit, no table
    uint32_t crc = 0xFFFFFFFFu;
    for (size_t i = 0; i < size; ++i) {
        crc ^= data[i];
        for (int k = 0; k < 8; ++k) crc = (crc & 1u) ? (crc >> 1) ^ 0xEDB88320u : crc >> 1;
    }
    return ~crc;
}

inline uint32_t be32(const uint8_t *p) {
    return static_cast<uint32_t>(p[0]) << 24 | static_cast<uint32_t>(p[1]) << 16 | static_cast<uint32_t>(p[2]) << 8 |
           p[3];
}

// Throws on any error (bad header, bad check value).
inline std::vector<uint8_t> zlib_decompress(const std::vector<uint8_t> &z) {
    if (z.size() < 6) throw std::runtime_error("zlib stream too short");
    if ((z[0] & 0x0Fu) != 8u || ((z[0] << 8) | z[1]) % 31 != 0 || (z[1] & 0x20u)) {
        throw std::runtime_error("bad zlib header");
    }
    std::vector<uint8_t> out;
    size_t consumed = 0;
    inflate_raw(z.data() + 2, z.size() - 2, &out, &consumed);
    if (2 + consumed + 4 > z.size()) throw std::runtime_error("zlib stream lacks its Adler-32");
    if (be32(z.data() + 2 + consumed) != test_adler32(out)) throw std::runtime_error("Adler-32 mismatch");
    return out;
}

struct PngImage {
    uint32_t width = 0, height = 0;
    std::vector<uint8_t> rgb; // width * height * 3
};

// Reads an 8-bit RGB, non-interlaced PNG whose rows all use filter 0 (what the tool writes). Throws on any
// deviation, including a chunk CRC mismatch.
inline PngImage decode_png(const std::string &bytes) {
    static const uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    const uint8_t *p = reinterpret_cast<const uint8_t *>(bytes.data());
    if (bytes.size() < 8 || std::memcmp(p, kSignature, 8) != 0) throw std::runtime_error("no PNG signature");
    size_t pos = 8;
    PngImage img;
    std::vector<uint8_t> idat;
    bool seen_end = false, seen_header = false;
    while (pos + 12 <= bytes.size() && !seen_end) {
        const uint32_t len = be32(p + pos);
        if (pos + 12 + len > bytes.size()) throw std::runtime_error("chunk runs past the end");
        const std::string type(bytes, pos + 4, 4);
        if (be32(p + pos + 8 + len) != test_crc32(p + pos + 4, len + 4))
            throw std::runtime_error("CRC mismatch in " + type);
        const uint8_t *data = p + pos + 8;
        if (type == "IHDR") {
            if (len != 13) throw std::runtime_error("bad IHDR");
            img.width = be32(data);
            img.height = be32(data + 4);
            if (data[8] != 8 || data[9] != 2 || data[10] != 0 || data[11] != 0 || data[12] != 0) {
                throw std::runtime_error("not 8-bit RGB non-interlaced");
            }
            seen_header = true;
        } else if (type == "IDAT") {
            idat.insert(idat.end(), data, data + len);
        } else if (type == "IEND") {
            seen_end = true;
        }
        pos += 12 + len;
    }
    if (!seen_header || !seen_end) throw std::runtime_error("missing IHDR or IEND");
    const std::vector<uint8_t> raw = zlib_decompress(idat);
    const size_t row = static_cast<size_t>(img.width) * 3u;
    if (raw.size() != (row + 1) * img.height) throw std::runtime_error("image data has the wrong size");
    img.rgb.reserve(row * img.height);
    for (size_t y = 0; y < img.height; ++y) {
        if (raw[y * (row + 1)] != 0) throw std::runtime_error("unexpected row filter");
        img.rgb.insert(img.rgb.end(), raw.begin() + static_cast<std::ptrdiff_t>(y * (row + 1) + 1),
                       raw.begin() + static_cast<std::ptrdiff_t>((y + 1) * (row + 1)));
    }
    return img;
}

} // namespace cli_test
