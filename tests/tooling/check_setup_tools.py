#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Every program our scripts and CMake call is one that tools/setup.sh installs or the base image has.

A script that calls a tool nobody installs works on the machine of whoever wrote it and fails (or, worse,
skips) on a fresh one. This reads every shell script of tools/, bindings/*/ and tests/ and every
find_program() of the CMake files, finds the programs they run, and fails naming the file and line of each
one that is neither in tools/packages.tsv (its "programs" column) nor in BASE_IMAGE below.

The shell reading is a small lexer, not bash: quotes, $(...), `...`, <(...), ${...}, $((...)), here-docs,
[[ ... ]], case patterns, redirections, functions, assignments and the prefixes env/command/exec/xargs/
timeout are understood; a command word that holds an expansion or a slash (a variable, a path like
$venv/bin/python) is not a program name and is left alone. `command -v X` counts as calling X.

    python3 tests/tooling/check_setup_tools.py [--root DIR]     exit 0 when all are listed, 1 otherwise
"""

from __future__ import annotations

import argparse
import re
import sys
from dataclasses import dataclass
from pathlib import Path

# What a fresh Debian 12 image of CI has before setup runs, and why each may be assumed.
BASE_IMAGE: dict[str, str] = {}
for _names, _why in [
    (
        "bash sh env cat cp mv rm ln mkdir rmdir mktemp touch chmod ls head tail sort uniq wc tr cut tee "
        "basename dirname realpath readlink date sleep nproc printf echo true false test yes seq comm diff "
        "cmp sha256sum md5sum stat du df id uname whoami install split paste join expr nice timeout nohup "
        "tac od xargs find grep egrep sed gzip gunzip tar",
        "Debian's essential set (coreutils, findutils, grep, sed, gzip, tar): on every Debian image",
    ),
    ("awk mawk", "mawk is priority required in Debian 12"),
    ("apt-get dpkg dpkg-query dpkg-deb", "apt and dpkg: how setup installs anything at all"),
    ("ldconfig ldd", "libc-bin: the loader and its cache, part of every Debian image"),
    ("python3", "Python 3.11 is on CI's image (the guide's machine); setup makes the venvs from it"),
    ("git", "CI clones the repository with it"),
    (
        "cargo rustc rustup rustfmt cargo-clippy clippy-driver",
        "Rust 1.95 with clippy and rustfmt is on CI's image; cargo fetches the crates",
    ),
    ("valgrind", "on CI's image (the guide's machine list)"),
    ("kissm", "ours: the CLI this repository builds, which the package tests install and then look for"),
]:
    for _name in _names.split():
        BASE_IMAGE[_name] = _why

# Shell builtins and reserved words: never programs.
BUILTINS = set(
    "alias bg bind break builtin caller cd command compgen complete continue declare dirs disown echo enable "
    "eval exec exit export false fc fg getopts hash help history jobs kill let local logout mapfile popd "
    "printf pushd pwd read readarray readonly return set shift shopt source suspend test times trap true "
    "type typeset ulimit umask unalias unset wait . : [ [[ ]] { } ! if then else elif fi do done while "
    "until for in case esac function select time coproc".split()
)
# Prefix commands: the program they run is the next word (after their options).
PREFIXES = {"env", "exec", "nice", "nohup", "timeout", "xargs", "builtin", "time", "sudo"}
# Their options that take a value (`env -u NAME`).
PREFIX_VALUE_OPTIONS = {"env": {"-u", "--unset", "-C", "--chdir"}, "xargs": {"-n", "-P", "-I", "-d", "-L"}}

ASSIGNMENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(\[[^]]*\])?\+?=")


@dataclass
class Word:
    text: str
    line: int
    expanded: bool  # held a $-expansion, a substitution or a glob: not a literal name


@dataclass
class Op:
    text: str
    line: int


class Lexer:
    """Splits shell text into words and operators; the bodies of substitutions become commands of their own."""

    def __init__(self, text: str, line: int = 1):
        self.s = text
        self.i = 0
        self.line = line
        self.tokens: list[Word | Op] = []
        self.nested: list[tuple[str, int]] = []  # (text, first line) of $(...), `...`, <(...) bodies
        self.heredocs: list[tuple[str, bool]] = []  # delimiters waiting for the next newline

    def peek(self, k: int = 0) -> str:
        j = self.i + k
        return self.s[j] if j < len(self.s) else ""

    def advance(self, n: int = 1) -> str:
        out = self.s[self.i : self.i + n]
        self.line += out.count("\n")
        self.i += n
        return out

    def matching(self, open_: str, close: str) -> str:
        """From just after `open_`, the text up to its matching `close` (quotes respected); consumes it."""
        depth, start = 1, self.i
        while self.i < len(self.s):
            c = self.peek()
            if c == "\\":
                self.advance(2)
                continue
            if c == "'" and open_ != "{":
                self.advance()
                while self.i < len(self.s) and self.peek() != "'":
                    self.advance()
                self.advance()
                continue
            if c == '"':
                self.advance()
                while self.i < len(self.s) and self.peek() != '"':
                    self.advance(2 if self.peek() == "\\" else 1)
                self.advance()
                continue
            if c == open_:
                depth += 1
            elif c == close:
                depth -= 1
                if depth == 0:
                    body = self.s[start : self.i]
                    self.advance()
                    return body
            self.advance()
        return self.s[start:]

    def dollar(self) -> None:
        """At a '$': consumes the expansion, queueing command substitutions."""
        self.advance()
        if self.peek() == "(" and self.peek(1) == "(":
            self.advance(2)
            self.matching("(", ")")
            if self.peek() == ")":
                self.advance()
        elif self.peek() == "(":
            self.advance()
            line = self.line
            self.nested.append((self.matching("(", ")"), line))
        elif self.peek() == "{":
            self.advance()
            self.matching("{", "}")
        elif self.peek() == "'":  # $'...'
            self.advance()
            while self.i < len(self.s) and self.peek() != "'":
                self.advance(2 if self.peek() == "\\" else 1)
            self.advance()
        else:
            while self.peek() and (self.peek().isalnum() or self.peek() in "_@*#?$!-"):
                self.advance()
                if not (self.s[self.i - 1].isalnum() or self.s[self.i - 1] == "_"):
                    break

    def backtick(self) -> None:
        self.advance()
        line, start = self.line, self.i
        while self.i < len(self.s) and self.peek() != "`":
            self.advance(2 if self.peek() == "\\" else 1)
        self.nested.append((self.s[start : self.i], line))
        self.advance()

    def skip_heredocs(self) -> None:
        """After a newline: the bodies of the here-docs opened on the line just ended."""
        for delim, strip in self.heredocs:
            while self.i < len(self.s):
                end = self.s.find("\n", self.i)
                end = len(self.s) if end < 0 else end
                body_line = self.s[self.i : end]
                self.advance(end - self.i + 1)
                if (body_line.lstrip("\t") if strip else body_line) == delim:
                    break
        self.heredocs = []

    def word(self) -> Word:
        line, text, expanded = self.line, [], False
        while self.i < len(self.s):
            c = self.peek()
            if c in " \t\n;&|()<>":
                break
            if c == "\\":
                if self.peek(1) == "\n":
                    self.advance(2)
                    continue
                text.append(self.peek(1))
                self.advance(2)
            elif c == "'":
                self.advance()
                start = self.i
                while self.i < len(self.s) and self.peek() != "'":
                    self.advance()
                text.append(self.s[start : self.i])
                self.advance()
            elif c == '"':
                self.advance()
                while self.i < len(self.s) and self.peek() != '"':
                    d = self.peek()
                    if d == "\\":
                        text.append(self.peek(1))
                        self.advance(2)
                    elif d == "$":
                        expanded = True
                        self.dollar()
                    elif d == "`":
                        expanded = True
                        self.backtick()
                    else:
                        text.append(d)
                        self.advance()
                self.advance()
            elif c == "$":
                expanded = True
                self.dollar()
            elif c == "`":
                expanded = True
                self.backtick()
            else:
                if c in "*?[":
                    expanded = True
                text.append(c)
                self.advance()
        return Word("".join(text), line, expanded)

    def run(self) -> Lexer:
        while self.i < len(self.s):
            c = self.peek()
            if c in " \t":
                self.advance()
            elif c == "\\" and self.peek(1) == "\n":
                self.advance(2)
            elif c == "\n":
                self.tokens.append(Op(";", self.line))
                self.advance()
                self.skip_heredocs()
            elif c == "#":
                while self.i < len(self.s) and self.peek() != "\n":
                    self.advance()
            elif c in "<>" and self.peek(1) == "(":  # process substitution: a command of its own
                self.advance(2)
                line = self.line
                self.nested.append((self.matching("(", ")"), line))
                self.tokens.append(Word("<(...)", line, True))
            elif c == "<" and self.s.startswith("<<<", self.i):
                self.advance(3)
                self.tokens.append(Op("<", self.line))
            elif c == "<" and self.peek(1) == "<":
                self.advance(2)
                strip = self.peek() == "-"
                if strip:
                    self.advance()
                while self.peek() in " \t":
                    self.advance()
                delim = self.word()
                self.heredocs.append((delim.text, strip))
            elif c in "<>":
                line = self.line
                self.advance()
                while self.peek() in "&>|":
                    self.advance()
                self.tokens.append(Op("<", line))  # the next word is a file, not a command
            elif c == "(" and self.peek(1) == "(":  # (( arithmetic )): no command in it
                self.advance(2)
                self.matching("(", ")")
                if self.peek() == ")":
                    self.advance()
                self.tokens.append(Word("((...))", self.line, True))
            elif c in ";&|()":
                line = self.line
                two = self.s[self.i : self.i + 2]
                if two in ("&&", "||", ";;", "|&"):
                    self.advance(2)
                    if two == ";;" and self.peek() == "&":
                        self.advance()
                    self.tokens.append(Op(two if two != "|&" else "|", line))
                elif two == "&>":
                    self.advance(2)
                    self.tokens.append(Op("<", line))
                elif two == ";&":
                    self.advance(2)
                    self.tokens.append(Op(";;", line))
                else:
                    self.advance()
                    self.tokens.append(Op(c, line))
            else:
                w = self.word()
                if self.peek() == "(" and not w.expanded and ASSIGNMENT.match(w.text) and w.text.endswith("="):
                    self.advance()  # an array literal x=(a b c): words, not commands
                    self.matching("(", ")")
                    w.expanded = True
                if re.fullmatch(r"[0-9]+", w.text) and not w.expanded and self.peek() in "<>":
                    continue  # a file descriptor of the redirection that follows
                self.tokens.append(w)
        return self


def programs_called(text: str, functions: set[str], line: int = 1) -> list[tuple[str, int]]:
    """(program, line) of every command word in `text` that names a program."""
    lexer = Lexer(text, line).run()
    found: list[tuple[str, int]] = []
    segments: list[tuple[list[Word], str]] = []  # words of a simple command, and the operator ending it
    current: list[Word] = []
    redirect = False
    for tok in lexer.tokens:
        if isinstance(tok, Op):
            if tok.text == "<":
                redirect = True
                continue
            segments.append((current, tok.text))
            current, redirect = [], False
        elif redirect:
            redirect = False
        else:
            current.append(tok)
    segments.append((current, ";"))

    in_case_pattern = False
    in_test = False
    for words, end in segments:
        if in_case_pattern:
            if end == ")":
                in_case_pattern = False
            if words and words[0].text == "esac":
                in_case_pattern = False
            else:
                continue
        if end == ";;":
            in_case_pattern = True
        k = 0
        while k < len(words):
            w = words[k]
            if in_test:
                if w.text == "]]":
                    in_test = False
                k += 1
                continue
            if not w.expanded and ASSIGNMENT.match(w.text):
                k += 1
                continue
            if w.text == "[[":
                in_test = True
                k += 1
                continue
            if w.text in ("for", "select", "case") and not w.expanded:
                if w.text == "case":
                    in_case_pattern = True
                break  # the rest of the segment is a word list
            if (
                w.text
                in (
                    "if",
                    "then",
                    "else",
                    "elif",
                    "fi",
                    "do",
                    "done",
                    "while",
                    "until",
                    "!",
                    "{",
                    "}",
                    "time",
                    "esac",
                    "function",
                )
                and not w.expanded
            ):
                if w.text == "function":
                    break
                k += 1
                continue
            break
        if in_test or k >= len(words):
            continue
        name, first = words[k], k
        if name.expanded or "/" in name.text:
            continue
        # A function definition `name()`: its body follows as commands of its own.
        if end == "(" and first == len(words) - 1:
            continue
        args = words[first + 1 :]
        if name.text in ("bash", "sh") and len(args) >= 2 and args[0].text == "-c":
            found += programs_called(args[1].text, functions, args[1].line)
        if name.text == "trap" and args:
            found += programs_called(args[0].text, functions, args[0].line)
        if name.text in PREFIXES:
            if name.text not in BUILTINS:
                found.append((name.text, name.line))
            rest = args
            while rest and (
                rest[0].text.startswith("-")
                or ASSIGNMENT.match(rest[0].text)
                or (name.text == "timeout" and re.fullmatch(r"[0-9.]+[smhd]?", rest[0].text))
            ):
                takes_value = rest[0].text in PREFIX_VALUE_OPTIONS.get(name.text, ())
                rest = rest[2:] if takes_value else rest[1:]
            if (
                rest
                and not rest[0].expanded
                and "/" not in rest[0].text
                and rest[0].text not in functions
                and rest[0].text not in BUILTINS
            ):
                found.append((rest[0].text, rest[0].line))
            continue
        if name.text == "command" and args and args[0].text in ("-v", "-V"):
            for a in args[1:]:
                if not a.expanded and "/" not in a.text and a.text not in functions and a.text not in BUILTINS:
                    found.append((a.text, a.line))
            continue
        if name.text == "command" and args:
            name = args[0]
            if name.expanded or "/" in name.text:
                continue
        if name.text in BUILTINS or name.text in functions:
            continue
        found.append((name.text, name.line))
    for body, body_line in lexer.nested:
        found += programs_called(body, functions, body_line)
    return found


def functions_defined(text: str) -> set[str]:
    """The names of `name() ...` and `function name ...` definitions (here-doc bodies are not code)."""
    tokens = Lexer(text).run().tokens
    names = set()
    for a, b, c in zip(tokens, tokens[1:], tokens[2:], strict=False):
        if (
            isinstance(a, Word)
            and not a.expanded
            and isinstance(b, Op)
            and b.text == "("
            and isinstance(c, Op)
            and c.text == ")"
        ):
            names.add(a.text)
        if isinstance(a, Word) and a.text == "function" and isinstance(b, Word):
            names.add(b.text)
    return names


def cmake_find_programs(text: str) -> list[tuple[str, int]]:
    """The program names of every find_program(VAR name | NAMES n1 n2 ... [options])."""
    found = []
    keywords = {
        "NAMES_PER_DIR",
        "HINTS",
        "PATHS",
        "PATH_SUFFIXES",
        "DOC",
        "REQUIRED",
        "NO_CACHE",
        "VALIDATOR",
        "REGISTRY_VIEW",
        "NO_DEFAULT_PATH",
        "NO_PACKAGE_ROOT_PATH",
        "NO_CMAKE_PATH",
        "NO_CMAKE_ENVIRONMENT_PATH",
        "NO_SYSTEM_ENVIRONMENT_PATH",
        "NO_CMAKE_SYSTEM_PATH",
        "CMAKE_FIND_ROOT_PATH_BOTH",
        "ONLY_CMAKE_FIND_ROOT_PATH",
        "NO_CMAKE_FIND_ROOT_PATH",
        "ENV",
        "NO_CMAKE_INSTALL_PREFIX",
    }
    for m in re.finditer(r"\bfind_program\s*\(([^)]*)\)", text, re.I):
        line = text.count("\n", 0, m.start()) + 1
        args = re.sub(r"#[^\n]*", "", m.group(1)).split()
        if len(args) < 2:
            continue
        names = []
        if args[1] == "NAMES":
            for a in args[2:]:
                if a in keywords:
                    break
                names.append(a)
        else:
            names.append(args[1])
        found += [(n.strip('"'), line) for n in names if "$" not in n]
    return found


def listed_programs(root: Path) -> set[str]:
    names = set()
    for row in (root / "tools" / "packages.tsv").read_text().splitlines():
        if not row.strip() or row.startswith("#") or row.startswith("group\t"):
            continue
        cols = row.split("\t")
        if len(cols) >= 3 and cols[2] != "-":
            names.update(p.strip() for p in cols[2].split(","))
    return names


def shell_scripts(root: Path) -> list[Path]:
    files = set(root.glob("tools/*.sh")) | set(root.glob("bindings/*/*.sh")) | set(root.glob("tests/**/*.sh"))
    files |= {p for p in (root / ".ci").glob("*") if p.is_file()} if (root / ".ci").is_dir() else set()
    return sorted(f for f in files if f.is_file())


def cmake_files(root: Path) -> list[Path]:
    found = []
    for pattern in ("CMakeLists.txt", "**/CMakeLists.txt", "**/*.cmake"):
        found += root.glob(pattern)
    # Build trees, vendored code and hidden folders (.git, venvs such as bench/.venv with a pip build tree inside)
    # hold no script of ours; a folder named like a file (a build tree's ".cmake") is no file.
    skip = ("build", "third_party", "target")
    return sorted(
        {
            f
            for f in found
            if f.is_file()
            and not any(part in skip or part.startswith(("build-", ".")) for part in f.relative_to(root).parts[:-1])
        }
    )


def check(root: Path) -> list[str]:
    allowed = listed_programs(root) | set(BASE_IMAGE)
    scripts = shell_scripts(root)
    # A script's functions are its own and those of the scripts it sources (tools/skips.sh, common.sh).
    defined = {f: functions_defined(f.read_text(errors="replace")) for f in scripts}
    problems = []
    for f in scripts:
        text = f.read_text(errors="replace")
        sourced = {
            name
            for line in re.findall(r"^\s*(?:source|\.)\s.*$", text, re.M)
            for name in re.findall(r"([\w.-]+\.sh)\b", line)
        }
        functions = set(defined[f])
        for g in scripts:
            if g.name in sourced:
                functions |= defined[g]
        for name, line in programs_called(text, functions):
            if name not in allowed:
                problems.append(f"{f.relative_to(root)}:{line}: calls '{name}'")
    for f in cmake_files(root):
        for name, line in cmake_find_programs(f.read_text(errors="replace")):
            if name not in allowed:
                problems.append(f"{f.relative_to(root)}:{line}: find_program looks for '{name}'")
    return problems


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", type=Path, default=Path(__file__).resolve().parents[2])
    args = parser.parse_args()
    problems = check(args.root)
    for p in problems:
        print(
            f"{p}, which is neither in tools/packages.tsv (a row setup installs, with the program in its "
            f"'programs' column) nor in BASE_IMAGE of tests/tooling/check_setup_tools.py",
            file=sys.stderr,
        )
    if problems:
        return 1
    print(
        f"check_setup_tools: every program of {len(shell_scripts(args.root))} scripts and "
        f"{len(cmake_files(args.root))} CMake files is installed by setup or on the base image"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
