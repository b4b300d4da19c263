#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Writes the fuzz targets' seed corpus (tests/fuzz/corpus/<target>/): small valid files for every reader
and byte strings for the pipeline targets that decode (tests/fuzz/fuzz_input.hpp) into a registrable pair.
Deterministic (fixed seeds); standard library only. Run from anywhere:  python3 tools/make_fuzz_seeds.py"""

import math
import random
import struct
from collections.abc import Sequence
from pathlib import Path

Point = tuple[float, float, float]

OUT = Path(__file__).resolve().parent.parent / "tests" / "fuzz" / "corpus"


def write(target: str, name: str, data: bytes | str) -> None:
    d = OUT / target
    d.mkdir(parents=True, exist_ok=True)
    (d / name).write_bytes(data if isinstance(data, bytes) else data.encode())


PTS = [(0.0, 0.0, 0.0), (1.0, 0.5, -0.25), (2.5, -1.0, 0.75), (-3.0, 4.0, 1.5), (0.125, 0.25, 8.0)]


def readers() -> None:
    v = "".join(f"{x} {y} {z}\n" for x, y, z in PTS)
    write(
        "ply",
        "ascii.ply",
        f"ply\nformat ascii 1.0\nelement vertex {len(PTS)}\nproperty float x\n"
        f"property float y\nproperty float z\nend_header\n{v}",
    )
    body = b"".join(struct.pack("<dddB", x, y, z, 7) for x, y, z in PTS)
    write(
        "ply",
        "binary_le_double.ply",
        (
            f"ply\nformat binary_little_endian 1.0\ncomment seed\n"
            f"element vertex {len(PTS)}\nproperty double x\nproperty double y\nproperty double z\n"
            f"property uchar intensity\nelement face 1\nproperty list uchar int vertex_indices\n"
            f"end_header\n"
        ).encode()
        + body
        + struct.pack("<Biii", 3, 0, 1, 2),
    )
    body = b"".join(struct.pack(">fff", x, y, z) for x, y, z in PTS)
    write(
        "ply",
        "binary_be_float.ply",
        (
            f"ply\nformat binary_big_endian 1.0\nelement vertex {len(PTS)}\n"
            f"property float32 x\nproperty float32 y\nproperty float32 z\nend_header\n"
        ).encode()
        + body,
    )

    head = (
        "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
        f"WIDTH {len(PTS)}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {len(PTS)}\n"
    )
    write("pcd", "ascii.pcd", head + "DATA ascii\n" + v)
    head4 = (
        "VERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n"
        f"WIDTH {len(PTS)}\nHEIGHT 1\nPOINTS {len(PTS)}\nDATA binary\n"
    )
    write("pcd", "binary.pcd", head4.encode() + b"".join(struct.pack("<ffff", x, y, z, 1.0) for x, y, z in PTS))

    def npy(descr: str, shape: tuple[int, int], values: Sequence[float], fmt: str) -> bytes:
        header = f"{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}"
        header += " " * ((64 - (10 + len(header) + 1) % 64) % 64) + "\n"
        return b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)) + header.encode() + struct.pack(fmt, *values)

    flat = [c for p in PTS for c in p]
    write("npy", "f4_n3.npy", npy("<f4", (len(PTS), 3), flat, f"<{len(flat)}f"))
    wide = [c for p in PTS for c in (*p, 9.0)]
    write("npy", "f8_n4.npy", npy("<f8", (len(PTS), 4), wide, f"<{len(wide)}d"))

    write("xyz", "plain.xyz", v)
    write("xyz", "commented.xyz", "# x y z r g b\n" + "".join(f"{x},{y},{z},1,2,3\n" for x, y, z in PTS))
    write("kitti_bin", "four.bin", b"".join(struct.pack("<ffff", x, y, z, 0.5) for x, y, z in PTS))
    write("bin_xyz", "four.bin", b"".join(struct.pack("<fff", x, y, z) for x, y, z in PTS))


LAS_MIN_RECORD = (20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67)


def las(
    minor: int,
    fmt: int,
    pts: Sequence[Point],
    *,
    extra: int = 0,
    withheld: Sequence[int] = (),
    scale: float = 1e-3,
    offset: float = 0.0,
    legacy: int | None = None,
    wide: int | None = None,
    fmt_id: int | None = None,
    vlrs: bytes = b"",
    header_scale: float | None = None,
) -> bytes:
    """A LAS file (ASPRS LAS 1.4 public header block layout): header, `vlrs`, then the points."""
    size = 375 if minor >= 4 else 235 if minor == 3 else 227
    record = LAS_MIN_RECORD[fmt] + extra
    n = len(pts)
    h = bytearray(size if size >= 375 else 375)
    h[0:4] = b"LASF"
    h[24:26] = bytes([1, minor])
    h[26:36] = b"kissm seed"
    struct.pack_into(
        "<HIIBHI",
        h,
        94,
        size,
        size + len(vlrs),
        1 if vlrs else 0,
        fmt if fmt_id is None else fmt_id,
        record,
        (0 if minor >= 4 and fmt >= 6 else n) if legacy is None else legacy,
    )
    hs = scale if header_scale is None else header_scale
    struct.pack_into("<3d3d", h, 131, hs, hs, hs, offset, offset, offset)
    if minor >= 4:
        struct.pack_into("<Q", h, 247, n if wide is None else wide)
    body = bytearray()
    for i, (x, y, z) in enumerate(pts):
        r = bytearray(record)
        struct.pack_into("<3i", r, 0, *(round((c - offset) / scale) for c in (x, y, z)))
        flags = (0x80 if fmt <= 5 else 0x04) if i in withheld else 0
        r[15] = flags | (2 if fmt <= 5 else 0)
        if fmt >= 6:
            r[16] = 2
        body += r
    return bytes(h[:size]) + vlrs + bytes(body)


def las_seeds() -> None:
    write("las", "v10_f0.las", las(0, 0, PTS))
    write("las", "v12_f3_extra.las", las(2, 3, PTS, extra=6, withheld=(1,)))
    write("las", "v13_f1_geo.las", las(3, 1, PTS, scale=1e-3, offset=1e6))
    write("las", "v14_f6_wide.las", las(4, 6, PTS, withheld=(0, 4), vlrs=b"\0" * 54 + b"kissm vlr"))
    write("las", "v14_f10.las", las(4, 10, PTS[:2]))
    # Hostile headers: a count far beyond the file, a record shorter than its format, a zero scale, LAZ.
    write("las", "count_lie.las", las(4, 7, PTS[:1], wide=1 << 62))
    write("las", "short_record.las", las(2, 1, PTS[:2], extra=-9))
    write("las", "zero_scale.las", las(2, 0, PTS[:1], header_scale=0.0))
    write("las", "laz_id.las", las(2, 3, PTS[:1], fmt_id=0x83))


def scene(rng: random.Random, n: int) -> list[Point]:
    """Points on a floor, two walls and some boxes of a 30 m x 30 m yard."""
    pts: list[Point] = []
    for _ in range(n):
        k = rng.random()
        if k < 0.4:
            pts.append((rng.uniform(-15, 15), rng.uniform(-15, 15), -1.7))
        elif k < 0.6:
            pts.append((rng.uniform(-15, 15), 15.0, rng.uniform(-1.7, 2)))
        elif k < 0.75:
            pts.append((-15.0, rng.uniform(-15, 15), rng.uniform(-1.7, 3)))
        else:
            cx, cy = rng.choice([(3, 4), (-6, 2), (5, -7), (-4, -8)])
            f = rng.randrange(5)
            a, b = rng.uniform(-1, 1), rng.uniform(-1.7, 0.5)
            pts.append(
                [
                    (cx + a, cy - 1, b),
                    (cx + a, cy + 1, b),
                    (cx - 1, cy + a, b),
                    (cx + 1, cy + a, b),
                    (cx + a, cy + rng.uniform(-1, 1), 0.5),
                ][f]
            )
    return pts


def encode_cloud(pts: Sequence[Sequence[float]], head: int = 0x00, scale: float = 1e-3) -> bytes:
    """The fuzz_input.hpp cloud encoding: head byte (bit 0 float64; bit 1 set: 1 mm steps), uint16 count,
    uint16 coordinates offset by 32768."""
    out = bytearray([head | 0x02]) + struct.pack("<H", len(pts))
    for p in pts:
        for c in p:
            q = int(round(c / scale)) + 32768
            out += struct.pack("<H", min(max(q, 0), 0xFFFA))
    return bytes(out)


def encode_transform(
    kind: int,
    rotation_vector: Sequence[float] = (0.0, 0.0, 0.0),
    translation: Sequence[float] = (0.0, 0.0, 0.0),
    at: int = 0,
) -> bytes:
    """The fuzz_input.hpp transform encoding: kind byte (0 identity, 1-5 rigid, 6-12 refused), then for kinds
    above 0 a rotation vector (3 x uint16 at 1e-4 rad, offset 32768), a translation (3 x uint16 at 1 mm) and
    the byte choosing the entry a refused kind spoils."""
    if kind == 0:
        return bytes([0])
    out = bytearray([kind])
    for w in rotation_vector:
        out += struct.pack("<H", int(round(w / 1e-4)) + 32768)
    for t in translation:
        out += struct.pack("<H", int(round(t / 1e-3)) + 32768)
    return bytes(out + bytes([at]))


def pipeline() -> None:
    rng = random.Random(7)
    base = scene(rng, 1500)
    ang = math.radians(25.0)
    ca, sa = math.cos(ang), math.sin(ang)
    moved = [(ca * x - sa * y + 1.5, sa * x + ca * y - 0.5, z + 0.1) for x, y, z in scene(rng, 1500)]
    config = bytes([3, 0x20, 0xC5])  # voxel 0.5, 1 thread, reject non-finite, min_inliers 5, gains 3.5/5, 903 matches
    pair = encode_cloud(base) + encode_cloud(moved)
    write("register", "yard_pair", config + pair)
    write(
        "register", "yard_pair_two_threads_f64", bytes([3, 0x21, 0xC5]) + encode_cloud(base, 0x01) + encode_cloud(moved)
    )
    write("register", "tiny_clouds", config + encode_cloud(base[:4]) + encode_cloud(base[:5], 0x01))
    nan = bytearray(config[:1] + bytes([0x22]) + config[2:] + encode_cloud(base[:600]) + encode_cloud(moved[:600]))
    nan[3 + 3 + 6 * 10 : 3 + 3 + 6 * 10 + 2] = b"\xff\xff"  # one NaN x, dropped by the policy
    write("register", "nan_dropped", bytes(nan))
    small = scene(random.Random(3), 500)
    three = encode_cloud(base[:500]) + encode_cloud(moved[:500]) + encode_cloud(small)
    ops = bytes([0x01, 0x01, 0x10, 0x11, 0x12, 0x21, 0x30, 0x01, 0x40, 0x05, 0x25, 0x01])
    write("stateful", "register_features_cancel", config + three + ops)

    # Refinement (the voxel byte's tens pick refine_mode and a variant of its settings, fuzz_input.hpp): the
    # trailing bytes of a register input are kissm_refine's initial transform, here the true one (moved =
    # R_z(25 deg) base + (1.5, -0.5, 0.1)) or one kissm_refine must refuse.
    truth = ((0.0, 0.0, ang), (1.5, -0.5, 0.1))
    gicp, p2p = 13, 23  # voxel 0.5 with refine_mode GICP / point-to-plane, default settings
    write("register", "refine_gicp_true_prior", bytes([gicp, 0x20, 0xC5]) + pair + encode_transform(1, *truth))
    write("register", "refine_p2p_float_prior", bytes([p2p, 0x21, 0xC5]) + pair + encode_transform(5, *truth, at=4))
    write(
        "register",
        "refine_capped_reflected_prior",
        bytes([3 + 10 * 5, 0x20, 0xC5]) + pair + encode_transform(10, *truth, at=2),
    )  # p2p, 1 iteration
    write(
        "register",
        "refine_min_overlap_all_nan_prior",
        bytes([3 + 10 * 16, 0x20, 0xC5]) + pair + encode_transform(6, *truth, at=7),
    )  # GICP, min_overlap 1
    write(
        "register",
        "loose_validity_rules",  # no refinement, every validity setting at its loosest
        bytes([3 + 10 * 24, 0x20, 0xC5]) + pair + encode_transform(1, *truth),
    )
    write(
        "register",
        "refine_far_prior",
        bytes([gicp, 0x22, 0xC5]) + pair + encode_transform(1, (0.0, 0.0, ang), (30.0, -30.0, 0.0)),
    )
    # One matcher: features of clouds 0 and 1, kissm_refine 0 -> 1 from the truth, kissm_refine_features from a
    # float-rounded truth and from a sheared one, a registration, kissm_refine from the identity.
    refine_ops = (
        bytes([0x12, 0x10, 0x54])
        + encode_transform(1, *truth)
        + bytes([0x66])
        + encode_transform(5, *truth, at=1)
        + bytes([0x66])
        + encode_transform(9, *truth, at=3)
        + bytes([0x03, 0x54])
        + encode_transform(0)
    )
    write("stateful", "refine_features_and_points", bytes([gicp, 0x20, 0xC5]) + three + refine_ops)


def information(kind: int, scales: Sequence[tuple[int, int]], at: int = 0) -> bytes:
    """The fuzz_pose_graph.cpp information encoding: kind byte (0 diagonal, 1 coupled, 2-6 refused), six (mantissa,
    exponent) byte pairs giving (1 + m / 64) 2^(e - 10), the byte choosing the entry a refused kind spoils."""
    return bytes([kind]) + b"".join(bytes([m, e]) for m, e in scales) + bytes([at])


def pose_graph() -> None:
    """A square of four nodes: trusted odometry around it, two robust diagonals (one right, one far off), optimised
    from two anchors; then refused edges and bounds; and a graph of two parts."""
    step = (0.0, 0.0, math.pi / 2)
    odo = encode_transform(1, step, (4.0, 0.0, 0.0))
    sharp = information(0, [(0, 24)] * 3 + [(0, 16)] * 3)
    ops = b""
    for s, t in ((1, 0), (2, 1), (3, 2)):
        ops += bytes([0x00, s, t]) + odo + sharp + bytes([1])  # robust byte 1 - 1 = 0: trusted
    ops += bytes([0x01, 2, 0]) + encode_transform(1, (0.0, 0.0, math.pi), (0.0, 8.0, 0.0)) + sharp + bytes([2])
    ops += bytes([0x01, 3, 1]) + encode_transform(1, (0.3, 0.2, 1.0), (9.0, -3.0, 1.0)) + sharp + bytes([2])
    ops += bytes([0x02, 0, 0, 0x02, 2, 1, 0x03, 0x02, 3, 3])
    write("pose_graph", "square_two_diagonals", bytes([4]) + ops)
    refused = bytes([0x00, 0, 0]) + odo + sharp + bytes([1])  # self edge
    refused += bytes([0x00, 1, 9]) + odo + sharp + bytes([1])  # target out of range
    refused += bytes([0x00, 1, 0]) + encode_transform(9, step, (4.0, 0.0, 0.0), at=2) + sharp + bytes([1])
    refused += bytes([0x00, 1, 0]) + odo + information(4, [(0, 20)] * 6, at=3) + bytes([1])
    refused += bytes([0x00, 1, 0]) + odo + information(6, [(0, 20)] * 6) + bytes([2])
    refused += bytes([0x00, 1, 0]) + odo + sharp + bytes([3])  # robust 2
    refused += bytes([0x02, 0, 4, 0x02, 0, 6, 0x02, 3, 0])
    write("pose_graph", "refused_calls", bytes([4]) + refused)
    parts = bytes([0x00, 1, 0]) + odo + sharp + bytes([2]) + bytes([0x00, 3, 2]) + odo + information(1, [(9, 22)] * 6)
    parts += bytes([1, 0x02, 1, 0, 0x02, 2, 0])
    write("pose_graph", "two_parts", bytes([5]) + parts)


if __name__ == "__main__":
    readers()
    las_seeds()
    pipeline()
    pose_graph()
    print(f"wrote {sum(1 for _ in OUT.rglob('*') if _.is_file())} seed files under {OUT}")
