# SPDX-License-Identifier: MIT
"""``kissm.Matcher`` and ``kissm.Features``: the C handles, owned, locked and released."""

from __future__ import annotations

import pickle
import threading
import warnings
from typing import Any

import numpy as np

from ._config import Config
from ._errors import InternalError, check, raise_status
from ._ffi import ffi, lib
from ._points import PointsLike, points_view
from ._result import Result

#: What :meth:`Matcher.refine` accepts as ``initial``: a (4, 4) array-like of real numbers (``Any`` for type
#: checkers, as numpy's ``ArrayLike``).
TransformLike = Any


def _new_result() -> Any:
    """A kissm_result prepared by ``kissm_result_init`` (struct_size set, no pose)."""
    result = ffi.new("kissm_result *")
    check(lib.kissm_result_init(result, ffi.sizeof("kissm_result")))
    return result


def transform_view(initial: TransformLike, name: str = "initial") -> Any:
    """A ``double[16]`` holding ``initial`` row-major: the shape and type are checked here, the values (finite,
    rigid) by the library, whose :class:`kissm.InvalidArgumentError` names ``initial_transform``."""
    try:
        array = np.asarray(initial)
    except (TypeError, ValueError) as e:
        raise ValueError(f"{name} cannot be read as a (4, 4) array: {e}") from None
    if array.dtype.kind not in "fiu":
        raise TypeError(
            f"{name} has dtype {array.dtype}; it must be a (4, 4) array of real numbers (the initial_transform)"
        )
    if array.shape != (4, 4):
        raise ValueError(f"{name} must have shape (4, 4), the initial_transform as a 4x4 matrix, not {array.shape}")
    return ffi.new("double[16]", array.astype(np.float64).ravel().tolist())


class Features:
    """A cloud described once (voxels, normals, FPFH descriptors), to be matched against many others.

    Made by :meth:`Matcher.compute_features`. Immutable: one Features object may be used by several threads and
    matchers at once, and may outlive the matcher that made it. It can be matched by any matcher whose
    descriptor settings (voxel size, radii, ``min_normal_neighbors``, ``max_linearity``, viewpoint) are the
    same, else :class:`kissm.FeaturesMismatchError` is raised.

    Portable: :meth:`to_bytes` writes them in the library's versioned, little-endian format with a checksum
    (docs/features-format.md) and :meth:`from_bytes` reads them back, in another process or on another
    machine; registering loaded features gives bit for bit the result of the original ones. Features pickle
    through these bytes, so they can be sent to worker processes (``concurrent.futures``, ``multiprocessing``)
    and cached. The bytes carry the descriptor settings the features were computed under, so loaded features
    still raise :class:`kissm.FeaturesMismatchError` against a matcher of other settings.
    """

    __slots__ = ("_ptr", "num_points", "num_voxels", "num_keypoints", "memory_bytes", "__weakref__")
    _ptr: Any
    num_points: int
    """Points given."""
    num_voxels: int
    """Occupied voxels."""
    num_keypoints: int
    """Voxels with a descriptor."""
    memory_bytes: int
    """Memory the features hold (voxels, normals, descriptors and their search index), in bytes."""

    def __init__(self) -> None:
        raise TypeError("kissm.Features objects are made by Matcher.compute_features(cloud)")

    @classmethod
    def _adopt(cls, ptr: Any) -> Features:
        self = object.__new__(cls)
        self._ptr = ffi.gc(ptr, lib.kissm_features_destroy)
        self.num_points = int(lib.kissm_features_num_points(ptr))
        self.num_voxels = int(lib.kissm_features_num_voxels(ptr))
        self.num_keypoints = int(lib.kissm_features_num_keypoints(ptr))
        self.memory_bytes = int(lib.kissm_features_memory_bytes(ptr))
        return self

    def __sizeof__(self) -> int:
        # What sys.getsizeof() reports, and Dask's memory accounting with it: the library's memory, not only
        # this small Python object's.
        return object.__sizeof__(self) + self.memory_bytes

    def __repr__(self) -> str:
        return f"<kissm.Features: {self.num_points} points, {self.num_voxels} voxels, {self.num_keypoints} keypoints>"

    def signature(self) -> np.ndarray:
        """A fixed-length summary of the features for finding scans that see the same place
        (``kissm_features_signature``): a (``KISSM_SIGNATURE_SIZE``,) float64 array whose Euclidean distance to
        another cloud's is small when the two overlap. Three unit-length blocks: the keypoints' mean FPFH, its
        standard deviation per bin, and the square roots of the shares of keypoints per 12-voxel band of distance
        from their centroid. It depends on no coordinate frame, is the same bits for loaded features and at any
        thread count, and is all zeros for features without keypoints. Compare signatures of one voxel size only;
        :mod:`kissm.multiway` takes its loop candidates from them (docs/multiway.md).
        """
        out = np.empty(int(lib.KISSM_SIGNATURE_SIZE), dtype=np.float64)
        check(lib.kissm_features_signature(self._ptr, ffi.from_buffer("double[]", out, require_writable=True)))
        return out

    def to_bytes(self) -> bytes:
        """The features as bytes (``kissm_features_serialize``) that :meth:`from_bytes` reads back on any machine.

        The same features always give the same bytes, so they can be hashed or deduplicated. They hold the
        voxels, normals, descriptors, counts and the descriptor settings, not the search indexes (rebuilt on
        load): about 170 bytes per voxel when most voxels are keypoints.
        """
        # The one copy beyond the library's makes the result immutable.
        return bytes(self._serialized())

    def _serialized(self) -> bytearray:
        """The bytes of :meth:`to_bytes`, written by the library straight into a new bytearray."""
        size = ffi.new("uint64_t *")
        check(lib.kissm_features_serialize(self._ptr, ffi.NULL, 0, size))
        buffer = bytearray(int(size[0]))
        with ffi.from_buffer("char[]", buffer, require_writable=True) as c:
            check(lib.kissm_features_serialize(self._ptr, c, len(buffer), size))
        if int(size[0]) != len(buffer):
            raise InternalError(f"kissm_features_serialize wrote {int(size[0])} bytes after announcing {len(buffer)}")
        return buffer

    @classmethod
    def from_bytes(cls, data: bytes | bytearray | memoryview) -> Features:
        """Features from the bytes of :meth:`to_bytes` (``kissm_features_deserialize``), possibly written by
        another process or machine. ``data`` is any C-contiguous bytes-like object (``bytes``, ``bytearray``,
        ``memoryview``, ``mmap``, a contiguous numpy array...), read without copying and exactly as long as
        :meth:`to_bytes` made it (trailing bytes are refused).

        Nothing in the bytes is trusted: they are bounds-checked and validated (magic, version, checksum,
        counts, values). The search indexes are rebuilt, on the calling thread, with the GIL released.

        Raises:
            TypeError: ``data`` is not a bytes-like object (a ``str``, for example) or is not C-contiguous.
            kissm.ParseError: the bytes are not kissm features of this format version, are truncated or
                corrupted, or hold a value the library cannot have written; the message names what is wrong
                and its byte offset.
        """
        if isinstance(data, str):
            raise TypeError("Features.from_bytes() needs a bytes-like object (bytes, bytearray, memoryview), not str")
        try:
            view = memoryview(data)
        except TypeError:
            raise TypeError(
                f"Features.from_bytes() needs a bytes-like object (bytes, bytearray, memoryview), "
                f"not {type(data).__name__}"
            ) from None
        with view:
            if not view.c_contiguous:
                raise TypeError("Features.from_bytes() needs C-contiguous bytes; copy them first (bytes(data))")
            out = ffi.new("kissm_features **")
            # Any item format and shape, as its bytes (no copy). An empty buffer may have no address: the library
            # gets a valid one and refuses the size.
            with view.cast("B") as flat:
                size = flat.nbytes
                c_bytes = ffi.from_buffer("char[]", flat) if size else ffi.new("char[1]")
                with c_bytes:  # releases the buffer (a bytearray can be resized again)
                    check(lib.kissm_features_deserialize(c_bytes, size, out))
        return cls._adopt(out[0])

    def __reduce_ex__(self, protocol: Any) -> tuple[Any, tuple[Any]]:
        # Protocol 5 gets the bytes as a buffer, which a pickler with a buffer_callback (Dask's, Ray's) sends out
        # of band: the bytes are not copied into the pickle, nor out of it on the other side, where from_bytes
        # reads the received buffer in place (docs/batch.md, "Where Dask's time goes").
        if isinstance(protocol, int) and protocol >= 5:
            return (_features_from_bytes, (pickle.PickleBuffer(self._serialized()),))
        return (_features_from_bytes, (self.to_bytes(),))


def _features_from_bytes(data: Any) -> Features:
    """``Features.from_bytes`` as a module-level function: cloudpickle (Dask's and Ray's) pickles a bound
    classmethod by value, with the module globals it reaches (cffi's library, locks), and fails; a plain
    function it pickles by reference, as pickle does."""
    return Features.from_bytes(data)


def _check_features(source: Features, target: Features) -> None:
    for name, value in (("source", source), ("target", target)):
        if not isinstance(value, Features):
            raise TypeError(
                f"{name} must be kissm.Features (from Matcher.compute_features), not {type(value).__name__}"
            )


class Matcher:
    """A registration engine with fixed settings.

    ``Matcher(config=None, **overrides)``: ``config`` is a :class:`Config` (default: the library's
    defaults) and keyword arguments override its fields, e.g. ``Matcher(voxel_size=0.5, num_threads=2)``.
    Invalid settings raise :class:`ValueError` here.

    One Matcher may be shared between threads: its calls are serialised by a lock. Different Matchers run
    in parallel (the GIL is released while the library works). Use it as a context manager, or call
    :meth:`close`, to free it at once; otherwise it is freed when garbage-collected. A Matcher pickles as
    its settings.
    """

    def __init__(self, config: Config | None = None, **overrides: Any) -> None:
        if config is not None and not isinstance(config, Config):
            raise TypeError(f"config must be a kissm.Config or None, not {type(config).__name__}")
        config = config if config is not None else Config()
        if overrides:
            config = config.replace(**overrides)
        out = ffi.new("kissm_matcher **")
        check(lib.kissm_create(config._to_c(), out))
        self._config = config
        self._ptr: Any = ffi.gc(out[0], lib.kissm_destroy)
        self._call_lock = threading.Lock()  # one C call at a time (the C matcher is single-threaded)
        self._handle_lock = threading.Lock()  # guards _ptr between close() and cancel()

    @property
    def config(self) -> Config:
        """The settings this matcher was made with."""
        return self._config

    @property
    def closed(self) -> bool:
        """Whether :meth:`close` was called (then every other method raises ValueError)."""
        return self._ptr is None

    def _handle(self) -> Any:
        ptr = self._ptr
        if ptr is None:
            raise ValueError("operation on a closed kissm.Matcher")
        return ptr

    def _call_for_result(self, function: Any, *args: Any) -> Result:
        """``function(matcher, *args, result)``, one call at a time: its Result, or the library's exception.
        The caller keeps what ``args`` point into alive (its locals) until this returns."""
        result = _new_result()
        with self._call_lock:
            status = function(self._handle(), *args, result)
            if status != 0:
                raise_status(status)  # reads the thread-local message before any other call
        return Result._from_c(result)

    def register(self, source: PointsLike, target: PointsLike) -> Result:
        """Globally register ``source`` against ``target``; no initial guess is needed.

        Both are (N, 3) float32/float64 array-likes (or objects with a ``.points`` attribute, such as Open3D
        point clouds), read without copying when their layout allows. Returns a :class:`Result` whose
        ``transform`` maps source points into the target frame. A well-formed input that yields no
        trustworthy pose gives ``valid=False`` and a ``reason``, not an exception.

        Raises:
            TypeError, ValueError: the inputs are not (N, 3) arrays of real numbers (before the library is
                called); or the library refused them (:class:`kissm.TooFewPointsError`,
                :class:`kissm.NonFiniteError`, :class:`kissm.VoxelRangeError`... all ValueErrors).
            kissm.CancelledError: :meth:`cancel` was called meanwhile.
        """
        src = points_view(source, "source")
        tgt = points_view(target, "target")
        return self._call_for_result(lib.kissm_register, src.c, tgt.c)

    def compute_features(self, cloud: PointsLike) -> Features:
        """Describe ``cloud`` once (``kissm_features_compute``), for :meth:`register_features` against any
        number of other clouds. ``cloud`` is read like :meth:`register`'s inputs.

        Raises:
            TypeError, ValueError: as :meth:`register` (e.g. :class:`kissm.TooFewPointsError`).
        """
        view = points_view(cloud, "cloud")
        out = ffi.new("kissm_features **")
        with self._call_lock:
            status = lib.kissm_features_compute(self._handle(), view.c, out)
            if status != 0:
                raise_status(status)
        return Features._adopt(out[0])

    def ground_mask(self, cloud: PointsLike) -> np.ndarray:
        """Which points of ``cloud`` the ground model of ``suppression='ground'`` labels ground
        (``kissm_ground_mask``), under this matcher's ``voxel_size``, ``up``, ``viewpoint`` and ``sensor_height``,
        whatever its ``suppression``: a bool array of ``len(cloud)`` (points dropped as non-finite are False).

        Raises:
            TypeError, ValueError: as :meth:`register`.
        """
        view = points_view(cloud, "cloud")
        mask = np.zeros(view.array.shape[0], dtype=np.uint8)
        with self._call_lock:
            status = lib.kissm_ground_mask(self._handle(), view.c, ffi.from_buffer("uint8_t[]", mask))
            if status != 0:
                raise_status(status)
        return mask.astype(bool)

    def features(self, cloud: PointsLike) -> Features:
        """Deprecated alias of :meth:`compute_features` (the name of the C ``kissm_features_compute``)."""
        warnings.warn(
            "kissm.Matcher.features() is deprecated; use Matcher.compute_features()", DeprecationWarning, stacklevel=2
        )
        return self.compute_features(cloud)

    def register_features(self, source: Features, target: Features) -> Result:
        """Register two described clouds: the same pose, counts and validity as :meth:`register` on the
        clouds they were computed from (voxelisation and feature times are reported as 0)."""
        _check_features(source, target)
        return self._call_for_result(lib.kissm_register_features, source._ptr, target._ptr)

    def refine(self, source: PointsLike, target: PointsLike, initial: TransformLike) -> Result:
        """Fine registration from a known pose (tracking, re-localisation from a prior): no descriptors, no
        global search. ``initial`` is a (4, 4) array-like mapping source points into the target frame, as
        ``Result.transform`` does; ``source`` and ``target`` are read as by :meth:`register`.

        Both clouds are voxelised, their normals estimated, and ``initial`` refined with ``config.refine_mode``
        ('gicp' when it is 'none'). The Result's ``coarse_transform`` is ``initial`` (made exactly rigid),
        ``transform`` the refined pose, ``information`` its information matrix; ``valid`` says whether the
        refined pose overlaps the target enough, is constrained in every direction (unless
        ``config.allow_degenerate``; ``degenerate`` and ``weak_directions`` say which directions are free),
        refinement converged and left the clouds close (else ``reason``).

        Raises:
            TypeError, ValueError: ``initial`` is not a (4, 4) array of real numbers, or the clouds are not
                (N, 3) arrays (before the library is called).
            kissm.InvalidArgumentError: ``initial`` is not finite, its last row is not (0, 0, 0, 1), its
                rotation block is not a rotation, or its translation is beyond 1e9 (the library's message
                names ``initial_transform``).
            ValueError: the library refused a cloud, as for :meth:`register`.
            kissm.CancelledError: :meth:`cancel` was called meanwhile.
        """
        src = points_view(source, "source")
        tgt = points_view(target, "target")
        return self._call_for_result(lib.kissm_refine, src.c, tgt.c, transform_view(initial))

    def refine_features(self, source: Features, target: Features, initial: TransformLike) -> Result:
        """:meth:`refine` on described clouds: the same refined pose and counts as :meth:`refine` on the clouds they
        were computed from (no keypoints, as refinement uses no descriptors; voxelisation and feature times are
        reported as 0). Features computed by a matcher with
        refinement on (``refine_mode`` other than 'none') carry the search index refinement uses, so a map
        described once is not indexed again for every scan.

        Raises:
            TypeError, ValueError, kissm.InvalidArgumentError: as :meth:`refine`.
            kissm.FeaturesMismatchError: as :meth:`register_features`.
        """
        _check_features(source, target)
        return self._call_for_result(lib.kissm_refine_features, source._ptr, target._ptr, transform_view(initial))

    def cancel(self) -> None:
        """Ask the call running on this matcher (in another thread) to stop with
        :class:`kissm.CancelledError`. Does nothing when no call is running."""
        with self._handle_lock:
            if self._ptr is not None:
                lib.kissm_cancel(self._ptr)

    def close(self) -> None:
        """Free the C matcher now (waiting for a running call). Idempotent."""
        with self._call_lock, self._handle_lock:
            ptr, self._ptr = self._ptr, None
        if ptr is not None:
            ffi.release(ptr)

    def __enter__(self) -> Matcher:
        self._handle()
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def __reduce__(self) -> tuple[Any, tuple[Config]]:
        self._handle()
        return (Matcher, (self._config,))

    def __repr__(self) -> str:
        state = " (closed)" if self._ptr is None else ""
        return f"kissm.Matcher({self._config!r}){state}"
