# SPDX-License-Identifier: MIT
"""Running `kissm register --json` and comparing its output with a Python Result, bit for bit."""

from __future__ import annotations

import json
import math
import subprocess
from pathlib import Path
from typing import Any

import numpy as np

import kissm

from helpers import bits

#: CLI JSON "counts" key -> Result field.
COUNTS = {
    "source_points": "num_source_points",
    "target_points": "num_target_points",
    "source_nonfinite": "num_source_nonfinite",
    "target_nonfinite": "num_target_nonfinite",
    "source_voxels": "num_source_voxels",
    "target_voxels": "num_target_voxels",
    "source_keypoints": "num_source_keypoints",
    "target_keypoints": "num_target_keypoints",
    "initial_correspondences": "num_initial_correspondences",
    "pruned_correspondences": "num_pruned_correspondences",
    "max_core_number": "max_core_number",
    "rotation_inliers": "num_rotation_inliers",
    "final_inliers": "num_final_inliers",
}
#: The refinement's keys of the JSON: doubles and ints by Result field.
REFINE_DOUBLES = ("overlap", "refine_rmse", "refine_condition")
REFINE_INTS = ("refine_iterations",)
#: The validity measures, each with the key the JSON prints it right after (numbers; null for NaN and inf).
MEASURES = {"rotation_uncertainty": "inlier_extent", "inlier_coverage": "weak_directions"}


def _parse_int(text: str) -> Any:
    return -0.0 if text == "-0" else int(text)  # the CLI prints doubles -0.0 and 0.0 as "-0" and "0"


def run_cli(
    cli: Path,
    source: Path,
    target: Path,
    voxel: float,
    extra: list[str] | None = None,
    threads: int = 1,
    command_name: str = "register",
) -> dict[str, Any]:
    """`kissm register SOURCE TARGET --voxel V --threads 1 --json` (or `kissm refine ...` with
    ``command_name="refine"``) as a dict (exact doubles, null = NaN)."""
    command = [
        str(cli),
        command_name,
        str(source),
        str(target),
        "--voxel",
        repr(float(voxel)),
        "--threads",
        str(threads),
        "--json",
        *(extra or []),
    ]
    done = subprocess.run(command, capture_output=True, text=True, timeout=600)
    assert done.returncode in (0, 1), f"{command}: exit {done.returncode}: {done.stderr}"
    return json.loads(done.stdout, parse_int=_parse_int, parse_float=float)


def _doubles(value: Any) -> np.ndarray:
    return np.array(value, dtype=object).astype(float)  # None -> nan


def write_transform(path: Path, transform: np.ndarray) -> None:
    """A 4x4 transform as the CLI reads it (`--initial`) and writes it (`--out-transform`): 4 lines of 4
    numbers, here Python's shortest round-trip repr, so the CLI reads back the exact doubles."""
    path.write_text(
        "# p_target = T p_source\n" + "".join(" ".join(map(repr, row)) + "\n" for row in transform.tolist())
    )


def _assert_same_bits(name: str, got: Any, expected: Any) -> None:
    expected = _doubles(expected).reshape(np.shape(got))
    assert bits(np.asarray(got, dtype=np.float64)) == bits(expected), f"{name}:\n{got!r}\n!=\n{expected!r}"


def _assert_same_number(name: str, got: float, expected: float | None) -> None:
    """The JSON's number is the Result's to the bit; its null stands for any non-finite value (NaN or inf)."""
    if expected is None:
        assert not math.isfinite(got), f"{name}: {got!r} != null"
    else:
        assert bits(np.float64(got)) == bits(np.float64(expected)), f"{name}: {got!r} != {expected!r}"


def assert_matches_cli(result: kissm.Result, cli: dict[str, Any], refine_mode: str | None = None) -> None:
    """Every field the CLI prints equals the Result's, bit for bit; ``refine_mode`` (a Config name) is checked
    against the JSON's "refine" when given."""
    assert result.valid == cli["valid"]
    assert (result.reason, result.reason_code) == (cli["reason"], cli["reason_code"])
    for name in ("transform", "rotation", "translation", "inlier_extent"):
        _assert_same_bits(name, getattr(result, name), cli[name])
    assert result.num_final_inliers == cli["final_inliers"]
    for key, field in COUNTS.items():
        assert getattr(result, field) == cli["counts"][key], field
    for name in ("inlier_ratio", "residual_rms", "noise_bound", "voxel_size_used"):
        _assert_same_bits(name, getattr(result, name), cli[name])
    if refine_mode is not None:
        assert cli["refine"] == refine_mode.replace("_", "-")  # the CLI spells it point-to-plane
    _assert_same_bits("coarse_transform", result.coarse_transform, cli["coarse_transform"])
    information = cli["information"]
    assert (information is not None) == result.refined
    _assert_same_bits("information", result.information, information if information is not None else [math.nan] * 36)
    for name in REFINE_DOUBLES:
        _assert_same_bits(name, getattr(result, name), cli[name])
    for name in REFINE_INTS:
        assert getattr(result, name) == cli[name], name
    assert result.refine_converged is cli["refine_converged"]
    # the degeneracy right after refine_condition: a bool, and the k weak directions as k rows of 6 ([] when none)
    assert result.degenerate is cli["degenerate"]
    assert len(cli["weak_directions"]) == result.num_weak_directions == len(result.weak_directions)
    assert all(len(row) == 6 for row in cli["weak_directions"]), cli["weak_directions"]
    _assert_same_bits("weak_directions", result.weak_directions, cli["weak_directions"])
    assert result.num_refine_correspondences == cli["counts"]["refine_correspondences"]
    assert list(cli["counts"]).index("refine_correspondences") == list(cli["counts"]).index("final_inliers") + 1
    assert list(cli["time_ms"])[-2:] == ["refine", "total"]
    keys = list(cli)
    assert keys.index("degenerate") == keys.index("refine_condition") + 1, keys
    assert keys.index("weak_directions") == keys.index("degenerate") + 1, keys
    for name, after in MEASURES.items():
        _assert_same_number(name, getattr(result, name), cli[name])
        assert keys.index(name) == keys.index(after) + 1, (name, keys)
