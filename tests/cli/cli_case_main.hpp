// SPDX-License-Identifier: MIT
// The main() the command-line test programs share: "PROGRAM KISSM_BINARY WORK_DIR CASE", a fresh WORK_DIR,
// then the named case, whose harness result is the exit status.
#pragma once

#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>

#include "harness.h"

namespace cli_test {

struct CliCase {
    const char *name;
    void (*run)();
};

// Reads the arguments into *kissm, *work (made empty) and *which; false (after a message) when they are
// wrong or the folder cannot be made.
inline bool prepare_case(int argc, char **argv, std::string *kissm, std::string *work, std::string *which) {
    if (argc != 4) {
        std::fprintf(stderr, "usage: %s KISSM_BINARY WORK_DIR CASE\n", argc > 0 ? argv[0] : "cli_test");
        return false;
    }
    *kissm = argv[1];
    *work = argv[2];
    *which = argv[3];
    std::error_code ec;
    std::filesystem::remove_all(*work, ec);
    std::filesystem::create_directories(*work, ec);
    if (ec) {
        std::fprintf(stderr, "cannot create %s: %s\n", work->c_str(), ec.message().c_str());
        return false;
    }
    return true;
}

// Runs the case named `which` and returns the harness summary; 2 for an unknown name.
template <size_t N>
int run_named_case(const std::string &which, const CliCase (&cases)[N]) {
    for (const CliCase &c : cases) {
        if (which != c.name) continue;
        c.run();
        std::fprintf(stderr, "%s %s\n", harness_failed ? "[FAIL]" : "[ ok ]", c.name);
        return TEST_SUMMARY();
    }
    std::fprintf(stderr, "unknown case '%s'\n", which.c_str());
    return 2;
}

} // namespace cli_test
