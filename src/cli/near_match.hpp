// SPDX-License-Identifier: MIT
// "Did you mean": the known word nearest to a mistyped one (a command, an option), for usage errors that say
// what to type instead.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

namespace kissm_cli {

// The candidate nearest to `word` by edit distance (insertions, deletions, substitutions and swaps of two
// neighbours each count one), when it is near enough to be a typo: at most 1 edit for words of up to 4
// characters, 2 up to 8, 3 beyond. Ties go to the first candidate. "" when none is near.
std::string nearest_word(const std::string &word, const std::vector<std::string> &candidates);

// The long options ("--name") a help text mentions, in order, each once: the command's options as its --help
// lists them, so suggestions cannot drift from what the parser takes.
std::vector<std::string> options_in_help(void (*print_help)(std::FILE *));

// " (did you mean 'X'?)" for the nearest candidate, or "" when none is near.
std::string did_you_mean(const std::string &word, const std::vector<std::string> &candidates);

} // namespace kissm_cli
