# SPDX-License-Identifier: MIT
"""Objects of symmetric parts: six spheres and five boxes about 0.2 m across, seen by a depth camera from turntable
views 25-40 degrees apart (the validity study's "spheres and boxes" family, bench/kissm_bench/raycast.py, written
again here). A sphere matches itself under any rotation and two alike parts match each other swapped, so the
solver's largest consistent set can be one part turned onto itself: a pose 90 or 180 degrees off that explains
that part as well as the right pose does. The ambiguity stage places the pose of the next core (the matches that
agree with each other once the winner's are out) and refuses the winner when that pose lays clearly more of the
source beside the target ("a rival", kRivalDense in src/core/ambiguity.hpp). Measured on these views before that
rule: seeds 3, 13, 16 and 28 below were wrong and valid (178, 180, 90 and 180 degrees off); now refused, and the
right ones still right and valid."""

from __future__ import annotations

import math

import numpy as np
import pytest

import kissm

VOXEL = 0.006
AMBIGUOUS = "a second, distinct pose has nearly as much support (a repetitive or symmetric scene)"


def rotation(rng: np.random.Generator) -> np.ndarray:
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return np.asarray(q * np.sign(np.linalg.det(q)))


def ray_cast(spheres, boxes, origin: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """Distance along each unit ray to the first surface (inf when none)."""
    best = np.full(len(dirs), np.inf)
    for centre, radius in spheres:
        oc = origin - centre
        b = dirs @ oc
        disc = b * b - (oc @ oc - radius * radius)
        with np.errstate(invalid="ignore"):
            s = -b - np.sqrt(disc)
        best = np.where((disc > 0) & (s > 0) & (s < best), s, best)
    for centre, rot, half in boxes:
        o, d = rot.T @ (origin - centre), dirs @ rot
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / np.where(d == 0, 1e-300, d)
            t1, t2 = (-half - o) * inv, (half - o) * inv
        tmin, tmax = np.minimum(t1, t2).max(axis=1), np.maximum(t1, t2).min(axis=1)
        best = np.where((tmax >= tmin) & (tmin > 0) & (tmin < best), tmin, best)
    return best


def views(seed: int) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Three views of the seed's object (points in each camera's frame) and the cameras' poses."""
    rng = np.random.default_rng([seed, 1])
    spheres = [(rng.uniform(-0.06, 0.06, 3), float(rng.uniform(0.012, 0.04))) for _ in range(6)]
    boxes = [(rng.uniform(-0.06, 0.06, 3), rotation(rng), rng.uniform(0.006, 0.04, 3)) for _ in range(5)]
    az = rng.uniform(0, 2 * math.pi)
    poses = []
    for _ in range(3):
        el = math.radians(rng.uniform(0, 35))
        eye = 0.5 * np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
        z = -eye / np.linalg.norm(eye)
        x = np.cross(z, [0.0, 0.0, 1.0])
        x /= np.linalg.norm(x)
        pose = np.eye(4)
        pose[:3, :3] = np.column_stack([x, np.cross(z, x), z])
        pose[:3, 3] = eye
        poses.append(pose)
        az += math.radians(rng.uniform(25, 40))
    clouds = []
    n, half = 320, math.tan(math.radians(15))
    for pose in poses:
        uv = np.stack(np.meshgrid(np.arange(n), np.arange(n)), -1).reshape(-1, 2) + rng.uniform(0, 1, (n * n, 2))
        uv = (uv / n * 2 - 1) * half
        dirs = np.column_stack([uv, np.ones(n * n)])
        dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
        world = dirs @ pose[:3, :3].T
        s = ray_cast(spheres, boxes, pose[:3, 3], world)
        hit = np.isfinite(s)
        r = s[hit] + rng.normal(0, 0.05 * VOXEL, int(hit.sum()))
        clouds.append(np.ascontiguousarray(dirs[hit] * r[:, None]))
    return clouds, poses


def errors(result: kissm.Result, truth: np.ndarray, at: np.ndarray) -> tuple[float, float]:
    """Rotation error (degrees) and translation error at the object (metres)."""
    t = np.asarray(result.transform)
    cos = (np.trace(t[:3, :3].T @ truth[:3, :3]) - 1.0) / 2.0
    moved = t[:3, :3] @ at + t[:3, 3] - (truth[:3, :3] @ at + truth[:3, 3])
    return math.degrees(math.acos(max(-1.0, min(1.0, cos)))), float(np.linalg.norm(moved))


#: (seed, target view, source view): the four that were wrong and valid, and two right ones.
CASES = [(3, 0, 1), (13, 0, 2), (16, 1, 2), (28, 0, 2), (1, 0, 1), (2, 1, 2)]


@pytest.mark.parametrize("seed, i, j", CASES)
@pytest.mark.parametrize("refine", ["none", "gicp"])
def test_parts_turned_onto_themselves_are_refused(seed: int, i: int, j: int, refine: str) -> None:
    clouds, poses = views(seed)
    truth = np.linalg.inv(poses[i]) @ poses[j]
    result = kissm.register(clouds[j], clouds[i], voxel_size=VOXEL, refine=refine)
    rot, trans = errors(result, truth, clouds[j].mean(axis=0))
    right = rot <= 5.0 and trans <= 0.01
    assert right or not result.valid, (rot, trans, result.reason)  # never wrong and valid
    if (seed, i, j) in CASES[:4]:
        assert not right and result.reason == AMBIGUOUS and result.ambiguity == 1.0, (rot, result.reason)
    else:
        assert right and result.valid, (rot, trans, result.reason)
