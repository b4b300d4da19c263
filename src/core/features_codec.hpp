// SPDX-License-Identifier: MIT
// Features as bytes (docs/features-format.md): a cloud described on one machine, registered on another. The
// format holds what was computed from the points (voxels, normals, descriptors, counts) and the settings that
// computed it; the search indexes are rebuilt on load, so a file can never hand the matcher a broken tree.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "detail_namespace.hpp"
#include "pipeline.hpp"
#include "run_context.hpp"

KISSM_DETAIL_BEGIN

// The format's version this kissm writes (and the only one it reads).
constexpr std::uint32_t kFeaturesFormatVersion = 1;

// The bytes encode_features() writes for f.
std::size_t encoded_features_size(const CloudFeatures &f);
// Writes exactly encoded_features_size(f) bytes to out.
void encode_features_to(const CloudFeatures &f, std::uint8_t *out);
std::vector<std::uint8_t> encode_features(const CloudFeatures &f);

// The FNV-1a 64-bit hash of bytes: the format's checksum.
std::uint64_t features_checksum(const std::uint8_t *data, std::size_t size);

// Features from bytes, their indexes rebuilt as describe_cloud() builds them. Throws Failure(Parse) naming what
// is wrong and its byte offset for anything malformed: truncated, corrupted (checksum), of another version, or
// holding values the pipeline could not have produced. Never reads outside [data, data + size).
CloudFeatures decode_features(const std::uint8_t *data, std::size_t size, RunContext &ctx);

KISSM_DETAIL_END
