# SPDX-License-Identifier: MIT
"""Cross-language round trip, Python side: the clouds of tests/data registered as listed in
tests/data/golden.json (written by the C library) give the same result bit for bit. The C suite
(tests/roundtrip) and the Rust suite (kissm/tests/golden.rs) check the same file."""

from __future__ import annotations

import json
import struct

import numpy as np
import pytest

import kissm

import testdata

DATA = testdata.data_dir()  # the committed pair and golden.json, from tests/data
GOLDEN = json.loads((DATA / "golden.json").read_text())

COUNTS = [
    "num_source_points",
    "num_target_points",
    "num_source_voxels",
    "num_target_voxels",
    "num_source_keypoints",
    "num_target_keypoints",
    "num_initial_correspondences",
    "num_pruned_correspondences",
    "num_rotation_inliers",
    "num_final_inliers",
    "max_core_number",
]


def bits(x: float) -> bytes:
    return struct.pack("<d", x)


@pytest.mark.parametrize("case", GOLDEN["cases"], ids=lambda c: c["name"])
@pytest.mark.parametrize("threads", [1, 2])
def test_golden(case: dict, threads: int) -> None:
    source = kissm.read_points(DATA / GOLDEN["source"])
    target = kissm.read_points(DATA / GOLDEN["target"])
    if case["scalar"] == "float32":
        source, target = source.astype(np.float32), target.astype(np.float32)
    with kissm.Matcher(voxel_size=case["voxel_size"], num_threads=threads) as matcher:
        result = matcher.register(source, target)
    assert result.valid == bool(case["valid"])
    assert result.reason_code == case["reason"]
    got = [bits(v) for v in result.transform.ravel()]
    expect = [bits(v) for v in case["transform"]]
    assert got == expect
    for name in COUNTS:
        assert getattr(result, name) == case[name], name
    assert bits(result.residual_rms) == bits(case["residual_rms"])
