"""Loading libkissm: the cffi declarations, the library file, and the check that they agree.

The declarations come from ``_kissm_cffi.py``, an out-of-line ABI-mode module that the package build
generates from ``_cdef.h`` (itself generated from ``include/kissm.h``; a test fails when it drifts). In a
source tree where no build has run, ``_cdef.h`` is parsed at import instead.

ABI mode does no checking of its own: a library built from another header would be called with the wrong
struct layouts. So at import the library's version, ABI version and the size of every public struct are
compared with the declarations, and any difference raises :class:`ImportError` before a single struct is
passed to the library.
"""

from __future__ import annotations

import importlib.resources
import os
import sys
from typing import Any

LIBRARY_ENV = "KISSM_LIBRARY"

#: (cdef type name, id for kissm_abi_sizeof), for the self-check.
_STRUCTS = (("kissm_config", "KISSM_STRUCT_CONFIG"), ("kissm_points", "KISSM_STRUCT_POINTS"),
            ("kissm_result", "KISSM_STRUCT_RESULT"))


def _load_declarations() -> Any:
    try:
        from ._kissm_cffi import ffi as built_ffi
    except ModuleNotFoundError as e:
        if e.name != f"{__package__}._kissm_cffi":
            raise
    else:
        return built_ffi
    import cffi  # a source tree without a build: parse the committed cdef (needs pycparser)

    source_ffi = cffi.FFI()
    source_ffi.cdef(importlib.resources.files(__package__).joinpath("_cdef.h").read_text(encoding="utf-8"))
    return source_ffi


def library_file_name() -> str:
    """The shared library's file name on this platform."""
    if sys.platform == "win32":
        return "kissm.dll"
    if sys.platform == "darwin":
        return "libkissm.dylib"
    return "libkissm.so"


def find_library() -> str:
    """The path of the library to load: ``$KISSM_LIBRARY`` when set, else the one inside the package."""
    override = os.environ.get(LIBRARY_ENV)
    if override:
        if not os.path.isfile(override):
            raise ImportError(f"kissm: {LIBRARY_ENV}={override!r} is not a file; point it at a built "
                              f"{library_file_name()} or unset it to use the package's own library")
        return os.path.abspath(override)
    resource = importlib.resources.files(__package__).joinpath(library_file_name())
    path = os.fspath(resource) if isinstance(resource, os.PathLike) else str(resource)
    if not os.path.isfile(path):
        raise ImportError(
            f"kissm: the shared library {library_file_name()} is not in {os.path.dirname(path)}: this copy of "
            f"the package was not built. Install it with 'pip install ./bindings/python' from a kissm "
            f"checkout, or set {LIBRARY_ENV} to a built {library_file_name()}.")
    return path


def _version_text(number: int) -> str:
    return f"{number // 10000}.{number // 100 % 100}.{number % 100}"


def check_library(ffi: Any, lib: Any, path: str) -> None:
    """Raise ImportError unless ``lib`` is the kissm these declarations describe.

    The library must have the same version number and ABI version as the header the declarations were
    generated from, and the same ``sizeof`` for every public struct.
    """
    try:
        abi = int(lib.kissm_abi_version())
        number = int(lib.kissm_version_number())
        sizes = {name: int(lib.kissm_abi_sizeof(getattr(lib, which))) for name, which in _STRUCTS}
    except AttributeError as e:  # a symbol is missing: not a kissm library, or a very different one
        raise ImportError(f"kissm: {path} is not a compatible kissm library ({e})") from None
    expected_number = int(lib.KISSM_VERSION_NUMBER)
    expected_abi = int(lib.KISSM_ABI_VERSION)
    hint = (f" Reinstall the package (pip install ./bindings/python) so that its library and declarations "
            f"match{', or unset ' + LIBRARY_ENV if os.environ.get(LIBRARY_ENV) else ''}.")
    if abi != expected_abi or number != expected_number:
        raise ImportError(
            f"kissm: the library {path} is kissm {_version_text(number)} (ABI {abi}), but this package's "
            f"declarations are for kissm {_version_text(expected_number)} (ABI {expected_abi})." + hint)
    for name, _ in _STRUCTS:
        if sizes[name] != ffi.sizeof(name):
            raise ImportError(
                f"kissm: sizeof({name}) is {sizes[name]} in the library {path} but {ffi.sizeof(name)} in this "
                f"package's declarations: they were built from different headers." + hint)


def _open() -> tuple[Any, Any, str]:
    declarations = _load_declarations()
    path = find_library()
    try:
        library = declarations.dlopen(path)
    except OSError as e:
        raise ImportError(f"kissm: cannot load {path}: {e}") from None
    check_library(declarations, library, path)
    return declarations, library, path


ffi, lib, library_path = _open()


def text(c_string: Any) -> str:
    """A library-owned ``const char *`` as str (copied at once: such strings are short-lived)."""
    if c_string == ffi.NULL:
        return ""
    return str(ffi.string(c_string).decode("utf-8", errors="replace"))
