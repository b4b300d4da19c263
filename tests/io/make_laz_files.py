# SPDX-License-Identifier: MIT
"""Writes the LAZ test files of tests/io/test_io_laz.cpp with the reference implementation.

laspy with its lazrs backend (both Apache-2.0/BSD, PyPI) writes each cloud twice, as NAME.las and NAME.laz,
with the same header (version, point format, scale, offset) and points, a share of them flagged withheld.
The C++ test then reads both with kissm and wants the same bits. manifest.tsv lists name, points kept and
points withheld.

Usage: python make_laz_files.py OUT_DIR   (exit 77, skipped, when laspy or lazrs is missing)
       python make_laz_files.py --fuzz-seeds tests/fuzz/corpus/las   (the LAZ seeds of the las fuzz target)
"""

import sys
from pathlib import Path

try:
    import laspy
    import numpy as np
    from laspy import LazBackend
except ImportError as e:  # pragma: no cover - the CTest skip path
    print(f"skipped: laspy with lazrs is not installed ({e})")
    sys.exit(77)

# (name, LAS version, point format, points): formats 0-5 compress point-wise in chunks, 6-10 in layers;
# 120,000 points span three of LASzip's 50,000-point chunks.
CASES = [
    ("v12_f0", "1.2", 0, 3000),
    ("v12_f1", "1.2", 1, 120_000),
    ("v12_f3", "1.2", 3, 2500),
    ("v13_f1", "1.3", 1, 1000),
    ("v14_f6", "1.4", 6, 120_000),
    ("v14_f7", "1.4", 7, 3000),
    ("v14_f8", "1.4", 8, 2000),
    ("v14_f1", "1.4", 1, 1500),
    # Small ones for the corruption tests, which read thousands of altered copies.
    ("small_f1", "1.2", 1, 60),
    ("small_f6", "1.4", 6, 60),
]


def cloud(n: int, seed: int) -> np.ndarray:
    """A street-like cloud around a UTM position: a ground plane, walls and noise, in metres."""
    rng = np.random.default_rng(seed)
    xyz = rng.uniform([-40, -40, -2], [40, 40, 10], size=(n, 3))
    xyz[: n // 2, 2] = rng.normal(0, 0.05, n // 2)  # ground
    return xyz + np.array([500_000.0, 4_500_000.0, 120.0])


def write_pair(out: Path, name: str, version: str, fmt: int, n: int, seed: int) -> tuple[int, int]:
    header = laspy.LasHeader(point_format=fmt, version=version)
    header.scales = np.array([0.001, 0.001, 0.001])
    header.offsets = np.array([500_000.0, 4_500_000.0, 100.0])
    las = laspy.LasData(header)
    xyz = cloud(n, seed)
    las.x, las.y, las.z = xyz[:, 0], xyz[:, 1], xyz[:, 2]
    rng = np.random.default_rng(seed + 1)
    withheld = rng.random(n) < 0.05
    withheld[3] = True  # at least one, in the small files too
    las.withheld = withheld
    las.intensity = rng.integers(0, 65535, n, dtype=np.uint16)
    if "gps_time" in las.point_format.dimension_names:
        las.gps_time = np.cumsum(rng.uniform(0, 1e-4, n))
    las.write(out / f"{name}.las")
    las.write(out / f"{name}.laz", laz_backend=LazBackend.Lazrs)
    return int(n - withheld.sum()), int(withheld.sum())


def fuzz_seeds(out: Path) -> None:
    """Two small LAZ files (point-wise and layered) for the las fuzz target's corpus: committed, so that the
    fuzzer starts from valid compressed data."""
    for name, version, fmt in (("laz_v12_f1.laz", "1.2", 1), ("laz_v14_f6.laz", "1.4", 6)):
        header = laspy.LasHeader(point_format=fmt, version=version)
        header.scales = np.array([0.01, 0.01, 0.01])
        las = laspy.LasData(header)
        xyz = cloud(40, 7) - np.array([500_000.0, 4_500_000.0, 120.0])
        las.x, las.y, las.z = xyz[:, 0], xyz[:, 1], xyz[:, 2]
        las.withheld = np.arange(40) % 9 == 0
        las.write(out / name, laz_backend=LazBackend.Lazrs)


def main() -> int:
    if sys.argv[1] == "--fuzz-seeds":
        fuzz_seeds(Path(sys.argv[2]))
        return 0
    out = Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for seed, (name, version, fmt, n) in enumerate(CASES):
        kept, withheld = write_pair(out, name, version, fmt, n, seed)
        rows.append(f"{name}\t{kept}\t{withheld}\n")
    (out / "manifest.tsv").write_text("".join(rows))
    print(f"wrote {len(rows)} LAS/LAZ pairs to {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
