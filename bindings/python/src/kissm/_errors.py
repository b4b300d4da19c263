# SPDX-License-Identifier: MIT
"""Exceptions: one class per kissm status code, each carrying the library's message."""

from __future__ import annotations

from typing import NoReturn

from ._ffi import lib, text


class Error(Exception):
    """Base class of every error the kissm library reports.

    ``str(error)`` is the library's detailed message (it names the offending argument); ``status`` is the
    C status code (a negative ``KISSM_ERR_*`` value) and ``status_name`` its name.
    """

    status: int = 0
    """The C status code, a negative ``KISSM_ERR_*`` value (each subclass has its own)."""
    status_name: str = ""
    """The name of ``status``, e.g. ``"KISSM_ERR_TOO_FEW_POINTS"``."""

    def __init__(self, message: str, status: int | None = None) -> None:
        super().__init__(message)
        if status is not None and status != type(self).status:
            self.status = status
            self.status_name = f"status {status}"

    @property
    def message(self) -> str:
        """The library's message."""
        return str(self.args[0]) if self.args else ""

    def __reduce__(self) -> tuple[type[Error], tuple[str, int]]:
        # Rebuilt through __init__ (message, status). Without its own __reduce__, tblib's exception pickling
        # (installed by Dask) takes an Error for one it must rebuild through __new__, which MemoryError's refuses
        # for OutOfMemoryError: a job's error could not travel back from a Dask worker.
        return (type(self), (self.message, self.status))


class InvalidArgumentError(Error, ValueError):
    """A config value or argument is out of its documented range (KISSM_ERR_INVALID_ARGUMENT)."""


class NullArgumentError(Error, ValueError):
    """A required pointer was NULL (KISSM_ERR_NULL_ARGUMENT); the Python API never passes one."""


class EmptyInputError(Error, ValueError):
    """A cloud has no points, or none left after dropping non-finite ones (KISSM_ERR_EMPTY_INPUT)."""


class TooFewPointsError(Error, ValueError):
    """A cloud has fewer than ``kissm.MIN_POINTS`` points (KISSM_ERR_TOO_FEW_POINTS)."""


class NonFiniteError(Error, ValueError):
    """A NaN or infinite coordinate under ``nonfinite_policy='reject'`` (KISSM_ERR_NONFINITE)."""


class VoxelRangeError(Error, ValueError):
    """The voxel size is too small for the cloud's extent (KISSM_ERR_VOXEL_RANGE)."""


class StructSizeError(Error):
    """A struct size the library does not accept (KISSM_ERR_STRUCT_SIZE): a packaging error."""


class OutOfMemoryError(Error, MemoryError):
    """An allocation failed; nothing was changed (KISSM_ERR_OUT_OF_MEMORY)."""


class CancelledError(Error):
    """``Matcher.cancel()`` stopped the call (KISSM_ERR_CANCELLED)."""


class FeaturesMismatchError(Error, ValueError):
    """Features computed under different descriptor settings than the matcher's (KISSM_ERR_FEATURES_MISMATCH)."""


class IoError(Error, OSError):
    """A file could not be opened or read (KISSM_ERR_IO)."""


class ParseError(Error, ValueError):
    """A file, or the bytes given to ``Features.from_bytes``, is malformed, truncated or of an unsupported layout
    (KISSM_ERR_PARSE)."""


class UnsupportedFormatError(Error, ValueError):
    """A file's format is not recognised (KISSM_ERR_UNSUPPORTED_FORMAT)."""


class InternalError(Error):
    """A bug in kissm (KISSM_ERR_INTERNAL): please report it with the message."""


ERROR_CLASSES: dict[int, type[Error]] = {}
for _cls, _name in (
    (InvalidArgumentError, "KISSM_ERR_INVALID_ARGUMENT"),
    (NullArgumentError, "KISSM_ERR_NULL_ARGUMENT"),
    (EmptyInputError, "KISSM_ERR_EMPTY_INPUT"),
    (TooFewPointsError, "KISSM_ERR_TOO_FEW_POINTS"),
    (NonFiniteError, "KISSM_ERR_NONFINITE"),
    (VoxelRangeError, "KISSM_ERR_VOXEL_RANGE"),
    (StructSizeError, "KISSM_ERR_STRUCT_SIZE"),
    (OutOfMemoryError, "KISSM_ERR_OUT_OF_MEMORY"),
    (CancelledError, "KISSM_ERR_CANCELLED"),
    (FeaturesMismatchError, "KISSM_ERR_FEATURES_MISMATCH"),
    (IoError, "KISSM_ERR_IO"),
    (ParseError, "KISSM_ERR_PARSE"),
    (UnsupportedFormatError, "KISSM_ERR_UNSUPPORTED_FORMAT"),
    (InternalError, "KISSM_ERR_INTERNAL"),
):
    _cls.status = int(getattr(lib, _name))
    _cls.status_name = _name
    ERROR_CLASSES[_cls.status] = _cls
del _cls, _name


def status_string(status: int) -> str:
    """The library's static description of a status code."""
    return text(lib.kissm_status_string(status))


def raise_status(status: int) -> NoReturn:
    """Raise the exception for a failed call. Must run right after the call, on the same thread (the
    library's message is thread-local and overwritten by the next call)."""
    message = text(lib.kissm_last_error_message()) or status_string(status)
    cls = ERROR_CLASSES.get(status, Error)
    raise cls(message, status)


def check(status: int) -> None:
    """Raise the matching :class:`Error` subclass when ``status`` is not KISSM_OK."""
    if status != 0:
        raise_status(status)
