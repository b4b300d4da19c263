# SPDX-License-Identifier: MIT
"""Every numeric setting's range and default, wherever the documentation restates them, is the one of
docs/parameters.md's "Ranges" table (which core_setting_limits checks against src/core/setting_limits.hpp and
kissm_config_init): the field comments of kissm_config in include/kissm.h (range and "Default X"), the field
docstrings of the Python Config (range) and the Rust ConfigBuilder's setter docs (range and "default X").

Every table row must be found in every source, so a parser that stops matching fails rather than passes.
A range is written `in [a, b]` / `in (a, b]`, `a..b` (Python, C) or `a..=b` (Rust) for counts, `> 0` for
(0, inf) and `>= 0, finite` for [0, 1e+300]. A stated default may round the table's (`0.0349` for 0.0349066).

    python3 tests/tooling/check_setting_docs.py --root REPO
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

Range = tuple[str, str, str, str]  # lower bracket, lower, upper, upper bracket


def table(text: str) -> dict[str, tuple[str, str]]:
    """The `| `field` | range | default |` rows of the "## Ranges" section."""
    rows: dict[str, tuple[str, str]] = {}
    inside = False
    for line in text.splitlines():
        if line.startswith("## "):
            inside = line == "## Ranges"
        m = re.match(r"\| `(\w+)` \| ([^|]+) \| ([^|]+) \|$", line) if inside else None
        if m:
            rows[m.group(1)] = (m.group(2).strip(), m.group(3).strip())
    return rows


def parse_cell(cell: str) -> Range:
    m = re.fullmatch(r"([\[(])(\S+), (\S+)([\])])", cell)
    if not m:
        raise ValueError(f"table range {cell!r} is not [a, b] / (a, b] / (a, inf)")
    return m.group(1), m.group(2), m.group(3), m.group(4)


_STATED = [
    (re.compile(r"\bin ([\[(])\s*([\w.+-]+),\s*([\w.+-]+)\s*([\])])"), lambda m: m.groups()),
    (re.compile(r"\b(\d+)\.\.=?(\d+)\b"), lambda m: ("[", m.group(1), m.group(2), "]")),
    (re.compile(r">= 0, finite"), lambda m: ("[", "0", "1e300", "]")),
    (re.compile(r"> 0\b"), lambda m: ("(", "0", "inf", ")")),
]


def stated_range(doc: str) -> Range | None:
    """The first range the text states, in the order of _STATED's patterns by position."""
    found = [(m.start(), conv(m)) for pattern, conv in _STATED for m in [pattern.search(doc)] if m]
    return min(found)[1] if found else None


def same_number(a: str, b: str) -> bool:
    try:
        return float(a) == float(b)
    except ValueError:
        return a == b  # a symbolic bound (fpfh_radius_gain)


def same_range(doc: Range, cell: Range) -> bool:
    return doc[0] == cell[0] and doc[3] == cell[3] and same_number(doc[1], cell[1]) and same_number(doc[2], cell[2])


def rounds_to(table_value: str, stated: str) -> bool:
    """The stated default is the table's, perhaps rounded to the digits it shows."""
    digits = len(re.sub(r"^0+", "", re.sub(r"[^0-9]", "", stated.split("e")[0]))) or 1
    return float(f"{float(table_value):.{digits}g}") == float(stated)


def kissm_h(text: str) -> dict[str, str]:
    body = text[text.index("typedef struct kissm_config {") : text.index("} kissm_config;")]
    docs = {}
    for m in re.finditer(r"/\*\*(.*?)\*/\s*(?:double|int32_t)\s+(\w+)\s*;", body, re.S):
        docs[m.group(2)] = " ".join(line.strip().lstrip("*").strip() for line in m.group(1).splitlines())
    return docs


def python_config(text: str) -> dict[str, str]:
    pattern = r'^    (\w+): [^=\n]+= _DEFAULTS\["\w+"\]\n    """(.*?)"""'
    return {m.group(1): " ".join(m.group(2).split()) for m in re.finditer(pattern, text, re.S | re.M)}


def rust_builder(text: str) -> dict[str, str]:
    """The setters' docs: the entries of the `builder_setters! { ... }` blocks (the getters restate nothing)."""
    docs = {}
    for block in re.finditer(r"^\s*builder_setters! \{\n(.*?)^\s*\}\n", text, re.S | re.M):
        for m in re.finditer(r"((?:[ \t]*///[^\n]*\n)+)[ \t]*(\w+): (?:count|f64|bool),", block.group(1)):
            docs[m.group(2)] = " ".join(line.strip()[3:].strip() for line in m.group(1).splitlines())
    return docs


_DEFAULT = {
    "kissm.h": re.compile(r"\bDefault ([-+0-9.e]+)"),
    "Rust": re.compile(r"\(default ([-+0-9.e]+)[);,]|\b([-+0-9.e]+) \(the default\)"),
}


def check(root: Path) -> list[str]:
    rows = table((root / "docs/parameters.md").read_text())
    if not rows:
        return ["docs/parameters.md: no '## Ranges' table with a default column"]
    sources = {
        "kissm.h": kissm_h((root / "include/kissm.h").read_text()),
        "Python": python_config((root / "bindings/python/src/kissm/_config.py").read_text()),
        "Rust": rust_builder((root / "bindings/rust/kissm/src/config.rs").read_text()),
    }
    problems = []
    for name, (cell, default) in rows.items():
        want = parse_cell(cell)
        for source, docs in sources.items():
            doc = docs.get(name)
            if doc is None:
                problems.append(f"{source}: no documentation found for {name}")
                continue
            got = stated_range(doc)
            if got is None or not same_range(got, want):
                shown = "no range" if got is None else f"{got[0]}{got[1]}, {got[2]}{got[3]}"
                problems.append(f"{source}: {name} states {shown}; docs/parameters.md says {cell}")
            if source in _DEFAULT:
                m = _DEFAULT[source].search(doc)
                stated = next((g for g in m.groups() if g), None) if m else None
                if stated is None:
                    problems.append(f"{source}: {name} states no default; docs/parameters.md says {default}")
                elif not rounds_to(default, stated.rstrip(".")):
                    problems.append(f"{source}: {name} default {stated}; docs/parameters.md says {default}")
    return problems


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--root", type=Path, default=Path(__file__).resolve().parents[2])
    args = parser.parse_args()
    problems = check(args.root)
    for p in problems:
        print(p, file=sys.stderr)
    if problems:
        print(f"setting docs: {len(problems)} disagreement(s) with docs/parameters.md, 'Ranges'", file=sys.stderr)
        return 1
    print("setting docs: every restated range and default agrees with docs/parameters.md")
    return 0


if __name__ == "__main__":
    sys.exit(main())
