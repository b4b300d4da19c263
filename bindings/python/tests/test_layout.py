# SPDX-License-Identifier: MIT
"""The struct layout the Python declarations use equals the C ABI's committed layout
(tests/abi/layout.json, checked against the compiled header by the C suite) and the loaded library's
kissm_abi_sizeof: every struct's size and every field's offset and size."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from kissm import _ffi

LAYOUT = Path(__file__).resolve().parents[3] / "tests" / "abi" / "layout.json"


@pytest.mark.skipif(not LAYOUT.exists(), reason="tests/abi/layout.json not found (not a source checkout)")
@pytest.mark.skipif(_ffi.ffi.sizeof("void *") != 8, reason="layout.json describes 64-bit targets")
def test_layout_matches_c_abi() -> None:
    layout = json.loads(LAYOUT.read_text())
    ffi, lib = _ffi.ffi, _ffi.lib
    assert layout["structs"], "layout.json lists no structs"
    for name, struct in layout["structs"].items():
        assert ffi.sizeof(name) == struct["size"], name
        assert lib.kissm_abi_sizeof(struct["id"]) == struct["size"], name
        declared = [field for field, _ in ffi.typeof(name).fields]
        assert declared == [f["name"] for f in struct["fields"]], name
        for field in struct["fields"]:
            assert ffi.offsetof(name, field["name"]) == field["offset"], (name, field["name"])
            assert ffi.sizeof(ffi.typeof(name).fields[declared.index(field["name"])][1].type) == field["size"], (
                name,
                field["name"],
            )
