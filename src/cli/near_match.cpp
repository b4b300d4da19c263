// SPDX-License-Identifier: MIT
#include "near_match.hpp"

#include <algorithm>
#include <cctype>

namespace kissm_cli {

namespace {

// Optimal string alignment distance: Levenshtein plus the swap of two neighbouring characters, the commonest
// typo ("regsiter").
size_t edit_distance(const std::string &a, const std::string &b) {
    const size_t n = a.size(), m = b.size();
    std::vector<std::vector<size_t>> d(n + 1, std::vector<size_t>(m + 1, 0));
    for (size_t i = 0; i <= n; ++i) d[i][0] = i;
    for (size_t j = 0; j <= m; ++j) d[0][j] = j;
    for (size_t i = 1; i <= n; ++i) {
        for (size_t j = 1; j <= m; ++j) {
            const size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
            d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
            if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
                d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
        }
    }
    return d[n][m];
}

size_t allowed_edits(const std::string &word) { return word.size() <= 4 ? 1 : word.size() <= 8 ? 2 : 3; }

} // namespace

std::string nearest_word(const std::string &word, const std::vector<std::string> &candidates) {
    // Words far longer than any candidate are not typos of one (and would cost a large table).
    if (word.empty() || word.size() > 64) return "";
    std::string best;
    size_t best_distance = allowed_edits(word) + 1;
    for (const std::string &c : candidates) {
        if (c == word) continue;
        const size_t d = edit_distance(word, c);
        if (d < best_distance) best = c, best_distance = d;
    }
    return best;
}

std::vector<std::string> options_in_help(void (*print_help)(std::FILE *)) {
    std::vector<std::string> options;
    std::FILE *text = std::tmpfile();
    if (text == nullptr) return options; // no suggestion then, the error itself still stands
    print_help(text);
    std::rewind(text);
    std::string token;
    int c = 0;
    const auto flush = [&] {
        // "--name", optionally followed by "=VALUE" or punctuation in the help's prose.
        size_t end = 2;
        while (end < token.size() && (std::isalnum(static_cast<unsigned char>(token[end])) || token[end] == '-')) ++end;
        if (token.size() > 2 && token.compare(0, 2, "--") == 0 && end > 2) {
            const std::string name = token.substr(0, end);
            if (std::find(options.begin(), options.end(), name) == options.end()) options.push_back(name);
        }
        token.clear();
    };
    while ((c = std::fgetc(text)) != EOF) {
        if (std::isspace(c) || c == '[' || c == '(' || c == '|' || c == ',' || c == '\'' || c == '`')
            flush();
        else
            token.push_back(static_cast<char>(c));
    }
    flush();
    std::fclose(text);
    return options;
}

std::string did_you_mean(const std::string &word, const std::vector<std::string> &candidates) {
    const std::string near = nearest_word(word, candidates);
    return near.empty() ? "" : " (did you mean '" + near + "'?)";
}

} // namespace kissm_cli
