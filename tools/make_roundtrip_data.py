#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Writes the small synthetic clouds of tests/data/ that the C, Python and Rust suites all register and
compare with tests/data/golden.json (bitwise). Pure Python, no dependencies; the output is committed, so
this only needs to run again when the scene itself should change (then regenerate the golden file with
tests/data/update_golden.sh).

Scene: a walled yard with boxes, poles and a sphere on rough ground, sampled twice with independent noise
and partial crops; the source is expressed in a frame turned by 140 degrees about a tilted axis and moved
by 4 m. Files: binary little-endian PLY with float64 x y z (exact values, no text rounding).

SplitMix64 is a copy of src/common/splitmix64.h, the reference (next, uniform, range, gauss); the
test splitmix64_python runs `make_roundtrip_data.py --selftest PROGRAM`, which compares this class with
the numbers that header gives (PROGRAM: the C test capi_splitmix64).
"""

import math
import os
import struct
import subprocess
import sys
from collections.abc import Sequence

Point = tuple[float, ...]  # x, y, z

MASK = (1 << 64) - 1


class SplitMix64:
    def __init__(self, seed: int) -> None:
        self.state = seed & MASK

    def next(self) -> int:
        self.state = (self.state + 0x9E3779B97F4A7C15) & MASK
        z = self.state
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & MASK
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & MASK
        return z ^ (z >> 31)

    def uniform(self, lo: float = 0.0, hi: float = 1.0) -> float:
        return lo + (hi - lo) * ((self.next() >> 11) * (1.0 / 9007199254740992.0))

    def normal(self) -> float:
        u1 = self.uniform() + 1e-300
        u2 = self.uniform()
        return math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)


def scene(rng: SplitMix64, n: int) -> list[Point]:
    """n points on the yard's surfaces, in the world frame."""
    pts: list[Point] = []
    boxes = [
        (3.0, 2.0, 1.2, 1.0, 0.8),
        (-4.0, 3.5, 0.9, 1.6, 1.4),
        (1.5, -4.0, 2.0, 0.7, 0.6),
        (-2.5, -2.0, 0.6, 0.6, 2.2),
    ]  # x, y, sx, sy, height
    poles = [(5.5, -1.0, 0.15, 3.0), (-6.0, -5.0, 0.2, 2.5), (0.5, 5.5, 0.12, 3.5)]
    while len(pts) < n:
        r = rng.uniform()
        if r < 0.35:  # rough ground
            x, y = rng.uniform(-8, 8), rng.uniform(-8, 8)
            z = 0.05 * math.sin(0.7 * x) * math.cos(0.5 * y)
            pts.append((x, y, z))
        elif r < 0.6:  # three walls of different heights
            w = rng.next() % 3
            t, h = rng.uniform(-8, 8), rng.uniform(0, [3.0, 2.2, 4.0][w])
            pts.append([(t, 8.0, h), (8.0, t, h), (-8.0, t * 0.5, h)][w])
        elif r < 0.82:  # boxes (sides and tops)
            bx, by, sx, sy, bh = boxes[rng.next() % len(boxes)]
            f = rng.next() % 5
            u, v = rng.uniform(-1, 1), rng.uniform(0, 1)
            if f == 0:
                pts.append((bx + sx * u, by + sy * rng.uniform(-1, 1), bh))
            elif f == 1:
                pts.append((bx + sx, by + sy * u, bh * v))
            elif f == 2:
                pts.append((bx - sx, by + sy * u, bh * v))
            elif f == 3:
                pts.append((bx + sx * u, by + sy, bh * v))
            else:
                pts.append((bx + sx * u, by - sy, bh * v))
        elif r < 0.93:  # poles
            px, py, pr, ph = poles[rng.next() % len(poles)]
            a = rng.uniform(0, 2 * math.pi)
            pts.append((px + pr * math.cos(a), py + pr * math.sin(a), rng.uniform(0, ph)))
        else:  # a sphere on a plinth
            d = (rng.normal(), rng.normal(), rng.normal())
            s = math.sqrt(sum(c * c for c in d))
            pts.append((-5.0 + 0.9 * d[0] / s, 5.0 + 0.9 * d[1] / s, 1.5 + 0.9 * d[2] / s))
    return pts


def rotation(axis: Sequence[float], angle: float) -> list[list[float]]:
    s = math.sqrt(sum(a * a for a in axis))
    x, y, z = (a / s for a in axis)
    c, n = math.cos(angle), math.sin(angle)
    C = 1 - c
    return [
        [c + x * x * C, x * y * C - z * n, x * z * C + y * n],
        [y * x * C + z * n, c + y * y * C, y * z * C - x * n],
        [z * x * C - y * n, z * y * C + x * n, c + z * z * C],
    ]


def write_ply(path: str, pts: Sequence[Sequence[float]]) -> None:
    header = (
        "ply\nformat binary_little_endian 1.0\ncomment kissm round-trip test cloud "
        "(tools/make_roundtrip_data.py)\nelement vertex %d\nproperty double x\nproperty double y\n"
        "property double z\nend_header\n" % len(pts)
    ).encode("ascii")
    with open(path, "wb") as f:
        f.write(header)
        for p in pts:
            f.write(struct.pack("<3d", *p))


def selftest(program: str) -> int:
    """0 when SplitMix64 draws the same numbers as src/common/splitmix64.h (printed by program)."""
    checked = 0
    for seed in (0, 20261122, MASK):
        printed = subprocess.run([program, "--print", str(seed), "100"], check=True, capture_output=True, text=True)
        rng = SplitMix64(seed)
        for line in printed.stdout.splitlines():
            bits, u, r, g = line.split()
            ours = (rng.next(), rng.uniform(), rng.uniform(-2.0, 3.0), rng.normal())
            if ours != (int(bits), float(u), float(r), float(g)):
                print("selftest: seed %d, draw %d: C header %s, Python %r" % (seed, checked, line, ours))
                return 1
            checked += 1
    if checked != 300:
        print("selftest: %s printed %d lines, not 300" % (program, checked))
        return 1
    print("selftest: %d draws of next, uniform, range and gauss match the C header" % checked)
    return 0


def main() -> None:
    if len(sys.argv) == 3 and sys.argv[1] == "--selftest":
        sys.exit(selftest(sys.argv[2]))
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "tests", "data")
    rng = SplitMix64(20261122)
    noise = 0.01
    target = [p for p in scene(rng, 9000) if p[0] > -6.5]  # partial overlap: crop each side differently
    world_src = [p for p in scene(rng, 9000) if p[1] < 6.5]
    target = [tuple(c + noise * rng.normal() for c in p) for p in target]
    # Source frame: p_world = R p_src + t, so p_src = R^T (p_world - t); the ground truth maps source into
    # target (= world) with (R, t).
    R = rotation((0.3, -0.5, 1.0), math.radians(140.0))
    t = (2.5, -3.0, 0.4)
    source = []
    for p in world_src:
        q = [p[i] - t[i] + noise * rng.normal() for i in range(3)]
        source.append(tuple(sum(R[j][i] * q[j] for j in range(3)) for i in range(3)))
    os.makedirs(out, exist_ok=True)
    write_ply(os.path.join(out, "roundtrip_source.ply"), source)
    write_ply(os.path.join(out, "roundtrip_target.ply"), target)
    with open(os.path.join(out, "roundtrip_ground_truth.txt"), "w") as f:
        f.write("# p_target = R p_source + t (4x4, row-major); made by tools/make_roundtrip_data.py\n")
        for i in range(3):
            f.write(" ".join("%.17g" % v for v in (R[i][0], R[i][1], R[i][2], t[i])) + "\n")
        f.write("0 0 0 1\n")
    print("wrote %d source and %d target points to %s" % (len(source), len(target), out))


if __name__ == "__main__":
    main()
