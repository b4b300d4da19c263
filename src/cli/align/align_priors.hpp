// SPDX-License-Identifier: MIT
// `kissm align --priors FILE`: world <- scan poses (GNSS, a SLAM run, an earlier alignment's --out) whose positions
// choose a sequence's loop candidates, as Python's kissm.multiway.align(priors=...) takes them.
#pragma once

#include <string>
#include <vector>

#include "align/align_scans.hpp"

namespace kissm_cli {

// Parses a priors table's text in the layout of the poses table (--out): tab-separated, blank and '#' lines
// ignored, a header naming `scan` and T00 T01 T02 T03 T10 ... T23 (the first three rows of T_world_scan; other
// columns, such as placed and component, ignored), then one row per scan with a prior. Returns 16 numbers per scan
// of `scans`, in its order, the last row (0 0 0 1) added; a scan without a row, or with a non-finite number
// ("nan" where an alignment did not place it), gets NaN (no prior). A UsageError names the line: a missing column,
// a scan the scans file does not name, a scan given twice, a field that is not a number.
std::vector<double> parse_priors(const std::string &text, const std::string &name, const std::vector<Scan> &scans);
// The same from the file (a UsageError when it cannot be read).
std::vector<double> read_priors(const std::string &path, const std::vector<Scan> &scans);

} // namespace kissm_cli
