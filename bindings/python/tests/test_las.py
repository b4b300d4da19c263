# SPDX-License-Identifier: MIT
"""LAS through ``kissm.read_points`` (LAZ: test_io_laz.py): files written byte by byte here (no dependency), and
files written by laspy (the test extra) from a real cloud of ../shared/data at point formats 0, 1, 3, 6 and
versions 1.2 and 1.4: the points equal the source's within the scale and laspy's own scaled values bit for bit,
withheld points are left out, and a georeferenced copy (offsets of 1e6 m) registers with the unshifted pose. Then the
CLI's LAS writer (``--out-aligned x.las``) read back by laspy and by kissm."""

from __future__ import annotations

import re
import struct
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from laspy_records import write_laspy

import kissm
import kissm._read

from realdata import RealPair, read_cached
from testdata import rotation_error_deg

MIN_RECORD = (20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67)


def las_bytes(
    ints: np.ndarray,
    *,
    fmt: int = 1,
    minor: int = 2,
    scale: float = 0.01,
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0),
    withheld: tuple[int, ...] = (),
    fmt_id: int | None = None,
) -> bytes:
    """A LAS file (the ASPRS LAS 1.4 public header block layout) holding int32 X, Y, Z records."""
    size = 375 if minor >= 4 else 235 if minor == 3 else 227
    n = len(ints)
    head = bytearray(375)
    head[0:4] = b"LASF"
    head[24:26] = bytes([1, minor])
    legacy = 0 if minor >= 4 and fmt >= 6 else n
    struct.pack_into("<HIIBHI", head, 94, size, size, 0, fmt if fmt_id is None else fmt_id, MIN_RECORD[fmt], legacy)
    struct.pack_into("<6d", head, 131, scale, scale, scale, *offset)
    if minor >= 4:
        struct.pack_into("<Q", head, 247, n)
    body = bytearray()
    for i, xyz in enumerate(ints):
        record = bytearray(MIN_RECORD[fmt])
        struct.pack_into("<3i", record, 0, *(int(v) for v in xyz))
        if i in withheld:
            record[15] = 0x80 if fmt <= 5 else 0x04
        body += record
    return bytes(head[:size]) + bytes(body)


INTS = np.array([[0, 0, 0], [123456, -654321, 1], [-(2**31), 2**31 - 1, 7]], dtype=np.int64)


def test_formats_has_las() -> None:
    assert kissm.FORMATS["las"] == 7  # KISSM_FORMAT_LAS


@pytest.mark.parametrize(("fmt", "minor"), [(0, 0), (1, 2), (3, 2), (6, 4), (7, 4), (10, 4)])
def test_read_own_bytes(tmp_path: Path, fmt: int, minor: int) -> None:
    path = tmp_path / "c.las"
    offset = (1e6, -2.5e6, 100.0)
    path.write_bytes(las_bytes(INTS, fmt=fmt, minor=minor, scale=0.001, offset=offset, withheld=(0,)))
    expected = INTS[1:] * 0.001 + np.array(offset)  # float64, the reader's operation order
    got = kissm.read_points(path)
    assert got.dtype == np.float64 and got.shape == (2, 3)
    assert np.array_equal(got, expected)
    assert np.array_equal(kissm.read_points(path, format="las"), expected)
    assert np.array_equal(kissm.read_points(path, format="auto"), expected)
    points, withheld = kissm.read_points(path, return_withheld=True)
    assert np.array_equal(points, expected) and withheld == 1


def test_errors(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # A LAS header marked compressed is LAZ (tests/test_io_laz.py): without laspy, the library's refusal is the
    # cause of an error naming the extra that reads it.
    laz = tmp_path / "c.laz"
    laz.write_bytes(las_bytes(INTS, fmt_id=0x83, fmt=3))
    monkeypatch.setattr(kissm._read, "laspy_with_lazrs", lambda: None)
    with pytest.raises(kissm.UnsupportedFormatError, match=r"pip install kissm\[las\]") as caught:
        kissm.read_points(laz)
    # The package's library is built without LAZ (KISSM_WITH_LAZ is off by default): its refusal, by the format
    # id's compression bit, is the cause.
    cause = caught.value.__cause__
    assert isinstance(cause, kissm.UnsupportedFormatError)
    assert re.search(r"LAZ support was not built in .*-DKISSM_WITH_LAZ=ON", str(cause))
    short = tmp_path / "short.las"
    short.write_bytes(las_bytes(INTS)[:-1])
    with pytest.raises(kissm.ParseError, match="truncated: the header says 3 points of 28 bytes"):
        kissm.read_points(short)
    zero = tmp_path / "zero.las"
    zero.write_bytes(las_bytes(INTS, scale=0.0))
    with pytest.raises(kissm.ParseError, match="the x scale factor is 0"):
        kissm.read_points(zero)
    not_las = tmp_path / "ply.las"
    not_las.write_bytes(b"ply\nformat ascii 1.0\n")
    with pytest.raises(kissm.ParseError, match="not a LAS file"):
        kissm.read_points(not_las)


# ---- laspy-written files from a real cloud ---------------------------------------------------------------

COMBOS = [(0, "1.2"), (1, "1.2"), (3, "1.2"), (0, "1.4"), (1, "1.4"), (3, "1.4"), (6, "1.4")]


def _laspy() -> Any:
    return pytest.importorskip("laspy", reason="laspy is not installed (it is in the test extra: pip install .[test])")


def _lidar_pair(real_pairs: dict[str, RealPair]) -> RealPair:
    lidar = [p for p in real_pairs.values() if p.is_lidar]
    if not lidar:
        pytest.skip("no LiDAR pairs in the data")
    return lidar[0]


@pytest.mark.parametrize(("fmt", "version"), COMBOS)
def test_laspy_files(real_pairs: dict[str, RealPair], tmp_path: Path, fmt: int, version: str) -> None:
    pair = _lidar_pair(real_pairs)
    source = read_cached(pair.source, pair.source_format)
    path = tmp_path / f"f{fmt}_v{version}.las"
    back = write_laspy(path, source, fmt, version, np.floor(source.min(axis=0)))
    got = kissm.read_points(path)
    # laspy's own scaled values (X * scale + offset in float64), bit for bit, and the source within the scale.
    assert np.array_equal(got, np.stack([np.asarray(back.x), np.asarray(back.y), np.asarray(back.z)], axis=1))
    assert got.shape == source.shape
    assert np.max(np.abs(got - source)) <= 0.5e-3 + 1e-9


@pytest.mark.parametrize(("fmt", "version"), [(1, "1.2"), (6, "1.4")])
def test_laspy_withheld(real_pairs: dict[str, RealPair], tmp_path: Path, fmt: int, version: str) -> None:
    pair = _lidar_pair(real_pairs)
    source = read_cached(pair.source, pair.source_format)
    withheld = np.zeros(len(source), dtype=bool)
    withheld[::7] = True
    path = tmp_path / "withheld.las"
    write_laspy(path, source, fmt, version, np.floor(source.min(axis=0)), withheld=withheld)
    got, left_out = kissm.read_points(path, return_withheld=True)
    assert left_out == int(withheld.sum())
    assert got.shape == (int((~withheld).sum()), 3)
    assert np.max(np.abs(got - source[~withheld])) <= 0.5e-3 + 1e-9


def test_laspy_georeferenced_registers_as_unshifted(real_pairs: dict[str, RealPair], tmp_path: Path) -> None:
    """The same integer records with offsets 1e6 m larger: the clouds read differ from the unshifted ones by
    the shift up to float64 rounding (at most 2.5e-10 m at 1e6), and the pose is the unshifted one moved by the
    shift. Not bit for bit (that takes shifts exact in float64, test_frames.py): the rounding moves a few points
    across voxel borders, so the poses agree within the registration's resolution (measured: 0.09 deg and 8 mm
    at the cloud's centre without refinement, 0.004 deg and 0.4 mm with GICP)."""
    pair = _lidar_pair(real_pairs)
    source = read_cached(pair.source, pair.source_format)
    target = read_cached(pair.target, pair.target_format)
    base = np.floor(np.minimum(source.min(axis=0), target.min(axis=0)))
    shift = np.array([1e6, 1e6, 1e6])
    clouds = {}
    for name, cloud in (("source", source), ("target", target)):
        write_laspy(tmp_path / f"{name}.las", cloud, 3, "1.2", base)
        write_laspy(tmp_path / f"{name}_geo.las", cloud + shift, 3, "1.2", base + shift)
        clouds[name] = kissm.read_points(tmp_path / f"{name}.las")
        clouds[name + "_geo"] = kissm.read_points(tmp_path / f"{name}_geo.las")
        assert np.max(np.abs(clouds[name + "_geo"] - shift - clouds[name])) <= 2.5e-10
    centre = clouds["source"].mean(axis=0)
    for refine, max_deg, max_m in (("none", 0.3, 0.03), ("gicp", 0.02, 0.002)):
        kw: dict[str, Any] = {"voxel_size": pair.kind.voxel, "num_threads": 2, "refine_mode": refine}
        a = kissm.register(clouds["source"], clouds["target"], **kw)
        b = kissm.register(clouds["source_geo"], clouds["target_geo"], **kw)
        assert a.valid and b.valid, (refine, a, b)
        assert rotation_error_deg(a.rotation, pair.gt[:3, :3]) < pair.kind.max_rot_deg, (refine, a)
        assert rotation_error_deg(a.rotation, b.rotation) < max_deg, (refine, a.rotation, b.rotation)
        # Where each pose puts the source's centre (t' = t + s - R s up to the rotation's difference).
        moved = a.rotation @ centre + a.translation + shift
        moved_geo = b.rotation @ (centre + shift) + b.translation
        assert np.linalg.norm(moved - moved_geo) < max_m, (refine, moved, moved_geo)


# ---- the CLI's LAS writer (--out-aligned FILE.las) ---------------------------------------------------------


def _register_out_aligned(cli: Path, source: Path, target: Path, out: Path) -> tuple[np.ndarray, Any]:
    """Runs `kissm register SOURCE TARGET --out-aligned OUT` on the demo pair; returns the transform it wrote
    and laspy's reading of OUT."""
    laspy = _laspy()
    transform = out.parent / "T.txt"
    args = ["register", str(source), str(target), "--voxel", "0.3", "--threads", "2", "--out-aligned", str(out)]
    run = subprocess.run(
        [str(cli), *args, "--out-transform", str(transform)], capture_output=True, text=True, timeout=300
    )
    assert run.returncode in (0, 1), run.stderr  # 1: a pose that is not valid is still written
    T = np.array([[float(v) for v in line.split()] for line in transform.read_text().splitlines()])
    return T, laspy.read(str(out))


def _xyz(las: Any) -> np.ndarray:
    return np.stack([np.asarray(las.x), np.asarray(las.y), np.asarray(las.z)], axis=1)


def test_cli_out_aligned_las_keeps_target_frame(cli: Path, demo_clouds: tuple[Path, Path], tmp_path: Path) -> None:
    """A georeferenced LAS target (offsets near 1e6 m, 1 mm scale): the aligned source is written with the
    target's scale and offset, laspy and kissm read the same bits, and every point is R p + t within half a
    scale step."""
    source_ply, target_ply = demo_clouds
    source = kissm.read_points(source_ply)
    target = kissm.read_points(target_ply)
    shift = np.array([500_000.0, 4_500_000.0, 100.0])
    offset = np.floor(target.min(axis=0)) + shift
    target_las = tmp_path / "target.las"
    write_laspy(target_las, target + shift, 3, "1.2", offset)
    out = tmp_path / "aligned.las"
    T, written = _register_out_aligned(cli, source_ply, target_las, out)
    assert written.header.version.major == 1 and written.header.version.minor == 2
    assert written.header.point_format.id == 0
    assert np.array_equal(written.header.scales, [1e-3] * 3)
    assert np.array_equal(written.header.offsets, offset)
    xyz = _xyz(written)
    assert np.array_equal(kissm.read_points(out), xyz)
    moved = source @ T[:3, :3].T + T[:3, 3]
    assert xyz.shape == moved.shape
    assert np.max(np.abs(xyz - moved)) <= 0.5e-3 + 1e-9
    # The pose is the demo's: the aligned source lies on the target (the shift is in the pose).
    assert np.linalg.norm(T[:3, 3] - shift) < 100


def test_cli_out_aligned_las_own_frame(cli: Path, demo_clouds: tuple[Path, Path], tmp_path: Path) -> None:
    """A target that is not LAS: scale 0.0001 and an offset of whole units near the aligned cloud's centre."""
    source_ply, target_ply = demo_clouds
    out = tmp_path / "aligned.LAS"
    T, written = _register_out_aligned(cli, source_ply, target_ply, out)
    moved = kissm.read_points(source_ply) @ T[:3, :3].T + T[:3, 3]
    assert np.array_equal(written.header.scales, [1e-4] * 3)
    centre = (moved.min(axis=0) + moved.max(axis=0)) / 2
    assert np.all(np.abs(written.header.offsets - centre) <= 0.5 + 1e-9)
    assert np.array_equal(written.header.offsets, np.round(written.header.offsets))
    xyz = _xyz(written)
    assert np.array_equal(kissm.read_points(out), xyz)
    assert np.max(np.abs(xyz - moved)) <= 0.5e-4 + 1e-9


def test_cli_out_aligned_laz_refused(cli: Path, demo_clouds: tuple[Path, Path], tmp_path: Path) -> None:
    source_ply, target_ply = demo_clouds
    run = subprocess.run(
        [
            str(cli),
            "register",
            str(source_ply),
            str(target_ply),
            "--voxel",
            "0.3",
            "--out-aligned",
            str(tmp_path / "x.laz"),
        ],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert run.returncode == 2
    assert "--out-aligned: kissm does not write LAZ" in run.stderr
    assert not (tmp_path / "x.laz").exists()


def test_cli_names_withheld_points(cli: Path, demo_clouds: tuple[Path, Path], tmp_path: Path) -> None:
    """The CLI says how many points flagged withheld it left out of a LAS input (kissm_cloud_num_withheld)."""
    _laspy()
    source_ply, target_ply = demo_clouds
    target = kissm.read_points(target_ply)
    withheld = np.zeros(len(target), dtype=bool)
    withheld[::100] = True
    target_las = tmp_path / "target.las"
    write_laspy(target_las, target, 1, "1.2", np.floor(target.min(axis=0)), withheld=withheld)
    run = subprocess.run(
        [str(cli), "register", str(source_ply), str(target_las), "--voxel", "0.3", "--json"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode in (0, 1), run.stderr
    assert f"kissm: target '{target_las}': {int(withheld.sum())} points flagged withheld left out" in run.stderr
    assert "source" not in run.stderr
