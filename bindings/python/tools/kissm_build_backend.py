# SPDX-License-Identifier: MIT
"""The package's PEP 517 build backend: scikit-build-core, after refreshing ``_core/`` from the checkout.

pyproject.toml names this module (``backend-path = ["tools"]``). Every hook first runs
:func:`vendor_core.vendor` when the package sits in a kissm checkout, then hands over to
``scikit_build_core.build`` unchanged. In an unpacked sdist there is no checkout around the package and
the shipped ``_core/`` is used as it is.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from scikit_build_core import build as _skbuild

import vendor_core

#: The PEP 517 / 660 hooks scikit-build-core provides, all of them passed through.
HOOKS = (
    "get_requires_for_build_sdist",
    "get_requires_for_build_wheel",
    "get_requires_for_build_editable",
    "prepare_metadata_for_build_wheel",
    "prepare_metadata_for_build_editable",
    "build_sdist",
    "build_wheel",
    "build_editable",
)


def _refresh_core() -> None:
    if vendor_core.is_checkout(vendor_core.DEFAULT_REPO):
        vendor_core.vendor()


def _after_refreshing_core(name: str) -> Callable[..., Any]:
    hook = getattr(_skbuild, name)

    def run(*args: Any, **kwargs: Any) -> Any:
        _refresh_core()
        return hook(*args, **kwargs)

    run.__name__ = run.__qualname__ = name
    run.__doc__ = f"scikit_build_core.build.{name}, after refreshing _core/ from the checkout."
    return run


globals().update({name: _after_refreshing_core(name) for name in HOOKS})
