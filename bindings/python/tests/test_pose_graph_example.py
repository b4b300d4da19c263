# SPDX-License-Identifier: MIT
"""examples/python/pose_graph.py on the real KITTI 07 keyframes: the trajectory against graph.txt, and checks
that fail when the graph reads ``Result.information`` in the wrong order or frame.

What separates the conventions on this data (measured at 0.5 m voxels, GICP; 8 of the 10 pairs valid: the four
odometry steps and the loop closures 0-2, 0-3, 1-3, 2-4; 0-4 and 1-4 "too few inliers"):

* **The trajectory does not.** Every valid edge is within 0.19 deg / 3.7 cm of graph.txt, so
  any positive-definite weighting lands near the same optimum: keyframe errors at most 0.055 m / 0.135 deg with
  the documented information. The bounds below catch a broken graph, not a convention.
* **The real residuals show the order, and the calibration.** The optimised graph's chi-square (r^T I r summed
  over the edges) is 30.6 for 24 degrees of freedom with the documented information, 1.27 per dof: inside the
  [0.5, 2] that issue 33 asks of a calibrated information, with no factor (before the calibration, 3.1); every
  edge's value is at most 9.5, under the 99.9% chi-square quantile of 6 dof (22.5). Translation-first reads the
  millimetre-sigma translations as 0.1 mrad rotations and vice versa: 80 per dof, one edge at 727. The target's
  frame passes (1.36 per dof, edge max 10.0; conjugated the other way 1.81 and 15.9): the real errors do not
  show it.
* **The frame needs noise in every direction.** Between the two frames the information changes through the
  lever arm (the other keyframe 3-16 m away), which matters only against sigma_t / sigma_r, about 3 mm /
  0.1 mrad = 30 m here, and through the rotation of near-isotropic blocks: the two matrices differ by more
  than 3x (up to 17x, generalised eigenvalues) only for the loop closures 0-3 and 1-3, and there only along
  directions the real errors do not take. ``simulated_consistency`` draws each edge's error from the
  documented meaning of the information (source frame, rotation first, ``T_gt @ Exp(xi)``) on graph.txt's
  poses and the real graph (edges, informations), and optimises: with the right reading the mean chi-square
  per dof is 0.988-1.037 and the mean NEES 5.98-6.16 (seeds 0-2, 200 draws; the standard error of the
  chi-square ratio is about 0.02), as theory says (1 and 6); in the target's frame 1.51-1.68 and 9.7-10.2
  (conjugated the other way 1.81-2.10 and 12.8-14.2); translation-first about 80 and 4700. The bounds, 1 +- 0.15
  and 6 +- 15%, are 6 standard errors from the right reading and far from every wrong one.

The checks run on the example's own reading (``build_graph``'s default), so a wrong conversion in the example
fails them; each wrong reading is also passed in explicitly, and the same checks must fail. The noise is drawn
from ``result.information`` directly, never through the reading under test, which would make it agree with
itself. (Measured by editing the example: the blocks swapped, the target's frame, and the factor's keys
swapped with the inverse measurement each fail the test.)
"""

from __future__ import annotations

import importlib.util
import sys
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import pytest

from conftest import REPO_ROOT

gtsam = pytest.importorskip(
    "gtsam", reason="gtsam is not installed (the test extra installs gtsam 4.3.0 on Linux x86_64, Python >= 3.11)"
)

EXAMPLE = REPO_ROOT / "examples" / "python" / "pose_graph.py"
VOXEL = 0.5
DRAWS = 200

#: Trajectory bounds (measured 0.055 m / 0.135 deg absolute, 0.029 m / 0.145 deg between consecutive keyframes).
MAX_ABSOLUTE = (0.10, 0.30)
MAX_RELATIVE = (0.06, 0.30)
#: Every valid edge against graph.txt (measured at most 0.037 m / 0.19 deg): none is a wrong registration.
MAX_EDGE = (0.10, 0.50)
#: The real graph's chi-square per degree of freedom with a calibrated information (issue 33; measured 1.27).
CHI2_PER_DOF = (0.5, 2.0)
#: 99.9% quantile of the chi-square distribution with 6 degrees of freedom.
CHI2_6_999 = 22.458
#: The simulation: mean chi-square per dof within 1 +- this, mean NEES within 6 x (1 +- this).
SIMULATION_TOLERANCE = 0.15


def load_example() -> ModuleType:
    spec = importlib.util.spec_from_file_location("pose_graph_example", EXAMPLE)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up while the file runs
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def example() -> ModuleType:
    if not EXAMPLE.is_file():  # package_test.sh runs a copy of the tests outside the repository
        pytest.skip(f"{EXAMPLE} not found: the tests run outside the repository")
    return load_example()


@pytest.fixture(scope="module")
def keyframes(example: ModuleType, real_data: Path) -> Any:
    if not (real_data / example.DATASET / "graph.txt").is_file():
        pytest.skip(f"{real_data}/{example.DATASET}/graph.txt not found")
    return example.load_keyframes(real_data)


@pytest.fixture(scope="module")
def edges(example: ModuleType, keyframes: Any) -> list[Any]:
    return list(example.register_pairs(keyframes, voxel=VOXEL))


# The wrong readings of Result.information the checks must catch.


def translation_first(result: Any) -> np.ndarray:
    """g2o's order (translation, rotation) given to GTSAM unchanged: the 3x3 blocks swapped."""
    swap = np.block([[np.zeros((3, 3)), np.eye(3)], [np.eye(3), np.zeros((3, 3))]])
    return np.asarray(swap @ result.information @ swap.T)


def target_frame(result: Any) -> np.ndarray:
    """The information of the same error expressed in the target's frame (``Exp(eta) @ T = T @ Exp(xi)``,
    ``eta = Ad(T) xi``), as if it were the source's."""
    inverse_adjoint = np.linalg.inv(gtsam.Pose3(result.transform).AdjointMap())
    return np.asarray(inverse_adjoint.T @ result.information @ inverse_adjoint)


def target_frame_transposed(result: Any) -> np.ndarray:
    """The same mistake with the adjoint taken the other way round."""
    adjoint = gtsam.Pose3(result.transform).AdjointMap()
    return np.asarray(adjoint.T @ result.information @ adjoint)


Reading = Callable[[Any], np.ndarray]


def residual_failures(example: ModuleType, edges: list[Any], information: Reading | None = None) -> list[str]:
    """The real graph's optimised chi-square against the information as it is: per degree of freedom within
    ``CHI2_PER_DOF``, and every edge's under the 99.9% quantile. ``None``: the example's own reading (its
    default)."""
    graph, initial = example.build_graph(edges) if information is None else example.build_graph(edges, information)
    estimate = example.optimise(graph, initial)
    per_edge = example.edge_chi2(graph, estimate)
    accepted = [e for e in edges if e.accepted]
    dof = 6 * len(accepted) - 6 * (len({k for e in edges for k in (e.source, e.target)}) - 1)
    failures = []
    total = 2.0 * graph.error(estimate)
    if not CHI2_PER_DOF[0] * dof <= total <= CHI2_PER_DOF[1] * dof:
        failures.append(f"real chi-square {total:.1f} for {dof} dof, outside {CHI2_PER_DOF} per dof")
    for e, value in zip(accepted, per_edge, strict=True):
        if value > CHI2_6_999:
            failures.append(f"edge {e.target} <- {e.source}: chi-square {value:.1f} > {CHI2_6_999}")
    return failures


def simulation_failures(
    example: ModuleType, edges: list[Any], truth: Any, information: Reading | None = None
) -> list[str]:
    readings = {} if information is None else {"information": information}
    check = example.simulated_consistency(edges, truth, draws=DRAWS, seed=0, **readings)
    failures = []
    if abs(check.chi2 / check.dof - 1.0) > SIMULATION_TOLERANCE:
        failures.append(f"simulated chi-square {check.chi2:.2f} for {check.dof} dof")
    if abs(check.nees / 6.0 - 1.0) > SIMULATION_TOLERANCE:
        failures.append(f"simulated NEES {check.nees:.2f} for 6")
    return failures


def test_the_graph_gets_only_right_edges_and_enough_of_them(example: ModuleType, keyframes: Any, edges) -> None:
    assert len(edges) == 10  # every pair of five keyframes, once
    accepted = [e for e in edges if e.accepted]
    assert all(e.odometry for e in edges[:4]) and all(e.accepted for e in edges[:4]), [e.why for e in edges]
    assert sum(not e.odometry for e in accepted) >= 2, "the checks need loop closures: redundancy"
    truth = example.anchored(keyframes.poses)
    for e in accepted:
        expected = np.linalg.inv(truth[e.target]) @ truth[e.source]
        metres, degrees = example.pose_error(e.result.transform, expected)
        assert metres < MAX_EDGE[0] and degrees < MAX_EDGE[1], (e.target, e.source, metres, degrees)
    for e in edges:
        assert e.accepted == (e.why == "accepted")


def test_trajectory_against_graph_txt(example: ModuleType, keyframes: Any, edges) -> None:
    graph, initial = example.build_graph(edges)
    estimate = example.optimise(graph, initial)
    errors = example.trajectory_errors(example.estimate_poses(estimate, sorted(keyframes.clouds)), keyframes.poses)
    assert set(errors.absolute) == set(keyframes.poses)
    assert errors.absolute[0] == pytest.approx((0.0, 0.0), abs=1e-5)  # the anchor
    metres, degrees = errors.max_absolute
    assert metres < MAX_ABSOLUTE[0] and degrees < MAX_ABSOLUTE[1], errors.absolute
    metres, degrees = errors.max_relative
    assert metres < MAX_RELATIVE[0] and degrees < MAX_RELATIVE[1], errors.relative


def test_the_documented_information_passes_both_checks(example: ModuleType, keyframes: Any, edges) -> None:
    assert residual_failures(example, edges) == []
    assert simulation_failures(example, edges, keyframes.poses) == []


@pytest.mark.parametrize(
    ("reading", "caught_by_residuals"),
    [(translation_first, True), (target_frame, False), (target_frame_transposed, False)],
    ids=["translation_first", "target_frame", "target_frame_transposed"],
)
def test_a_wrong_reading_fails(
    example: ModuleType, keyframes: Any, edges, reading: Reading, caught_by_residuals: bool
) -> None:
    """The checks of the documented reading, run with a wrong one, must fail: the simulation always, the real
    residuals for the order (the real errors cannot show the frame; see the module's docstring)."""
    assert bool(residual_failures(example, edges, reading)) == caught_by_residuals
    assert simulation_failures(example, edges, keyframes.poses, reading)


def test_the_script_prints_its_report(example: ModuleType, real_data: Path, keyframes: Any, capsys) -> None:
    assert example.main(["--data", str(real_data), "--voxel", str(VOXEL), "--draws", str(DRAWS)]) == 0
    out = capsys.readouterr().out
    assert "0 <- 1                odometry  accepted" in out
    assert "absolute error against graph.txt" in out and "relative error" in out
    assert "simulated noise of the documented meaning" in out and "both near expectation" in out


def test_the_script_says_when_the_data_is_missing(example: ModuleType, tmp_path: Path, capsys) -> None:
    assert example.main(["--data", str(tmp_path)]) == 2
    assert "graph.txt" in capsys.readouterr().err
