// SPDX-License-Identifier: MIT
// `kissm batch`'s progress line on stderr: pairs done, rate and ETA. On a terminal it is rewritten in place
// (\r) at most 4 times a second; otherwise (a log file) a line at most every 5 seconds, so that logs stay short.
#pragma once

#include <chrono>
#include <cstddef>
#include <string>

namespace kissm_cli {

class BatchProgress {
public:
    // total: the pairs this run registers; enabled false (--quiet) prints nothing; label starts the line.
    BatchProgress(size_t total, bool enabled, std::string label = "kissm batch");
    void pair_done(); // the caller serialises the calls
    void finish();    // the last state (on a terminal), and ends the line
    double elapsed_s() const;

private:
    void print();

    size_t total_, done_ = 0;
    std::string label_;
    bool enabled_, tty_;
    bool printed_ = false;
    size_t last_width_ = 0;
    std::chrono::steady_clock::time_point start_, last_print_;
};

// "12/40 pairs (30%), 3.1 pairs/s, ETA 9 s": the text of the line (the unit tests check it).
std::string progress_text(size_t done, size_t total, double elapsed_s);

} // namespace kissm_cli
