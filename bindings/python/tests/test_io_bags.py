# SPDX-License-Identifier: MIT
"""ROS bags and MCAP through ``kissm.io.read_bag`` (rosbags, the extra ``kissm[ros]``): ROS 1 bags, ROS 2 bags
with sqlite3 and MCAP storage, and a bare MCAP file, written by rosbags (the reference writer) from a real cloud
of ../shared/data and from a synthetic one. ``sensor_msgs/PointCloud2`` messages with float32 fields (a NaN
point, an intensity field, padded rows of an organised cloud), float64 fields in big-endian order and
reversed offsets, and int16 fields: the points read are the ones written, bit for bit, NaN points left out, in
recording order with their header stamps; the topic is guessed only when there is one, and wrong or missing
topics raise errors that name the available ones."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import kissm
import kissm.io

from realdata import RealPair, read_cached

FLOAT32, FLOAT64, INT16 = 7, 8, 3
KINDS = ("ros1", "ros2_sqlite3", "ros2_mcap")


@pytest.fixture()
def rosbags() -> Any:
    """The reference writer; the test extra installs it (bindings/python/run_tests.sh), package_test.sh's venvs
    do not (test_malformed_clouds needs no rosbags)."""
    return pytest.importorskip(
        "rosbags", reason="rosbags is not installed (it is in the test extra: pip install .[test])"
    )


def typestore(kind: str) -> Any:
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS1_NOETIC if kind == "ros1" else Stores.LATEST)


class Message:
    """A PointCloud2 to write: its layout and the points a reader must return."""

    def __init__(self, stamp: int, fields: list[tuple[str, int, int]], point_step: int, records: bytes) -> None:
        self.stamp, self.fields, self.point_step, self.records = stamp, fields, point_step, records
        self.height, self.width, self.row_step, self.bigendian = 1, 0, 0, False


def packed(columns: dict[str, np.ndarray], layout: list[tuple[str, int, str]], point_step: int) -> bytes:
    """Records of ``point_step`` bytes, each column at its offset in its numpy dtype (padding bytes 0xAB)."""
    n = len(next(iter(columns.values())))
    out = np.full((n, point_step), 0xAB, dtype=np.uint8)
    for name, offset, dtype in layout:
        raw = np.ascontiguousarray(columns[name].astype(dtype)).view(np.uint8).reshape(n, -1)
        out[:, offset : offset + raw.shape[1]] = raw
    return out.tobytes()


def float32_message(points: np.ndarray, stamp: int) -> tuple[Message, np.ndarray]:
    """x y z intensity as float32 (16-byte records), the third point NaN."""
    xyz = points.astype(np.float32)
    xyz[2] = np.nan
    columns = {"x": xyz[:, 0], "y": xyz[:, 1], "z": xyz[:, 2], "intensity": np.arange(len(xyz), dtype=np.float32)}
    layout = [("x", 0, "<f4"), ("y", 4, "<f4"), ("z", 8, "<f4"), ("intensity", 12, "<f4")]
    message = Message(stamp, [(n, o, FLOAT32) for n, o, _ in layout], 16, packed(columns, layout, 16))
    message.width = len(xyz)
    message.row_step = 16 * len(xyz)
    expected = np.delete(xyz, 2, axis=0).astype(np.float64)
    return message, expected


def organised_message(points: np.ndarray, stamp: int) -> tuple[Message, np.ndarray]:
    """float32 x y z in 4 rows, each padded by 8 bytes beyond width * point_step."""
    rows = 4
    width = len(points) // rows
    xyz = points[: rows * width].astype(np.float32)
    records = packed(
        {"x": xyz[:, 0], "y": xyz[:, 1], "z": xyz[:, 2]}, [("x", 0, "<f4"), ("y", 4, "<f4"), ("z", 8, "<f4")], 12
    )
    row_step = 12 * width + 8
    data = b"".join(records[r * 12 * width : (r + 1) * 12 * width] + b"\xcd" * 8 for r in range(rows))
    message = Message(stamp, [("x", 0, FLOAT32), ("y", 4, FLOAT32), ("z", 8, FLOAT32)], 12, data)
    message.height, message.width, message.row_step = rows, width, row_step
    return message, xyz.astype(np.float64)


def float64_message(points: np.ndarray, stamp: int) -> tuple[Message, np.ndarray]:
    """float64 big-endian, z y x at offsets 0 8 16, 32-byte records."""
    layout = [("z", 0, ">f8"), ("y", 8, ">f8"), ("x", 16, ">f8")]
    columns = {"x": points[:, 0], "y": points[:, 1], "z": points[:, 2]}
    message = Message(stamp, [(n, o, FLOAT64) for n, o, _ in layout], 32, packed(columns, layout, 32))
    message.width, message.row_step, message.bigendian = len(points), 32 * len(points), True
    return message, points.copy()


def int16_message(points: np.ndarray, stamp: int) -> tuple[Message, np.ndarray]:
    """int16 x y z (centimetres, clipped), 6-byte records."""
    ints = np.clip(np.round(points * 100), -32768, 32767).astype(np.int16)
    layout = [("x", 0, "<i2"), ("y", 2, "<i2"), ("z", 4, "<i2")]
    columns = {"x": ints[:, 0], "y": ints[:, 1], "z": ints[:, 2]}
    message = Message(stamp, [(n, o, INT16) for n, o, _ in layout], 6, packed(columns, layout, 6))
    message.width, message.row_step = len(points), 6 * len(points)
    return message, ints.astype(np.float64)


Maker = Callable[[np.ndarray, int], tuple[Message, np.ndarray]]
#: Topic -> the messages written on it (each from a different slice of the cloud).
TOPICS: dict[str, list[Maker]] = {
    "/lidar/f32": [float32_message, organised_message, float32_message],
    "/lidar/mixed": [float64_message, int16_message],
}


def ros_message(store: Any, kind: str, message: Message) -> Any:
    types = store.types
    stamp = types["builtin_interfaces/msg/Time"](sec=message.stamp // 10**9, nanosec=message.stamp % 10**9)
    header_type = types["std_msgs/msg/Header"]
    header = (
        header_type(seq=0, stamp=stamp, frame_id="lidar")
        if kind == "ros1"
        else header_type(stamp=stamp, frame_id="lidar")
    )
    field = types["sensor_msgs/msg/PointField"]
    return types["sensor_msgs/msg/PointCloud2"](
        header=header,
        height=message.height,
        width=message.width,
        fields=[field(name=n, offset=o, datatype=d, count=1) for n, o, d in message.fields],
        is_bigendian=message.bigendian,
        point_step=message.point_step,
        row_step=message.row_step,
        data=np.frombuffer(message.records, dtype=np.uint8),
        is_dense=False,
    )


def write_bag(
    path: Path, kind: str, cloud: np.ndarray, topics: dict[str, list[Maker]]
) -> dict[str, list[tuple[int, np.ndarray]]]:
    """A bag of ``kind`` with ``topics`` and a std_msgs/String topic; returns what read_bag must give per topic.
    Messages are recorded in stamp order, the topics interleaved."""
    store = typestore(kind)
    expected: dict[str, list[tuple[int, np.ndarray]]] = {topic: [] for topic in topics}
    plan = []
    for t, (topic, makers) in enumerate(topics.items()):
        for k, make in enumerate(makers):
            stamp = 1_700_000_000_123_456_789 + (2 * k + t) * 100_000_000
            part = cloud[(k * 997 + t * 331) % len(cloud) :][:5000]
            message, points = make(part, stamp)
            plan.append((stamp, topic, message))
            expected[topic].append((stamp, points))
    plan.sort(key=lambda item: item[0])
    serialize = store.serialize_ros1 if kind == "ros1" else store.serialize_cdr
    cloud_type = "sensor_msgs/msg/PointCloud2"
    if kind == "ros1":
        from rosbags.rosbag1 import Writer

        writer: Any = Writer(path)
    else:
        from rosbags.rosbag2 import StoragePlugin, Writer

        plugin = StoragePlugin.MCAP if kind == "ros2_mcap" else StoragePlugin.SQLITE3
        writer = Writer(path, version=9, storage_plugin=plugin)
    with writer:
        connections = {topic: writer.add_connection(topic, cloud_type, typestore=store) for topic in topics}
        note = writer.add_connection("/note", "std_msgs/msg/String", typestore=store)
        writer.write(
            note,
            1_600_000_000_000_000_000,
            serialize(store.types["std_msgs/msg/String"](data="hi"), "std_msgs/msg/String"),
        )
        for stamp, topic, message in plan:
            writer.write(connections[topic], stamp, serialize(ros_message(store, kind, message), cloud_type))
    return expected


def bag_path(folder: Path, kind: str) -> Path:
    return folder / ("drive.bag" if kind == "ros1" else f"drive_{kind}")


def check_topic(path: Path, topic: str | None, expected: list[tuple[int, np.ndarray]]) -> None:
    got = list(kissm.io.read_bag(path, topic=topic))
    assert [stamp for stamp, _ in got] == [stamp for stamp, _ in expected]
    for (_, points), (_, want) in zip(got, expected, strict=True):
        assert points.dtype == np.float64 and points.shape == want.shape
        assert np.array_equal(points, want)  # bit for bit, no NaN left


def synthetic_cloud() -> np.ndarray:
    return np.random.default_rng(11).uniform(-80, 80, size=(6000, 3))


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.usefixtures("rosbags")
def test_synthetic_bags(tmp_path: Path, kind: str) -> None:
    """No real data needed."""
    path = bag_path(tmp_path, kind)
    expected = write_bag(path, kind, synthetic_cloud(), TOPICS)
    for topic, messages in expected.items():
        check_topic(path, topic, messages)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.usefixtures("rosbags")
def test_real_cloud_bags(real_pairs: dict[str, RealPair], tmp_path: Path, kind: str) -> None:
    lidar = [p for p in real_pairs.values() if p.is_lidar]
    assert lidar, "no LiDAR pair in the real data's index.tsv"
    cloud = read_cached(lidar[0].source, lidar[0].source_format)
    path = bag_path(tmp_path, kind)
    expected = write_bag(path, kind, cloud, TOPICS)
    for topic, messages in expected.items():
        check_topic(path, topic, messages)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.usefixtures("rosbags")
def test_the_only_cloud_topic_is_guessed(tmp_path: Path, kind: str) -> None:
    path = bag_path(tmp_path, kind)
    expected = write_bag(path, kind, synthetic_cloud(), {"/points": [float64_message, float32_message]})
    check_topic(path, None, expected["/points"])


@pytest.mark.usefixtures("rosbags")
def test_bare_mcap_file(tmp_path: Path) -> None:
    """The .mcap file inside a ROS 2 bag directory, given alone."""
    path = bag_path(tmp_path, "ros2_mcap")
    expected = write_bag(path, "ros2_mcap", synthetic_cloud(), {"/points": [int16_message]})
    (mcap,) = path.glob("*.mcap")
    check_topic(mcap, None, expected["/points"])


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.usefixtures("rosbags")
def test_topic_errors(tmp_path: Path, kind: str) -> None:
    path = bag_path(tmp_path, kind)
    write_bag(path, kind, synthetic_cloud(), TOPICS)
    listed = "/lidar/f32, /lidar/mixed"
    with pytest.raises(kissm.InvalidArgumentError) as caught:
        kissm.io.read_bag(path)
    assert str(caught.value) == (
        f"read_bag: {path} has 2 sensor_msgs/msg/PointCloud2 topics ({listed}); pass topic= to pick one"
    )
    with pytest.raises(ValueError) as caught:  # InvalidArgumentError is a ValueError
        kissm.io.read_bag(path, topic="/lidar")
    assert (
        str(caught.value) == f"read_bag: {path} has no topic '/lidar'; its sensor_msgs/msg/PointCloud2 topics: {listed}"
    )
    with pytest.raises(kissm.InvalidArgumentError) as caught:
        kissm.io.read_bag(path, topic="/note")
    assert str(caught.value) == (
        f"read_bag: topic '/note' of {path} holds std_msgs/msg/String, not sensor_msgs/msg/PointCloud2; "
        f"its sensor_msgs/msg/PointCloud2 topics: {listed}"
    )


@pytest.mark.usefixtures("rosbags")
def test_no_cloud_topic_and_missing_bag(tmp_path: Path) -> None:
    path = bag_path(tmp_path, "ros1")
    write_bag(path, "ros1", synthetic_cloud(), {})
    with pytest.raises(kissm.InvalidArgumentError) as caught:
        kissm.io.read_bag(path)
    assert str(caught.value) == (
        f"read_bag: {path} has no sensor_msgs/msg/PointCloud2 topic (its topics: /note (std_msgs/msg/String))"
    )
    with pytest.raises(kissm.IoError) as caught:
        kissm.io.read_bag(tmp_path / "absent.bag")
    assert str(caught.value) == f"read_bag: {tmp_path / 'absent.bag'}: no such file or directory"
    junk = tmp_path / "junk.bag"
    junk.write_bytes(b"#ROSBAG V2.0\n" + bytes(64))
    with pytest.raises(kissm.ParseError, match=rf"^read_bag: {junk}: "):
        kissm.io.read_bag(junk)
    not_a_bag = tmp_path / "junk_dir"
    not_a_bag.mkdir()
    with pytest.raises(kissm.ParseError, match=rf"^read_bag: {not_a_bag}: "):
        kissm.io.read_bag(not_a_bag)


class Fake:
    """A PointCloud2 as rosbags deserialises one (attributes only), for the layout checks."""

    def __init__(self, **fields: Any) -> None:
        self.__dict__.update(fields)


def fake_cloud(**changes: Any) -> Fake:
    field = [Fake(name=n, offset=o, datatype=FLOAT32, count=1) for n, o in (("x", 0), ("y", 4), ("z", 8))]
    values: dict[str, Any] = dict(
        fields=field, width=2, height=1, point_step=12, row_step=24, is_bigendian=False, data=np.zeros(24, np.uint8)
    )
    values.update(changes)
    return Fake(**values)


def test_malformed_clouds() -> None:
    from kissm._bags import cloud_points

    assert cloud_points(fake_cloud()).shape == (2, 3)
    cases = [
        (fake_cloud(fields=[]), "m: no field x, y, z (its fields: none)"),
        (fake_cloud(row_step=20), "m: row_step 20 is shorter than width 2 x point_step 12"),
        (fake_cloud(data=np.zeros(23, np.uint8)), "m: 23 bytes of data for 1 rows of 24 bytes (2 points of 12)"),
    ]
    odd = fake_cloud()
    odd.fields[2] = Fake(name="z", offset=8, datatype=9, count=1)
    cases.append((odd, "m: field z has datatype 9; sensor_msgs/PointField's 1 to 8"))
    outside = fake_cloud()
    outside.fields[2] = Fake(name="z", offset=8, datatype=FLOAT64, count=1)
    cases.append((outside, "m: field z (8 bytes at offset 8) lies outside point_step 12"))
    for message, text in cases:
        with pytest.raises(kissm.ParseError) as caught:
            cloud_points(message, "m")
        assert str(caught.value) == text
