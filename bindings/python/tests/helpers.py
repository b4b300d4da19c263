# SPDX-License-Identifier: MIT
"""Comparisons and readers used by several test modules."""

from __future__ import annotations

import dataclasses
import re

import numpy as np

import kissm

TIME_FIELDS = {
    "time_voxelize_ms",
    "time_features_ms",
    "time_matching_ms",
    "time_pruning_ms",
    "time_solver_ms",
    "time_total_ms",
    "time_refine_ms",
}


def bits(value: object) -> object:
    """A value with floats replaced by their exact bit patterns (so NaN == NaN and -0.0 != 0.0)."""
    if isinstance(value, np.ndarray):
        return (value.dtype.str, value.shape, value.tobytes())
    if isinstance(value, float):
        return np.float64(value).tobytes()
    return value


def assert_same_result(a: kissm.Result, b: kissm.Result, ignore: set[str] = TIME_FIELDS) -> None:
    """Every field of two results bitwise equal, except the timings."""
    for field in dataclasses.fields(kissm.Result):
        if field.name in ignore:
            continue
        va, vb = getattr(a, field.name), getattr(b, field.name)
        assert bits(va) == bits(vb), f"{field.name}: {va!r} != {vb!r}"


def python_blocks(text: str) -> list[str]:
    """The bodies of the ```python blocks of a Markdown text, in order."""
    return re.findall(r"^```python\n(.*?)^```", text, flags=re.S | re.M)
