// SPDX-License-Identifier: MIT
// libFuzzer target for one point-file parser, chosen at compile time by KISSM_FUZZ_FORMAT (ply, pcd, npy,
// xyz_text, kitti_bin, bin_xyz, las; with KISSM_WITH_LAZ=ON las covers LAZ as well). Invariants: the parser returns
// whole points or throws kissm's Failure (Parse); any other exception, a crash or a sanitizer report is a finding.
// Allocation is bounded by the input (the readers check header counts against the size), so the fuzzer's RSS limit also
// catches overshoot.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "core/failure.hpp"
#include "io/format_readers.hpp"
#include "io/laz_records.hpp"

#define KISSM_FUZZ_CAT2(a, b) a##b
#define KISSM_FUZZ_CAT(a, b) KISSM_FUZZ_CAT2(a, b)
#define KISSM_FUZZ_PARSER KISSM_FUZZ_CAT(kissm::detail::parse_, KISSM_FUZZ_FORMAT)

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
    const std::string_view bytes(reinterpret_cast<const char *>(data), size);
    try {
        const auto xyz = KISSM_FUZZ_PARSER("fuzz-input", bytes);
        if (xyz.size() % 3 != 0) std::abort(); // a partial point
    } catch (const kissm::detail::Failure &f) {
        // The bytes are already in memory: Parse, or (LAS) a compressed file in a build without LAZ.
        const bool laz_absent = f.kind() == kissm::detail::ErrorKind::UnsupportedFormat && !kissm::detail::kLazBuiltIn;
        if (f.kind() != kissm::detail::ErrorKind::Parse && !laz_absent) std::abort();
    }
    return 0;
}
