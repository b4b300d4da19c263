#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Regenerate tests/abi/layout_table.h, the field-by-field layout of the public structs of kissm.h.

The table is the ABI promise that tests/abi/layout.c checks the compiled header against, so this generator
never changes a published row: it reads the committed table, asks the C compiler for the layout of the
header as it is now (offsetof / sizeof of every field, 64-bit target), and

- fails when a committed row differs (a field moved, changed type or size, or disappeared: an ABI break,
  see docs/abi-policy.md), or when kissm_points (frozen) gained a field;
- appends the rows of fields added at the end of kissm_config and kissm_result;
- rewrites the struct sizes.

Usage::

    python3 tools/gen_layout_table.py            # rewrite tests/abi/layout_table.h
    python3 tools/gen_layout_table.py --check    # exit 1 (with a diff) when it is out of date
    CC=clang python3 tools/gen_layout_table.py   # another C compiler (default: cc)

tools/regen.sh runs it with the other generators.
"""

from __future__ import annotations

import argparse
import difflib
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
HEADER = ROOT / "include" / "kissm.h"
TABLE = ROOT / "tests" / "abi" / "layout_table.h"

#: The structs in the table: (struct, KISSM_STRUCT_* id, table macro, may it grow?).
STRUCTS = [
    ("kissm_config", "KISSM_STRUCT_CONFIG", "KISSM_LAYOUT_CONFIG", True),
    ("kissm_points", "KISSM_STRUCT_POINTS", "KISSM_LAYOUT_POINTS", False),
    ("kissm_result", "KISSM_STRUCT_RESULT", "KISSM_LAYOUT_RESULT", True),
    ("kissm_align_options", "KISSM_STRUCT_ALIGN_OPTIONS", "KISSM_LAYOUT_ALIGN_OPTIONS", True),
]

_ROW = re.compile(r"X\((\w+), (\w+), ([^,]+), (\d+), (\d+)\)")
_STRUCT_SIZE = re.compile(r"X\((\w+), (KISSM_STRUCT_\w+), (\d+)\)")


class LayoutError(Exception):
    """The header's layout breaks a published row."""


def strip_comments(text: str) -> str:
    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
    return re.sub(r"//[^\n]*", " ", text)


def header_fields(header: str, struct: str) -> list[tuple[str, str]]:
    """(field, type as the table writes it) of `struct`, in declaration order."""
    body = re.search(r"typedef\s+struct\s+%s\s*\{(.*?)\}\s*%s\s*;" % (struct, struct), strip_comments(header), re.S)
    if body is None:
        raise LayoutError(f"struct {struct} not found in {HEADER}")
    fields = []
    for decl in body.group(1).split(";"):
        decl = " ".join(decl.split())
        if not decl:
            continue
        m = re.fullmatch(r"(.*?)\s*\b(\w+)\s*(\[\s*(\d+)\s*\])?", decl)
        if m is None:
            raise LayoutError(f"cannot read the field declaration '{decl}' of {struct}")
        ctype, name, count = m.group(1).strip(), m.group(2), m.group(4)
        ctype = re.sub(r"\s*\*", " *", ctype)  # "const void*" -> "const void *"
        fields.append((name, f"{ctype}[{count}]" if count else ctype))
    return fields


def compiled_layout(fields: dict[str, list[tuple[str, str]]]) -> dict[str, tuple[int, dict[str, tuple[int, int]]]]:
    """struct -> (sizeof, field -> (offset, size)), from the C compiler."""
    lines = ["#include <stddef.h>", "#include <stdio.h>", '#include "kissm.h"', "int main(void) {"]
    for struct, rows in fields.items():
        lines.append(f'    printf("S {struct} %zu\\n", sizeof({struct}));')
        for name, _ in rows:
            lines.append(
                f'    printf("F {struct} {name} %zu %zu\\n", offsetof({struct}, {name}), '
                f"sizeof((({struct} *)0)->{name}));"
            )
    lines += ["    return 0;", "}", ""]
    cc = os.environ.get("CC", "cc")
    with tempfile.TemporaryDirectory() as tmp:
        src, exe = Path(tmp) / "layout_probe.c", Path(tmp) / "layout_probe"
        src.write_text("\n".join(lines))
        subprocess.run([cc, "-std=c99", "-I", str(HEADER.parent), str(src), "-o", str(exe)], check=True)
        out = subprocess.run([str(exe)], check=True, capture_output=True, text=True).stdout
    layout: dict[str, tuple[int, dict[str, tuple[int, int]]]] = {}
    sizes: dict[str, int] = {}
    offsets: dict[str, dict[str, tuple[int, int]]] = {s: {} for s in fields}
    for line in out.splitlines():
        parts = line.split()
        if parts[0] == "S":
            sizes[parts[1]] = int(parts[2])
        else:
            offsets[parts[1]][parts[2]] = (int(parts[3]), int(parts[4]))
    for struct in fields:
        layout[struct] = (sizes[struct], offsets[struct])
    return layout


def committed_rows(table: str) -> dict[str, list[tuple[str, str, int, int]]]:
    rows: dict[str, list[tuple[str, str, int, int]]] = {s: [] for s, _, _, _ in STRUCTS}
    for struct, field, ctype, offset, size in _ROW.findall(table):
        rows[struct].append((field, ctype.strip(), int(offset), int(size)))
    return rows


def new_rows(table: str, header: str) -> tuple[dict[str, list[tuple[str, str, int, int]]], dict[str, int]]:
    fields = {s: header_fields(header, s) for s, _, _, _ in STRUCTS}
    layout = compiled_layout(fields)
    published = committed_rows(table)
    rows: dict[str, list[tuple[str, str, int, int]]] = {}
    for struct, _, _, may_grow in STRUCTS:
        size, offsets = layout[struct]
        now = [(name, ctype, *offsets[name]) for name, ctype in fields[struct]]
        old = published[struct]
        for i, row in enumerate(old):
            if i >= len(now) or now[i] != row:
                became = now[i] if i < len(now) else "gone"
                raise LayoutError(
                    f"{struct}: the published row {row} is now {became}. Published fields never change "
                    "(docs/abi-policy.md); append new fields at the end instead."
                )
        if len(now) > len(old) and old and not may_grow:
            raise LayoutError(f"{struct} is frozen (it has no struct_size): {now[len(old)][0]} cannot be added")
        rows[struct] = now
        if sum(r[3] for r in now) != size:
            raise LayoutError(
                f"{struct} has padding ({size} bytes, fields {sum(r[3] for r in now)}): add reserved fields"
            )
    return rows, {s: layout[s][0] for s, _, _, _ in STRUCTS}


def render(table: str, rows: dict[str, list[tuple[str, str, int, int]]], sizes: dict[str, int]) -> str:
    """The committed file with its rows and sizes replaced: the prose and the macro layout stay."""

    def macro(name: str, entries: list[str]) -> str:
        width = 120
        head = f"#define {name}(X)"
        lines = [head + " " * max(1, width - 1 - len(head)) + "\\"]
        for i, entry in enumerate(entries):
            text = "  " + entry
            lines.append(text if i == len(entries) - 1 else text + " " * max(1, width - 1 - len(text)) + "\\")
        return "\n".join(lines) + "\n"

    out = re.sub(
        r"#define KISSM_LAYOUT_STRUCTS\(X\).*?\n(?=\n)",
        lambda _: macro("KISSM_LAYOUT_STRUCTS", [f"X({s}, {i}, {sizes[s]})" for s, i, _, _ in STRUCTS]),
        table,
        count=1,
        flags=re.S,
    )
    for struct, _, name, _ in STRUCTS:
        entries = [f"X({struct}, {f}, {t}, {o}, {n})" for f, t, o, n in rows[struct]]

        def replacement(_: re.Match[str], name: str = name, entries: list[str] = entries) -> str:
            return macro(name, entries)

        out = re.sub(
            r"#define %s\(X\).*?\n(?=\n)" % name,
            replacement,
            out,
            count=1,
            flags=re.S,
        )
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--check", action="store_true", help="fail when tests/abi/layout_table.h is out of date")
    args = parser.parse_args()
    table = TABLE.read_text()
    try:
        rows, sizes = new_rows(table, HEADER.read_text())
    except LayoutError as e:
        print(f"gen_layout_table: {e}", file=sys.stderr)
        return 1
    fresh = render(table, rows, sizes)
    if shutil.which("clang-format"):
        fresh = subprocess.run(
            ["clang-format", f"--assume-filename={TABLE}"], input=fresh, capture_output=True, text=True, check=True
        ).stdout
    if args.check:
        if fresh != table:
            sys.stderr.writelines(
                difflib.unified_diff(table.splitlines(True), fresh.splitlines(True), "committed", "fresh")
            )
            print(f"gen_layout_table: {TABLE} is out of date: run python3 tools/gen_layout_table.py", file=sys.stderr)
            return 1
        return 0
    if fresh != table:
        TABLE.write_text(fresh)
        print(f"gen_layout_table: wrote {TABLE}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
