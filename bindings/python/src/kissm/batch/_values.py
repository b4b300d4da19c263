# SPDX-License-Identifier: MIT
"""The values ``kissm.batch`` takes and gives: a cloud file, a pair's outcome, a progress event."""

from __future__ import annotations

import dataclasses
from collections.abc import Hashable
from typing import Literal, NamedTuple

from .._errors import Error
from .._result import Result


class CloudFile(NamedTuple):
    """A cloud given as a file, read by the job that describes it (on the worker, so the path must be readable
    there): ``path`` and the ``format`` of :func:`kissm.read_points`. A plain ``str`` or ``os.PathLike`` in
    ``clouds`` means ``CloudFile(path, "auto")``, which picks by extension: KITTI keyframes stored as raw float32
    x y z need ``"bin_xyz_f32"``."""

    path: str
    """The file's path, as the worker sees it."""
    format: str = "auto"
    """A name of :data:`kissm.FORMATS`."""


@dataclasses.dataclass(frozen=True)
class PairResult:
    """The outcome of one pair of :func:`kissm.batch.register_many`: exactly one of ``result`` and ``error`` is
    None."""

    source: Hashable
    """The source cloud's key."""
    target: Hashable
    """The target cloud's key."""
    result: Result | None
    """The registration (which may be ``valid=False``), or None when ``error`` is set."""
    error: Error | None
    """None, or the :class:`kissm.Error` that stopped this pair: the registration's, or that of a cloud that could
    not be described (its class kept, e.g. :class:`kissm.IoError` for a missing file or
    :class:`kissm.TooFewPointsError`; its message starts with ``source:`` or ``target:``)."""

    @property
    def ok(self) -> bool:
        """Whether the pair was registered (``error`` is None); the pose may still be ``valid=False``."""
        return self.error is None


@dataclasses.dataclass(frozen=True)
class Progress:
    """One finished job, as given to a ``progress`` callable of :func:`kissm.batch.register_many` or
    :func:`kissm.batch.describe_many` (on the calling thread, in completion order)."""

    stage: Literal["describe", "register"]
    """``"describe"``: a cloud's features were computed (or failed); ``"register"``: a pair was registered."""
    key: Hashable
    """The cloud's key, or the pair's ``(source, target)``."""
    index: int
    """The pair's position in ``pairs``; for ``"describe"``, the cloud's position among the clouds described."""
    done: int
    """Jobs of this stage finished so far, this one included."""
    total: int
    """Jobs of this stage in the batch."""
    pair: PairResult | None = None
    """The pair's outcome (``"register"`` only)."""
