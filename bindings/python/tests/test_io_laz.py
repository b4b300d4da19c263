# SPDX-License-Identifier: MIT
"""LAZ through ``kissm.read_points`` (laspy with lazrs, the extra ``kissm[las]``): files compressed by laspy at
several point formats and versions, from synthetic records and from a real cloud of ../shared/data, read as the
same points, bit for bit, as the library's own LAS reader returns for the same data stored uncompressed
(withheld points left out, offsets of 1e6 m); the batch API and multiway read them by path; without laspy the
error names ``pip install kissm[las]``."""

from __future__ import annotations

import struct
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from laspy_records import write_laspy

import kissm
import kissm._read

from realdata import RealPair, read_cached

# (point format, version): the legacy formats at 1.2 and 1.4, the 1.4 formats up to the one with NIR and waveforms.
COMBOS = [(0, "1.2"), (1, "1.2"), (3, "1.2"), (1, "1.4"), (6, "1.4"), (7, "1.4"), (8, "1.4"), (10, "1.4")]


# The test extra installs both (bindings/python/run_tests.sh); package_test.sh's venvs have neither.
laspy: Any = pytest.importorskip(
    "laspy", reason="laspy is not installed (it is in the test extra: pip install .[test])"
)
pytest.importorskip("lazrs", reason="lazrs is not installed (it is in the test extra: pip install .[test])")


def write_pair(folder: Path, *records: Any, **options: Any) -> tuple[Path, Path]:
    """``write_laspy``'s records (its arguments after the path) written by laspy twice, as LAS and as LAZ (lazrs)."""
    fmt, version = records[1], records[2]
    plain = folder / f"f{fmt}_v{version}.las"
    compressed = plain.with_suffix(".laz")
    write_laspy(plain, *records, **options).write(str(compressed), laz_backend=laspy.LazBackend.Lazrs)
    return plain, compressed


def check_same_as_las(plain: Path, compressed: Path, expected_count: int) -> np.ndarray:
    assert compressed.read_bytes()[104] & 0x80  # laspy wrote LAZ (the compressed bit of the format id)
    reference = kissm.read_points(plain)  # the C reader
    got = kissm.read_points(compressed)
    assert got.dtype == np.float64 and got.flags.c_contiguous
    assert got.shape == (expected_count, 3)
    assert np.array_equal(got, reference)  # bit for bit (array_equal on float64 values, no NaN here)
    assert np.array_equal(kissm.read_points(compressed, format="las"), reference)
    return got


@pytest.mark.parametrize(("fmt", "version"), COMBOS)
def test_synthetic_laz_equals_the_c_readers_las(tmp_path: Path, fmt: int, version: str) -> None:
    """No real data needed: integer records across the int32 range around offsets of 1e6 m, every 5th withheld."""
    rng = np.random.default_rng(fmt)
    offset = np.array([1e6, -2.5e6, 100.0])
    ints = rng.integers(-(2**31), 2**31 - 1, size=(500, 3))
    xyz = ints * 1e-3 + offset  # laspy rounds back to the same integers
    withheld = np.zeros(len(xyz), dtype=bool)
    withheld[::5] = True
    plain, compressed = write_pair(tmp_path, xyz, fmt, version, offset, withheld=withheld)
    got = check_same_as_las(plain, compressed, int((~withheld).sum()))
    # And the library's formula itself: double(X) * scale + offset.
    records = laspy.read(str(plain))
    expected = np.stack([np.asarray(records.X), np.asarray(records.Y), np.asarray(records.Z)], axis=1)[~withheld]
    assert np.array_equal(got, expected.astype(np.float64) * 1e-3 + offset)
    # The withheld count, as the library's LAS reader reports it for the uncompressed copy.
    for path in (plain, compressed):
        points, count = kissm.read_points(path, return_withheld=True)
        assert np.array_equal(points, got) and count == int(withheld.sum()) > 0


def test_laz_named_las_is_read_by_its_header(tmp_path: Path) -> None:
    xyz = np.random.default_rng(3).uniform(-50, 50, size=(200, 3))
    plain, compressed = write_pair(tmp_path, xyz, 1, "1.2", np.zeros(3))
    disguised = tmp_path / "compressed_but_named.las"
    disguised.write_bytes(compressed.read_bytes())
    assert np.array_equal(kissm.read_points(disguised), kissm.read_points(plain))


def test_without_laspy_the_error_names_the_extra(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    xyz = np.random.default_rng(4).uniform(-50, 50, size=(100, 3))
    _, compressed = write_pair(tmp_path, xyz, 3, "1.2", np.zeros(3))
    monkeypatch.setattr(kissm._read, "laspy_with_lazrs", lambda: None)
    with pytest.raises(kissm.UnsupportedFormatError) as caught:
        kissm.read_points(compressed)
    assert str(caught.value).startswith(
        f"{compressed}: reading LAZ needs laspy with its lazrs backend: pip install kissm[las]"
    )
    assert "LAZ" in str(caught.value.__cause__)  # the library's own refusal, kept as the cause


def test_broken_laz_is_a_parse_error(tmp_path: Path) -> None:
    fake = tmp_path / "no_laz_data.laz"  # a LAS header marked compressed, with no LASzip VLR
    header = bytearray(227)
    header[0:4], header[24:26], header[104] = b"LASF", bytes([1, 2]), 0x83
    struct.pack_into("<HI", header, 94, 227, 227)
    fake.write_bytes(bytes(header))
    with pytest.raises(kissm.ParseError, match=rf"^{fake}: LAZ: "):
        kissm.read_points(fake)
    xyz = np.random.default_rng(5).uniform(-50, 50, size=(1000, 3))
    _, compressed = write_pair(tmp_path, xyz, 3, "1.2", np.zeros(3))
    cut = tmp_path / "cut.laz"
    cut.write_bytes(compressed.read_bytes()[:-200])
    with pytest.raises(kissm.ParseError, match=rf"^{cut}: LAZ: "):
        kissm.read_points(cut)


# ---- a real cloud -----------------------------------------------------------------------------------------


def lidar_pair(real_pairs: dict[str, RealPair]) -> RealPair:
    lidar = [p for p in real_pairs.values() if p.is_lidar]
    assert lidar, "no LiDAR pair in the real data's index.tsv"
    return lidar[0]


@pytest.mark.parametrize(("fmt", "version"), COMBOS)
def test_real_cloud_laz_equals_the_c_readers_las(
    real_pairs: dict[str, RealPair], tmp_path: Path, fmt: int, version: str
) -> None:
    pair = lidar_pair(real_pairs)
    source = read_cached(pair.source, pair.source_format)
    withheld = np.zeros(len(source), dtype=bool)
    withheld[3::11] = True
    offset = np.floor(source.min(axis=0)) + 1e6  # georeferenced
    plain, compressed = write_pair(tmp_path, source + 1e6, fmt, version, offset, withheld=withheld)
    got = check_same_as_las(plain, compressed, int((~withheld).sum()))
    assert np.max(np.abs(got - 1e6 - source[~withheld])) <= 0.5e-3 + 1e-6  # within the scale (and 1e6 rounding)


def test_batch_and_multiway_read_laz_paths(real_pairs: dict[str, RealPair], tmp_path: Path) -> None:
    """A pair given as LAZ paths (plain, and as CloudFile) registers with the same bits as the same data as LAS."""
    pair = lidar_pair(real_pairs)
    files: dict[str, tuple[Path, Path]] = {}
    for name, path, fmt in (("source", pair.source, pair.source_format), ("target", pair.target, pair.target_format)):
        cloud = read_cached(path, fmt)
        folder = tmp_path / name
        folder.mkdir()
        files[name] = write_pair(folder, cloud, 6, "1.4", np.floor(cloud.min(axis=0)))
    settings: dict[str, Any] = {"voxel_size": pair.kind.voxel, "threads_per_job": 2}
    las = {k: str(v[0]) for k, v in files.items()}
    laz = {"source": str(files["source"][1]), "target": kissm.batch.CloudFile(str(files["target"][1]), "las")}
    (reference,) = kissm.batch.register_many([("source", "target")], las, **settings)
    (got,) = kissm.batch.register_many([("source", "target")], laz, **settings)
    assert reference.result is not None and got.result is not None, (reference.error, got.error)
    assert reference.result.valid
    assert np.array_equal(got.result.transform, reference.result.transform)
    alignment = kissm.multiway.align([laz["target"], laz["source"]], pair.kind.voxel, refine=None)
    merged = alignment.merged([laz["target"], laz["source"]])
    assert alignment.placed.all() and len(merged) == sum(len(kissm.read_points(p[0])) for p in files.values())
