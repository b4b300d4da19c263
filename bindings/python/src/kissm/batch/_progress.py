# SPDX-License-Identifier: MIT
"""Progress of a batch: a bar on stderr (tqdm's when it is installed, else one rewritten line), or the caller's
callable. The only output this package ever writes, and only when asked for or on a terminal."""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Hashable
from typing import Any

from ._values import PairResult, Progress

#: Seconds between two redraws of the plain stderr line (a million pairs must not mean a million writes).
_REDRAW_SECONDS = 0.5


class _Line:
    """``kissm.batch: described 3/5 clouds, registered 2/10 pairs``, redrawn in place on stderr."""

    def __init__(self) -> None:
        self._last = 0.0
        self._text = ""

    def show(self, text: str, final: bool = False) -> None:
        self._text = text
        now = time.monotonic()
        if final or now - self._last >= _REDRAW_SECONDS:
            self._last = now
            sys.stderr.write(f"\r{text}")
            sys.stderr.flush()

    def close(self) -> None:
        if self._text:
            self.show(self._text, final=True)
            sys.stderr.write("\n")
            sys.stderr.flush()


class _Tqdm:
    def __init__(self, tqdm: Any, total: int) -> None:
        self._bar = tqdm(total=total, desc="kissm.batch", unit="job", file=sys.stderr, leave=True)

    def show(self, text: str) -> None:
        self._bar.set_postfix_str(text, refresh=False)
        self._bar.update(1)

    def close(self) -> None:
        self._bar.close()


def _bar(total: int) -> _Line | _Tqdm:
    try:
        from tqdm import tqdm  # optional: the plain line does without it
    except ImportError:
        return _Line()
    return _Tqdm(tqdm, total)


def check_progress(progress: object) -> None:
    """Raise before any work when ``progress`` is none of the accepted values."""
    from .._errors import InvalidArgumentError

    if not (progress is None or isinstance(progress, bool) or callable(progress)):
        raise InvalidArgumentError(
            f"progress must be True, False, None (a bar when stderr is a terminal) or a callable taking a "
            f"kissm.batch.Progress, not {type(progress).__name__}"
        )


class Reporter:
    """Counts the finished jobs of a batch and tells ``progress`` about each."""

    def __init__(self, progress: bool | None | Callable[[Progress], object], describes: int, pairs: int) -> None:
        self._totals = {"describe": describes, "register": pairs}
        self._done = {"describe": 0, "register": 0}
        self._callback: Callable[[Progress], object] | None = None
        self._bar: _Line | _Tqdm | None = None
        if callable(progress) and not isinstance(progress, bool):
            self._callback = progress
        elif progress or (progress is None and sys.stderr is not None and sys.stderr.isatty()):
            self._bar = _bar(describes + pairs)

    def described(self, key: Hashable, index: int) -> None:
        self._finished("describe", key, index, None)

    def registered(self, index: int, pair: PairResult) -> None:
        self._finished("register", (pair.source, pair.target), index, pair)

    def _finished(self, stage: Any, key: Hashable, index: int, pair: PairResult | None) -> None:
        self._done[stage] += 1
        if self._callback is not None:
            self._callback(Progress(stage, key, index, self._done[stage], self._totals[stage], pair))
        if self._bar is not None:
            d, r = self._done["describe"], self._done["register"]
            text = f"described {d}/{self._totals['describe']} clouds, registered {r}/{self._totals['register']} pairs"
            if isinstance(self._bar, _Line):
                self._bar.show(f"kissm.batch: {text}")
            else:
                self._bar.show(text)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
