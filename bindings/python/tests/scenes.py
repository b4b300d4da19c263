"""Deterministic synthetic clouds for the tests that need no real data.

The scene is a walled yard about 24 m x 16 m (ground, three walls, boxes, poles, spheres) sampled with
Gaussian noise; the source and target are two independent samplings of it, the target moved by a known
rigid transform. Everything derives from numpy's PCG64 with fixed seeds, so every run sees the same
clouds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


def rotation_zyx(yaw_deg: float, pitch_deg: float = 0.0, roll_deg: float = 0.0) -> np.ndarray:
    y, p, r = (math.radians(a) for a in (yaw_deg, pitch_deg, roll_deg))
    rz = np.array([[math.cos(y), -math.sin(y), 0], [math.sin(y), math.cos(y), 0], [0, 0, 1]])
    ry = np.array([[math.cos(p), 0, math.sin(p)], [0, 1, 0], [-math.sin(p), 0, math.cos(p)]])
    rx = np.array([[1, 0, 0], [0, math.cos(r), -math.sin(r)], [0, math.sin(r), math.cos(r)]])
    return rz @ ry @ rx


def _plane(rng: np.random.Generator, origin, u, v, density: float) -> np.ndarray:
    origin, u, v = (np.asarray(a, dtype=float) for a in (origin, u, v))
    area = np.linalg.norm(np.cross(u, v))
    n = max(1, int(area * density))
    a, b = rng.random(n), rng.random(n)
    return origin + a[:, None] * u + b[:, None] * v


def _box(rng: np.random.Generator, lo, size, density: float) -> np.ndarray:
    lo = np.asarray(lo, dtype=float)
    sx, sy, sz = size
    faces = [
        (lo, (sx, 0, 0), (0, sy, 0)),
        (lo + (0, 0, sz), (sx, 0, 0), (0, sy, 0)),
        (lo, (sx, 0, 0), (0, 0, sz)),
        (lo + (0, sy, 0), (sx, 0, 0), (0, 0, sz)),
        (lo, (0, sy, 0), (0, 0, sz)),
        (lo + (sx, 0, 0), (0, sy, 0), (0, 0, sz)),
    ]
    return np.concatenate([_plane(rng, o, u, v, density) for o, u, v in faces])


def _cylinder(rng: np.random.Generator, base, radius: float, height: float, density: float) -> np.ndarray:
    n = max(1, int(2 * math.pi * radius * height * density))
    angle, h = rng.random(n) * 2 * math.pi, rng.random(n) * height
    return np.asarray(base, dtype=float) + np.stack([radius * np.cos(angle), radius * np.sin(angle), h], axis=1)


def _sphere(rng: np.random.Generator, center, radius: float, density: float) -> np.ndarray:
    n = max(1, int(4 * math.pi * radius * radius * density))
    d = rng.normal(size=(n, 3))
    return np.asarray(center, dtype=float) + radius * d / np.linalg.norm(d, axis=1, keepdims=True)


def yard(seed: int, density: float = 60.0, noise: float = 0.01) -> np.ndarray:
    """One noisy sampling of the yard, in the yard's frame (sensor at the origin, ground at z = -1.7)."""
    layout = np.random.default_rng(1234)  # the same objects in every sampling
    rng = np.random.default_rng(seed)
    g = -1.7
    parts = [
        _plane(rng, (-12, -8, g), (24, 0, 0), (0, 16, 0), density * 0.5),
        _plane(rng, (-12, 8, g), (24, 0, 0), (0, 0, 4), density),  # north wall
        _plane(rng, (-12, -8, g), (0, 16, 0), (0, 0, 3), density),  # west wall
        _plane(rng, (12, -8, g), (0, 10, 0), (0, 0, 5), density),  # east wall, with a gap
        _plane(rng, (2, -6, g), (5, 0, 0), (0, 2, 1.2), density),  # ramp
    ]
    for _ in range(9):
        lo = (layout.uniform(-10, 9), layout.uniform(-7, 6), g)
        size = (layout.uniform(0.6, 2.5), layout.uniform(0.6, 2.0), layout.uniform(0.5, 2.5))
        parts.append(_box(rng, lo, size, density))
    for _ in range(6):
        base = (layout.uniform(-11, 11), layout.uniform(-7, 7), g)
        parts.append(_cylinder(rng, base, layout.uniform(0.08, 0.25), layout.uniform(2.0, 5.0), density))
    for _ in range(4):
        center = (layout.uniform(-10, 10), layout.uniform(-6, 6), g + layout.uniform(0.5, 1.5))
        parts.append(_sphere(rng, center, layout.uniform(0.3, 0.8), density))
    points = np.concatenate(parts)
    return points + rng.normal(scale=noise, size=points.shape)


@dataclass(frozen=True)
class Pair:
    source: np.ndarray  #: (N, 3) float64, C-contiguous
    target: np.ndarray
    rotation: np.ndarray  #: the true pose: p_target = rotation @ p_source + translation
    translation: np.ndarray
    voxel_size: float


def yard_pair(yaw_deg: float = 130.0, seed: int = 7) -> Pair:
    """Two samplings of the yard; the target frame is the source frame moved by a known pose."""
    rotation = rotation_zyx(yaw_deg, 2.0, -1.5)
    translation = np.array([3.0, -2.0, 0.4])
    source = yard(seed)
    scene_again = yard(seed + 1)
    target = scene_again @ rotation.T + translation
    return Pair(np.ascontiguousarray(source), np.ascontiguousarray(target), rotation, translation, 0.3)


def rotation_error_deg(a: np.ndarray, b: np.ndarray) -> float:
    cos = (np.trace(a.T @ b) - 1.0) / 2.0
    return math.degrees(math.acos(min(1.0, max(-1.0, cos))))
