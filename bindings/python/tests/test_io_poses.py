# SPDX-License-Identifier: MIT
"""``kissm.io.write_tum`` and ``write_kitti``: the same bytes as ``kissm.multiway.Alignment``'s writers (one
implementation), the numbers read back bit for bit, the quaternion the rotation's, NaN poses handled as the
formats need, and errors that name the argument."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import kissm
import kissm.io
import kissm.multiway
from kissm._pose_files import rotation_matrix


def poses(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    out = np.tile(np.eye(4), (n, 1, 1))
    for k in range(n):
        # Rotations about random axes by angles up to pi (every branch of the quaternion conversion).
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        angle = math.pi if k == 1 else rng.uniform(0, math.pi)
        skew = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
        out[k, :3, :3] = np.eye(3) + math.sin(angle) * skew + (1 - math.cos(angle)) * skew @ skew
        out[k, :3, 3] = rng.normal(0, 1e3, 3)
    return out


def alignment(p: np.ndarray, placed: np.ndarray) -> kissm.multiway.Alignment:
    shown = p.copy()
    shown[~placed] = np.nan
    return kissm.multiway.Alignment(
        keys=list(range(len(p))),
        poses=shown,
        placed=placed,
        components=np.where(placed, 0, np.arange(len(p))),
        edges=[],
        registrations=0,
    )


def test_same_bytes_as_the_alignment_writers(tmp_path: Path) -> None:
    p = poses(7, 1)
    placed = np.array([True, True, False, True, True, False, True])
    a = alignment(p, placed)
    stamps = [1.5e9 + 0.1 * k for k in range(7)]
    a.write_tum(tmp_path / "a.tum")
    a.write_tum(tmp_path / "a_stamped.tum", timestamps=stamps)
    a.write_kitti(tmp_path / "a.kitti")
    kissm.io.write_tum(tmp_path / "b.tum", a.poses)
    kissm.io.write_tum(tmp_path / "b_stamped.tum", a.poses, stamps)
    kissm.io.write_kitti(tmp_path / "b.kitti", a.poses)
    for name in ("tum", "_stamped.tum", "kitti"):
        suffix = name if name.startswith("_") else "." + name
        assert (tmp_path / f"a{suffix}").read_bytes() == (tmp_path / f"b{suffix}").read_bytes()
    assert len((tmp_path / "b.tum").read_text().splitlines()) == 5  # the NaN poses left out
    kitti = (tmp_path / "b.kitti").read_text().splitlines()
    assert len(kitti) == 7 and kitti[2] == " ".join(["nan"] * 12)


def test_numbers_read_back(tmp_path: Path) -> None:
    p = poses(6, 2)
    stamps = [1_700_000_000.25 + k / 3 for k in range(6)]
    kissm.io.write_tum(tmp_path / "p.tum", p, stamps)
    kissm.io.write_kitti(tmp_path / "p.kitti", p)
    tum = np.loadtxt(tmp_path / "p.tum")
    assert np.array_equal(tum[:, 0], stamps) and np.array_equal(tum[:, 1:4], p[:, :3, 3])
    for row, pose in zip(tum, p, strict=True):
        qx, qy, qz, qw = row[4:]
        assert qw >= 0 and abs(math.hypot(qx, qy, qz, qw) - 1) < 1e-15
        rotation = rotation_matrix(qw, qx, qy, qz)
        assert np.max(np.abs(rotation - pose[:3, :3])) < 1e-14
    kitti = np.loadtxt(tmp_path / "p.kitti")
    assert np.array_equal(kitti.reshape(6, 3, 4), p[:, :3, :])
    kissm.io.write_tum(tmp_path / "positions.tum", p[:2])
    assert [line.split()[0] for line in (tmp_path / "positions.tum").read_text().splitlines()] == ["0.0", "1.0"]


def test_errors(tmp_path: Path) -> None:
    with pytest.raises(kissm.InvalidArgumentError) as caught:
        kissm.io.write_tum(tmp_path / "x", np.eye(4))
    assert str(caught.value) == "write_tum: poses has shape (4, 4); (N, 4, 4), one 4x4 pose per scan"
    with pytest.raises(kissm.InvalidArgumentError) as caught:
        kissm.io.write_tum(tmp_path / "x", poses(3, 0), [0.0, 1.0])
    assert str(caught.value) == "write_tum: 2 stamps for 3 poses"
    with pytest.raises(kissm.InvalidArgumentError) as caught:
        kissm.io.write_kitti(tmp_path / "x", np.zeros((2, 3, 4)))
    assert str(caught.value) == "write_kitti: poses has shape (2, 3, 4); (N, 4, 4), one 4x4 pose per scan"
    assert not (tmp_path / "x").exists()
