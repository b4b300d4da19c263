# SPDX-License-Identifier: MIT
"""Scenes that hold more than one right-looking pose, with exact ground truth (docs/design/accuracy.md, "Ambiguity"):
a street of identical buildings every 10 m on both sides, pillars on a 5 m grid over a ground plane, and a table
(its top and four legs: the same turned 180 degrees about its vertical), each beside a control of the same kind
with the repetition broken (buildings of random sizes, pillars at random places, the table with a box on one
corner). Every cloud is sampled afresh (its own noise and sample positions) around its own sensor position, in
that sensor's frame, so a pair differs as two scans would. And compound objects of spheres and boxes (raycast.py),
whose parts match themselves turned: a wrong pose can explain a part as well as the right one explains it."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .data import Kind, Trial
from .geometry import axis_angle
from .raycast import object_scene

#: Streets and pillars are judged as LiDAR (0.3 m voxels); the table as an object a metre across.
SCENE_KIND = Kind("synthetic", 0.3, 5.0, 2.0)
TABLE_KIND = Kind("synthetic", 0.03, 5.0, 0.1)
#: The objects of spheres and boxes as the bunny is judged (6 mm voxels, 1 cm).
PARTS_KIND = Kind("synthetic", 0.006, 5.0, 0.01)


def _rect(rng: np.random.Generator, origin: np.ndarray, u: np.ndarray, v: np.ndarray, density: float) -> np.ndarray:
    """Points uniformly on the parallelogram origin + a u + b v (a, b in [0, 1]), `density` per square unit."""
    n = max(1, int(np.linalg.norm(u) * np.linalg.norm(v) * density))
    a, b = rng.uniform(size=(n, 1)), rng.uniform(size=(n, 1))
    out: np.ndarray = origin + a * u + b * v
    return out


def _building(
    rng: np.random.Generator, x0: float, side: int, length: float, height: float, windows: int
) -> list[np.ndarray]:
    """A facade along x at y = 7 * side, `windows` recesses 1 m wide and 0.3 m deep, and its two side walls."""
    density, y0, parts = 12.0, 7.0 * side, []
    parts.append(_rect(rng, np.array([x0, y0, 0.0]), np.array([length, 0, 0]), np.array([0, 0, height]), density))
    pitch = length / windows
    for w in range(windows):
        xw, depth = x0 + 0.5 * (pitch - 1.0) + pitch * w, 0.3 * side
        parts.append(_rect(rng, np.array([xw, y0 + depth, 2.0]), np.array([1.0, 0, 0]), np.array([0, 0, 2.0]), density))
        parts.append(_rect(rng, np.array([xw, y0, 2.0]), np.array([0, depth, 0]), np.array([0, 0, 2.0]), density))
        parts.append(_rect(rng, np.array([xw + 1, y0, 2.0]), np.array([0, depth, 0]), np.array([0, 0, 2.0]), density))
    for x in (x0, x0 + length):
        parts.append(
            _rect(rng, np.array([x, y0, 0.0]), np.array([0, 4.0 * side, 0]), np.array([0, 0, height]), density)
        )
    return parts


def street(
    rng: np.random.Generator, sensor_x: float, periodic: bool, layout_seed: int = 7, period: float = 10.0
) -> np.ndarray:
    """A street along x seen from (sensor_x, 0, 0) out to 25 m, in the world frame. Periodic: the same building
    (2 m short of the period, 6 m high, a window every 2 m) every `period` m on both sides; else buildings of the
    layout's own random sizes."""
    radius, density = 25.0, 12.0
    parts = [
        _rect(rng, np.array([sensor_x - radius, -12, 0.0]), np.array([2 * radius, 0, 0]), np.array([0, 24, 0]), density)
    ]
    layout = np.random.default_rng(layout_seed)  # the same buildings in every scan of the street
    for side in (-1, 1):
        x = -200.0
        while x < 200.0:
            if periodic:
                length, height, windows, gap = period - 2.0, 6.0, int(round((period - 2.0) / 2.0)), 2.0
            else:
                length, height = layout.uniform(4, 12), layout.uniform(4, 10)
                windows, gap = int(layout.integers(1, 6)), layout.uniform(1, 6)
            if abs(x + length / 2 - sensor_x) < radius + 10:
                parts += _building(rng, x, side, length, height, windows)
            x += length + gap
    points = np.vstack(parts)
    points = points[np.linalg.norm(points[:, :2] - [sensor_x, 0], axis=1) < radius]
    noisy: np.ndarray = points + rng.normal(scale=0.02, size=points.shape)
    return noisy


def pillars(rng: np.random.Generator, cx: float, cy: float, periodic: bool, layout_seed: int = 9) -> np.ndarray:
    """Pillars (0.3 m radius, 3 m high) on a 5 m grid over a ground plane, seen from (cx, cy) out to 12 m; not
    periodic: the same number of pillars at the layout's own random places."""
    ground = rng.uniform([-12, -12], [12, 12], size=(30000, 2))
    parts = [np.c_[ground + [cx, cy], np.zeros(len(ground))]]
    grid = np.array([(x, y) for x in np.arange(-40, 41, 5.0) for y in np.arange(-40, 41, 5.0)])
    if not periodic:
        grid = np.random.default_rng(layout_seed).uniform(-40, 40, size=grid.shape)
    for px, py in grid:
        if abs(px - cx) < 12 and abs(py - cy) < 12:
            a, z = rng.uniform(0, 2 * np.pi, 300), rng.uniform(0, 3, 300)
            parts.append(np.c_[px + 0.3 * np.cos(a), py + 0.3 * np.sin(a), z])
    points = np.vstack(parts)
    return points + rng.normal(scale=0.01, size=points.shape)


def table(rng: np.random.Generator, symmetric: bool) -> np.ndarray:
    """A table 1.2 x 0.8 m, 0.75 m high, on four square legs, its every surface sampled (no viewpoint); not
    symmetric: a 0.3 m box on one corner of its top."""
    density = 4000.0
    parts = []
    for z in (0.72, 0.75):
        parts.append(_rect(rng, np.array([-0.6, -0.4, z]), np.array([1.2, 0, 0]), np.array([0, 0.8, 0]), density))
    for sx in (-1, 1):
        parts.append(
            _rect(rng, np.array([0.6 * sx, -0.4, 0.72]), np.array([0, 0.8, 0]), np.array([0, 0, 0.03]), density)
        )
    for sy in (-1, 1):
        parts.append(
            _rect(rng, np.array([-0.6, 0.4 * sy, 0.72]), np.array([1.2, 0, 0]), np.array([0, 0, 0.03]), density)
        )
    for lx in (-0.5, 0.5):
        for ly in (-0.3, 0.3):
            for d in (-0.03, 0.03):  # a square leg 6 cm wide: its four faces
                parts.append(
                    _rect(
                        rng, np.array([lx - 0.03, ly + d, 0]), np.array([0.06, 0, 0]), np.array([0, 0, 0.72]), density
                    )
                )
                parts.append(
                    _rect(
                        rng, np.array([lx + d, ly - 0.03, 0]), np.array([0, 0.06, 0]), np.array([0, 0, 0.72]), density
                    )
                )
    if not symmetric:
        for z in (0.75, 1.05):
            parts.append(_rect(rng, np.array([0.2, 0.0, z]), np.array([0.3, 0, 0]), np.array([0, 0.3, 0]), density))
        for x in (0.2, 0.5):
            parts.append(_rect(rng, np.array([x, 0.0, 0.75]), np.array([0, 0.3, 0]), np.array([0, 0, 0.3]), density))
        for y in (0.0, 0.3):
            parts.append(_rect(rng, np.array([0.2, y, 0.75]), np.array([0.3, 0, 0]), np.array([0, 0, 0.3]), density))
    points = np.vstack(parts)
    return points + rng.normal(scale=0.002, size=points.shape)


@dataclass(frozen=True)
class Family:
    name: str
    trials: Callable[[], list[Trial]]


def _pose(turn_deg: float, axis: np.ndarray, shift: np.ndarray) -> np.ndarray:
    gt = np.eye(4)
    gt[:3, :3] = axis_angle(axis, turn_deg)
    gt[:3, 3] = shift
    return gt


def _in_sensor_frame(world: np.ndarray, gt: np.ndarray) -> np.ndarray:
    """World points seen from the source sensor whose pose in the target (world) frame is gt."""
    out: np.ndarray = (world - gt[:3, 3]) @ gt[:3, :3]
    return out


def street_trials(periodic: bool, period: float = 10.0, seed: int = 3) -> list[Trial]:
    """The source sensor 2-13 m further along the street, yawed 0 or 30 degrees."""
    rng = np.random.default_rng(seed)
    trials = []
    for shift in (2.0, 4.5, 7.0, 10.0, 13.0):
        for yaw in (0.0, 30.0):
            target = street(rng, 0.0, periodic, period=period)
            gt = _pose(yaw, np.array([0.0, 0.0, 1.0]), np.array([shift, 0.0, 0.0]))
            source = _in_sensor_frame(street(rng, shift, periodic, period=period), gt)
            kind = f"identical street, {period:.0f} m" if periodic else "varied street"
            name = f"{kind}, {shift:4.1f} m on, yaw {yaw:2.0f}"
            trials.append(Trial(name, source.astype(np.float32), target.astype(np.float32), gt, SCENE_KIND))
    return trials


def pillar_trials(periodic: bool) -> list[Trial]:
    """The source sensor 1.3-3.3 m away diagonally, yawed 10-110 degrees."""
    rng = np.random.default_rng(5)
    trials = []
    for k in range(6):
        shift = np.array([1.3 + 0.4 * k, -0.7 + 0.3 * k, 0.0])
        target = pillars(rng, 0.0, 0.0, periodic)
        gt = _pose(10.0 + 20.0 * k, np.array([0.0, 0.0, 1.0]), shift)
        source = _in_sensor_frame(pillars(rng, shift[0], shift[1], periodic), gt)
        name = f"{'grid of' if periodic else 'scattered'} pillars, {k}"
        trials.append(Trial(name, source.astype(np.float32), target.astype(np.float32), gt, SCENE_KIND))
    return trials


def table_trials(symmetric: bool) -> list[Trial]:
    """The table turned by 6 random rotations (any axis, 30-180 degrees) about the foot of its vertical axis, the
    origin of both frames: a viewpoint on the axis sees the symmetric table the same turned half a turn."""
    rng = np.random.default_rng(8)
    trials = []
    for k in range(6):
        gt = _pose(rng.uniform(30, 180), rng.normal(size=3), np.zeros(3))
        target = table(rng, symmetric)
        source = _in_sensor_frame(table(rng, symmetric), gt)
        name = f"{'symmetric' if symmetric else 'one-sided'} table, {k}"
        trials.append(Trial(name, source.astype(np.float32), target.astype(np.float32), gt, TABLE_KIND))
    return trials


def part_trials(seeds: int = 30) -> list[Trial]:
    """Compound objects of 6 spheres and 5 boxes (raycast.object_scene, 0.2 m across, three turntable views 25-40
    degrees apart): each view registered into the one before and the first, a pose a sphere or box can match
    onto itself turned, or two alike parts onto each other swapped, while the rest of the object disagrees."""
    trials = []
    for seed in range(1, seeds + 1):
        clouds, poses = object_scene(seed, PARTS_KIND.voxel)
        for i, j in ((0, 1), (1, 2), (0, 2)):
            gt = np.linalg.inv(poses[i]) @ poses[j]
            name = f"spheres and boxes {seed:2d}, view {i} <- {j}"
            source = clouds[j].astype(np.float32)
            # the translation error where the object is, not at the camera 0.5 m away (where 1 degree is 9 mm)
            at = source.mean(axis=0).astype(np.float64)
            trials.append(Trial(name, source, clouds[i].astype(np.float32), gt, PARTS_KIND, at=at))
    return trials


#: Each repetitive family beside its control, and the objects of symmetric parts (no control: most of their poses
#: are unique, and right).
FAMILIES = (
    Family("identical street (repetitive)", lambda: street_trials(True)),
    Family("identical street, 12 m period (repetitive)", lambda: street_trials(True, period=12.0, seed=4)),
    Family("varied street (control)", lambda: street_trials(False)),
    Family("pillar grid (repetitive)", lambda: pillar_trials(True)),
    Family("scattered pillars (control)", lambda: pillar_trials(False)),
    Family("symmetric table (repetitive)", lambda: table_trials(True)),
    Family("one-sided table (control)", lambda: table_trials(False)),
    Family("spheres and boxes (symmetric parts)", part_trials),
)
