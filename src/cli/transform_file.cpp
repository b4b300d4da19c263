// SPDX-License-Identifier: MIT
#include "transform_file.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>
#include <vector>

#include "cli_args.hpp"

namespace kissm_cli {

namespace {

// A transform file is 4 short lines; anything this large is the wrong file, and is not read whole.
constexpr std::uintmax_t kMaxTransformFileBytes = 1u << 20;

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

std::vector<std::string> tokens_of(const std::string &line) {
    std::vector<std::string> tokens;
    size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && is_blank(line[i])) ++i;
        const size_t begin = i;
        while (i < line.size() && !is_blank(line[i])) ++i;
        if (i > begin) tokens.push_back(line.substr(begin, i - begin));
    }
    return tokens;
}

} // namespace

bool write_transform_file(const std::string &path, const double T[16], std::string *error) {
    std::FILE *f = std::fopen(path.c_str(), "w");
    if (!f) {
        *error = "cannot create '" + path + "': " + std::strerror(errno);
        return false;
    }
    bool ok = true;
    for (int r = 0; r < 4 && ok; ++r) {
        ok = std::fprintf(f, "%.17g %.17g %.17g %.17g\n", T[4 * r], T[4 * r + 1], T[4 * r + 2], T[4 * r + 3]) > 0;
    }
    const int saved_errno = errno;
    if (std::fclose(f) != 0 || !ok) {
        *error = "cannot write '" + path + "': " + std::strerror(ok ? errno : saved_errno);
        return false;
    }
    return true;
}

bool read_transform_file(const std::string &path, double T[16], std::string *error) {
    const std::string name = "'" + one_line(path) + "'";
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) {
        *error = name + " is a folder, not a transform file";
        return false;
    }
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    if (!ec && size > kMaxTransformFileBytes) {
        *error = name + " is too large (" + std::to_string(size) + " bytes) for a transform file of 4 lines";
        return false;
    }
    std::ifstream in(path);
    if (!in) {
        *error = "cannot open " + name + ": " + std::strerror(errno);
        return false;
    }
    int rows = 0;
    int line_number = 0;
    std::string line;
    while (std::getline(in, line)) {
        ++line_number;
        const std::vector<std::string> tokens = tokens_of(line);
        if (tokens.empty() || tokens[0][0] == '#') continue;
        const std::string where = name + " line " + std::to_string(line_number);
        if (rows == 4) {
            *error = where + ": a transform has 4 rows, this is a fifth";
            return false;
        }
        if (tokens.size() != 4) {
            *error = where + " holds " + std::to_string(tokens.size()) + " values; a transform row has 4";
            return false;
        }
        for (int c = 0; c < 4; ++c) {
            const std::string &token = tokens[static_cast<size_t>(c)];
            char *end = nullptr;
            const double v = std::strtod(token.c_str(), &end);
            if (end != token.c_str() + token.size()) {
                *error = where + ": '" + token + "' is not a number";
                return false;
            }
            if (!std::isfinite(v)) {
                *error = where + ": '" + token + "' is not finite";
                return false;
            }
            T[4 * rows + c] = v;
        }
        ++rows;
    }
    if (in.bad()) {
        *error = "cannot read " + name + ": " + std::strerror(errno);
        return false;
    }
    if (rows != 4) {
        *error = name + " holds " + std::to_string(rows) + " rows; a transform has 4 rows of 4 numbers";
        return false;
    }
    return true;
}

} // namespace kissm_cli
