# SPDX-License-Identifier: MIT
"""ROS 1 bags, ROS 2 bags (sqlite3 and MCAP storage) and MCAP files through rosbags (pure Python, no ROS install;
the extra ``kissm[ros]``): the ``sensor_msgs/PointCloud2`` messages of one topic as (N, 3) float64 points."""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from ._errors import InvalidArgumentError, IoError, ParseError
from ._optional import require

POINTCLOUD2 = "sensor_msgs/msg/PointCloud2"

# sensor_msgs/PointField datatypes (INT8 = 1 ... FLOAT64 = 8) as numpy kinds; the byte order comes from the
# message's is_bigendian.
_DATATYPES = {1: "i1", 2: "u1", 3: "i2", 4: "u2", 5: "i4", 6: "u4", 7: "f4", 8: "f8"}


def _cloud_topics(reader: Any) -> list[str]:
    return sorted(name for name, info in reader.topics.items() if info.msgtype == POINTCLOUD2)


def _choose_topic(reader: Any, topic: str | None, path: str) -> str:
    clouds = _cloud_topics(reader)
    if topic is None:
        if len(clouds) == 1:
            return clouds[0]
        if not clouds:
            raise InvalidArgumentError(f"read_bag: {path} has no {POINTCLOUD2} topic (its topics: {_listed(reader)})")
        raise InvalidArgumentError(
            f"read_bag: {path} has {len(clouds)} {POINTCLOUD2} topics ({', '.join(clouds)}); pass topic= to pick one"
        )
    if topic not in clouds:
        listed = ", ".join(clouds) or "none"
        if topic in reader.topics:
            raise InvalidArgumentError(
                f"read_bag: topic {topic!r} of {path} holds {reader.topics[topic].msgtype}, not {POINTCLOUD2}; "
                f"its {POINTCLOUD2} topics: {listed}"
            )
        raise InvalidArgumentError(f"read_bag: {path} has no topic {topic!r}; its {POINTCLOUD2} topics: {listed}")
    return topic


def _listed(reader: Any) -> str:
    return ", ".join(f"{name} ({info.msgtype})" for name, info in sorted(reader.topics.items())) or "none"


def cloud_points(message: Any, what: str = "PointCloud2") -> np.ndarray:
    """(N, 3) float64 x, y, z of a ``sensor_msgs/PointCloud2`` (any numeric field type, either byte order, rows
    padded to ``row_step``), the points with a NaN coordinate left out (a return the sensor did not get)."""
    fields = {f.name: f for f in message.fields}
    missing = [axis for axis in "xyz" if axis not in fields]
    if missing:
        raise ParseError(f"{what}: no field {', '.join(missing)} (its fields: {', '.join(fields) or 'none'})")
    width, height = int(message.width), int(message.height)
    step, row_step = int(message.point_step), int(message.row_step)
    data = np.asarray(message.data, dtype=np.uint8).reshape(-1)
    if width * height == 0:
        return np.zeros((0, 3))
    if row_step < width * step:
        raise ParseError(f"{what}: row_step {row_step} is shorter than width {width} x point_step {step}")
    if data.size < (height - 1) * row_step + width * step:
        raise ParseError(
            f"{what}: {data.size} bytes of data for {height} rows of {row_step} bytes ({width} points of {step})"
        )
    order = ">" if message.is_bigendian else "<"
    # The records, one per point: the first width * point_step bytes of each row (the rest of a row is padding).
    rows = np.lib.stride_tricks.as_strided(data, shape=(height, width * step), strides=(row_step, 1))
    records = np.ascontiguousarray(rows).reshape(height * width, step)
    points = np.empty((height * width, 3))
    for k, axis in enumerate("xyz"):
        field = fields[axis]
        kind = _DATATYPES.get(int(field.datatype))
        if kind is None:
            raise ParseError(f"{what}: field {axis} has datatype {field.datatype}; sensor_msgs/PointField's 1 to 8")
        dtype = np.dtype(order + kind)
        offset = int(field.offset)
        if offset < 0 or offset + dtype.itemsize > step:
            raise ParseError(
                f"{what}: field {axis} ({dtype.itemsize} bytes at offset {offset}) lies outside point_step {step}"
            )
        raw = records[:, offset : offset + dtype.itemsize].copy().view(dtype).reshape(-1)
        points[:, k] = raw  # every PointField type converts to float64 exactly
    return points[~np.isnan(points).any(axis=1)]


def read_bag(path: str | os.PathLike[str], topic: str | None = None) -> Iterator[tuple[int, np.ndarray]]:
    """The ``sensor_msgs/PointCloud2`` messages of one topic of a ROS 1 bag (``.bag``), a ROS 2 bag (its
    directory, sqlite3 or MCAP storage) or an MCAP file, in the order they were recorded: ``(stamp, points)``
    with ``stamp`` the message header's time in integer nanoseconds (``stamp / 1e9`` seconds, e.g. for
    :func:`write_tum`) and ``points`` an (N, 3) float64 array of its x, y, z fields (any numeric PointField type,
    either byte order), points with a NaN coordinate left out.

    ``topic``: the topic to read; when not given, the bag's only PointCloud2 topic.

    The bag is opened and the topic checked by this call (so its errors raise here, not at the first message);
    the messages are read one at a time as the iterator is consumed.

    Raises :class:`kissm.InvalidArgumentError` (a ``ValueError``) when ``topic`` is not given and the bag holds
    no PointCloud2 topic or several (the message lists them), or names no PointCloud2 topic of the bag (the
    message lists those there are); :class:`kissm.IoError` when ``path`` does not exist;
    :class:`kissm.ParseError` when the bag or a message cannot be read; ``ModuleNotFoundError`` naming
    ``pip install kissm[ros]`` when rosbags is missing.
    """
    where = Path(os.fspath(path))
    with _Bag(where) as reader:
        chosen = _choose_topic(reader, topic, str(where))
    return _messages(where, chosen)


class _Bag:
    """An opened rosbags AnyReader, its errors as ours."""

    def __init__(self, where: Path) -> None:
        self.highlevel = require("rosbags.highlevel", "ros", "reading ROS bags and MCAP")
        typesys = require("rosbags.typesys", "ros", "reading ROS bags and MCAP")
        if not where.exists():
            raise IoError(f"read_bag: {where}: no such file or directory")
        self.where = where
        # Bags carry their message definitions (ROS 1 always, ROS 2 since Iron); older ROS 2 bags need a store.
        store = typesys.get_typestore(typesys.Stores.LATEST)
        try:
            self.reader = self.highlevel.AnyReader([where], default_typestore=store)
        except (self.highlevel.AnyReaderError, OSError, ValueError) as e:
            raise ParseError(f"read_bag: {where}: {e}") from e

    def __enter__(self) -> Any:
        try:
            self.reader.open()
        except (self.highlevel.AnyReaderError, OSError, ValueError) as e:
            raise ParseError(f"read_bag: {self.where}: {e}") from e
        return self.reader

    def __exit__(self, *exc: object) -> None:
        self.reader.close()


def _messages(where: Path, chosen: str) -> Iterator[tuple[int, np.ndarray]]:
    opened = _Bag(where)
    with opened as reader:
        connections = [c for c in reader.connections if c.topic == chosen]
        for connection, _, raw in reader.messages(connections=connections):
            try:
                message = reader.deserialize(raw, connection.msgtype)
            except opened.highlevel.AnyReaderError as e:
                raise ParseError(f"read_bag: {where}: a message of {chosen}: {e}") from e
            stamp = int(message.header.stamp.sec) * 1_000_000_000 + int(message.header.stamp.nanosec)
            yield stamp, cloud_points(message, f"read_bag: {where}: {chosen} at {stamp} ns")
