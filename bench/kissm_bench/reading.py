# SPDX-License-Identifier: MIT
"""Reading the files users have (issue 35): kissm's reader against laspy (and PDAL's Python reader when it
installs) on LAS and LAZ files made from the shared LiDAR clouds, tiled to a survey's size and moved to
georeferenced coordinates.

The clouds of every LiDAR pair of ``../shared/data`` are laid side by side (each tile shifted by 200 m) until
``--points`` points, then moved by (500,000 m, 5,000,000 m, 200 m), as a UTM survey stores them, and written by
laspy (the reference writer) with a scale of 1 mm: LAS 1.2 point format 1, LAS 1.4 point format 6, and both
compressed (LAZ, lazrs). Each file is read ``--repeats`` times, the readers taking turns, and the median wall time
is reported with the points per second. Every reader's points are compared with laspy's ``x, y, z`` (float64:
stored integer times scale plus offset) bit for bit.

    python bench/read_bench.py [--points 4000000] [--repeats 5] [--out docs/reports]
"""

from __future__ import annotations

import argparse
import importlib
import os
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from .common import add_data_option, machine_info, no_data
from .data import has_index, load_pairs

TILE_SHIFT = 200.0
GEO_OFFSET = np.array([500_000.0, 5_000_000.0, 200.0])
SCALE = 0.001

#: (file name, LAS version, point format, compressed)
FILES = (
    ("survey_1.2_pf1.las", "1.2", 1, False),
    ("survey_1.4_pf6.las", "1.4", 6, False),
    ("survey_1.2_pf1.laz", "1.2", 1, True),
    ("survey_1.4_pf6.laz", "1.4", 6, True),
)


def survey_points(data: Path, count: int) -> np.ndarray:
    """The LiDAR clouds of the shared pairs, tiled to ``count`` points and moved to georeferenced coordinates."""
    clouds: list[np.ndarray] = []
    for pair in load_pairs(data):
        if pair.is_lidar:
            clouds.extend(pair.read())
    if not clouds:
        raise SystemExit("read_bench: no LiDAR pair in the data")
    tiles, total, k = [], 0, 0
    while total < count:
        cloud = clouds[k % len(clouds)]
        shift = np.array([TILE_SHIFT * (k % 10), TILE_SHIFT * (k // 10), 0.0])
        tiles.append(cloud[np.all(np.isfinite(cloud), axis=1)] + shift)
        total += len(tiles[-1])
        k += 1
    out: np.ndarray = np.concatenate(tiles)[:count] + GEO_OFFSET
    return out


def optional(name: str) -> Any:
    """A module that may be missing (laspy, lazrs, pdal): imported by name, so the type checker needs no stubs."""
    return importlib.import_module(name)


def write_files(points: np.ndarray, folder: Path) -> list[Path]:
    laspy = optional("laspy")

    paths = []
    for name, version, point_format, _ in FILES:
        header = laspy.LasHeader(point_format=point_format, version=version)
        header.scales = np.array([SCALE] * 3)
        header.offsets = np.floor(points.min(axis=0))
        las = laspy.LasData(header)
        las.x, las.y, las.z = points[:, 0], points[:, 1], points[:, 2]
        path = folder / name
        las.write(str(path))
        paths.append(path)
    return paths


def read_kissm(path: Path) -> np.ndarray:
    import kissm

    points: np.ndarray = kissm.read_points(path)
    return points


def read_laspy(path: Path) -> np.ndarray:
    laspy = optional("laspy")

    las = laspy.read(str(path))
    return np.column_stack([np.asarray(las.x), np.asarray(las.y), np.asarray(las.z)])


def read_pdal(path: Path) -> np.ndarray:
    pdal = optional("pdal")
    pipeline = pdal.Reader(str(path)).pipeline()
    pipeline.execute()
    a = pipeline.arrays[0]
    return np.column_stack([a["X"], a["Y"], a["Z"]])


def readers() -> tuple[dict[str, Callable[[Path], np.ndarray]], dict[str, str]]:
    """The readers that import here, and why the others do not."""
    out: dict[str, Callable[[Path], np.ndarray]] = {"kissm": read_kissm, "laspy": read_laspy}
    missing = {}
    try:
        optional("pdal")
        out["PDAL"] = read_pdal
    except ImportError as e:
        missing["PDAL"] = (
            f"not importable ({e}): PyPI has only its source, which builds against libpdal, and Debian 12's "
            "apt here has no libpdal-dev"
        )
    return out, missing


def measure(paths: list[Path], repeats: int) -> dict[str, Any]:
    found, missing = readers()
    load = os.getloadavg()[0]
    rows = []
    for path, (name, version, point_format, compressed) in zip(paths, FILES, strict=True):
        reference = read_laspy(path)
        times: dict[str, list[float]] = {r: [] for r in found}
        same: dict[str, bool] = {}
        for _ in range(repeats):
            for reader, fn in found.items():  # taking turns, so a machine's drift falls on every reader alike
                t0 = time.perf_counter()
                points = fn(path)
                times[reader].append(time.perf_counter() - t0)
                same[reader] = bool(points.shape == reference.shape and np.array_equal(points, reference))
                del points
        rows.append(
            {
                "file": name,
                "version": version,
                "point_format": point_format,
                "compressed": compressed,
                "points": len(reference),
                "megabytes": path.stat().st_size / 1e6,
                "seconds": {r: statistics.median(t) for r, t in times.items()},
                "same_points": same,
            }
        )
    return {"rows": rows, "missing": missing, "repeats": repeats, "machine": machine_info(), "load": load}


def render(result: dict[str, Any], command: str) -> str:
    names = list(result["rows"][0]["seconds"])
    lines = [
        "# Reading LAS and LAZ (issue 35)",
        "",
        f"Generated by `{command}` (checkout {result['machine'].get('git', '?')}, load average "
        f"{result['load']:.1f} at the start). Median wall time of "
        f"{result['repeats']} reads per reader, the readers taking turns; points per second in millions. Every "
        "reader's points equal laspy's `x, y, z` bit for bit where the last column says so.",
        "",
        "| file | points | MB | "
        + " | ".join(f"{n} s (Mpts/s)" for n in names)
        + " | kissm / laspy time | same points |",
        "|---|--:|--:|" + "--:|" * len(names) + "--:|---|",
    ]
    for r in result["rows"]:
        cells = [f"{r['seconds'][n]:.3f} ({r['points'] / r['seconds'][n] / 1e6:.1f})" for n in names]
        ratio = r["seconds"]["kissm"] / r["seconds"]["laspy"]
        same = ", ".join(f"{n}: {'yes' if ok else 'NO'}" for n, ok in r["same_points"].items())
        lines.append(
            f"| {r['file']} | {r['points']:,} | {r['megabytes']:.0f} | "
            + " | ".join(cells)
            + f" | {ratio:.2f} | {same} |"
        )
    lines += [""]
    for n, why in result["missing"].items():
        lines.append(f"{n}: {why}.")
    lines += [
        "",
        "kissm reads LAS in its C library (scale and offset applied in double); LAZ goes through laspy and its lazrs",
        "backend (`kissm[las]`), so its LAZ rows measure what that path adds to laspy's own read.",
        "",
        f"Machine: {result['machine'].get('cpu', '?')}, {result['machine'].get('cpus_online', '?')} CPUs; "
        + ", ".join(f"{k} {v}" for k, v in sorted(result["machine"].get("packages", {}).items())),
        "",
    ]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    add_data_option(parser)
    parser.add_argument("--points", type=int, default=4_000_000, help="points per file (4,000,000)")
    parser.add_argument("--repeats", type=int, default=5, help="reads per reader and file (5)")
    parser.add_argument("--out", type=Path, help="writes reading.md there (default: print it)")
    args = parser.parse_args(argv)
    if not has_index(args.data):
        return no_data("read_bench", f"no index.tsv in {args.data}")
    try:
        optional("laspy")
        optional("lazrs")
    except ImportError as e:
        raise SystemExit(f"read_bench: needs laspy and lazrs ({e}): pip install 'laspy[lazrs]'") from e
    points = survey_points(args.data, args.points)
    with tempfile.TemporaryDirectory() as folder:
        result = measure(write_files(points, Path(folder)), args.repeats)
    command = "python bench/read_bench.py " + " ".join(argv if argv is not None else sys.argv[1:])
    page = render(result, command.strip())
    if args.out:
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "reading.md").write_text(page)
    else:
        print(page)
    return 0
