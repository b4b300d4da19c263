#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Does bindgen work here? Loads the libclang that bindgen (clang-sys) would pick and parses a one-line
header that includes <stddef.h>, as kissm.h does. Exit 0 when it parses without an error; 1 otherwise,
saying why and which package to install.

A libclang*.so file alone proves nothing: Debian's libclang1-14 (a dependency of doxygen) is the library
without clang's builtin headers (libclang-common-14-dev), and bindgen then fails with "'stddef.h' file not
found". This runs the same parse, so it fails the same way.

    python3 tools/probe_libclang.py [-v]
"""

from __future__ import annotations

import ctypes
import glob
import os
import re
import shutil
import subprocess
import sys

PACKAGE = "libclang-dev"
HEADER = b"#include <stddef.h>\nsize_t kissm_probe(void);\n"
CXDiagnostic_Error = 3


def candidates() -> list[str]:
    """libclang shared libraries in clang-sys's order of places: LIBCLANG_PATH, llvm-config --libdir, then
    the usual system folders; the newest version first within each, as clang-sys prefers it."""
    dirs: list[str] = []
    env = os.environ.get("LIBCLANG_PATH", "")
    if env:
        dirs.append(env if os.path.isdir(env) else os.path.dirname(env))
    llvm_config = shutil.which("llvm-config")
    if llvm_config:
        out = subprocess.run([llvm_config, "--libdir"], capture_output=True, text=True, check=False)
        if out.returncode == 0 and out.stdout.strip():
            dirs.append(out.stdout.strip())
    dirs += sorted(glob.glob("/usr/lib/llvm-*/lib"), key=version_key, reverse=True)
    dirs += ["/usr/local/lib", "/usr/lib/x86_64-linux-gnu", "/usr/lib/aarch64-linux-gnu", "/usr/lib64", "/usr/lib"]
    found: list[str] = []
    for d in dirs:
        names = [n for n in glob.glob(os.path.join(d, "libclang*.so*")) if re.search(r"/libclang(-[0-9.]+)?\.so", n)]
        for name in sorted(names, key=version_key, reverse=True):
            if name not in found:
                found.append(name)
    return found


def version_key(path: str) -> tuple[int, ...]:
    return tuple(
        int(n) for n in re.findall(r"[0-9]+", os.path.basename(os.path.dirname(path)) + os.path.basename(path))
    )


class CXUnsavedFile(ctypes.Structure):
    _fields_ = [("Filename", ctypes.c_char_p), ("Contents", ctypes.c_char_p), ("Length", ctypes.c_ulong)]


class CXString(ctypes.Structure):
    _fields_ = [("data", ctypes.c_void_p), ("private_flags", ctypes.c_uint)]


def parse_errors(path: str) -> list[str]:
    """The error diagnostics of parsing HEADER with the libclang at `path`."""
    lib = ctypes.CDLL(path)
    lib.clang_createIndex.restype = ctypes.c_void_p
    lib.clang_createIndex.argtypes = [ctypes.c_int, ctypes.c_int]
    lib.clang_parseTranslationUnit.restype = ctypes.c_void_p
    lib.clang_parseTranslationUnit.argtypes = [
        ctypes.c_void_p,
        ctypes.c_char_p,
        ctypes.POINTER(ctypes.c_char_p),
        ctypes.c_int,
        ctypes.POINTER(CXUnsavedFile),
        ctypes.c_uint,
        ctypes.c_uint,
    ]
    lib.clang_getNumDiagnostics.restype = ctypes.c_uint
    lib.clang_getNumDiagnostics.argtypes = [ctypes.c_void_p]
    lib.clang_getDiagnostic.restype = ctypes.c_void_p
    lib.clang_getDiagnostic.argtypes = [ctypes.c_void_p, ctypes.c_uint]
    lib.clang_getDiagnosticSeverity.restype = ctypes.c_int
    lib.clang_getDiagnosticSeverity.argtypes = [ctypes.c_void_p]
    lib.clang_formatDiagnostic.restype = CXString
    lib.clang_formatDiagnostic.argtypes = [ctypes.c_void_p, ctypes.c_uint]
    lib.clang_getCString.restype = ctypes.c_char_p
    lib.clang_getCString.argtypes = [CXString]
    lib.clang_disposeString.argtypes = [CXString]
    lib.clang_disposeDiagnostic.argtypes = [ctypes.c_void_p]
    lib.clang_disposeTranslationUnit.argtypes = [ctypes.c_void_p]
    lib.clang_disposeIndex.argtypes = [ctypes.c_void_p]

    index = lib.clang_createIndex(0, 0)
    unsaved = CXUnsavedFile(b"kissm_probe.h", HEADER, len(HEADER))
    args = (ctypes.c_char_p * 2)(b"-x", b"c")
    tu = lib.clang_parseTranslationUnit(index, b"kissm_probe.h", args, 2, ctypes.byref(unsaved), 1, 0)
    if not tu:
        lib.clang_disposeIndex(index)
        return ["libclang could not parse the probe header at all"]
    errors = []
    for i in range(lib.clang_getNumDiagnostics(tu)):
        diag = lib.clang_getDiagnostic(tu, i)
        if lib.clang_getDiagnosticSeverity(diag) >= CXDiagnostic_Error:
            text = lib.clang_formatDiagnostic(diag, 0)
            errors.append((lib.clang_getCString(text) or b"").decode(errors="replace"))
            lib.clang_disposeString(text)
        lib.clang_disposeDiagnostic(diag)
    lib.clang_disposeTranslationUnit(tu)
    lib.clang_disposeIndex(index)
    return errors


def main() -> int:
    verbose = "-v" in sys.argv[1:]
    libs = candidates()
    if not libs:
        print(f"probe_libclang: no libclang shared library found (apt-get install {PACKAGE}, or set LIBCLANG_PATH)")
        return 1
    for path in libs:
        try:
            errors = parse_errors(path)
        except (OSError, AttributeError) as exc:  # not loadable, or not a libclang: clang-sys would try the next
            if verbose:
                print(f"probe_libclang: {path}: not usable ({exc})")
            continue
        if errors:
            print(f"probe_libclang: {path} cannot parse a header including <stddef.h>: {'; '.join(errors)}")
            print(f"probe_libclang: clang's builtin headers are missing: apt-get install {PACKAGE}")
            return 1
        if verbose:
            print(f"probe_libclang: {path} parses a header including <stddef.h>")
        return 0
    print(f"probe_libclang: none of {', '.join(libs)} loads as libclang (apt-get install {PACKAGE})")
    return 1


if __name__ == "__main__":
    sys.exit(main())
