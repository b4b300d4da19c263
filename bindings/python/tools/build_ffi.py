#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Build step: write the out-of-line ABI-mode cffi module ``kissm/_kissm_cffi.py``.

Run by ``bindings/python/CMakeLists.txt`` with the build environment's Python (which has cffi). It first
checks that the committed cdef (``src/kissm/_cdef.h``) is exactly what ``gen_cdef.py`` makes of the header
being built, so a wheel can never carry declarations that drifted from the library inside it; then it
serialises the parsed declarations into a plain Python module (no compiler, no Python headers). At run time
that module needs only cffi's ``_cffi_backend``, not pycparser.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import gen_cdef  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--header", type=Path, required=True, help="include/kissm.h")
    parser.add_argument("--cdef", type=Path, required=True, help="the committed src/kissm/_cdef.h")
    parser.add_argument("--output", type=Path, required=True, help="where to write _kissm_cffi.py")
    args = parser.parse_args(argv)

    fresh = gen_cdef.generate_from_file(args.header)
    committed = args.cdef.read_text(encoding="utf-8")
    if committed != fresh:
        sys.stderr.write(
            f"error: {args.cdef} is out of date with {args.header}.\n"
            f"Regenerate it with: python3 bindings/python/tools/gen_cdef.py --write\n"
            + gen_cdef.diff(fresh, committed, "fresh", "committed")
        )
        return 1

    try:
        import cffi
    except ImportError:
        sys.stderr.write(
            f"error: {sys.executable} has no cffi; build the package with pip (pip install "
            f"./bindings/python), or install cffi for this interpreter\n"
        )
        return 1

    ffi = cffi.FFI()
    ffi.cdef(committed)
    ffi.set_source("kissm._kissm_cffi", None)
    args.output.parent.mkdir(parents=True, exist_ok=True)
    with contextlib.redirect_stdout(io.StringIO()):  # cffi announces "generating ..."
        ffi.emit_python_code(str(args.output))
    return 0


if __name__ == "__main__":
    sys.exit(main())
