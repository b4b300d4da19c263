// SPDX-License-Identifier: MIT
// A dependency-free PNG encoder for 8-bit RGB images. The image data is compressed with our own deflate
// encoder (LZ77 with hash chains, fixed Huffman codes: RFC 1951 block type 1) inside a zlib stream
// (RFC 1950); mostly-white pictures shrink about 30-fold compared with stored blocks.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace kissm_cli {

// CRC-32 (IEEE 802.3, as used by PNG and zip); pass the previous value to continue a running checksum.
uint32_t crc32_update(uint32_t crc, const uint8_t *data, size_t size);
inline uint32_t crc32(const uint8_t *data, size_t size) { return crc32_update(0u, data, size); }
// Adler-32 (zlib); start from 1.
uint32_t adler32_update(uint32_t adler, const uint8_t *data, size_t size);

// Raw deflate stream (one final block with fixed Huffman codes).
std::vector<uint8_t> deflate_fixed(const uint8_t *data, size_t size);
// zlib stream: header, deflate_fixed(data), Adler-32.
std::vector<uint8_t> zlib_compress(const uint8_t *data, size_t size);

// rgb: width * height * 3 bytes, rows top to bottom.
std::vector<uint8_t> encode_png_rgb(int width, int height, const uint8_t *rgb);
bool write_png_rgb(const std::string &path, int width, int height, const uint8_t *rgb, std::string *error);

} // namespace kissm_cli
