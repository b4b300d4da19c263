# SPDX-License-Identifier: MIT
"""The cffi declarations must be exactly what tools/gen_cdef.py makes of include/kissm.h."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import cffi
import pytest

import kissm
from kissm import _ffi

from conftest import PACKAGE_ROOT, REPO_ROOT

HEADER = REPO_ROOT / "include" / "kissm.h"
COMMITTED_CDEF = PACKAGE_ROOT / "src" / "kissm" / "_cdef.h"
GENERATOR = PACKAGE_ROOT / "tools" / "gen_cdef.py"


@pytest.fixture(scope="module")
def gen_cdef():
    if not GENERATOR.is_file():
        pytest.skip(f"{GENERATOR} not found (tests run outside the kissm checkout)")
    spec = importlib.util.spec_from_file_location("gen_cdef", GENERATOR)
    module = importlib.util.module_from_spec(spec)
    assert spec.loader is not None
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def fresh_cdef(gen_cdef) -> str:
    if not HEADER.is_file():
        pytest.skip(f"{HEADER} not found")
    return gen_cdef.generate_from_file(HEADER)


def test_committed_cdef_matches_the_header(gen_cdef, fresh_cdef: str) -> None:
    committed = COMMITTED_CDEF.read_text(encoding="utf-8")
    assert committed == fresh_cdef, (
        "bindings/python/src/kissm/_cdef.h drifted from include/kissm.h; regenerate it with "
        "'python3 bindings/python/tools/gen_cdef.py --write':\n"
        + gen_cdef.diff(fresh_cdef, committed, "fresh", "committed")
    )


def test_installed_cdef_matches_the_header(fresh_cdef: str) -> None:
    installed = Path(kissm.__file__).parent / "_cdef.h"
    assert installed.read_text(encoding="utf-8") == fresh_cdef


def test_loaded_declarations_match_the_header(fresh_cdef: str) -> None:
    """The module the build generated (what the package really uses) agrees with a fresh parse."""
    fresh = cffi.FFI()
    fresh.cdef(fresh_cdef)
    loaded = _ffi.ffi
    for name in ("kissm_config", "kissm_points", "kissm_result"):
        assert loaded.sizeof(name) == fresh.sizeof(name), name
        assert loaded.alignof(name) == fresh.alignof(name), name
        fresh_fields = [(f, field.offset, field.type.cname) for f, field in fresh.typeof(name).fields]
        loaded_fields = [(f, field.offset, field.type.cname) for f, field in loaded.typeof(name).fields]
        assert loaded_fields == fresh_fields, name
    for macro, value in re.findall(r"^#define (\w+) (-?\d+)$", fresh_cdef, flags=re.M):
        assert getattr(_ffi.lib, macro) == int(value), macro
    for function in re.findall(r"\b(kissm_\w+)\(", fresh_cdef):
        if function.endswith("_fn"):
            continue
        assert getattr(_ffi.lib, function) is not None, function


def test_every_header_function_is_declared(fresh_cdef: str) -> None:
    header_functions = set(re.findall(r"KISSM_API\s+[^;(]*?\b(kissm_\w+)\s*\(", HEADER.read_text()))
    cdef_functions = set(re.findall(r"\b(kissm_\w+)\(", fresh_cdef)) - {"kissm_log_fn", "kissm_progress_fn"}
    assert header_functions and header_functions == cdef_functions


def test_every_header_integer_macro_is_declared(fresh_cdef: str) -> None:
    header_macros = set(re.findall(r"^#define\s+(KISSM_[A-Z0-9_]+)\s+\(?-?\w", HEADER.read_text(), flags=re.M))
    header_macros -= {"KISSM_API", "KISSM_H", "KISSM_VERSION_STRING"}
    # floating-point macros are listed in the cdef's comment, like the string macro
    floats = set(re.findall(r"^#define\s+(KISSM_[A-Z0-9_]+)\s+-?\d+\.\d*\s*$", HEADER.read_text(), flags=re.M))
    assert floats == {"KISSM_POSE_GRAPH_DEFAULT_BOUND"}
    assert all(f" *   {name} " in fresh_cdef for name in floats)
    header_macros -= floats
    cdef_macros = set(re.findall(r"^#define (\w+) ", fresh_cdef, flags=re.M))
    assert header_macros == cdef_macros


# ---- the generator itself, on small headers -------------------------------------------------------------


def test_generator_evaluates_conditionals_and_expressions(gen_cdef) -> None:
    header = """
    /* a comment with #define FAKE 1 inside */
    #ifndef GUARD_H
    #define GUARD_H
    #include <stdint.h>
    #if defined(_WIN32)
    #  define API __declspec(dllexport)
    #elif defined(__GNUC__) || defined(__clang__)
    #  define API __attribute__((visibility("default")))
    #else
    #  define API
    #endif
    #ifdef __cplusplus
    extern "C" {
    #endif
    #define A 2
    #define B (A * 100 + 3) // trailing comment
    #define NEG -14
    #define NAME "text"
    API int32_t f(int32_t x,
                  double y); /* documented */
    #ifdef __cplusplus
    }
    #endif
    #endif
    """
    out = gen_cdef.generate(header)
    body = out.split("*/\n", 2)[-1]
    assert "#define A 2\n#define B 203\n#define NEG -14\n" in body
    assert "int32_t f(int32_t x,\n    double y);" in body
    for absent in ("API", "extern", "GUARD_H", "FAKE", "__declspec", "__attribute__", "#include", "comment"):
        assert absent not in body, absent
    assert 'NAME "text"' in out  # listed in the banner comment
    cffi.FFI().cdef(out)  # and cffi accepts it in ABI mode


def test_generator_refuses_what_it_cannot_translate(gen_cdef) -> None:
    with pytest.raises(gen_cdef.CdefError, match="function-like"):
        gen_cdef.generate("#define MAX(a, b) ((a) > (b) ? (a) : (b))\n")
    with pytest.raises(gen_cdef.CdefError, match="unterminated"):
        gen_cdef.generate("#if 1\nint x;\n")


def test_generator_check_mode_reports_drift(gen_cdef, tmp_path: Path, fresh_cdef: str) -> None:
    stale = tmp_path / "_cdef.h"
    stale.write_text(fresh_cdef.replace("int32_t min_inliers;", "int32_t min_inliers_renamed;"))
    assert gen_cdef.main(["--header", str(HEADER), "--cdef", str(stale), "--check"]) == 1
    stale.write_text(fresh_cdef)
    assert gen_cdef.main(["--header", str(HEADER), "--cdef", str(stale), "--check"]) == 0
