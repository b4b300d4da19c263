# SPDX-License-Identifier: MIT
"""Seeded synthetic outdoor scenes (wavy terrain, box buildings and poles) for bench.py's scaling runs and its
smoke run without data: source and target are independent samplings of one scene, overlapping by about 70%,
under a known pose. numpy is imported when first needed."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .geometry import rotation_about

if TYPE_CHECKING:
    import numpy as np


def _terrain(params: list[tuple[float, float, float, float]], xy: np.ndarray) -> np.ndarray:
    import numpy as np

    z = np.zeros(len(xy))
    for amp, kx, ky, phase in params:
        z += amp * np.sin(kx * xy[:, 0] + ky * xy[:, 1] + phase)
    return z


SYN_TILE = 40.0  # objects are placed per 40 m tile, each tile from its own seed: a larger scene adds objects


def scene_layout(size: float, seed: int) -> dict[str, Any]:
    """The scene's geometry (shared by source and target): terrain waves, boxes (buildings), poles."""
    import numpy as np

    rng = np.random.default_rng(seed)
    waves = []
    for _ in range(6):
        wavelength = rng.uniform(15.0, 90.0)
        direction = rng.uniform(0, 2 * math.pi)
        k = 2 * math.pi / wavelength
        amplitude = rng.uniform(0.2, 0.8)
        waves.append((amplitude, k * math.cos(direction), k * math.sin(direction), rng.uniform(0, 2 * math.pi)))
    box_tiles: list[np.ndarray] = []
    pole_tiles: list[np.ndarray] = []
    tiles = int(math.ceil(size / SYN_TILE))
    for i in range(tiles):
        for j in range(tiles):
            t = np.random.default_rng([seed, i, j])
            nb, npole = t.poisson(SYN_TILE**2 / 500.0), t.poisson(SYN_TILE**2 / 250.0)
            box_tiles.append(
                np.column_stack(
                    [
                        (i + t.uniform(0, 1, nb)) * SYN_TILE,
                        (j + t.uniform(0, 1, nb)) * SYN_TILE,  # centre
                        t.uniform(3.0, 18.0, nb),
                        t.uniform(3.0, 18.0, nb),  # width, depth
                        t.uniform(2.5, 14.0, nb),
                        t.uniform(0, math.pi, nb),  # height, yaw
                    ]
                )
            )
            pole_tiles.append(
                np.column_stack(
                    [
                        (i + t.uniform(0, 1, npole)) * SYN_TILE,
                        (j + t.uniform(0, 1, npole)) * SYN_TILE,
                        t.uniform(0.08, 0.35, npole),
                        t.uniform(3.0, 9.0, npole),  # radius, height
                    ]
                )
            )
    boxes, poles = np.concatenate(box_tiles), np.concatenate(pole_tiles)
    boxes = boxes[(boxes[:, 0] < size) & (boxes[:, 1] < size)]
    poles = poles[(poles[:, 0] < size) & (poles[:, 1] < size)]
    return {"size": size, "waves": waves, "boxes": boxes, "poles": poles}


def sample_scene(
    layout: dict[str, Any], density: float, seed: int, x_range: tuple[float, float], noise: float = 0.02
) -> np.ndarray:
    """Samples the scene's surfaces uniformly (``density`` points per m²), keeping x within ``x_range``."""
    import numpy as np

    rng = np.random.default_rng(seed)
    size, waves = layout["size"], layout["waves"]
    parts: list[np.ndarray] = []
    # terrain
    n = rng.poisson(density * size * size)
    xy = rng.uniform(0, size, (n, 2))
    parts.append(np.column_stack([xy, _terrain(waves, xy)]))
    # boxes: four walls and a roof, sunk 0.5 m into the terrain
    b = layout["boxes"]
    w, d, h, yaw = b[:, 2], b[:, 3], b[:, 4], b[:, 5]
    face_area = np.column_stack([d * h, d * h, w * h, w * h, w * d])
    counts = rng.poisson(density * face_area.sum(axis=1))
    box = np.repeat(np.arange(len(b)), counts)
    cum = np.cumsum(face_area, axis=1)[box]
    u = rng.uniform(0, 1, len(box)) * cum[:, -1]
    face = (u[:, None] >= cum).sum(axis=1)
    a, c = rng.uniform(-0.5, 0.5, len(box)), rng.uniform(0, 1, len(box))
    bw, bd, bh = w[box], d[box], h[box]
    lx = np.where(face < 2, np.where(face == 0, -0.5, 0.5) * bw, a * bw)
    ly = np.where(face < 2, a * bd, np.where(face == 2, -0.5, 0.5) * bd)
    ly = np.where(face == 4, rng.uniform(-0.5, 0.5, len(box)) * bd, ly)
    lz = np.where(face == 4, bh, c * bh)
    cy, sy = np.cos(yaw[box]), np.sin(yaw[box])
    base = _terrain(waves, b[:, :2])[box] - 0.5
    parts.append(np.column_stack([b[box, 0] + cy * lx - sy * ly, b[box, 1] + sy * lx + cy * ly, base + lz]))
    # poles
    p = layout["poles"]
    counts = rng.poisson(density * 2 * math.pi * p[:, 2] * p[:, 3])
    pole = np.repeat(np.arange(len(p)), counts)
    theta = rng.uniform(0, 2 * math.pi, len(pole))
    base = _terrain(waves, p[:, :2])[pole]
    parts.append(
        np.column_stack(
            [
                p[pole, 0] + p[pole, 2] * np.cos(theta),
                p[pole, 1] + p[pole, 2] * np.sin(theta),
                base + rng.uniform(0, 1, len(pole)) * p[pole, 3],
            ]
        )
    )
    pts: np.ndarray = np.concatenate(parts)
    pts = pts[(pts[:, 0] >= x_range[0] * size) & (pts[:, 0] <= x_range[1] * size)]
    pts += rng.normal(0, noise, pts.shape)
    return pts


def count_voxels(points: np.ndarray, voxel: float) -> int:
    import numpy as np

    keys = np.floor(points / voxel).astype(np.int64)
    keys -= keys.min(axis=0)
    span = keys.max(axis=0) + 1
    flat = (keys[:, 0] * span[1] + keys[:, 1]) * span[2] + keys[:, 2]
    return int(len(np.unique(flat)))


SYN_DENSITY = 16.0  # points per m² of surface: about 4 points per 0.5 m voxel on flat ground
SYN_POSE = (math.radians(40.0), (0.3, 0.2, 1.0), (6.0, -4.0, 0.5))  # angle, axis, translation


def synthetic_pose() -> np.ndarray:
    import numpy as np

    angle, axis, trans = SYN_POSE
    gt = np.eye(4)
    gt[:3, :3] = rotation_about(axis, angle)
    gt[:3, 3] = trans
    return gt


def make_synthetic(target_voxels: int, voxel: float, seed: int, tmp: Path, tag: str) -> dict[str, Any]:
    """Source/target clouds of one scene with about ``target_voxels`` voxels each (calibrated by size)."""
    import numpy as np

    size = math.sqrt(target_voxels / 1.3) * voxel  # first guess: ground voxels plus some walls
    for _ in range(6):
        layout = scene_layout(size, seed)
        # source and target overlap by about 70% (x in [0, 0.85] and [0.15, 1] of the extent)
        src_world = sample_scene(layout, SYN_DENSITY, seed + 1, (0.0, 0.85))
        n = count_voxels(src_world, voxel)
        if abs(n - target_voxels) <= 0.03 * target_voxels:
            break
        size *= math.sqrt(target_voxels / n)
    tgt = sample_scene(layout, SYN_DENSITY, seed + 2, (0.15, 1.0))
    gt = synthetic_pose()
    rot, trans = gt[:3, :3], gt[:3, 3]
    src = np.ascontiguousarray((src_world - trans) @ rot)  # R p_s + t = p_world
    src_path, tgt_path = tmp / f"syn_{tag}_src.npy", tmp / f"syn_{tag}_tgt.npy"
    np.save(src_path, src)
    np.save(tgt_path, tgt)
    return {
        "target_voxels": target_voxels,
        "extent_m": size,
        "n_src": len(src),
        "n_tgt": len(tgt),
        "voxels_numpy": n,
        "src_path": str(src_path),
        "tgt_path": str(tgt_path),
        "gt": gt.tolist(),
    }
