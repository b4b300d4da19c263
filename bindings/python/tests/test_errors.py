# SPDX-License-Identifier: MIT
"""One exception class per status code, each raised with the library's message; all picklable."""

from __future__ import annotations

import pickle
import re
import threading
import time

import numpy as np
import pytest

import kissm
from kissm import _errors, _ffi

DOCUMENTED_BASES = {
    kissm.InvalidArgumentError: ValueError,
    kissm.NullArgumentError: ValueError,
    kissm.EmptyInputError: ValueError,
    kissm.TooFewPointsError: ValueError,
    kissm.NonFiniteError: ValueError,
    kissm.VoxelRangeError: ValueError,
    kissm.StructSizeError: None,
    kissm.OutOfMemoryError: MemoryError,
    kissm.CancelledError: None,
    kissm.FeaturesMismatchError: ValueError,
    kissm.IoError: OSError,
    kissm.ParseError: ValueError,
    kissm.UnsupportedFormatError: ValueError,
    kissm.InternalError: None,
}


def test_one_class_per_status_code() -> None:
    codes = {name: getattr(_ffi.lib, name) for name in dir(_ffi.lib) if name.startswith("KISSM_ERR_")}
    assert len(codes) == 14
    assert {cls.status_name: cls.status for cls in _errors.ERROR_CLASSES.values()} == codes
    assert set(_errors.ERROR_CLASSES.values()) == set(DOCUMENTED_BASES)
    for cls, base in DOCUMENTED_BASES.items():
        assert issubclass(cls, kissm.Error)
        assert getattr(kissm, cls.__name__) is cls
        if base is not None:
            assert issubclass(cls, base)


@pytest.mark.parametrize("cls", list(DOCUMENTED_BASES), ids=lambda c: c.__name__)
def test_mapping_and_pickling(cls: type[kissm.Error]) -> None:
    kissm.Config()  # a successful call clears the thread's last message...
    with pytest.raises(cls) as info:
        _errors.raise_status(cls.status)  # ...so the static status text is the message
    error = info.value
    assert str(error) == _errors.status_string(cls.status) and error.message == str(error)
    for protocol in range(2, pickle.HIGHEST_PROTOCOL + 1):
        again = pickle.loads(pickle.dumps(error, protocol))
        assert type(again) is cls and str(again) == str(error)
        assert (again.status, again.status_name) == (cls.status, cls.status_name)


@pytest.mark.parametrize("cls", list(_errors.ERROR_CLASSES.values()), ids=lambda c: c.__name__)
def test_pickling_as_tblib_does(cls: type[kissm.Error]) -> None:
    """Dask installs tblib's exception pickling in every process that imports it, and kissm.batch returns errors
    as values from Dask workers: each class must survive tblib's reducer (MemoryError's __new__ refused it)."""
    pickling_support = pytest.importorskip("tblib.pickling_support", reason="tblib (from kissm[dask]) is not installed")
    error = cls("a message", cls.status)
    function, args, *_ = pickling_support.pickle_exception(error)
    again = function(*args)
    assert type(again) is cls and again.message == "a message"
    assert (again.status, again.status_name) == (cls.status, cls.status_name)


def test_unknown_status_is_a_plain_error() -> None:
    kissm.Config()
    with pytest.raises(kissm.Error) as info:
        _errors.raise_status(-99)
    assert type(info.value) is kissm.Error and info.value.status == -99
    assert str(info.value) == "unknown status"
    assert pickle.loads(pickle.dumps(info.value)).status == -99


def test_check_passes_ok() -> None:
    _errors.check(0)


# ---- every status the Python API can provoke, with the library's own message ----------------------------


def test_invalid_argument(pair) -> None:
    with pytest.raises(kissm.InvalidArgumentError, match=r"^kissm_config_validate: config\.ratio_test is 2"):
        kissm.Config(ratio_test=2.0)


def test_null_argument() -> None:
    with pytest.raises(kissm.NullArgumentError, match="^kissm_create: out_matcher is NULL$"):
        _errors.check(_ffi.lib.kissm_create(_ffi.ffi.NULL, _ffi.ffi.NULL))


def test_struct_size() -> None:
    c = _ffi.ffi.new("kissm_config *")
    with pytest.raises(
        kissm.StructSizeError, match=r"^kissm_config_init: struct_size is 4; .*\(set it to sizeof\(kissm_config\)\)$"
    ):
        _errors.check(_ffi.lib.kissm_config_init(c, 4))


def test_empty_input(pair) -> None:
    with pytest.raises(kissm.EmptyInputError, match="kissm_register: source has no points"):
        kissm.register(np.empty((0, 3)), pair.target, voxel_size=0.3)
    all_nan = np.full((10, 3), np.nan)
    with pytest.raises(kissm.EmptyInputError):
        kissm.register(pair.source, all_nan, voxel_size=0.3, nonfinite_policy="drop")


def test_too_few_points(pair) -> None:
    with pytest.raises(kissm.TooFewPointsError, match=f"target has 3 points; at least {kissm.MIN_POINTS}"):
        kissm.register(pair.source, pair.target[:3], voxel_size=0.3)
    with kissm.Matcher() as matcher, pytest.raises(kissm.TooFewPointsError, match="cloud has 1 points"):
        matcher.compute_features(pair.source[:1])


def test_nonfinite(pair) -> None:
    source = pair.source.copy()
    source[100, 1] = np.inf
    with pytest.raises(kissm.NonFiniteError) as info:
        kissm.register(source, pair.target, voxel_size=0.3)
    assert "source" in str(info.value)
    dropped = kissm.register(source, pair.target, voxel_size=0.3, nonfinite_policy="drop")
    assert dropped.num_source_nonfinite == 1 and dropped.valid


def test_voxel_range(pair) -> None:
    with pytest.raises(kissm.VoxelRangeError, match="voxel_size 1e-06 is too small for the source's extent"):
        kissm.register(pair.source, pair.target, voxel_size=1e-6)


def test_features_mismatch(pair) -> None:
    with kissm.Matcher(voxel_size=0.3) as a, kissm.Matcher(voxel_size=0.5) as b:
        source, target = a.compute_features(pair.source), a.compute_features(pair.target)
        with pytest.raises(kissm.FeaturesMismatchError, match="^kissm_register_features: source features"):
            b.register_features(source, target)
        assert a.register_features(source, target).valid


def test_io_error(tmp_path) -> None:
    missing = tmp_path / "missing.ply"
    with pytest.raises(kissm.IoError) as info:
        kissm.read_points(missing)
    assert isinstance(info.value, OSError)
    assert str(info.value).startswith(f"kissm_read_points: {missing}: cannot open")


def test_parse_error(tmp_path) -> None:
    bad = tmp_path / "bad.ply"
    bad.write_text(
        "ply\nformat ascii 1.0\nelement vertex 10\nproperty float x\nproperty float y\n"
        "property float z\nend_header\n1 2 3\n"
    )
    with pytest.raises(kissm.ParseError, match=re.escape(f"kissm_read_points: {bad}: ")):
        kissm.read_points(bad)


def test_unsupported_format(tmp_path) -> None:
    unknown = tmp_path / "cloud.foo"
    unknown.write_bytes(b"\x00\x01garbage")
    with pytest.raises(kissm.UnsupportedFormatError, match="unknown point file format"):
        kissm.read_points(unknown)


def test_cancelled(pair) -> None:
    """cancel() from another thread stops the running call."""
    big_source = np.concatenate([pair.source + (40.0 * k, 0.0, 0.0) for k in range(6)])
    big_target = np.concatenate([pair.target + (40.0 * k, 0.0, 0.0) for k in range(6)])
    with kissm.Matcher(voxel_size=0.3, num_threads=1) as matcher:
        outcome: list[object] = []

        def run() -> None:
            try:
                outcome.append(matcher.register(big_source, big_target))
            except kissm.Error as e:
                outcome.append(e)

        worker = threading.Thread(target=run)
        worker.start()
        while worker.is_alive():
            matcher.cancel()
            time.sleep(0.002)
        worker.join()
        assert len(outcome) == 1 and isinstance(outcome[0], kissm.CancelledError), outcome
        assert "cancel" in str(outcome[0])
        matcher.cancel()  # no call running: cleared when the next call starts
        assert matcher.register(pair.source, pair.target).valid


def test_errors_in_one_thread_do_not_leak_into_another(pair) -> None:
    """The message is the library's thread-local one, read right after the failing call."""
    messages: dict[str, str] = {}

    def fail(name: str, points: np.ndarray) -> None:
        try:
            kissm.register(points, pair.target, voxel_size=0.3)
        except kissm.Error as e:
            messages[name] = str(e)

    threads = [
        threading.Thread(target=fail, args=("few", pair.source[:2])),
        threading.Thread(target=fail, args=("empty", np.empty((0, 3)))),
    ]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert "source has 2 points" in messages["few"] and "source has no points" in messages["empty"]


def test_read_points_argument_checks() -> None:
    with pytest.raises(ValueError, match="format is 'e57'"):
        kissm.read_points("x.e57", format="e57")
    with pytest.raises(ValueError, match="NUL"):
        kissm.read_points("a\0b.ply")
