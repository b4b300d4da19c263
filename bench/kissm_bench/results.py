# SPDX-License-Identifier: MIT
"""Saving a run's results and reading them back.

Two forms: the *raw* results, every record a run made, as indented JSON (``--raw FILE``, and a run's default in
any --out but the committed one); and the *reduced* results, only the fields a page is rendered from (each page
module's ``reduce``), as gzip-compressed JSON written byte for byte the same from the same data (sorted keys,
compact separators, no time stamp in the gzip header). bench/results/ holds the reduced results of the committed
pages: ``python bench/<script> --report-from bench/results/<name>.json.gz`` (report.py takes the file as its
argument) rewrites a page from them.
"""

from __future__ import annotations

import gzip
import hashlib
import json
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any

from .common import is_committed, repo_relative


def _default(value: Any) -> Any:
    """numpy arrays and scalars in a record: as lists and Python numbers."""
    tolist = getattr(value, "tolist", None)
    if tolist is None:
        raise TypeError(f"{type(value).__name__} is not JSON serializable")
    return tolist()


def write_raw(path: Path, results: Mapping[str, Any]) -> None:
    """The raw results, indented JSON (in the records' own key order)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(results, indent=1, default=_default) + "\n")


def encode_reduced(reduced: Mapping[str, Any]) -> bytes:
    """The bytes of a reduced results file: the same data always gives the same bytes."""
    text = json.dumps(reduced, sort_keys=True, separators=(",", ":"), default=_default) + "\n"
    return gzip.compress(text.encode(), compresslevel=9, mtime=0)


def write_reduced(path: Path, reduced: Mapping[str, Any]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(encode_reduced(reduced))


def destinations(
    committed: Path, raw_name: str, out: Path, smoke: bool, raw: Path | None
) -> tuple[Path | None, Path | None]:
    """Where a run saves its results: the reduced ones to ``committed`` (in bench/results/) when the run writes the
    committed page, else nowhere; the raw ones to ``raw`` when asked for, else to OUT/``raw_name`` outside the
    committed location."""
    reduced = committed if is_committed(out, smoke) else None
    if raw is None and reduced is None:
        raw = out / raw_name
    return reduced, raw


def shown(reduced: Path | None, raw: Path | None) -> str:
    """The results file a page names (as the page quotes it): the reduced one when the run writes it, else the raw
    one."""
    path = reduced or raw
    if path is None:
        raise ValueError("destinations() always gives a run somewhere to save its results")
    return repo_relative(path)


def save(results: Mapping[str, Any], reduced: Mapping[str, Any], committed: Path | None, raw: Path | None) -> None:
    """A run's results: the reduced ones to ``committed`` (bench/results/, when the run writes the committed page)
    and the raw ones to ``raw`` (when asked for, or by default outside the committed location)."""
    if committed is not None:
        write_reduced(committed, reduced)
    if raw is not None:
        write_raw(raw, results)


def read(path: Path) -> dict[str, Any]:
    """Saved results, raw (.json) or reduced (.json.gz). A ``NAME.json`` that is absent is read from
    ``NAME.json.gz``: the pages written before the results were reduced name the .json files."""
    if not path.exists() and path.with_name(path.name + ".gz").is_file():
        path = path.with_name(path.name + ".gz")
    data = path.read_bytes()
    if data[:2] == b"\x1f\x8b":  # gzip's magic number
        data = gzip.decompress(data)
    loaded = json.loads(data)
    if not isinstance(loaded, dict):
        raise ValueError(f"{path}: not a results file (a JSON object)")
    return loaded


def rewrite_page(tag: str, saved: Path, out: Path, write: Callable[[dict[str, Any], Path], list[Path]]) -> int:
    """``--report-from``: the page (and its plots) rewritten into ``out`` from the results saved in ``saved``."""
    for path in write(read(saved), out):
        print(f"{tag}: wrote {path}")
    return 0


def pick(record: Mapping[str, Any], keys: Iterable[str]) -> dict[str, Any]:
    """The fields ``keys`` of ``record`` that it has (a field's presence can matter to a page)."""
    return {k: record[k] for k in keys if k in record}


def pose_digest(transform: Any) -> str:
    """A short fingerprint of a pose (its JSON text: equal poses, bit for bit, give equal fingerprints), for the
    pages that only ask whether two poses are the same."""
    return hashlib.sha256(json.dumps(transform, default=_default).encode()).hexdigest()[:16]
