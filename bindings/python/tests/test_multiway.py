# SPDX-License-Identifier: MIT
"""kissm.multiway.align: many clouds into the first one's frame. The shared multi-scan sets (../shared/data,
"Multi-scan sets": the KITTI 07 keyframes, the Stanford bunny's 9 scans, the 15 Happy Buddha turntable scans),
every pair registered: every scan placed, each within 2 degrees and 2 voxels of the ground truth anchored on the
first scan, also with wrong edges injected into their graphs; the ordered sets as a sequence; a synthetic set from
the committed test pair with a scan that cannot be placed; the writers' formats read back; errors."""

from __future__ import annotations

import csv
import inspect
import math
import struct
import subprocess
from pathlib import Path

import numpy as np
import pytest

import kissm
import kissm.multiway
from kissm._candidates import corroborated, loop_candidates, similar_candidates

from testdata import VOXEL_SIZE, committed_pair

#: (folder under the data, voxel): the voxels of bench/kissm_bench/data.py's SCAN_SETS.
SETS = {
    "kitti07": ("kitti07_keyframes_gtsam_points/multiway", 0.5),
    "bunny": ("stanford_bunny_scans/multiway", 0.006),
    "happy": ("stanford_happy_stand_scans", 0.004),
}


def angle_deg(rotation: np.ndarray) -> float:
    return math.degrees(math.acos(max(-1.0, min(1.0, (float(np.trace(rotation)) - 1.0) / 2.0))))


def read_set(folder: Path) -> tuple[list[str], list[kissm.batch.CloudFile], dict[str, np.ndarray]]:
    with open(folder / "scans.tsv", newline="") as f:
        rows = list(csv.DictReader(f, delimiter="\t"))
    poses = {}
    for line in (folder / "gt_poses.txt").read_text().splitlines():
        if line.strip():
            name, *numbers = line.split()
            pose = np.eye(4)
            pose[:3, :] = np.array([float(x) for x in numbers]).reshape(3, 4)
            poses[name] = pose
    names = [r["scan"] for r in rows]
    return names, [kissm.batch.CloudFile(str(folder / r["file"]), r["format"]) for r in rows], poses


ALIGNMENTS: dict[str, tuple[list[str], dict[str, np.ndarray], kissm.multiway.Alignment]] = {}


def aligned(real_data: Path, name: str) -> tuple[list[str], dict[str, np.ndarray], kissm.multiway.Alignment]:
    """A shared set aligned once per session (every pair, GICP), with its scan names and ground truth."""
    if name not in ALIGNMENTS:
        folder, voxel = SETS[name]
        if not (real_data / folder / "scans.tsv").is_file():
            pytest.fail(f"the multi-scan set {folder} is missing from {real_data}")
        names, files, truth = read_set(real_data / folder)
        alignment = kissm.multiway.align(dict(zip(names, files, strict=True)), voxel, threads_per_job=2)
        ALIGNMENTS[name] = names, truth, alignment
    return ALIGNMENTS[name]


@pytest.mark.parametrize("name", list(SETS))
def test_every_scan_of_the_shared_sets_is_placed_right(real_data: Path, name: str) -> None:
    voxel = SETS[name][1]
    names, truth, alignment = aligned(real_data, name)
    assert alignment.keys == names and alignment.registrations == len(names) * (len(names) - 1) // 2
    missing = [n for n, placed in zip(names, alignment.placed, strict=True) if not placed]
    assert alignment.placed.all(), f"not placed: {missing}"
    for k, scan in enumerate(names):
        expected = np.linalg.inv(truth[names[0]]) @ truth[scan]
        error = np.linalg.inv(expected) @ alignment.poses[k]
        assert angle_deg(error[:3, :3]) < 2.0 and np.linalg.norm(error[:3, 3]) < 2 * voxel, (
            scan,
            angle_deg(error[:3, :3]),
            np.linalg.norm(error[:3, 3]) / voxel,
        )
    assert np.array_equal(alignment.poses[0], np.eye(4))
    assert all(e.result.valid for e in alignment.edges)


def random_rigid(rng: np.random.Generator, scale: float) -> np.ndarray:
    """A random pose: a rotation of 0.2 to pi radians about a random axis, a translation of `scale` per axis."""
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    angle = rng.uniform(0.2, math.pi)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    pose = np.eye(4)
    pose[:3, :3] = np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k
    pose[:3, 3] = rng.normal(0, scale, 3)
    return pose


@pytest.mark.parametrize("name", list(SETS))
def test_injected_wrong_edges_are_rejected_on_the_shared_sets(real_data: Path, name: str) -> None:
    """Issue 34's target: wrong edges, 30% as many as the set's registrations, random poses (50 voxels of
    translation) with a real edge's confident information, between random scans: all rejected, and every pose
    within 0.1 degree and 0.1 voxel of the graph without them, in each of 10 draws."""
    voxel = SETS[name][1]
    names, _, alignment = aligned(real_data, name)
    n, real = len(names), [e for e in alignment.edges if e.accepted]
    with kissm.PoseGraph(n) as clean:
        for e in real:
            clean.add_edge(e.source, e.target, e.transform, e.information)
        reference = clean.optimize()
    count = max(2, round(0.3 * len(alignment.edges)))
    for draw in range(10):
        rng = np.random.default_rng(draw)
        with kissm.PoseGraph(n) as dirty:
            for e in real:
                dirty.add_edge(e.source, e.target, e.transform, e.information)
            for k in range(count):
                source, target = (int(v) for v in rng.choice(n, size=2, replace=False))
                dirty.add_edge(source, target, random_rigid(rng, 50 * voxel), real[k % len(real)].information)
            solution = dirty.optimize()
        assert not np.asarray(solution.accepted[len(real) :]).any(), (draw, solution.accepted)
        assert np.asarray(solution.accepted[: len(real)]).all(), (draw, solution.accepted)
        for k in range(n):
            difference = np.linalg.inv(reference.poses[k]) @ solution.poses[k]
            assert solution.placed[k]
            assert angle_deg(difference[:3, :3]) < 0.1 and np.linalg.norm(difference[:3, 3]) < 0.1 * voxel, (draw, k)


def synthetic_set() -> tuple[list[np.ndarray], list[np.ndarray]]:
    """The committed pair's source seen from three poses (crops of it, so that each pair overlaps in part) and an
    unrelated cloud: the clouds and each one's true world <- scan pose."""
    pair = committed_pair()
    scene = np.asarray(pair.source, dtype=np.float64)
    rng = np.random.default_rng(5)
    clouds, poses = [], []
    center = scene.mean(axis=0)
    for k in range(3):
        angle = 0.4 * k
        c, s = math.cos(angle), math.sin(angle)
        pose = np.eye(4)
        pose[:3, :3] = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
        pose[:3, 3] = [1.5 * k, -0.7 * k, 0.1 * k]
        keep = scene[:, 0] - center[0] < 6.0 - 3.0 * k  # a crop: the scans share most but not all of the scene
        world = scene[keep]
        clouds.append((world - pose[:3, 3]) @ pose[:3, :3])  # scan = inv(pose) world
        poses.append(pose)
    clouds.append(rng.uniform(-20, 20, size=(3000, 3)))  # unrelated: no valid edge reaches it
    return clouds, poses


def test_a_synthetic_set_and_a_scan_that_cannot_be_placed(tmp_path: Path) -> None:
    clouds, poses = synthetic_set()
    alignment = kissm.multiway.align(clouds, VOXEL_SIZE)
    assert alignment.keys == [0, 1, 2, 3] and alignment.registrations == 6
    assert alignment.placed.tolist() == [True, True, True, False]
    assert np.isnan(alignment.poses[3]).all() and alignment.components[3] == 3
    for k in range(3):
        expected = np.linalg.inv(poses[0]) @ poses[k]
        error = np.linalg.inv(expected) @ alignment.poses[k]
        assert angle_deg(error[:3, :3]) < 1.0 and np.linalg.norm(error[:3, 3]) < VOXEL_SIZE
    # the merged map: the placed scans' points in the first one's frame
    merged = alignment.merged(clouds)
    assert merged.shape == (sum(len(c) for c in clouds[:3]), 3)
    thinned = alignment.merged(clouds, voxel_size=1.0)
    assert 0 < len(thinned) < len(merged)
    # the same call again gives the same bits; so does a thread pool
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(2) as pool:
        again = kissm.multiway.align(clouds, VOXEL_SIZE, executor=pool)
    assert again.poses.tobytes() == alignment.poses.tobytes()

    # the writers, read back
    alignment.write_kitti(tmp_path / "poses.kitti")
    rows = np.loadtxt(tmp_path / "poses.kitti")
    assert rows.shape == (4, 12) and np.isnan(rows[3]).all()
    assert np.allclose(rows[1].reshape(3, 4), alignment.poses[1][:3, :], atol=1e-15)
    alignment.write_tum(tmp_path / "poses.tum", timestamps=[10.0, 11.0, 12.0, 13.0])
    tum = np.loadtxt(tmp_path / "poses.tum")
    assert tum.shape == (3, 8) and tum[:, 0].tolist() == [10.0, 11.0, 12.0]
    for row, pose in zip(tum, alignment.poses[:3], strict=True):
        x, y, z, w = row[4:]
        rotation = np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
            ]
        )
        assert np.allclose(rotation, pose[:3, :3], atol=1e-12) and np.allclose(row[1:4], pose[:3, 3])
    alignment.write_g2o(tmp_path / "graph.g2o")
    lines = (tmp_path / "graph.g2o").read_text().splitlines()
    vertices = [line for line in lines if line.startswith("VERTEX_SE3:QUAT")]
    edges = [line.split() for line in lines if line.startswith("EDGE_SE3:QUAT")]
    assert [int(v.split()[1]) for v in vertices] == [0, 1, 2]
    assert len(edges) == sum(e.accepted for e in alignment.edges) and all(len(e) == 3 + 7 + 21 for e in edges)
    first = next(e for e in alignment.edges if e.accepted)
    fields = next(f for f in edges if (int(f[1]), int(f[2])) == (first.target, first.source))
    upper = np.array([float(v) for v in fields[10:]])
    info = np.zeros((6, 6))
    info[np.triu_indices(6)] = upper
    info = info + np.triu(info, 1).T
    # translation block as it is, rotation block four times ours (g2o's quaternion vector part is half the angle)
    assert np.allclose(info[:3, :3], first.information[3:, 3:]) and np.allclose(
        info[3:, 3:], 4 * first.information[:3, :3]
    )


@pytest.mark.parametrize(("name", "gap", "per_scan"), [("kitti07", 2, 5), ("happy", 5, 10)])
def test_sequence_places_the_ordered_sets(real_data: Path, name: str, gap: int, per_scan: int) -> None:
    """pairs="sequence": consecutive pairs, then loop candidates from the chained odometry. KITTI's keyframes and
    Happy's turntable (whose last scan, at 336 degrees, closes the loop onto the first) are in acquisition order:
    every scan placed within 2 degrees and 2 voxels, with a fraction of the pairs of "all"."""
    folder, voxel = SETS[name]
    names, files, truth = read_set(real_data / folder)
    alignment = kissm.multiway.align(
        dict(zip(names, files, strict=True)),
        voxel,
        pairs="sequence",
        loop_gap=gap,
        loops_per_scan=per_scan,
        threads_per_job=2,
    )
    n = len(names)
    assert n - 1 < alignment.registrations < n * (n - 1) // 2
    assert alignment.placed.all()
    loops = [(e.source, e.target) for e in alignment.edges if e.source - e.target >= gap]
    assert loops and all(e.accepted for e in alignment.edges)
    for k, scan in enumerate(names):
        expected = np.linalg.inv(truth[names[0]]) @ truth[scan]
        error = np.linalg.inv(expected) @ alignment.poses[k]
        assert angle_deg(error[:3, :3]) < 2.0 and np.linalg.norm(error[:3, 3]) < 2 * voxel, scan
    if name == "happy":
        assert (n - 1, 0) in loops  # the closure


def test_sequence_loop_candidates_from_priors() -> None:
    """With priors, loop candidates are the pairs at least loop_gap apart within loop_radius, the nearest
    loops_per_scan per cloud; NaN priors get none."""
    positions = np.array([[0.0, 0, 0], [10, 0, 0], [20, 0, 0], [10.5, 0, 0], [0.2, 0, 0], [np.nan, 0, 0]])
    pairs = loop_candidates(positions, 1.0, 2, 5, drift=0.0)
    assert pairs == [(1, 3), (0, 4)]
    assert loop_candidates(positions, 100.0, 2, 1, drift=0.0) == [(0, 2), (1, 3), (0, 4)]
    assert loop_candidates(positions, 100.0, 4, 5, drift=0.0) == [(0, 4)]


def padded(rows: list[list[float]]) -> np.ndarray:
    """Signatures of a few numbers, padded with zeros to KISSM_SIGNATURE_SIZE (the same distances)."""
    out = np.zeros((len(rows), int(kissm._ffi.lib.KISSM_SIGNATURE_SIZE)))
    out[:, : len(rows[0])] = rows
    return out


def test_similar_candidates() -> None:
    """The per_scan nearest signatures at least gap back in other pieces of the chain, ties to the lower scan; a NaN
    row is nobody's candidate; an unbroken chain gives none (the library's kissm_sequence_similar)."""
    signatures = padded([[0.0, 0], [1, 0], [0, 1], [1, 0], [np.nan, np.nan], [0.1, 0]])
    apart = np.zeros(5, dtype=np.uint8)  # every step broken: each scan a piece of its own
    assert similar_candidates(signatures, 2, 1, apart) == [(0, 2), (1, 3), (0, 5)]
    assert similar_candidates(signatures, 2, 2, apart) == [(0, 2), (0, 3), (1, 3), (0, 5), (1, 5)]  # 1 and 3 tie
    assert similar_candidates(signatures, 2, 0, apart) == []
    assert similar_candidates(signatures, 5, 3, apart) == [(0, 5)]
    assert similar_candidates(signatures, 2, 3, np.ones(5, dtype=np.uint8)) == []  # one piece
    broken = np.array([1, 1, 0, 1, 1], dtype=np.uint8)  # pieces 0, 0, 0, 1, 1, 1
    assert similar_candidates(signatures, 2, 1, broken) == [(1, 3), (0, 5)]
    assert similar_candidates(signatures, 1, 9, broken) == [(0, 3), (1, 3), (2, 3), (0, 5), (1, 5), (2, 5)]
    with pytest.raises(kissm.InvalidArgumentError, match="gap"):
        similar_candidates(signatures, 0, 1, broken)


def test_registrations_between_pieces_are_kept_when_the_most_agree() -> None:
    """Of the registrations between two pieces, those agreeing with the one most others agree with are kept: three
    that put the later piece at its true place beat two that agree on a wrong one; a lone one is not kept; one
    within a piece always is (the library's kissm_sequence_corroborated)."""
    poses = np.tile(np.eye(4), (10, 1, 1))
    poses[:, 0, 3] = [0, 1, 2, 3, 0, 1, 2, 3, 0, 1]  # along x in each piece's frame
    step = np.eye(4)
    step[0, 3] = 1.0
    steps = np.tile(step, (9, 1, 1))
    valid = np.array([1, 1, 1, 0, 1, 1, 1, 0, 1], dtype=np.uint8)  # pieces 0-3, 4-7, 8-9
    chain = (steps, valid)

    def registration(i: int, j: int, offset: list[float]) -> tuple[int, int, np.ndarray]:
        frame = np.eye(4)
        frame[:3, 3] = offset  # the later piece's frame in the earlier one's
        return i, j, np.linalg.inv(poses[i]) @ frame @ poses[j]

    right, wrong = [0.0, 50.0, 0.0], [500.0, 0.0, 0.0]
    edges = [registration(0, 4, right), registration(1, 5, right), registration(2, 6, right)]
    edges += [registration(3, 7, wrong), registration(0, 5, wrong), registration(1, 8, right)]
    edges += [registration(0, 2, wrong)]  # within a piece: the odometry's business, not this check's
    assert corroborated(edges, chain, 1.0) == [True, True, True, False, False, False, True]
    # Two registrations of one later cloud do not corroborate each other.
    assert corroborated([registration(0, 4, right), registration(1, 4, right)], chain, 1.0) == [False, False]
    assert corroborated([], chain, 1.0) == []
    with pytest.raises(kissm.InvalidArgumentError, match="radius"):
        corroborated(edges, chain, 0.0)


def numpy_corroborated(
    edges: list[tuple[int, int, np.ndarray]], poses: np.ndarray, path: np.ndarray, piece: np.ndarray, radius: float
) -> list[bool]:
    """The agreement rule written independently in numpy (general inverse, numpy's sums): the oracle below."""
    out = [piece[i] == piece[j] for i, j, _ in edges]
    groups: dict[tuple[int, int], list[int]] = {}
    for k, (i, j, _) in enumerate(edges):
        if piece[i] != piece[j]:
            groups.setdefault((int(piece[i]), int(piece[j])), []).append(k)
    for members in groups.values():
        i = np.array([edges[k][0] for k in members])
        j = np.array([edges[k][1] for k in members])
        placed = np.array([poses[edges[k][0]] @ edges[k][2] for k in members])
        agree = np.zeros((len(members), len(members)), dtype=bool)
        for a in range(len(members)):
            relay = placed[a] @ np.linalg.inv(poses[j[a]])
            predicted = poses[j][:, :3, 3] @ relay[:3, :3].T + relay[:3, 3]
            error = np.linalg.norm(predicted - placed[:, :3, 3], axis=1)
            allowed = radius + 0.02 * (np.abs(path[i] - path[i[a]]) + np.abs(path[j] - path[j[a]]))
            agree[a] = (j != j[a]) & (error <= allowed)
        best = int(np.argmax(agree.sum(axis=1)))
        if agree[best].any():
            for a in [*np.flatnonzero(agree[best]).tolist(), best]:
                out[members[a]] = True
    return [bool(x) for x in out]


def test_the_library_rules_agree_with_numpy() -> None:
    """kissm_sequence_corroborated and kissm_sequence_similar against the rules written in numpy, on random broken
    chains: registrations between pieces, most of a piece's true frame with noise from 0.01 to 1 radius, the rest
    wrong; random signatures with a missing one. Every flag and every candidate list the same."""
    rng = np.random.default_rng(0)

    def rigid(scale: float) -> np.ndarray:
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
        angle = rng.uniform(-0.3, 0.3)
        pose = np.eye(4)
        pose[:3, :3] = np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k
        pose[:3, 3] = rng.normal(size=3) * scale
        return pose

    flags = 0
    for _ in range(60):
        n = 40
        valid = (rng.uniform(size=n - 1) > 0.1).astype(np.uint8)
        steps = np.array([rigid(2.0) for _ in range(n - 1)])
        poses, path, piece = np.tile(np.eye(4), (n, 1, 1)), np.zeros(n), np.zeros(n, dtype=np.int64)
        for k in range(n - 1):
            poses[k + 1] = poses[k] @ steps[k] if valid[k] else np.eye(4)
            path[k + 1] = path[k] + float(np.linalg.norm(steps[k][:3, 3])) if valid[k] else 0.0
            piece[k + 1] = piece[k] + (0 if valid[k] else 1)
        frames: dict[tuple[int, int], np.ndarray] = {}
        edges = []
        for _ in range(30):
            i, j = sorted(int(v) for v in rng.choice(n, 2, replace=False))
            frame = frames.setdefault((int(piece[i]), int(piece[j])), rigid(20.0))
            transform = np.linalg.inv(poses[i]) @ (frame if rng.uniform() < 0.7 else rigid(20.0)) @ poses[j]
            transform[:3, 3] += rng.normal(size=3) * rng.choice([0.01, 0.3, 1.0])
            edges.append((i, j, transform))
        assert corroborated(edges, (steps, valid), 1.0) == numpy_corroborated(edges, poses, path, piece, 1.0)
        flags += len(edges)
        signatures = rng.normal(size=(n, 82))
        signatures[rng.integers(n)] = np.nan
        expected = []
        for j in range(3, n):
            distance = np.sum((signatures[: j - 2] - signatures[j]) ** 2, axis=1)
            near = [i for i in range(j - 2) if piece[i] != piece[j] and np.isfinite(distance[i])]
            expected += [(i, j) for i in sorted(sorted(near, key=lambda i: (distance[i], i))[:3])]
        assert similar_candidates(signatures, 3, 3, valid) == expected
    assert flags == 60 * 30


def moved_view(cloud: np.ndarray, angle: float, shift: list[float]) -> tuple[np.ndarray, np.ndarray]:
    """The cloud as seen from another frame: the points in it and that frame's pose in the cloud's."""
    c, s = math.cos(angle), math.sin(angle)
    move = np.eye(4)
    move[:3, :3] = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
    move[:3, 3] = shift
    return (cloud - move[:3, 3]) @ move[:3, :3], move


def broken_sequence() -> tuple[list[np.ndarray], list[np.ndarray | None]]:
    """A sequence that sees a place, loses it (two unrelated clouds: the chain breaks twice, as for a robot
    kidnapped or a sensor blinded) and comes back: the clouds and their true poses (None for the unrelated)."""
    clouds, poses = synthetic_set()
    rng = np.random.default_rng(11)
    back, move = moved_view(clouds[1], 2.0, [3.0, -4.0, 0.5])
    sequence = [clouds[0], clouds[1], rng.uniform(-20, 20, (3000, 3)), rng.uniform(-30, 30, (3000, 3)), clouds[2], back]
    return sequence, [poses[0], poses[1], None, None, poses[2], poses[1] @ move]


def test_a_broken_chain_closes_its_loop_by_similarity() -> None:
    """broken_sequence(): the odometry cannot relate the pieces, the clouds' similarity can. With
    similar_per_scan=1 the later piece is placed right through the earlier scans it resembles (not the unrelated
    clouds); with 0, as before, it is not placed."""
    sequence, truth = broken_sequence()
    found = kissm.multiway.align(sequence, VOXEL_SIZE, pairs="sequence", loop_gap=2, similar_per_scan=1)
    assert found.placed.tolist() == [True, True, False, False, True, True]
    valid = {(e.source, e.target) for e in found.edges}
    assert (2, 1) not in valid and (3, 2) not in valid and (4, 3) not in valid  # the breaks
    assert found.registrations == 5 + 4  # the consecutive pairs, then one similar earlier scan for 2, 3, 4 and 5
    assert {(4, 0), (4, 1)} & valid and {(5, 0), (5, 1)} & valid  # the place seen again, not the unrelated clouds
    for k in (1, 4, 5):
        expected = np.linalg.inv(truth[0]) @ truth[k]
        error = np.linalg.inv(expected) @ found.poses[k]
        assert angle_deg(error[:3, :3]) < 1.0 and np.linalg.norm(error[:3, 3]) < VOXEL_SIZE, k
    before = kissm.multiway.align(sequence, VOXEL_SIZE, pairs="sequence", loop_gap=2, similar_per_scan=0)
    assert before.placed.tolist() == [True, True, False, False, False, False] and before.registrations == 5


def test_the_cli_gives_the_same_bytes_for_a_broken_chain(cli: Path, tmp_path: Path) -> None:
    """`kissm align --pairs sequence` on broken_sequence() written as files takes the candidates by similarity and
    holds out the uncorroborated pairs as Python does: its KITTI and g2o files are Python's bytes, at 2 jobs and
    after a resume from the first round's records; --similar-per-scan 0 leaves the later piece unplaced."""
    sequence, _ = broken_sequence()
    files = []
    for k, cloud in enumerate(sequence):
        files.append(tmp_path / f"s{k}.npy")
        np.save(files[-1], cloud)
    scans = tmp_path / "scans.tsv"
    scans.write_text("scan\tfile\n" + "".join(f"s{k}\t{f.name}\n" for k, f in enumerate(files)))
    python = kissm.multiway.align(
        {f"s{k}": kissm.batch.CloudFile(str(f)) for k, f in enumerate(files)}, VOXEL_SIZE, pairs="sequence", loop_gap=2
    )
    assert python.placed.tolist() == [True, True, False, False, True, True]
    python.write_kitti(tmp_path / "python.kitti")
    python.write_g2o(tmp_path / "python.g2o")

    def run(out: str, *more: str) -> subprocess.CompletedProcess[str]:
        command = [str(cli), "align", str(scans), "--voxel", repr(VOXEL_SIZE), "--out", str(tmp_path / out)]
        command += ["--pairs", "sequence", "--loop-gap", "2", "--kitti", str(tmp_path / f"{out}.kitti")]
        command += ["--g2o", str(tmp_path / f"{out}.g2o"), "-q", *more]
        return subprocess.run(command, capture_output=True, text=True, check=False)

    done = run("cli.tsv", "--jobs", "2")
    assert done.returncode == 1, done.stderr  # two scans not placed
    assert (tmp_path / "cli.tsv.kitti").read_bytes() == (tmp_path / "python.kitti").read_bytes()
    assert (tmp_path / "cli.tsv.g2o").read_bytes() == (tmp_path / "python.g2o").read_bytes()
    results = (tmp_path / "cli.tsv.pairs.jsonl").read_text().splitlines()
    assert len(results) == python.registrations
    # Killed after the first round (its 5 consecutive pairs): the resumed run finds the same candidates.
    first = [line for line in results if int(line.split('"pair":')[1].split(",")[0]) <= 5]
    (tmp_path / "again.tsv.pairs.jsonl").write_text("".join(line + "\n" for line in first))
    resumed = run("again.tsv", "--resume")
    assert resumed.returncode == 1, resumed.stderr
    assert (tmp_path / "again.tsv.kitti").read_bytes() == (tmp_path / "python.kitti").read_bytes()
    off = run("off.tsv", "--similar-per-scan", "0")
    assert off.returncode == 1 and len((tmp_path / "off.tsv.pairs.jsonl").read_text().splitlines()) == 5
    assert "nan" in (tmp_path / "off.tsv.kitti").read_text().splitlines()[4]
    usage = run("bad.tsv", "--similar-per-scan", "-1")
    assert usage.returncode == 2 and "--similar-per-scan" in usage.stderr


def test_the_cli_takes_voxel_auto_as_python_does(cli: Path, tmp_path: Path) -> None:
    """`kissm align --voxel auto` uses one voxel for every scan, the suggestion of them together, as
    kissm.multiway.align(..., "auto") does: the same KITTI bytes, every scan placed right."""
    clouds, truth = synthetic_set()
    clouds, truth = clouds[:3], truth[:3]  # the three views of one scene, not the unrelated cloud
    files = []
    for k, cloud in enumerate(clouds):
        files.append(tmp_path / f"c{k}.npy")
        np.save(files[-1], cloud)
    (tmp_path / "scans.tsv").write_text("scan\tfile\n" + "".join(f"c{k}\t{f.name}\n" for k, f in enumerate(files)))
    python = kissm.multiway.align({f"c{k}": kissm.batch.CloudFile(str(f)) for k, f in enumerate(files)}, "auto")
    python.write_kitti(tmp_path / "python.kitti")
    assert python.placed.all()
    for k in range(len(clouds)):
        expected = np.linalg.inv(truth[0]) @ truth[k]
        error = np.linalg.inv(expected) @ python.poses[k]
        assert angle_deg(error[:3, :3]) < 2.0, k
    command = [str(cli), "align", str(tmp_path / "scans.tsv"), "--voxel", "auto", "--out", str(tmp_path / "cli.tsv")]
    done = subprocess.run([*command, "--kitti", str(tmp_path / "cli.kitti"), "-q"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "cli.kitti").read_bytes() == (tmp_path / "python.kitti").read_bytes()


def test_bad_arguments() -> None:
    clouds, _ = synthetic_set()
    with pytest.raises(kissm.InvalidArgumentError, match="pairs"):
        kissm.multiway.align(clouds[:2], VOXEL_SIZE, pairs="sequential")
    with pytest.raises(kissm.InvalidArgumentError, match="priors"):
        kissm.multiway.align(clouds[:2], VOXEL_SIZE, priors=np.zeros((2, 4, 4)))  # read by "sequence" only
    with pytest.raises(kissm.InvalidArgumentError, match="priors"):
        kissm.multiway.align(clouds[:2], VOXEL_SIZE, pairs="sequence", priors=np.zeros((3, 4, 4)))
    with pytest.raises(kissm.InvalidArgumentError, match="loop_gap"):
        kissm.multiway.align(clouds[:2], VOXEL_SIZE, pairs="sequence", loop_gap=0)
    with pytest.raises(kissm.InvalidArgumentError, match="loop_radius"):
        kissm.multiway.align(clouds[:2], VOXEL_SIZE, pairs="sequence", loop_radius=float("nan"))
    with pytest.raises(kissm.InvalidArgumentError, match="loops_per_scan"):
        kissm.multiway.align(clouds[:2], VOXEL_SIZE, pairs="sequence", loops_per_scan=-1)
    for bad in (-1, 1.5, True, 1_000_001):
        with pytest.raises(kissm.InvalidArgumentError, match="similar_per_scan"):
            kissm.multiway.align(clouds[:2], VOXEL_SIZE, pairs="sequence", similar_per_scan=bad)
    with pytest.raises(kissm.InvalidArgumentError, match="pair"):
        kissm.multiway.align(clouds[:2], VOXEL_SIZE, pairs=[(0, 5)])
    with pytest.raises(kissm.InvalidArgumentError, match="empty"):
        kissm.multiway.align([], VOXEL_SIZE)
    with pytest.raises(kissm.InvalidArgumentError, match="voxel_size"):
        kissm.multiway.align(clouds[:2], -1.0)
    one = kissm.multiway.align(clouds[:1], VOXEL_SIZE)  # one cloud: itself, nothing registered
    assert one.placed.tolist() == [True] and one.registrations == 0 and np.array_equal(one.poses[0], np.eye(4))
    with pytest.raises(kissm.InvalidArgumentError, match="voxel_size"):
        one.merged(clouds[:1], voxel_size=0.0)


def test_two_sessions_merge_into_one_frame(real_data: Path) -> None:
    """Happy's turntable as two sessions, the even scans (48 degrees apart) and the odd ones: each session's
    odometry trusted, the sessions found each other through the coarse grid and the nearby candidates; every scan
    of both placed within 2 degrees and 2 voxels in the frame of the first session's first scan."""
    folder, voxel = SETS["happy"]
    names, files, truth = read_set(real_data / folder)
    even = {n: f for k, (n, f) in enumerate(zip(names, files, strict=True)) if k % 2 == 0}
    odd = {n: f for k, (n, f) in enumerate(zip(names, files, strict=True)) if k % 2 == 1}
    alignment = kissm.multiway.align_sessions([even, odd], voxel, stride=3, loop_gap=3, threads_per_job=2)
    assert alignment.keys == [(0, n) for n in even] + [(1, n) for n in odd]
    assert alignment.placed.all()
    across = [e for e in alignment.edges if alignment.keys[e.source][0] != alignment.keys[e.target][0]]
    assert across and any(e.accepted for e in across)
    anchor = truth[alignment.keys[0][1]]
    for k, (_, scan) in enumerate(alignment.keys):
        error = np.linalg.inv(np.linalg.inv(anchor) @ truth[scan]) @ alignment.poses[k]
        assert angle_deg(error[:3, :3]) < 2.0 and np.linalg.norm(error[:3, 3]) < 2 * voxel, scan
    merged = alignment.merged(kissm.multiway.session_clouds([even, odd]), voxel_size=voxel)
    assert merged.shape[1] == 3 and len(merged) > 1000
    with pytest.raises(kissm.InvalidArgumentError, match="stride"):
        kissm.multiway.align_sessions([even, odd], voxel, stride=0)
    with pytest.raises(kissm.InvalidArgumentError, match="sessions"):
        kissm.multiway.align_sessions([], voxel)


def test_sessions_that_cannot_be_placed_are_not() -> None:
    """A later session of unrelated clouds is not placed (NaN poses, its own component), and the first session's
    poses are right; a session whose first cloud meets the first session is placed up to its unrelated cloud."""
    clouds, poses = synthetic_set()
    rng = np.random.default_rng(9)
    noise = [rng.uniform(-20, 20, size=(3000, 3)) for _ in range(2)]
    alignment = kissm.multiway.align_sessions([clouds[:3], noise], VOXEL_SIZE, stride=1, loop_gap=2)
    assert alignment.keys == [(0, 0), (0, 1), (0, 2), (1, 0), (1, 1)]
    assert alignment.placed.tolist() == [True, True, True, False, False]
    assert np.isnan(alignment.poses[3:]).all() and set(alignment.components[3:].tolist()) <= {3, 4}
    for k in range(3):
        expected = np.linalg.inv(poses[0]) @ poses[k]
        error = np.linalg.inv(expected) @ alignment.poses[k]
        assert angle_deg(error[:3, :3]) < 1.0 and np.linalg.norm(error[:3, 3]) < VOXEL_SIZE
    mixed = kissm.multiway.align_sessions([clouds[:2], clouds[2:]], VOXEL_SIZE, stride=1, loop_gap=2)
    assert mixed.placed.tolist() == [True, True, True, False]
    expected = np.linalg.inv(poses[0]) @ poses[2]
    error = np.linalg.inv(expected) @ mixed.poses[2]
    assert angle_deg(error[:3, :3]) < 1.0 and np.linalg.norm(error[:3, 3]) < VOXEL_SIZE


@pytest.mark.parametrize(
    ("name", "pairs", "gap", "per_scan"),
    [
        ("kitti07", "all", 10, 5),
        ("happy", "sequence", 5, 10),
        ("happy", "sessions", 3, 5),
        ("broken", "sequence", 2, 5),
        ("happy-broken", "sequence", 3, 5),
    ],
)
def test_the_c_job_gives_the_same_bits(real_data: Path, name: str, pairs: str, gap: int, per_scan: int) -> None:
    """kissm_align_features (the whole job in one C call, as C and Rust users run it) on features computed here
    gives the poses, registrations, accepted edges and residuals of kissm.multiway.align (or align_sessions, Happy's
    even and odd scans as two sessions), bit for bit. Two sequences whose chain breaks take loop candidates by
    similarity and hold out the registrations between pieces that others do not corroborate, in both (the default
    similar_per_scan): broken_sequence(), and Happy's turntable without the scans from 72 to 168 degrees."""
    from kissm._ffi import ffi, lib

    broken = name in ("broken", "happy-broken")
    if name == "broken":
        voxel = VOXEL_SIZE
        sequence, _ = broken_sequence()
        names, files = [str(k) for k in range(len(sequence))], sequence
    else:
        folder, voxel = SETS[name.removesuffix("-broken")]
        names, files, _ = read_set(real_data / folder)
        if broken:
            kept = [k for k in range(len(names)) if not 3 <= k <= 7]
            names, files = [names[k] for k in kept], [files[k] for k in kept]
    sessions: list[int] = []
    if pairs == "sessions":
        order = list(range(0, len(files), 2)) + list(range(1, len(files), 2))
        even = {names[k]: files[k] for k in order[: (len(files) + 1) // 2]}
        odd = {names[k]: files[k] for k in order[(len(files) + 1) // 2 :]}
        python = kissm.multiway.align_sessions([even, odd], voxel, stride=3, loop_gap=gap, loops_per_scan=per_scan)
        files = [files[k] for k in order]
        sessions = [0] * len(even) + [1] * len(odd)
    else:
        python = kissm.multiway.align(
            dict(zip(names, files, strict=True)), voxel, pairs=pairs, loop_gap=gap, loops_per_scan=per_scan
        )
    matcher = kissm.Matcher(voxel_size=voxel, refine_mode="gicp", num_threads=2)
    features = [
        matcher.compute_features(f if isinstance(f, np.ndarray) else kissm.read_points(f.path, f.format)) for f in files
    ]
    options = ffi.new("kissm_align_options *")
    assert lib.kissm_align_options_init(options, ffi.sizeof("kissm_align_options")) == 0
    # The same default in both: a broken chain takes 3 similar scans per scan unless told otherwise.
    assert inspect.signature(kissm.multiway.align).parameters["similar_per_scan"].default == options.similar_per_scan
    policy = {"all": lib.KISSM_PAIRS_ALL, "sequence": lib.KISSM_PAIRS_SEQUENCE, "sessions": lib.KISSM_PAIRS_SESSIONS}
    options.pairs = policy[pairs]
    options.loop_gap, options.loops_per_scan = gap, per_scan
    session_numbers = ffi.new("uint32_t[]", sessions)
    if sessions:
        options.sessions, options.stride = session_numbers, 3
    handles = ffi.new("kissm_features *[]", [f._ptr for f in features])
    out = ffi.new("kissm_alignment **")
    assert lib.kissm_align_features(matcher._ptr, handles, len(features), options, out) == 0, ffi.string(
        lib.kissm_last_error_message()
    )
    alignment = ffi.gc(out[0], lib.kissm_alignment_destroy)
    n = len(files)
    poses = np.empty((n, 4, 4))
    placed = np.empty(n, dtype=np.uint8)
    status = lib.kissm_alignment_poses(alignment, ffi.from_buffer("double[]", poses), ffi.from_buffer(placed), ffi.NULL)
    assert status == 0
    assert placed.tolist() == python.placed.tolist()
    assert placed.all() or broken
    assert poses.tobytes() == python.poses.tobytes()
    assert lib.kissm_alignment_num_registrations(alignment) == python.registrations
    edges = []
    source, target, edge, residual = (ffi.new(t) for t in ("uint64_t *", "uint64_t *", "int32_t *", "double *"))
    for k in range(python.registrations):
        assert lib.kissm_alignment_registration(alignment, k, source, target, ffi.NULL, edge, ffi.NULL, residual) == 0
        if edge[0] >= 0:
            edges.append((source[0], target[0], edge[0] == 1, struct.pack("<d", residual[0])))
    assert edges == [(e.source, e.target, e.accepted, struct.pack("<d", e.residual)) for e in python.edges]
    if broken:
        # The chain broke, and its pieces were joined by similarity: registrations beyond the consecutive pairs and
        # the loops by position, of scans in different pieces, some of them valid edges.
        steps = {e.source for e in python.edges if e.source == e.target + 1}
        pieces = np.cumsum([0] + [0 if k + 1 in steps else 1 for k in range(n - 1)])
        across = [e for e in python.edges if pieces[e.source] != pieces[e.target]]
        assert pieces[-1] > 0 and across, (pieces, python.registrations)
        if name == "broken":
            assert python.placed.tolist() == [True, True, False, False, True, True]
