# SPDX-License-Identifier: MIT
"""Cross-language round trip, Python side: the clouds of tests/data registered (``"call": "register"``) or
refined from the case's initial transform (``"call": "refine"``) as listed in tests/data/golden.json (written by
the C library) give the same result bit for bit: validity, reason, every count, the transforms, the information
matrix, the degeneracy and its weak directions, and every double (null in the file is NaN). The C suite
(tests/roundtrip) and the Rust suite (kissm/tests/golden.rs) check the same file."""

from __future__ import annotations

import json
import math
import struct
from typing import Any

import numpy as np
import pytest

import kissm
from kissm import _ffi

import testdata

DATA = testdata.data_dir()  # the committed pair and golden.json, from tests/data
# (%.17g prints -0.0 as "-0", which json would read as the integer 0.)
GOLDEN = json.loads((DATA / "golden.json").read_text(), parse_int=lambda t: -0.0 if t == "-0" else int(t))

#: Every golden integer, by its kissm_result name (refine_converged is a bool in Python, 0/1 in the file).
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
    "num_refine_correspondences",
    "refine_iterations",
    "refine_converged",
    "degenerate",
    "num_weak_directions",
    "num_source_suppressed",
    "num_target_suppressed",
]
DOUBLES = [
    "residual_rms",
    "overlap",
    "refine_rmse",
    "refine_condition",
    "rotation_uncertainty",
    "inlier_coverage",
    "tilt",
    "ambiguity",
    "confidence",
    "voxel_size_used",
]
ARRAYS = ["transform", "coarse_transform", "information"]
#: The weak directions: 36 doubles in the file (row-major 6x6, the rows beyond num_weak_directions NaN), the
#: rows in use in Python, shape (num_weak_directions, 6).
WEAK = ["weak_directions"]


def bits(x: float | None) -> bytes:
    """The exact bits of a golden number; every NaN (JSON null) as one pattern."""
    return struct.pack("<d", math.nan if x is None or math.isnan(x) else x)


def run_case(case: dict[str, Any], threads: int) -> kissm.Result:
    source = kissm.read_points(DATA / GOLDEN["source"])
    target = kissm.read_points(DATA / GOLDEN["target"])
    if case["scalar"] == "float32":
        source, target = source.astype(np.float32), target.astype(np.float32)
    else:
        assert case["scalar"] == "float64", case["scalar"]
    config = kissm.Config(
        voxel_size=case["voxel_size"],
        num_threads=threads,
        refine_mode=case["refine"],
        viewpoint_mode=case["viewpoint"],
        suppression=case["suppression"],
        rotation_dof=case["rotation_dof"],
        max_refine_rmse_gain=case["max_refine_rmse_gain"],
        min_refine_condition=case["min_refine_condition"],
        allow_degenerate=bool(case["allow_degenerate"]),
        max_ambiguity=case["max_ambiguity"],
    )
    with kissm.Matcher(config) as matcher:
        if case["call"] == "refine":
            initial = np.array(case["initial_transform"], dtype=np.float64).reshape(4, 4)
            return matcher.refine(source, target, initial)
        assert case["call"] == "register", case["call"]
        return matcher.register(source, target)


def test_golden_file_lists_every_kind_of_case() -> None:
    """The cases this test must understand are all there (a new kind needs code here)."""
    calls = {(case["call"], case["refine"]) for case in GOLDEN["cases"]}
    assert {("register", "none"), ("register", "gicp"), ("register", "point_to_plane"), ("refine", "gicp")} <= calls
    assert {"fixed", "sign_free", "local"} <= {case["viewpoint"] for case in GOLDEN["cases"]}
    assert {"none", "ground"} <= {case["suppression"] for case in GOLDEN["cases"]}
    assert {3, 1} <= {case["rotation_dof"] for case in GOLDEN["cases"]}
    # A refinement held to a tighter residual than its alignment leaves: KISSM_REASON_LOOSE_ALIGNMENT.
    assert _ffi.lib.KISSM_REASON_LOOSE_ALIGNMENT in {case["reason"] for case in GOLDEN["cases"]}
    # A degenerate refined pose, valid under allow_degenerate, with its weak directions.
    assert any(case["valid"] and case["degenerate"] and case["allow_degenerate"] for case in GOLDEN["cases"])
    # A pose refused for its ambiguity under a bound below the yard's competitor's share.
    assert _ffi.lib.KISSM_REASON_AMBIGUOUS in {case["reason"] for case in GOLDEN["cases"]}
    for case in GOLDEN["cases"]:
        assert case["call"] in ("register", "refine") and case["refine"] in kissm._config.REFINE_MODES
        assert case["viewpoint"] in kissm._config.VIEWPOINT_MODES
        assert ("initial_transform" in case) == (case["call"] == "refine")
        assert all(name in case for name in COUNTS + DOUBLES + ARRAYS + WEAK), case["name"]
        assert case["allow_degenerate"] in (0, 1) and 0.0 <= case["min_refine_condition"] <= 1.0, case["name"]
        assert 0.0 <= case["max_ambiguity"] <= 1.0, case["name"]
        assert 0 <= case["num_weak_directions"] <= 6 and len(case["weak_directions"]) == 36, case["name"]
        assert case["degenerate"] == (case["num_weak_directions"] > 0), case["name"]


@pytest.mark.parametrize("case", GOLDEN["cases"], ids=lambda c: c["name"])
@pytest.mark.parametrize("threads", [1, 2])
def test_golden(case: dict[str, Any], threads: int) -> None:
    result = run_case(case, threads)
    assert result.valid == bool(case["valid"])
    assert result.reason_code == case["reason"]
    for name in ARRAYS:
        got = [bits(v) for v in getattr(result, name).ravel()]
        expect = [bits(v) for v in case[name]]
        assert got == expect, f"{name}: {getattr(result, name).ravel().tolist()} != {case[name]}"
    for name in COUNTS:
        assert int(getattr(result, name)) == case[name], name
    k = case["num_weak_directions"]
    weak = result.weak_directions
    assert weak.shape == (k, 6) and weak.dtype == np.float64 and type(result.degenerate) is bool
    got = [bits(v) for v in weak.ravel()]
    expect = [bits(v) for v in case["weak_directions"][: 6 * k]]
    assert got == expect, f"weak_directions: {weak.tolist()} != {case['weak_directions'][: 6 * k]}"
    assert all(bits(v) == bits(math.nan) for v in case["weak_directions"][6 * k :])  # the unused rows, NaN in C
    for name in DOUBLES:
        assert bits(getattr(result, name)) == bits(case[name]), f"{name}: {getattr(result, name)!r} != {case[name]}"
    assert result.refined == (case["refine"] != "none" or case["call"] == "refine")
