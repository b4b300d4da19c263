# SPDX-License-Identifier: MIT
"""Features.to_bytes / Features.from_bytes and pickling: byte round trips, registrations from loaded features
bitwise equal to the originals' (in this process and in a spawned worker), malformed bytes, wrong argument types
and features of another configuration, and Features.signature (loaded, other thread counts, a moved cloud); on the
committed pair and on a KITTI 07 keyframe pair of the real data."""

from __future__ import annotations

import concurrent.futures
import copy
import multiprocessing
import pickle
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest

import kissm

from helpers import assert_same_result

KITTI_PAIR = "kitti07_keyframes_gtsam_points/pairs/000000__000001"


@dataclass(frozen=True)
class Case:
    name: str
    source: np.ndarray
    target: np.ndarray
    config: kissm.Config


@pytest.fixture(scope="module", params=["committed", "kitti07"])
def case(request: pytest.FixtureRequest) -> Case:
    if request.param == "committed":
        pair = request.getfixturevalue("pair")
        return Case("committed", pair.source, pair.target, kissm.Config(voxel_size=pair.voxel_size))
    real_pairs = request.getfixturevalue("real_pairs")  # skips when the real data is absent
    if KITTI_PAIR not in real_pairs:
        pytest.skip(f"{KITTI_PAIR} is not in the real data")
    real = real_pairs[KITTI_PAIR]
    return Case(
        "kitti07",
        kissm.read_points(real.source, format=real.source_format),
        kissm.read_points(real.target, format=real.target_format),
        kissm.Config(voxel_size=real.kind.voxel),
    )


@pytest.fixture(scope="module")
def described(case: Case) -> tuple[kissm.Features, kissm.Features, kissm.Result]:
    """The case's features and their registration."""
    with kissm.Matcher(case.config) as matcher:
        source, target = matcher.compute_features(case.source), matcher.compute_features(case.target)
        return source, target, matcher.register_features(source, target)


def assert_same_features(loaded: kissm.Features, original: kissm.Features) -> None:
    assert (loaded.num_points, loaded.num_voxels, loaded.num_keypoints) == (
        original.num_points,
        original.num_voxels,
        original.num_keypoints,
    )
    # memory_bytes counts the vectors' capacities: the original's may hold the slack of their growth, which the
    # exactly sized loaded vectors do not have, so the loaded features hold at most the original's memory.
    assert 0.99 * original.memory_bytes <= loaded.memory_bytes <= original.memory_bytes


def test_bytes_round_trip(case: Case, described: Any) -> None:
    source, target, _ = described
    for features in (source, target):
        data = features.to_bytes()
        assert type(data) is bytes and data[:8] == b"KISSMFT\0"
        assert features.to_bytes() == data  # the same features always give the same bytes
        loaded = kissm.Features.from_bytes(data)
        assert isinstance(loaded, kissm.Features) and loaded is not features
        assert_same_features(loaded, features)
        assert loaded.to_bytes() == data
        # Every C-contiguous bytes-like object is read, whatever its item type and shape.
        as_array = np.frombuffer(data, dtype=np.uint8)
        for like in (bytearray(data), memoryview(data), as_array, as_array.reshape(1, -1)):
            assert kissm.Features.from_bytes(like).to_bytes() == data
        if len(data) % 8 == 0:
            assert kissm.Features.from_bytes(np.frombuffer(data, dtype=np.float64)).to_bytes() == data


def test_signature_of_loaded_features_and_other_thread_counts(case: Case, described: Any) -> None:
    """Features.signature(): (KISSM_SIGNATURE_SIZE,) float64 of three unit-length blocks, the same bits for loaded
    features and for features computed at 1 and 4 threads, nearly the same for the cloud moved rigidly (the voxel
    grid differs) and farther from the other cloud of the pair."""
    source, target, _ = described
    signature = source.signature()
    assert signature.shape == (kissm._ffi.lib.KISSM_SIGNATURE_SIZE,) == (82,) and signature.dtype == np.float64
    for block in (signature[:33], signature[33:66], signature[66:]):
        assert abs(float(block @ block) - 1.0) < 1e-12 and (block >= 0).all()
    assert kissm.Features.from_bytes(source.to_bytes()).signature().tobytes() == signature.tobytes()
    for threads in (1, 4):
        with kissm.Matcher(case.config.replace(num_threads=threads)) as matcher:
            assert matcher.compute_features(case.source).signature().tobytes() == signature.tobytes()
    c, s = np.cos(2.6), np.sin(2.6)
    rotation = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    moved = np.asarray(case.source, dtype=np.float64) @ rotation.T + [40.0, -25.0, 3.0]
    with kissm.Matcher(case.config) as matcher:
        near = float(np.linalg.norm(matcher.compute_features(moved).signature() - signature))
    far = float(np.linalg.norm(target.signature() - signature))
    assert near < 0.1 and far > near, (near, far)


def test_registration_from_loaded_features_is_bitwise_the_original(case: Case, described: Any) -> None:
    source, target, expected = described
    loaded_source = kissm.Features.from_bytes(source.to_bytes())
    loaded_target = kissm.Features.from_bytes(target.to_bytes())
    with kissm.Matcher(case.config) as matcher:
        got = matcher.register_features(loaded_source, loaded_target)
        assert np.array_equal(got.transform, expected.transform, equal_nan=True)
        assert_same_result(got, expected)
        assert_same_result(matcher.register_features(loaded_source, target), expected)  # mixed
    if case.name == "kitti07":
        assert expected.valid


@pytest.mark.parametrize("refine_mode", ["gicp", "point_to_plane"])
def test_refinement_from_loaded_features_is_bitwise_the_original(pair, refine_mode: str) -> None:
    """Features computed with refinement on carry the refinement index, which loading rebuilds."""
    with kissm.Matcher(voxel_size=pair.voxel_size, refine_mode=refine_mode) as matcher:
        source, target = matcher.compute_features(pair.source), matcher.compute_features(pair.target)
        loaded_source = kissm.Features.from_bytes(source.to_bytes())
        loaded_target = kissm.Features.from_bytes(target.to_bytes())
        assert_same_features(loaded_source, source)
        registered = matcher.register_features(source, target)
        assert registered.refined
        assert_same_result(matcher.register_features(loaded_source, loaded_target), registered)
        initial = pair.transform
        assert_same_result(
            matcher.refine_features(loaded_source, loaded_target, initial),
            matcher.refine_features(source, target, initial),
        )


def test_pickle_round_trip(case: Case, described: Any) -> None:
    source, target, expected = described
    for protocol in range(2, pickle.HIGHEST_PROTOCOL + 1):
        loaded = pickle.loads(pickle.dumps(source, protocol))
        assert isinstance(loaded, kissm.Features)
        assert_same_features(loaded, source)
        assert loaded.to_bytes() == source.to_bytes()
    assert copy.deepcopy(target).to_bytes() == target.to_bytes()
    assert copy.copy(target).to_bytes() == target.to_bytes()
    with kissm.Matcher(case.config) as matcher:
        pair = pickle.loads(pickle.dumps((source, target)))
        assert_same_result(matcher.register_features(*pair), expected)


def test_pickle_protocol_5_sends_the_bytes_out_of_band(case: Case, described: Any) -> None:
    """With a buffer_callback (Dask's and Ray's picklers), the features' bytes leave the pickle as one buffer, and
    loading reads that buffer in place (a read-only view of it too, as Ray's shared memory gives)."""
    source, target, expected = described
    buffers: list[pickle.PickleBuffer] = []
    stream = pickle.dumps((source, target), protocol=5, buffer_callback=buffers.append)
    sizes = sorted(len(b.raw()) for b in buffers)
    assert sizes == sorted([len(source.to_bytes()), len(target.to_bytes())])
    assert len(stream) < 1024  # the function's name and two buffer references, not the bytes
    loaded_source, loaded_target = pickle.loads(stream, buffers=buffers)
    assert loaded_source.to_bytes() == source.to_bytes()
    read_only = [memoryview(bytes(b.raw())) for b in buffers]
    again_source, again_target = pickle.loads(stream, buffers=read_only)
    assert again_target.to_bytes() == target.to_bytes()
    with kissm.Matcher(case.config) as matcher:
        assert_same_result(matcher.register_features(loaded_source, loaded_target), expected)
        assert_same_result(matcher.register_features(again_source, again_target), expected)
    # Without a callback, protocol 5 keeps the bytes in the pickle, as the older protocols do.
    assert pickle.loads(pickle.dumps(source, protocol=5)).to_bytes() == source.to_bytes()


def test_cloudpickle_round_trip(case: Case, described: Any) -> None:
    """Dask and Ray pickle with cloudpickle, which pickled the bound classmethod Features.from_bytes by value
    (and failed on the library's locks): the features must travel by reference to a module function."""
    cloudpickle = pytest.importorskip("cloudpickle", reason="cloudpickle (from kissm[dask]) is not installed")
    source, target, expected = described
    loaded_source, loaded_target = cloudpickle.loads(cloudpickle.dumps((source, target)))
    assert loaded_source.to_bytes() == source.to_bytes()
    with kissm.Matcher(case.config) as matcher:
        assert_same_result(matcher.register_features(loaded_source, loaded_target), expected)


def _register_in_worker(config: kissm.Config, source: kissm.Features, target: kissm.Features) -> tuple[Any, ...]:
    """Runs in a spawned process: registers the unpickled features."""
    with kissm.Matcher(config) as matcher:
        return matcher.register_features(source, target), source.to_bytes()


def test_features_pickle_to_a_spawned_process(case: Case, described: Any) -> None:
    source, target, expected = described
    with concurrent.futures.ProcessPoolExecutor(max_workers=1, mp_context=multiprocessing.get_context("spawn")) as pool:
        got, source_bytes = pool.submit(_register_in_worker, case.config, source, target).result(timeout=300)
    assert isinstance(got, kissm.Result)
    assert np.array_equal(got.transform, expected.transform, equal_nan=True)
    assert_same_result(got, expected)
    assert source_bytes == source.to_bytes()


def test_truncated_bytes_are_parse_errors(pair) -> None:
    with kissm.Matcher(voxel_size=pair.voxel_size) as matcher:
        data = matcher.compute_features(pair.source).to_bytes()
    for size in (0, 1, 7, 8, 12, 100, 213, 214, len(data) // 2, len(data) - 8, len(data) - 1):
        with pytest.raises(kissm.ParseError, match="truncated") as caught:
            kissm.Features.from_bytes(data[:size])
        assert caught.value.status == kissm.ParseError.status
        assert "features bytes" in caught.value.message, caught.value.message
    with pytest.raises(kissm.ParseError, match="corrupted"):  # trailing bytes are refused too
        kissm.Features.from_bytes(data + b"\0")
    with pytest.raises(kissm.ParseError, match="not kissm features"):
        kissm.Features.from_bytes(b"PLY\n" + data[4:])


def test_flipped_bits_are_parse_errors(pair) -> None:
    with kissm.Matcher(voxel_size=pair.voxel_size) as matcher:
        data = matcher.compute_features(pair.source).to_bytes()
    # The magic is checked first, then the version, then the checksum over everything else.
    expected = {0: "not kissm features", 8: "version", 24: "checksum mismatch", 200: "checksum mismatch"}
    expected.update({len(data) // 2: "checksum mismatch", len(data) - 9: "checksum mismatch"})
    expected[len(data) - 1] = "checksum mismatch"  # the checksum itself
    for offset, what in expected.items():
        for bit in (0, 7):
            flipped = bytearray(data)
            flipped[offset] ^= 1 << bit
            with pytest.raises(kissm.ParseError, match=what):
                kissm.Features.from_bytes(flipped)
    assert kissm.Features.from_bytes(data).to_bytes() == data


def test_from_bytes_refuses_what_is_not_contiguous_bytes(pair) -> None:
    with kissm.Matcher(voxel_size=pair.voxel_size) as matcher:
        data = matcher.compute_features(pair.source).to_bytes()
    with pytest.raises(TypeError, match="not str"):
        kissm.Features.from_bytes(data.decode("latin-1"))  # type: ignore[arg-type]
    for wrong in (None, 12, [1, 2, 3]):
        with pytest.raises(TypeError, match="bytes-like"):
            kissm.Features.from_bytes(wrong)  # type: ignore[arg-type]
    doubled = memoryview(bytes(b for byte in data for b in (byte, 0)))[::2]
    assert not doubled.c_contiguous and doubled.tobytes() == data
    with pytest.raises(TypeError, match="C-contiguous"):
        kissm.Features.from_bytes(doubled)
    with pytest.raises(TypeError, match="C-contiguous"):
        kissm.Features.from_bytes(np.frombuffer(data + data, dtype=np.uint8)[::2])
    assert kissm.Features.from_bytes(doubled.tobytes()).to_bytes() == data


def test_loaded_features_of_another_config_mismatch_on_use(pair) -> None:
    with kissm.Matcher(voxel_size=pair.voxel_size) as matcher, kissm.Matcher(voxel_size=2 * pair.voxel_size) as other:
        mine = kissm.Features.from_bytes(matcher.compute_features(pair.source).to_bytes())
        theirs = kissm.Features.from_bytes(other.compute_features(pair.target).to_bytes())
        with pytest.raises(kissm.FeaturesMismatchError) as caught:
            matcher.register_features(mine, theirs)
        assert caught.value.message
        with pytest.raises(kissm.FeaturesMismatchError):
            matcher.refine_features(theirs, mine, np.eye(4))
        unpickled = pickle.loads(pickle.dumps(theirs))
        with pytest.raises(kissm.FeaturesMismatchError):
            matcher.register_features(mine, unpickled)
        assert other.register_features(theirs, unpickled).num_source_voxels == theirs.num_voxels
