# SPDX-License-Identifier: MIT
"""``kissm.PoseGraph`` and ``kissm.PoseGraphSolution``: the C pose graph (``kissm_pose_graph_*``), owned, locked
and released, and its solution copied out into numpy arrays."""

from __future__ import annotations

import dataclasses
import numbers
import operator
import threading
from typing import Any

import numpy as np

from ._errors import InvalidArgumentError, check, raise_status
from ._ffi import ffi, lib

#: What :meth:`PoseGraph.add_edge` accepts as a matrix: an array-like of real numbers (``Any`` for type checkers,
#: as numpy's ``ArrayLike``).
MatrixLike = Any

#: One more than the largest value a C ``uint64_t`` holds: node numbers at or above it cannot reach the library.
_UINT64_END = 1 << 64


def _integer(value: object, name: str) -> int:
    """``value`` as a Python int: an int or an integer numpy scalar, not a bool, a float or a string."""
    if isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be an integer, not bool")
    try:
        return operator.index(value)  # type: ignore[arg-type]
    except TypeError:
        raise TypeError(f"{name} must be an integer, not {type(value).__name__}") from None


def _node(value: object, name: str, num_nodes: int, function: str) -> int:
    """A node number for a C ``uint64_t``. Values it cannot hold (negative ones: cffi would refuse them, a cast
    would wrap them around) are refused here with the library's own class and wording (``function`` is the C
    function the message names); the library checks the rest against the graph."""
    number = _integer(value, name)
    if not 0 <= number < _UINT64_END:
        raise InvalidArgumentError(f"{function}: {name} is {number}; the graph has nodes 0 to {num_nodes - 1}")
    return number


def _flag(robust: object) -> int:
    """``robust`` as the C ``int32_t`` 0 or 1: a bool, or the integer 0 or 1."""
    if isinstance(robust, (bool, np.bool_)):
        return int(robust)
    try:
        value = operator.index(robust)  # type: ignore[arg-type]
    except TypeError:
        raise TypeError(f"robust must be a bool, not {type(robust).__name__}") from None
    if value not in (0, 1):
        raise InvalidArgumentError(f"kissm_pose_graph_add_edge: robust is {value}; 0 or 1 (False or True)")
    return value


def _matrix(value: MatrixLike, name: str, size: int) -> np.ndarray:
    """``value`` as a C-contiguous (size, size) float64 array (a copy only when its layout or type needs one).
    The shape and type are checked here; the values by the library, whose message names ``name``."""
    try:
        array = np.asarray(value)
    except (TypeError, ValueError) as e:
        raise ValueError(f"{name} cannot be read as a ({size}, {size}) array: {e}") from None
    if array.dtype.kind not in "fiu":
        raise TypeError(f"{name} has dtype {array.dtype}; it must be a ({size}, {size}) array of real numbers")
    if array.shape != (size, size):
        raise ValueError(f"{name} must have shape ({size}, {size}), not {array.shape}")
    return np.ascontiguousarray(array, dtype=np.float64)


def _bound(value: object) -> float:
    """``bound`` as a C double; the library refuses NaN, infinities and values not above 0."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise TypeError(f"bound must be a real number, not {type(value).__name__}")
    return float(value)


def _output(c_type: str, array: np.ndarray) -> Any:
    """A writable ``c_type`` array over ``array``'s memory, NULL when it is empty (the library's outputs may be
    NULL, and then it writes nothing there)."""
    return ffi.from_buffer(c_type, array, require_writable=True) if array.size else ffi.NULL


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class PoseGraphSolution:
    """The outcome of :meth:`PoseGraph.optimize`: every node's pose in the anchor's frame and the verdict on every
    edge, copied out of the library (``kissm_pose_graph_poses`` and ``kissm_pose_graph_edges``).

    A node is placed when accepted edges (trusted ones, and robust ones the optimisation kept) join it to the
    anchor; a node that is not placed has a NaN pose, never a guess. The arrays are plain numpy arrays owned by
    this object; the graph may be changed, optimised again or closed without affecting them.
    """

    poses: np.ndarray
    """(N, 4, 4) float64: world-from-node poses, world being the anchor's frame (``poses[anchor]`` is the
    identity), so ``poses[i] @ [x, y, z, 1]`` carries a point of node ``i`` into the anchor's frame. All NaN for a
    node that is not placed."""
    placed: np.ndarray
    """(N,) bool: whether accepted edges join the node to the anchor."""
    components: np.ndarray
    """(N,) int64: for each node the smallest node joined to it by trusted and accepted edges. The anchor's
    component is the placed nodes; a node joined by nothing is its own component."""
    accepted: np.ndarray
    """(E,) bool, in the order the edges were added: True for a trusted edge and for a robust edge the
    optimisation kept; False for a rejected robust edge and for any edge outside the anchor's component."""
    residuals: np.ndarray
    """(E,) float64: each edge's squared error ``xi^T I xi`` at the solution (``I`` its information), rejected
    edges included; NaN for an edge with a node that is not placed."""

    @property
    def num_placed(self) -> int:
        """How many nodes are placed."""
        return int(np.count_nonzero(self.placed))

    @property
    def num_accepted(self) -> int:
        """How many edges are accepted."""
        return int(np.count_nonzero(self.accepted))

    def __repr__(self) -> str:
        return (
            f"kissm.PoseGraphSolution({self.num_placed} of {len(self.placed)} nodes placed, "
            f"{self.num_accepted} of {len(self.accepted)} edges accepted)"
        )


class PoseGraph:
    """A pose graph: nodes (scans, numbered 0 to ``num_nodes - 1``) joined by edges (relative poses: a
    registration's transform and information, an odometry step, a user's constraint), made into one consistent
    set of absolute poses by :meth:`optimize` (the C ``kissm_pose_graph``).

    An edge from ``source`` to ``target`` states ``transform = inv(X_target) @ X_source`` for the nodes'
    world-from-node poses ``X``: ``transform`` maps the source's points into the target's frame, as
    ``Result.transform`` does for a registration of the source scan against the target scan, and
    ``Result.information`` is its information as it is. In GTSAM terms the edge is
    ``BetweenFactorPose3(target, source, Pose3(transform), noiseModel.Gaussian.Information(information))``.

    Edges added with ``robust=True`` (loop closures, registrations that may be wrong) may be rejected by the
    optimisation (graduated non-convexity with a truncated least-squares cost); the others are always kept.

    One PoseGraph may be shared between threads: its calls are serialised by a lock, and :meth:`cancel` may be
    called from any thread. The GIL is released while the library optimises. Use it as a context manager, or call
    :meth:`close`, to free it at once; otherwise it is freed when garbage-collected.

    Raises:
        TypeError: ``num_nodes`` is not an integer.
        kissm.InvalidArgumentError: ``num_nodes`` is not 1 to :attr:`MAX_NODES`.
    """

    DEFAULT_BOUND: float = 22.4577
    """The default ``bound`` of :meth:`optimize` (the C ``KISSM_POSE_GRAPH_DEFAULT_BOUND``): the 99.9% quantile
    of a chi-square with 6 degrees of freedom, for calibrated informations."""

    MAX_NODES: int = int(lib.KISSM_POSE_GRAPH_MAX_NODES)
    """Most nodes a graph may have (the C ``KISSM_POSE_GRAPH_MAX_NODES``)."""

    def __init__(self, num_nodes: int) -> None:
        count = _integer(num_nodes, "num_nodes")
        if not 0 <= count < _UINT64_END:
            raise InvalidArgumentError(f"kissm_pose_graph_create: num_nodes is {count}; 1 to {self.MAX_NODES}")
        out = ffi.new("kissm_pose_graph **")
        check(lib.kissm_pose_graph_create(count, out))
        self._ptr: Any = ffi.gc(out[0], lib.kissm_pose_graph_destroy)
        self._num_nodes = count
        self._call_lock = threading.Lock()  # one C call at a time (a C graph is used by one thread at a time)
        self._handle_lock = threading.Lock()  # guards _ptr between close() and cancel()

    @property
    def num_nodes(self) -> int:
        """The number of nodes, fixed at construction."""
        return self._num_nodes

    @property
    def num_edges(self) -> int:
        """The number of edges added so far (edges are numbered 0 to ``num_edges - 1`` in that order)."""
        with self._call_lock:
            return int(lib.kissm_pose_graph_num_edges(self._handle()))

    @property
    def closed(self) -> bool:
        """Whether :meth:`close` was called (then every other method raises ValueError)."""
        return self._ptr is None

    def _handle(self) -> Any:
        ptr = self._ptr
        if ptr is None:
            raise ValueError("operation on a closed kissm.PoseGraph")
        return ptr

    def add_edge(
        self, source: int, target: int, transform: MatrixLike, information: MatrixLike, robust: bool = True
    ) -> int:
        """Add an edge stating ``transform = inv(X_target) @ X_source``; returns its number (0 for the first edge,
        then 1, 2...: the index of its entries in :attr:`PoseGraphSolution.accepted` and ``.residuals``).

        ``transform`` is a (4, 4) array-like (``T_target_source``: it maps the source's points into the target's
        frame) and must be rigid; ``information`` a (6, 6) array-like, the inverse covariance of the error
        ``xi = Log(inv(transform) @ inv(X_target) @ X_source)``, rotation (radians) first, in the source's frame
        (``Result.information`` as it is), symmetric (to 1e-9 of its largest entry) and positive definite.
        ``robust=True`` marks a candidate that may be wrong (a loop closure), which :meth:`optimize` may reject;
        ``robust=False`` a trusted edge (odometry, a user's constraint), always kept. Solutions already returned
        by :meth:`optimize` are unaffected; on an error the graph is unchanged.

        Raises:
            TypeError: a node number or ``robust`` is not an integer (or bool), or a matrix is not of real
                numbers.
            ValueError: ``transform`` is not (4, 4) or ``information`` not (6, 6) (before the library is called).
            kissm.InvalidArgumentError: a node is not in the graph, ``source`` equals ``target``, ``transform``
                is not finite and rigid, ``information`` is not finite, symmetric and positive definite, or
                ``robust`` is not 0 or 1; the message names the argument.
        """
        s = _node(source, "source", self._num_nodes, "kissm_pose_graph_add_edge")
        t = _node(target, "target", self._num_nodes, "kissm_pose_graph_add_edge")
        flag = _flag(robust)
        transform_array = _matrix(transform, "transform", 4)
        information_array = _matrix(information, "information", 6)
        out = ffi.new("uint64_t *")
        with self._call_lock:
            status = lib.kissm_pose_graph_add_edge(
                self._handle(),
                s,
                t,
                ffi.from_buffer("double[]", transform_array),
                ffi.from_buffer("double[]", information_array),
                flag,
                out,
            )
            if status != 0:
                raise_status(status)  # reads the thread-local message before any other call
        return int(out[0])

    def optimize(self, anchor: int = 0, bound: float = DEFAULT_BOUND) -> PoseGraphSolution:
        """Find every node's pose in the frame of node ``anchor`` (whose own pose is the identity) and decide
        which robust edges to keep.

        Starts from a spanning tree of the graph from the anchor (trusted edges first, then the most
        informative), then runs Levenberg-Marquardt on SE(3); robust edges are weighed by graduated
        non-convexity, and one whose squared error ``xi^T I xi`` ends above ``bound`` is rejected. The default
        :attr:`DEFAULT_BOUND` suits calibrated informations (``Result.information``). Nodes that accepted edges
        do not join to the anchor are not placed (NaN poses). The same graph gives bitwise the same solution on
        every run.

        Raises:
            TypeError: ``anchor`` is not an integer or ``bound`` not a real number.
            kissm.InvalidArgumentError: ``anchor`` is not in the graph, or ``bound`` is not a finite number above
                0.
            kissm.CancelledError: :meth:`cancel` stopped the optimisation.
        """
        a = _node(anchor, "anchor", self._num_nodes, "kissm_pose_graph_optimize")
        b = _bound(bound)
        n = self._num_nodes
        with self._call_lock:
            ptr = self._handle()
            m = int(lib.kissm_pose_graph_num_edges(ptr))
            # Allocated before the optimisation, so that a lack of memory shows before the work, not after it.
            poses = np.empty((n, 4, 4), dtype=np.float64)
            placed = np.empty(n, dtype=np.uint8)
            components = np.empty(n, dtype=np.uint64)
            accepted = np.empty(m, dtype=np.uint8)
            residuals = np.empty(m, dtype=np.float64)
            status = lib.kissm_pose_graph_optimize(ptr, a, b)
            if status != 0:
                raise_status(status)
            out_poses = _output("double[]", poses)
            out_components = _output("uint64_t[]", components)
            check(lib.kissm_pose_graph_poses(ptr, out_poses, _output("uint8_t[]", placed), out_components))
            check(lib.kissm_pose_graph_edges(ptr, _output("uint8_t[]", accepted), _output("double[]", residuals)))
        return PoseGraphSolution(
            poses=poses,
            placed=placed.astype(bool),
            components=components.astype(np.int64),
            accepted=accepted.astype(bool),
            residuals=residuals,
        )

    def cancel(self) -> None:
        """Ask the :meth:`optimize` running on this graph (in another thread) to stop with
        :class:`kissm.CancelledError`. Callable from any thread. The library drops a request made before the
        optimisation starts, so a call with no optimisation running does nothing (and does not cancel the next
        one)."""
        with self._handle_lock:
            if self._ptr is not None:
                lib.kissm_pose_graph_cancel(self._ptr)

    def close(self) -> None:
        """Free the C graph now (waiting for a running call). Idempotent."""
        with self._call_lock, self._handle_lock:
            ptr, self._ptr = self._ptr, None
        if ptr is not None:
            ffi.release(ptr)

    def __enter__(self) -> PoseGraph:
        self._handle()
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def __repr__(self) -> str:
        head = f"<kissm.PoseGraph: {self._num_nodes} nodes"
        if not self._call_lock.acquire(blocking=False):  # never wait in a repr (a debugger's, a log's)
            return f"{head}, busy>"
        try:
            if self._ptr is None:
                return f"{head} (closed)>"
            return f"{head}, {int(lib.kissm_pose_graph_num_edges(self._ptr))} edges>"
        finally:
            self._call_lock.release()
