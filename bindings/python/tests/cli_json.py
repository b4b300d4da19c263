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


def _parse_int(text: str) -> Any:
    return -0.0 if text == "-0" else int(text)  # the CLI prints doubles -0.0 and 0.0 as "-0" and "0"


def run_cli(
    cli: Path, source: Path, target: Path, voxel: float, extra: list[str] | None = None, threads: int = 1
) -> dict[str, Any]:
    """`kissm register SOURCE TARGET --voxel V --threads 1 --json` as a dict (exact doubles, null = NaN)."""
    command = [
        str(cli),
        "register",
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


def assert_matches_cli(result: kissm.Result, cli: dict[str, Any]) -> None:
    assert result.valid == cli["valid"]
    assert (result.reason, result.reason_code) == (cli["reason"], cli["reason_code"])
    for name in ("transform", "rotation", "translation", "inlier_extent"):
        expected = _doubles(cli[name]).reshape(getattr(result, name).shape)
        assert bits(getattr(result, name)) == bits(expected), f"{name}:\n{getattr(result, name)!r}\n!=\n{expected!r}"
    assert result.num_final_inliers == cli["final_inliers"]
    for key, field in COUNTS.items():
        assert getattr(result, field) == cli["counts"][key], field
    for name in ("inlier_ratio", "residual_rms", "noise_bound"):
        value = math.nan if cli[name] is None else float(cli[name])
        assert bits(getattr(result, name)) == bits(value), f"{name}: {getattr(result, name)!r} != {value!r}"
