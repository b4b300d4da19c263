// SPDX-License-Identifier: MIT
// --resume: the finished pairs of an existing results file, checked against the pairs being run, with a killed
// run's partial last line cut off. `kissm batch` and `kissm align` resume through it.
#pragma once

#include <string>
#include <vector>

#include "batch_pairs.hpp"

namespace kissm_cli {

// The records of the results file at `path` (empty when it does not exist). Each must be one of `rows` (its
// "pair" a row's index, its source and target that row's) and appear once; otherwise a UsageError that calls
// the rows `table` ("the pairs file has 6 (results of another pairs file?)"), the file untouched. A partial
// last line is cut off the file, with a note on stderr unless quiet.
std::vector<DoneRecord> resume_results(const std::string &path, const std::vector<PairRow> &rows,
                                       const std::string &table, bool quiet);

} // namespace kissm_cli
