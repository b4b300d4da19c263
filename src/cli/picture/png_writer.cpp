// SPDX-License-Identifier: MIT
#include "png_writer.hpp"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>

namespace kissm_cli {
namespace {

std::array<uint32_t, 256> make_crc_table() {
    std::array<uint32_t, 256> table{};
    for (uint32_t n = 0; n < 256; ++n) {
        uint32_t c = n;
        for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
        table[n] = c;
    }
    return table;
}

// Deflate: bits are packed starting from the least significant bit of each byte; Huffman codes are sent
// most significant bit first, so they are reversed before packing.
class BitWriter {
public:
    explicit BitWriter(std::vector<uint8_t> &out) : out_(out) {}
    void put(uint32_t bits, int count) {
        acc_ |= static_cast<uint64_t>(bits) << nbits_;
        nbits_ += count;
        while (nbits_ >= 8) {
            out_.push_back(static_cast<uint8_t>(acc_ & 0xFFu));
            acc_ >>= 8;
            nbits_ -= 8;
        }
    }
    void put_code(uint32_t code, int length) { // a Huffman code, most significant bit first
        uint32_t reversed = 0;
        for (int i = 0; i < length; ++i) reversed |= ((code >> i) & 1u) << (length - 1 - i);
        put(reversed, length);
    }
    void flush() {
        if (nbits_ > 0) out_.push_back(static_cast<uint8_t>(acc_ & 0xFFu));
        acc_ = 0;
        nbits_ = 0;
    }

private:
    std::vector<uint8_t> &out_;
    uint64_t acc_ = 0;
    int nbits_ = 0;
};

constexpr uint16_t kLengthBase[29] = {3,  4,  5,  6,  7,  8,  9,  10, 11,  13,  15,  17,  19,  23, 27,
                                      31, 35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258};
constexpr uint8_t kLengthExtra[29] = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2,
                                      2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};
constexpr uint16_t kDistBase[30] = {1,    2,    3,    4,    5,    7,    9,    13,    17,    25,
                                    33,   49,   65,   97,   129,  193,  257,  385,   513,   769,
                                    1025, 1537, 2049, 3073, 4097, 6145, 8193, 12289, 16385, 24577};
constexpr uint8_t kDistExtra[30] = {0, 0, 0, 0, 1, 1, 2, 2,  3,  3,  4,  4,  5,  5,  6,
                                    6, 7, 7, 8, 8, 9, 9, 10, 10, 11, 11, 12, 12, 13, 13};

// Fixed literal/length code (RFC 1951, 3.2.6).
void put_symbol(BitWriter &bw, uint32_t sym) {
    if (sym <= 143) {
        bw.put_code(0x30u + sym, 8);
    } else if (sym <= 255) {
        bw.put_code(0x190u + (sym - 144u), 9);
    } else if (sym <= 279) {
        bw.put_code(sym - 256u, 7);
    } else {
        bw.put_code(0xC0u + (sym - 280u), 8);
    }
}

void put_match(BitWriter &bw, uint32_t length, uint32_t distance) {
    int li = 28;
    while (kLengthBase[li] > length) --li;
    put_symbol(bw, 257u + static_cast<uint32_t>(li));
    if (kLengthExtra[li]) bw.put(length - kLengthBase[li], kLengthExtra[li]);
    int di = 29;
    while (kDistBase[di] > distance) --di;
    bw.put_code(static_cast<uint32_t>(di), 5);
    if (kDistExtra[di]) bw.put(distance - kDistBase[di], kDistExtra[di]);
}

void put_be32(std::vector<uint8_t> &out, uint32_t v) {
    out.push_back(static_cast<uint8_t>(v >> 24));
    out.push_back(static_cast<uint8_t>(v >> 16));
    out.push_back(static_cast<uint8_t>(v >> 8));
    out.push_back(static_cast<uint8_t>(v));
}

void put_chunk(std::vector<uint8_t> &png, const char type[4], const std::vector<uint8_t> &data) {
    put_be32(png, static_cast<uint32_t>(data.size()));
    const size_t start = png.size();
    png.insert(png.end(), type, type + 4);
    png.insert(png.end(), data.begin(), data.end());
    put_be32(png, crc32(png.data() + start, png.size() - start));
}

} // namespace

uint32_t crc32_update(uint32_t crc, const uint8_t *data, size_t size) {
    static const std::array<uint32_t, 256> table = make_crc_table();
    uint32_t c = crc ^ 0xFFFFFFFFu;
    for (size_t i = 0; i < size; ++i) c = table[(c ^ data[i]) & 0xFFu] ^ (c >> 8);
    return c ^ 0xFFFFFFFFu;
}

uint32_t adler32_update(uint32_t adler, const uint8_t *data, size_t size) {
    constexpr uint32_t kMod = 65521u;
    uint32_t a = adler & 0xFFFFu, b = adler >> 16;
    while (size > 0) {
        const size_t n = std::min<size_t>(size, 5552); // the largest run without 32-bit overflow
        for (size_t i = 0; i < n; ++i) {
            a += data[i];
            b += a;
        }
        a %= kMod;
        b %= kMod;
        data += n;
        size -= n;
    }
    return (b << 16) | a;
}

std::vector<uint8_t> deflate_fixed(const uint8_t *data, size_t size) {
    constexpr size_t kWindow = 32768;
    constexpr int kHashBits = 15;
    constexpr size_t kMinMatch = 3, kMaxMatch = 258;
    constexpr int kMaxChain = 32;

    std::vector<uint8_t> out;
    out.reserve(size / 8 + 64);
    BitWriter bw(out);
    bw.put(1u, 1); // BFINAL
    bw.put(1u, 2); // BTYPE = 01, fixed Huffman codes

    std::vector<int64_t> head(size_t{1} << kHashBits, -1);
    std::vector<int64_t> prev(kWindow, -1);
    const auto hash_at = [&](size_t i) {
        const uint32_t v = static_cast<uint32_t>(data[i]) | static_cast<uint32_t>(data[i + 1]) << 8 |
                           static_cast<uint32_t>(data[i + 2]) << 16;
        return static_cast<size_t>((v * 2654435761u) >> (32 - kHashBits));
    };
    const auto insert = [&](size_t i) {
        if (i + kMinMatch > size) return;
        const size_t h = hash_at(i);
        prev[i & (kWindow - 1)] = head[h];
        head[h] = static_cast<int64_t>(i);
    };

    size_t i = 0;
    while (i < size) {
        size_t best_len = 0, best_dist = 0;
        if (i + kMinMatch <= size) {
            const size_t max_len = std::min(kMaxMatch, size - i);
            int64_t cand = head[hash_at(i)];
            for (int chain = 0; chain < kMaxChain && cand >= 0; ++chain) {
                const size_t c = static_cast<size_t>(cand);
                if (i - c > kWindow) break;
                size_t len = 0;
                while (len < max_len && data[c + len] == data[i + len]) ++len;
                if (len > best_len) {
                    best_len = len;
                    best_dist = i - c;
                    if (len == max_len) break;
                }
                cand = prev[c & (kWindow - 1)];
            }
        }
        if (best_len >= kMinMatch) {
            put_match(bw, static_cast<uint32_t>(best_len), static_cast<uint32_t>(best_dist));
            for (size_t k = 0; k < best_len; ++k) insert(i + k);
            i += best_len;
        } else {
            put_symbol(bw, data[i]);
            insert(i);
            ++i;
        }
    }
    put_symbol(bw, 256u); // end of block
    bw.flush();
    return out;
}

std::vector<uint8_t> zlib_compress(const uint8_t *data, size_t size) {
    std::vector<uint8_t> out = {0x78, 0x01}; // deflate, 32 KiB window, no dictionary; (0x7801 % 31) == 0
    const std::vector<uint8_t> body = deflate_fixed(data, size);
    out.insert(out.end(), body.begin(), body.end());
    put_be32(out, adler32_update(1u, data, size));
    return out;
}

std::vector<uint8_t> encode_png_rgb(int width, int height, const uint8_t *rgb) {
    const size_t row = static_cast<size_t>(width) * 3u;
    std::vector<uint8_t> raw;
    raw.reserve((row + 1) * static_cast<size_t>(height));
    for (int y = 0; y < height; ++y) {
        raw.push_back(0); // filter type: none
        const uint8_t *src = rgb + row * static_cast<size_t>(y);
        raw.insert(raw.end(), src, src + row);
    }
    std::vector<uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    std::vector<uint8_t> ihdr;
    put_be32(ihdr, static_cast<uint32_t>(width));
    put_be32(ihdr, static_cast<uint32_t>(height));
    ihdr.insert(ihdr.end(), {8, 2, 0, 0, 0}); // 8 bits, RGB, deflate, adaptive filtering, no interlace
    put_chunk(png, "IHDR", ihdr);
    put_chunk(png, "IDAT", zlib_compress(raw.data(), raw.size()));
    put_chunk(png, "IEND", {});
    return png;
}

bool write_png_rgb(const std::string &path, int width, int height, const uint8_t *rgb, std::string *error) {
    const std::vector<uint8_t> png = encode_png_rgb(width, height, rgb);
    std::FILE *f = std::fopen(path.c_str(), "wb");
    if (!f) {
        *error = "cannot create '" + path + "': " + std::strerror(errno);
        return false;
    }
    const bool ok = std::fwrite(png.data(), 1, png.size(), f) == png.size();
    const int saved_errno = errno;
    if (std::fclose(f) != 0 || !ok) {
        *error = "cannot write '" + path + "': " + std::strerror(ok ? errno : saved_errno);
        return false;
    }
    return true;
}

} // namespace kissm_cli
