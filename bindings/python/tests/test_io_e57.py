# SPDX-License-Identifier: MIT
"""E57 through ``kissm.io`` (pye57, the extra ``kissm[e57]``): multi-scan files written by pye57 (the reference
writer) from synthetic scans and from three Happy Buddha scans of ../shared/data with their ground-truth poses.
``read_e57`` gives each scan's points as stored (bit for bit, invalid points left out), its pose and its name;
``kissm.multiway.align`` places the scans right from those poses (``priors``) and without them; and
``write_e57_poses`` writes a copy whose poses are the ones given and whose points and other fields are the
source's, bit for bit."""

from __future__ import annotations

import csv
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import kissm
import kissm._e57
import kissm.io

HAPPY = "stanford_happy_stand_scans"
HAPPY_SCANS = ("happyStandRight_0", "happyStandRight_24", "happyStandRight_48")
HAPPY_VOXEL = 0.004


# The test extra installs it (bindings/python/run_tests.sh); package_test.sh's venvs do not.
pye57: Any = pytest.importorskip(
    "pye57", reason="pye57 is not installed (it is in the test extra: pip install .[test])"
)


def angle_deg(rotation: np.ndarray) -> float:
    return math.degrees(math.acos(max(-1.0, min(1.0, (float(np.trace(rotation)) - 1.0) / 2.0))))


def quaternion_wxyz(rotation: np.ndarray) -> np.ndarray:
    """(w, x, y, z) of a rotation matrix by Shepperd's method (the largest of the four first), for the writer."""
    m = rotation
    candidates = [1 + m[0, 0] + m[1, 1] + m[2, 2], 1 + m[0, 0] - m[1, 1] - m[2, 2], 1 - m[0, 0] + m[1, 1] - m[2, 2]]
    candidates.append(1 - m[0, 0] - m[1, 1] + m[2, 2])
    k = int(np.argmax(candidates))
    s = 2 * math.sqrt(candidates[k])
    if k == 0:
        q = [s / 4, (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s]
    elif k == 1:
        q = [(m[2, 1] - m[1, 2]) / s, s / 4, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s]
    elif k == 2:
        q = [(m[0, 2] - m[2, 0]) / s, (m[0, 1] + m[1, 0]) / s, s / 4, (m[1, 2] + m[2, 1]) / s]
    else:
        q = [(m[1, 0] - m[0, 1]) / s, (m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, s / 4]
    array = np.array(q)
    return array / np.linalg.norm(array)


def write_e57(path: Path, scans: list[tuple[str, np.ndarray, np.ndarray]], extra: bool = False) -> None:
    """A multi-scan E57 written by pye57: (name, points in the scan's frame, world <- scan pose) per scan; with
    ``extra``, an intensity per point and every 7th point marked invalid."""
    with pye57.E57(str(path), mode="w") as e57:
        for name, points, pose in scans:
            data = {
                axis: np.ascontiguousarray(points[:, k])
                for k, axis in enumerate(("cartesianX", "cartesianY", "cartesianZ"))
            }
            if extra:
                data["intensity"] = np.linspace(0.0, 1.0, len(points))
                invalid = np.zeros(len(points), dtype=np.int8)
                invalid[::7] = 1
                data["cartesianInvalidState"] = invalid
            e57.write_scan_raw(data, name=name, rotation=quaternion_wxyz(pose[:3, :3]), translation=pose[:3, 3])


def random_pose(rng: np.random.Generator) -> np.ndarray:
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    angle = rng.uniform(0.1, 3.0)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    pose = np.eye(4)
    pose[:3, :3] = np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k
    pose[:3, 3] = rng.uniform(-100, 100, 3)
    return pose


def float32_exact(points: np.ndarray) -> np.ndarray:
    """The points as pye57 stores them (single-precision fields)."""
    return points.astype(np.float32).astype(np.float64)


# ---- synthetic scans: no real data needed ------------------------------------------------------------------


@pytest.fixture()
def synthetic(tmp_path: Path) -> tuple[Path, list[tuple[str, np.ndarray, np.ndarray]]]:
    rng = np.random.default_rng(7)
    scans = [(f"station {k}", rng.uniform(-20, 20, size=(300 + 50 * k, 3)), random_pose(rng)) for k in range(3)]
    path = tmp_path / "synthetic.e57"
    write_e57(path, scans, extra=True)
    return path, scans


def test_read_e57_gives_points_poses_and_names(
    synthetic: tuple[Path, list[tuple[str, np.ndarray, np.ndarray]]],
) -> None:
    path, scans = synthetic
    got = kissm.io.read_e57(path)
    assert [s.name for s in got] == [name for name, _, _ in scans]
    for scan, (_, points, pose) in zip(got, scans, strict=True):
        valid = np.ones(len(points), dtype=bool)
        valid[::7] = False  # marked invalid by the writer
        assert scan.points.dtype == np.float64 and scan.points.flags.c_contiguous
        assert np.array_equal(scan.points, float32_exact(points[valid]))
        assert np.max(np.abs(scan.pose - pose)) < 1e-14
        assert np.array_equal(scan.pose[3], [0.0, 0.0, 0.0, 1.0])
    # pye57's own world points (its transform) are ours moved by our pose.
    with pye57.E57(str(path)) as e57:
        world = e57.read_scan(1, transform=True)
    ours = got[1].points @ got[1].pose[:3, :3].T + got[1].pose[:3, 3]
    assert (
        np.max(np.abs(np.stack([world["cartesianX"], world["cartesianY"], world["cartesianZ"]], axis=1) - ours)) < 1e-9
    )


def test_write_e57_poses_changes_only_the_poses(
    synthetic: tuple[Path, list[tuple[str, np.ndarray, np.ndarray]]], tmp_path: Path
) -> None:
    path, scans = synthetic
    rng = np.random.default_rng(8)
    poses = np.stack([random_pose(rng) for _ in scans])
    out = tmp_path / "posed.e57"
    kissm.io.write_e57_poses(path, out, poses)
    before, after = kissm.io.read_e57(path), kissm.io.read_e57(out)
    for old, new, pose in zip(before, after, poses, strict=True):
        assert new.name == old.name
        assert np.array_equal(new.points, old.points)
        assert np.max(np.abs(new.pose - pose)) < 1e-14
    # Every stored field, invalid points included, read raw by pye57: the same values.
    with pye57.E57(str(path)) as a, pye57.E57(str(out)) as b:
        assert a.scan_count == b.scan_count == len(scans)
        for k in range(a.scan_count):
            raw_a, raw_b = a.read_scan_raw(k), b.read_scan_raw(k)
            assert (
                sorted(raw_a)
                == sorted(raw_b)
                == sorted(["cartesianX", "cartesianY", "cartesianZ", "intensity", "cartesianInvalidState"])
            )
            for field in raw_a:
                assert np.array_equal(raw_a[field], raw_b[field]), field
            assert a.get_header(k).node["guid"].value() == b.get_header(k).node["guid"].value()


def test_a_failed_copy_leaves_no_file(
    synthetic: tuple[Path, list[tuple[str, np.ndarray, np.ndarray]]], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path, scans = synthetic

    def fail(*args: object) -> None:
        raise RuntimeError("stopped in the middle of the copy")

    monkeypatch.setattr(kissm._e57, "_copy_points", fail)
    out = tmp_path / "half.e57"
    with pytest.raises(RuntimeError, match="stopped in the middle"):
        kissm.io.write_e57_poses(path, out, np.stack([np.eye(4)] * len(scans)))
    assert not out.exists()


def test_e57_errors(synthetic: tuple[Path, list[tuple[str, np.ndarray, np.ndarray]]], tmp_path: Path) -> None:
    path, scans = synthetic
    out = tmp_path / "out.e57"
    with pytest.raises(kissm.InvalidArgumentError, match=r"^write_e57_poses: 2 poses for the 3 scans of "):
        kissm.io.write_e57_poses(path, out, np.stack([np.eye(4)] * 2))
    with pytest.raises(kissm.InvalidArgumentError, match=r"^write_e57_poses: poses has shape \(3, 3, 4\); \(N, 4, 4\)"):
        kissm.io.write_e57_poses(path, out, np.zeros((3, 3, 4)))
    bad = np.stack([np.eye(4)] * 3)
    bad[1, 0, 0] = 2.0
    with pytest.raises(kissm.InvalidArgumentError, match=r"^write_e57_poses: poses\[1\] is not a rigid transform"):
        kissm.io.write_e57_poses(path, out, bad)
    bad[1] = np.nan
    with pytest.raises(kissm.InvalidArgumentError, match=r"^write_e57_poses: poses\[1\] has a non-finite entry"):
        kissm.io.write_e57_poses(path, out, bad)
    with pytest.raises(kissm.InvalidArgumentError, match=r"^write_e57_poses: dst is src"):
        kissm.io.write_e57_poses(path, path, np.stack([np.eye(4)] * 3))
    assert not out.exists()
    with pytest.raises(kissm.IoError, match=r"No such file or directory$"):
        kissm.io.read_e57(tmp_path / "missing.e57")
    with pytest.raises(kissm.IoError, match=r"No such file or directory$"):
        kissm.io.write_e57_poses(tmp_path / "missing.e57", out, np.stack([np.eye(4)] * 3))
    junk = tmp_path / "junk.e57"
    junk.write_bytes(b"not an e57 file" * 100)
    with pytest.raises(kissm.ParseError, match=rf"^{junk}: E57: not an E57 file"):
        kissm.io.read_e57(junk)
    cut = tmp_path / "cut.e57"  # the signature, then a broken file (pye57 also writes libE57's report to stderr)
    cut.write_bytes(path.read_bytes()[:3000])
    with pytest.raises(kissm.ParseError, match=rf"^{cut}: E57: "):
        kissm.io.read_e57(cut)
    with pytest.raises(kissm.ParseError, match=rf"^{cut}: E57: "):
        kissm.io.write_e57_poses(cut, out, np.stack([np.eye(4)] * 3))
    assert not out.exists()


IMAGE_BYTES = bytes(range(256)) * 4096 + b"end"  # 1 MiB and 3 bytes: more than one chunk of the copy


def write_raw_e57(path: Path, x_raw: np.ndarray, y: np.ndarray, z: np.ndarray) -> None:
    """One scan built with libE57's nodes (pye57.libe57): x a scaled integer (scale 1e-4, offset 12.5), y and z
    double precision, no pose and no name (pye57's own writer stores single-precision floats only). ``x_raw`` is
    a longlong array: pye57 reads an int64 array's buffer format "l" as int32."""
    libe57 = pye57.libe57
    with pye57.E57(str(path), mode="w") as e57:
        image = e57.image_file
        scan = libe57.StructureNode(image)
        scan.set("guid", libe57.StringNode(image, "{raw-scan}"))
        prototype = libe57.StructureNode(image)
        prototype.set("cartesianX", libe57.ScaledIntegerNode(image, 0, -(10**13), 10**13, 1e-4, 12.5))
        prototype.set("cartesianY", libe57.FloatNode(image, 0.0, libe57.E57_DOUBLE, -1e6, 1e6))
        prototype.set("cartesianZ", libe57.FloatNode(image, 0.0, libe57.E57_DOUBLE, -1e6, 1e6))
        points = libe57.CompressedVectorNode(image, prototype, libe57.VectorNode(image, True))
        scan.set("points", points)
        e57.data3d.append(scan)
        buffers = libe57.VectorSourceDestBuffer()
        for field, values in (("cartesianX", x_raw), ("cartesianY", y), ("cartesianZ", z)):
            buffers.append(libe57.SourceDestBuffer(image, field, values, len(values), True, False))
        writer = points.writer(buffers)
        writer.write(len(x_raw))
        writer.close()
        # An image (a blob), as scanners store their photos: the copy must carry it too.
        image_node = libe57.StructureNode(image)
        image_node.set("name", libe57.StringNode(image, "photo"))
        blob = libe57.BlobNode(image, len(IMAGE_BYTES))
        image_node.set("jpegImage", blob)
        e57.root["images2D"].append(image_node)
        blob.write(np.frombuffer(IMAGE_BYTES, dtype=np.uint8).copy(), 0, len(IMAGE_BYTES))


def read_image(path: Path) -> bytes:
    with pye57.E57(str(path)) as e57:
        (image,) = list(e57.root["images2D"])
        return bytes(image["jpegImage"].read_buffer())


def read_raw_e57(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The stored values of write_raw_e57's scan: x's integers unscaled, y and z."""
    libe57 = pye57.libe57
    with pye57.E57(str(path)) as e57:
        points = e57.get_header(0).points
        n = points.childCount()
        x, y, z = np.empty(n, np.longlong), np.empty(n), np.empty(n)
        buffers = libe57.VectorSourceDestBuffer()
        for field, values in (("cartesianX", x), ("cartesianY", y), ("cartesianZ", z)):
            buffers.append(libe57.SourceDestBuffer(e57.image_file, field, values, n, True, False))
        reader = points.reader(buffers)
        assert reader.read() == n
        reader.close()
    return x, y, z


def test_scaled_integers_and_doubles_copied_exactly(tmp_path: Path) -> None:
    rng = np.random.default_rng(9)
    # Beyond 32 bits, where a 32-bit buffer would cut them.
    x_raw = rng.integers(-(10**12), 10**12, 1000).astype(np.longlong)
    y, z = rng.normal(0, 1e3, 1000), rng.normal(0, 1e3, 1000)
    path, out = tmp_path / "raw.e57", tmp_path / "raw_posed.e57"
    write_raw_e57(path, x_raw, y, z)
    (scan,) = kissm.io.read_e57(path)
    assert scan.name == "scan 0" and np.array_equal(scan.pose, np.eye(4))  # neither in the file
    assert np.array_equal(scan.points, np.stack([x_raw * 1e-4 + 12.5, y, z], axis=1))
    pose = np.eye(4)
    pose[:3, 3] = [1e6, -2e6, 30.0]
    kissm.io.write_e57_poses(path, out, pose[None])
    (copied,) = kissm.io.read_e57(out)
    assert np.array_equal(copied.pose, pose) and np.array_equal(copied.points, scan.points)
    for stored, written in zip(read_raw_e57(out), (x_raw, y, z), strict=True):
        assert stored.dtype == written.dtype and np.array_equal(stored, written)
    assert read_image(path) == read_image(out) == IMAGE_BYTES


# ---- three Happy Buddha scans with their ground truth --------------------------------------------------------


#: A site frame for the scans' poses (30 degrees about z, 1 km away): the turntable's own frame is nearly scan 0's,
#: which would hide a pose composed the wrong way round.
SITE = np.array(
    [
        [math.cos(math.pi / 6), -math.sin(math.pi / 6), 0.0, 1000.0],
        [math.sin(math.pi / 6), math.cos(math.pi / 6), 0.0, 2000.0],
        [0.0, 0.0, 1.0, 50.0],
        [0.0, 0.0, 0.0, 1.0],
    ]
)


def happy_scans(root: Path) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """Three Happy Buddha scans with their ground-truth poses in the site frame."""
    folder = root / HAPPY
    with open(folder / "scans.tsv", newline="") as f:
        files = {row["scan"]: (folder / row["file"], row["format"]) for row in csv.DictReader(f, delimiter="\t")}
    truth = {}
    for line in (folder / "gt_poses.txt").read_text().splitlines():
        name, *numbers = line.split()
        pose = np.eye(4)
        pose[:3, :] = np.array([float(v) for v in numbers]).reshape(3, 4)
        # The ground truth's rotations are orthonormal to the printed digits only: made exact (SVD) so that a
        # quaternion stores them.
        u, _, vt = np.linalg.svd(pose[:3, :3])
        pose[:3, :3] = u @ vt
        truth[name] = SITE @ pose
    return [(name, kissm.read_points(*files[name]), truth[name]) for name in HAPPY_SCANS]


def check_placed(alignment: kissm.multiway.Alignment, truth: list[np.ndarray], anchor: np.ndarray) -> None:
    """Each scan's world pose (the file's frame: the anchor's file pose times the alignment's) within 2 degrees
    and 2 voxels of the ground truth, test_multiway.py's bound for this set (measured: 0.43 and 0.82 degrees,
    0.8 and 1.3 mm; the poses composed the wrong way round are 12 and 24 degrees, 0.4 and 0.8 km off)."""
    assert alignment.placed.all()
    for k, pose in enumerate(alignment.poses):
        error = np.linalg.inv(truth[k]) @ (anchor @ pose)
        assert angle_deg(error[:3, :3]) < 2.0 and np.linalg.norm(error[:3, 3]) < 2 * HAPPY_VOXEL, (
            k,
            angle_deg(error[:3, :3]),
            np.linalg.norm(error[:3, 3]),
        )


@pytest.fixture(scope="module")
def happy_e57(
    real_data: Path, tmp_path_factory: pytest.TempPathFactory
) -> tuple[Path, list[tuple[str, np.ndarray, np.ndarray]]]:
    scans = happy_scans(real_data)
    path = tmp_path_factory.mktemp("e57") / "happy.e57"
    write_e57(path, scans)
    return path, scans


def test_happy_e57_reads_back(happy_e57: tuple[Path, list[tuple[str, np.ndarray, np.ndarray]]]) -> None:
    path, scans = happy_e57
    got = kissm.io.read_e57(path)
    assert [s.name for s in got] == list(HAPPY_SCANS)
    for scan, (_, points, pose) in zip(got, scans, strict=True):
        assert np.array_equal(scan.points, float32_exact(points))
        assert np.max(np.abs(scan.pose - pose)) < 1e-12


@pytest.mark.parametrize("use_priors", [True, False], ids=["from_file_poses", "ignoring_file_poses"])
def test_happy_e57_aligns_and_writes_back(
    happy_e57: tuple[Path, list[tuple[str, np.ndarray, np.ndarray]]], tmp_path: Path, use_priors: bool
) -> None:
    """From the file's poses (priors, pairs="sequence": the consecutive scans, then the loop 0-48 the priors
    propose) or ignoring them (every pair, no initial guess): every scan placed right, and the poses written back
    into a copy of the file read back as written."""
    path, scans = happy_e57
    truth = [pose for _, _, pose in scans]
    read = kissm.io.read_e57(path)
    clouds = [scan.points for scan in read]
    if use_priors:
        priors = np.stack([scan.pose for scan in read])
        alignment = kissm.multiway.align(
            clouds, HAPPY_VOXEL, pairs="sequence", priors=priors, loop_gap=2, threads_per_job=2
        )
        assert alignment.registrations == 3  # 24->0, 48->24 and the loop 48->0 the priors put within reach
    else:
        alignment = kissm.multiway.align(clouds, HAPPY_VOXEL, threads_per_job=2)
        assert alignment.registrations == 3
    anchor = read[0].pose  # the alignment's world is scan 0's frame; the file's world is scan 0's pose away
    check_placed(alignment, truth, anchor)
    world = anchor @ alignment.poses
    out = tmp_path / "aligned.e57"
    kissm.io.write_e57_poses(path, out, world)
    back = kissm.io.read_e57(out)
    for k, scan in enumerate(back):
        assert np.max(np.abs(scan.pose - world[k])) < 1e-12  # through a quaternion
        assert np.array_equal(scan.points, read[k].points)
