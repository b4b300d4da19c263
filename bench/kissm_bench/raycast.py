# SPDX-License-Identifier: MIT
"""Ray-cast scenes with exact truth: solids (spheres, boxes, a room seen from inside) and range sensors with Gaussian
range noise. A compound object of spheres and boxes seen by a depth camera from turntable views, and a furnished
room seen by a panoramic depth sensor from three places (``nees_study`` measures the information on them; the
validity study registers the objects, whose spheres and boxes match themselves turned)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .geometry import axis_angle

NOISE_GAIN = 0.05  # the simulated range noise, in voxels


@dataclass
class Solids:
    spheres: list[tuple[np.ndarray, float]] = field(default_factory=list)
    boxes: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = field(default_factory=list)  #: centre, R, half sides
    room: tuple[np.ndarray, np.ndarray] | None = None  #: an enclosing box seen from inside: low and high corners


def _slabs(o: np.ndarray, d: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / np.where(d == 0, 1e-300, d)
        t1, t2 = (lo - o) * inv, (hi - o) * inv
    return np.minimum(t1, t2).max(axis=1), np.maximum(t1, t2).min(axis=1)


def ray_cast(solids: Solids, origin: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """The distance along each unit ray from ``origin`` to the first surface (inf when none)."""
    best = np.full(len(dirs), np.inf)
    for centre, radius in solids.spheres:
        oc = origin - centre
        b = dirs @ oc
        disc = b * b - (oc @ oc - radius * radius)
        with np.errstate(invalid="ignore"):
            s = -b - np.sqrt(disc)
        best = np.where((disc > 0) & (s > 0) & (s < best), s, best)
    for centre, rot, half in solids.boxes:
        tmin, tmax = _slabs(rot.T @ (origin - centre), dirs @ rot, -half, half)
        best = np.where((tmax >= tmin) & (tmin > 0) & (tmin < best), tmin, best)
    if solids.room is not None:
        _, tmax = _slabs(origin, dirs, *solids.room)
        best = np.where(tmax < best, tmax, best)
    return best


def scan(
    solids: Solids, pose: np.ndarray, dirs_sensor: np.ndarray, sigma: float, rng: np.random.Generator
) -> np.ndarray:
    """The points a range sensor at ``pose`` (sensor to world) sees along ``dirs_sensor``, with Gaussian range
    noise ``sigma``, in its own frame."""
    dirs = dirs_sensor @ pose[:3, :3].T
    s = ray_cast(solids, pose[:3, 3], dirs)
    hit = np.isfinite(s)
    r = s[hit] + rng.normal(0, sigma, int(hit.sum()))
    return np.ascontiguousarray(dirs_sensor[hit] * r[:, None])


def look_at(eye: np.ndarray, centre: np.ndarray, up: np.ndarray) -> np.ndarray:
    """The camera pose (z forward, x right, y down) at ``eye`` looking at ``centre``."""
    z = centre - eye
    z /= np.linalg.norm(z)
    x = np.cross(z, up)
    x /= np.linalg.norm(x)
    t = np.eye(4)
    t[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    t[:3, 3] = eye
    return t


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return np.asarray(q * np.sign(np.linalg.det(q)))


Views = tuple[list[np.ndarray], list[np.ndarray]]  # clouds, each in its sensor's frame, and the sensors' world poses


def object_scene(seed: int, voxel: float, noise: float = NOISE_GAIN) -> Views:
    """A compound object about 0.2 m across (6 spheres, 5 boxes) on a turntable, seen by a depth camera 0.5 m
    away (320 x 320 rays over 30 degrees) from three views 25-40 degrees apart, 0-35 degrees up."""
    rng = np.random.default_rng([seed, 1])
    solids = Solids()
    for _ in range(6):
        solids.spheres.append((rng.uniform(-0.06, 0.06, 3), float(rng.uniform(0.012, 0.04))))
    for _ in range(5):
        solids.boxes.append((rng.uniform(-0.06, 0.06, 3), random_rotation(rng), rng.uniform(0.006, 0.04, 3)))
    up = np.array([0.0, 0.0, 1.0])
    az = rng.uniform(0, 2 * math.pi)
    poses = []
    for _ in range(3):
        el = math.radians(rng.uniform(0, 35))
        eye = 0.5 * np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
        poses.append(look_at(eye, np.zeros(3), up))
        az += math.radians(rng.uniform(25, 40))
    clouds = []
    n, half = 320, math.tan(math.radians(15))
    for pose in poses:
        uv = np.stack(np.meshgrid(np.arange(n), np.arange(n)), -1).reshape(-1, 2) + rng.uniform(0, 1, (n * n, 2))
        uv = (uv / n * 2 - 1) * half
        dirs = np.column_stack([uv, np.ones(n * n)])
        dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
        clouds.append(scan(solids, pose, dirs, noise * voxel, rng))
    return clouds, poses


def room_scene(seed: int, voxel: float, noise: float = NOISE_GAIN) -> Views:
    """An 8 x 5 x 3 m room, L-shaped by a column, with 8-11 pieces of furniture, 2 wall shelves and 24 pieces of
    clutter, seen by a panoramic depth sensor (900 x 160 rays, -55 to 55 degrees) from three places, each
    1-2.5 m from the one before, turned and tilted up to 3 degrees."""
    rng = np.random.default_rng([seed, 2])
    size = np.array([8.0, 5.0, 3.0])
    solids = Solids(room=(np.zeros(3), size))
    footprints = []
    # a column from floor to ceiling in one corner makes the room L-shaped
    corner = np.array([rng.uniform(0.6, 1.2), rng.uniform(0.5, 1.0), 1.5])
    solids.boxes.append((corner, np.eye(3), corner))
    footprints.append((corner[:2], float(np.linalg.norm(corner[:2]))))
    for _ in range(12):  # clutter: lamps, pots, balls, books, boxes
        centre = np.array([rng.uniform(0.3, 7.7), rng.uniform(0.3, 4.7), rng.uniform(0.1, 2.6)])
        solids.spheres.append((centre, float(rng.uniform(0.05, 0.25))))
        centre = np.array([rng.uniform(0.3, 7.7), rng.uniform(0.3, 4.7), rng.uniform(0.1, 2.6)])
        solids.boxes.append((centre, random_rotation(rng), rng.uniform(0.04, 0.2, 3)))
    for _ in range(int(rng.integers(8, 12))):
        half = np.array([rng.uniform(0.2, 1.0), rng.uniform(0.2, 0.6), rng.uniform(0.2, 1.0)])
        centre = np.array([rng.uniform(1, 7), rng.uniform(0.8, 4.2), half[2]])
        solids.boxes.append((centre, axis_angle([0, 0, 1], rng.uniform(0, 180)), half))
        footprints.append((centre[:2], float(np.linalg.norm(half[:2]))))
    for wall in range(2):  # shelves on the long walls
        half = np.array([rng.uniform(0.4, 1.0), 0.15, 0.05])
        y = 0.15 if wall == 0 else size[1] - 0.15
        solids.boxes.append((np.array([rng.uniform(1.5, 6.5), y, rng.uniform(1.2, 2.2)]), np.eye(3), half))

    def free(p: np.ndarray) -> bool:
        return all(np.linalg.norm(p[:2] - c) > r + 0.3 for c, r in footprints)

    def place(near: np.ndarray | None) -> np.ndarray:
        for _ in range(1000):
            if near is None:
                p = np.array([rng.uniform(1.2, 6.8), rng.uniform(1.0, 4.0), rng.uniform(1.2, 1.7)])
            else:
                d, a = rng.uniform(1.0, 2.5), rng.uniform(0, 2 * math.pi)
                p = near + np.array([d * math.cos(a), d * math.sin(a), rng.uniform(-0.2, 0.2)])
                if not (np.array([0.5, 0.5, 1.0]) < p).all() or not (p < size - np.array([0.5, 0.5, 1.0])).all():
                    continue
            if free(p):
                return p
        raise RuntimeError("no free place for the sensor")

    places = [place(None)]
    places += [place(places[-1]) for _ in range(2)]
    poses = []
    for p in places:
        t = np.eye(4)
        t[:3, :3] = axis_angle([0, 0, 1], rng.uniform(0, 360)) @ axis_angle(rng.normal(size=3), rng.uniform(0, 3))
        t[:3, 3] = p
        poses.append(t)
    clouds = []
    n_az, n_el = 900, 160
    for pose in poses:
        az = (np.arange(n_az)[:, None] + rng.uniform(0, 1, (n_az, n_el))) / n_az * 2 * math.pi
        el = np.radians(-55 + (np.arange(n_el)[None, :] + rng.uniform(0, 1, (n_az, n_el))) / n_el * 110)
        dirs = np.column_stack(
            [(np.cos(el) * np.cos(az)).ravel(), (np.cos(el) * np.sin(az)).ravel(), np.sin(el).ravel()]
        )
        clouds.append(scan(solids, pose, dirs, noise * voxel, rng))
    return clouds, poses
