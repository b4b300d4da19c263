# SPDX-License-Identifier: MIT
"""The import-time self-check: version, ABI version and struct sizes, with clear ImportErrors."""

from __future__ import annotations

import os
import subprocess
import sys
import types
from pathlib import Path

import pytest

import kissm
from kissm import _ffi

FAKE_LIBRARY = r"""
#include <stdint.h>
uint32_t kissm_version_number(void) { return FAKE_VERSION; }
const char *kissm_version_string(void) { return "fake"; }
uint32_t kissm_abi_version(void) { return FAKE_ABI; }
uint32_t kissm_abi_sizeof(int32_t which) {
    switch (which) {
    case 1: return CONFIG_SIZE;
    case 2: return POINTS_SIZE;
    case 3: return RESULT_SIZE;
    default: return 0;
    }
}
"""


def import_kissm(library: str | os.PathLike[str]) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ, KISSM_LIBRARY=str(library))
    code = "import kissm, sys; sys.stdout.write(kissm.library_path)"
    return subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)


def fake_library(cc: str, tmp_path: Path, **overrides: int) -> Path:
    values = {
        "FAKE_VERSION": int(_ffi.lib.KISSM_VERSION_NUMBER),
        "FAKE_ABI": int(_ffi.lib.KISSM_ABI_VERSION),
        "CONFIG_SIZE": _ffi.ffi.sizeof("kissm_config"),
        "POINTS_SIZE": _ffi.ffi.sizeof("kissm_points"),
        "RESULT_SIZE": _ffi.ffi.sizeof("kissm_result"),
    }
    values.update(overrides)
    source = tmp_path / "fake.c"
    source.write_text(FAKE_LIBRARY)
    library = tmp_path / "libfake.so"
    defines = [f"-D{name}={value}" for name, value in values.items()]
    subprocess.run([cc, "-shared", "-fPIC", "-o", str(library), str(source), *defines], check=True)
    return library


def test_version_is_the_librarys_and_the_packages() -> None:
    assert kissm.__version__ == _ffi.text(_ffi.lib.kissm_version_string())
    major, minor, patch = (int(p) for p in kissm.__version__.split("."))
    assert major * 10000 + minor * 100 + patch == _ffi.lib.KISSM_VERSION_NUMBER
    from importlib.metadata import PackageNotFoundError, version

    try:
        assert version("kissm") == kissm.__version__
    except PackageNotFoundError:
        pass  # running from the source tree (PYTHONPATH=src)


def test_library_is_the_one_inside_the_package() -> None:
    if os.environ.get(_ffi.LIBRARY_ENV):
        pytest.skip(f"{_ffi.LIBRARY_ENV} is set")
    assert Path(kissm.library_path).parent == Path(kissm.__file__).parent
    assert Path(kissm.library_path).name == _ffi.library_file_name()
    assert not Path(kissm.library_path).is_symlink()


def test_struct_sizes_agree() -> None:
    for name, which in (("kissm_config", 1), ("kissm_points", 2), ("kissm_result", 3)):
        assert _ffi.ffi.sizeof(name) == _ffi.lib.kissm_abi_sizeof(which)


def _fake(**values: int) -> types.SimpleNamespace:
    lib = _ffi.lib
    defaults = {
        "kissm_abi_version": lambda: lib.KISSM_ABI_VERSION,
        "kissm_version_number": lambda: lib.KISSM_VERSION_NUMBER,
        "kissm_abi_sizeof": lambda which: lib.kissm_abi_sizeof(which),
        "KISSM_VERSION_NUMBER": lib.KISSM_VERSION_NUMBER,
        "KISSM_ABI_VERSION": lib.KISSM_ABI_VERSION,
        "KISSM_STRUCT_CONFIG": 1,
        "KISSM_STRUCT_POINTS": 2,
        "KISSM_STRUCT_RESULT": 3,
    }
    defaults.update(values)
    return types.SimpleNamespace(**defaults)


def test_check_library_accepts_the_real_library() -> None:
    _ffi.check_library(_ffi.ffi, _fake(), "real")


@pytest.mark.parametrize(
    ("fake", "expected"),
    [
        (_fake(kissm_version_number=lambda: 20301), "is kissm 2.3.1"),
        (_fake(kissm_abi_version=lambda: 7), "(ABI 7)"),
        (
            _fake(kissm_abi_sizeof=lambda which: 8 if which == 3 else _ffi.lib.kissm_abi_sizeof(which)),
            "sizeof(kissm_result) is 8",
        ),
    ],
    ids=["version", "abi", "struct-size"],
)
def test_check_library_refuses_a_mismatch(fake: types.SimpleNamespace, expected: str) -> None:
    with pytest.raises(ImportError, match="kissm:") as info:
        _ffi.check_library(_ffi.ffi, fake, "/some/libkissm.so")
    assert expected in str(info.value)
    assert "/some/libkissm.so" in str(info.value)


def test_check_library_refuses_a_library_without_the_symbols() -> None:
    fake = _fake()
    del fake.kissm_abi_sizeof
    with pytest.raises(ImportError, match="not a compatible kissm library"):
        _ffi.check_library(_ffi.ffi, fake, "/other.so")


def test_kissm_library_override_is_used() -> None:
    done = import_kissm(kissm.library_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout == os.path.abspath(kissm.library_path)


def test_kissm_library_override_must_exist(tmp_path: Path) -> None:
    done = import_kissm(tmp_path / "missing.so")
    assert done.returncode != 0
    assert "ImportError: kissm: KISSM_LIBRARY=" in done.stderr and "is not a file" in done.stderr


def test_a_file_that_is_no_library_is_an_import_error(tmp_path: Path) -> None:
    bogus = tmp_path / "libkissm.so"
    bogus.write_bytes(b"not an ELF file")
    done = import_kissm(bogus)
    assert done.returncode != 0
    assert "ImportError: kissm: cannot load" in done.stderr


@pytest.mark.parametrize(
    ("overrides", "expected"),
    [
        ({"FAKE_VERSION": 90909}, "is kissm 9.9.9"),
        ({"FAKE_ABI": 3}, "(ABI 3)"),
        ({"RESULT_SIZE": 8}, "sizeof(kissm_result) is 8 in the library"),
        ({"CONFIG_SIZE": 1024}, "sizeof(kissm_config) is 1024 in the library"),
    ],
    ids=["version", "abi", "result-size", "config-size"],
)
def test_a_mismatched_library_fails_the_import(
    cc: str, tmp_path: Path, overrides: dict[str, int], expected: str
) -> None:
    library = fake_library(cc, tmp_path, **overrides)
    done = import_kissm(library)
    assert done.returncode != 0, done.stdout
    assert "ImportError: kissm:" in done.stderr
    assert expected in done.stderr, done.stderr
