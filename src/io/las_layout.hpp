// SPDX-License-Identifier: MIT
// Where the fields of an ASPRS LAS file are (LAS 1.4 R15 specification): the public header block's field
// offsets and sizes, and the record bytes kissm reads. The reader (las_reader.cpp) and the CLI's writer
// (src/cli/las_writer.cpp) share them. Header only.
#pragma once

#include <cstddef>
#include <cstdint>

#include "core/detail_namespace.hpp"

KISSM_DETAIL_BEGIN

namespace las {

// Public header block sizes: LAS 1.0-1.2, 1.3 (adds the waveform data start), 1.4 (EVLRs, 64-bit counts).
constexpr std::size_t kHeader12 = 227;
constexpr std::size_t kHeader13 = 235;
constexpr std::size_t kHeader14 = 375;

// Field offsets in the public header block.
constexpr std::size_t kSystemId = 26;           // char[32]
constexpr std::size_t kGeneratingSoftware = 58; // char[32]
constexpr std::size_t kVersionMajor = 24;
constexpr std::size_t kVersionMinor = 25;
constexpr std::size_t kHeaderSize = 94;
constexpr std::size_t kOffsetToPoints = 96;
constexpr std::size_t kVlrCount = 100;
constexpr std::size_t kFormatId = 104;
constexpr std::size_t kRecordLength = 105;
constexpr std::size_t kLegacyCount = 107;
constexpr std::size_t kLegacyByReturn = 111; // uint32[5]
constexpr std::size_t kScale = 131;          // x, y, z float64
constexpr std::size_t kOffset = 155;         // x, y, z float64
constexpr std::size_t kBounds = 179;         // max x, min x, max y, min y, max z, min z float64
constexpr std::size_t kCount64 = 247;

// The minimum record length of point data record formats 0 to 10.
constexpr std::uint16_t kMinRecord[11] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};

// Record bytes: X, Y, Z int32 first in every format; byte 14 of formats 0-5 holds the return number (bits
// 0-2) and the number of returns (bits 3-5); byte 15 holds the withheld flag: bit 7 of the classification
// byte (formats 0-5), bit 2 of the classification flags byte (formats 6-10).
constexpr std::size_t kReturnsByte = 14;
constexpr std::size_t kFlagsByte = 15;

} // namespace las

KISSM_DETAIL_END
