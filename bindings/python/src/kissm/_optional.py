# SPDX-License-Identifier: MIT
"""The optional dependencies of ``kissm.io``: imported when first needed, so ``import kissm`` needs none of them,
and named with the extra that installs them when missing."""

from __future__ import annotations

import importlib
from typing import Any


def require(module: str, extra: str, what: str) -> Any:
    """The module ``module``; ``ModuleNotFoundError`` naming ``pip install kissm[extra]`` when it is missing."""
    try:
        return importlib.import_module(module)
    except ImportError as e:
        raise ModuleNotFoundError(
            f"{what} needs the Python package {module.split('.')[0]}: pip install kissm[{extra}] ({e})",
            name=module,
        ) from e
