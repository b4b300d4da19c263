# SPDX-License-Identifier: MIT
"""E57 (ASTM E2807) through pye57, the Python binding of libE57Format (the extra ``kissm[e57]``): the scans of a
file with their own poses, and a copy of a file with other poses."""

from __future__ import annotations

import dataclasses
import os
from typing import Any

import numpy as np

from ._errors import InvalidArgumentError, IoError, ParseError
from ._optional import require
from ._pose_files import check_poses, quaternion, rotation_matrix

StrPath = str | os.PathLike[str]


@dataclasses.dataclass(frozen=True, eq=False)
class E57Scan:
    """One scan of an E57 file (one ``/data3D`` entry)."""

    name: str
    """The scan's ``name`` (``"scan <k>"`` when the file gives none)."""
    points: np.ndarray
    """(N, 3) float64 points in the scan's own frame, as stored (Cartesian, or converted from spherical); points
    the file marks invalid are left out."""
    pose: np.ndarray
    """(4, 4) world <- scan: the file's ``pose`` (its quaternion normalised), the identity when it has none. The
    world points are ``points @ pose[:3, :3].T + pose[:3, 3]``."""


def _pye57() -> Any:
    pye57 = require("pye57", "e57", "reading and writing E57")
    require("pye57.utils", "e57", "reading and writing E57")  # copy_node, get_node, the spherical conversion
    return pye57


def _check_readable(name: str) -> None:
    """IoError for a missing file, ParseError for one without the E57 signature: checked here because pye57
    writes libE57's exceptions to stderr before raising them, and kissm prints nothing."""
    try:
        with open(name, "rb") as f:
            signature = f.read(8)
    except OSError as e:
        raise IoError(f"{name}: {e.strerror or e}") from e
    if signature != b"ASTM-E57":
        raise ParseError(f"{name}: E57: not an E57 file (it does not start with the ASTM-E57 signature)")


def _open(pye57: Any, path: StrPath, mode: str) -> Any:
    name = os.fspath(path)
    if mode == "r":
        _check_readable(name)
    try:
        return pye57.libe57.ImageFile(name, mode)
    except pye57.libe57.E57Exception as e:
        raise (ParseError if mode == "r" else IoError)(f"{name}: E57: {e}") from e


def _pose(scan: Any, libe57: Any) -> np.ndarray:
    pose = np.eye(4)
    if not scan.isDefined("pose"):
        return pose
    node = libe57.StructureNode(scan.get("pose"))
    if node.isDefined("rotation"):
        r = libe57.StructureNode(node.get("rotation"))
        w, x, y, z = (float(libe57.FloatNode(r.get(c)).value()) for c in "wxyz")
        pose[:3, :3] = rotation_matrix(w, x, y, z)
    if node.isDefined("translation"):
        t = libe57.StructureNode(node.get("translation"))
        pose[:3, 3] = [float(libe57.FloatNode(t.get(c)).value()) for c in "xyz"]
    return pose


def read_e57(path: StrPath) -> list[E57Scan]:
    """The scans of the E57 file ``path``, in the file's order, each with its points (in its own frame), its pose
    (world <- scan) and its name.

    Give the poses to :func:`kissm.multiway.align` as ``priors`` (with ``pairs="sequence"``) to start from them, or
    leave them out to register the scans with no initial guess (docs/files.md).

    Raises :class:`kissm.IoError` when the file does not exist, :class:`kissm.ParseError` when libE57Format
    cannot read it, and ``ModuleNotFoundError`` naming ``pip install kissm[e57]`` when pye57 is missing.
    """
    pye57 = _pye57()
    name = os.fspath(path)
    _check_readable(name)
    scans = []
    try:
        e57 = pye57.E57(name, mode="r")
        try:
            for k in range(e57.scan_count):
                node = e57.data3d[k]
                fields = e57.get_header(k).point_fields
                data = e57.read_scan(k, transform=False, ignore_missing_fields=True)
                if "cartesianX" in fields:
                    points = np.stack([data["cartesianX"], data["cartesianY"], data["cartesianZ"]], axis=1)
                else:
                    rae = np.stack(
                        [data["sphericalRange"], data["sphericalAzimuth"], data["sphericalElevation"]], axis=1
                    )
                    points = pye57.utils.convert_spherical_to_cartesian(rae)
                scan_name = pye57.libe57.StringNode(node.get("name")).value() if node.isDefined("name") else f"scan {k}"
                scans.append(
                    E57Scan(
                        str(scan_name),
                        np.ascontiguousarray(points, dtype=np.float64),
                        _pose(node, pye57.libe57),
                    )
                )
        finally:
            e57.close()
    except pye57.libe57.E57Exception as e:
        raise ParseError(f"{name}: E57: {e}") from e
    except (KeyError, ValueError) as e:  # pye57's: a scan with neither Cartesian nor spherical coordinates
        raise ParseError(f"{name}: E57: {e}") from e
    return scans


def _check_rotations(poses: np.ndarray) -> None:
    for k, pose in enumerate(poses):
        if not np.all(np.isfinite(pose)):
            raise InvalidArgumentError(f"write_e57_poses: poses[{k}] has a non-finite entry")
        r = pose[:3, :3]
        if np.max(np.abs(r.T @ r - np.eye(3))) > 1e-6 or np.linalg.det(r) <= 0:
            raise InvalidArgumentError(f"write_e57_poses: poses[{k}] is not a rigid transform (its 3x3 is no rotation)")


def _pose_node(libe57: Any, image: Any, pose: np.ndarray) -> Any:
    qx, qy, qz, qw = quaternion(pose[:3, :3])
    node = libe57.StructureNode(image)
    rotation = libe57.StructureNode(image)
    for key, value in (("w", qw), ("x", qx), ("y", qy), ("z", qz)):
        rotation.set(key, libe57.FloatNode(image, value))
    translation = libe57.StructureNode(image)
    for key, value in zip("xyz", pose[:3, 3], strict=True):
        translation.set(key, libe57.FloatNode(image, float(value)))
    node.set("rotation", rotation)
    node.set("translation", translation)
    return node


def _buffers(libe57: Any, prototype: Any, capacity: int, what: str) -> tuple[dict[str, np.ndarray], Any]:
    """Per field of a points prototype, an array and its libE57 buffer holding the stored values exactly:
    float64 for floats (a single-precision field converts without loss), 64-bit integers for integers and the raw
    integers of scaled integers (no scaling, so nothing is rounded on the way back)."""
    arrays: dict[str, np.ndarray] = {}
    buffers = libe57.VectorSourceDestBuffer()
    image = prototype.destImageFile()
    for k in range(prototype.childCount()):
        child = prototype.get(k)
        kind = child.type()
        field = child.elementName()
        if kind == libe57.NodeType.E57_FLOAT:
            array = np.empty(capacity, np.float64)
        elif kind in (libe57.NodeType.E57_INTEGER, libe57.NodeType.E57_SCALED_INTEGER):
            # longlong, whose buffer format is "q": pye57 takes an int64 array's "l" for int32 (as on Windows).
            array = np.empty(capacity, np.longlong)
        else:
            raise ParseError(f"{what}: the points field {field!r} is not a number (nested prototypes are not copied)")
        arrays[field] = array
        buffers.append(libe57.SourceDestBuffer(image, field, array, capacity, True, False))
    return arrays, buffers


def _copy_points(libe57: Any, source: Any, target: Any, what: str) -> None:
    """The records of one compressed vector (a scan's points) into its copy, a chunk at a time."""
    chunk = 1 << 16
    src_arrays, src_buffers = _buffers(libe57, libe57.StructureNode(source.prototype()), chunk, what)
    dst_arrays, dst_buffers = _buffers(libe57, libe57.StructureNode(target.prototype()), chunk, what)
    reader = source.reader(src_buffers)
    writer = target.writer(dst_buffers)
    try:
        left = source.childCount()
        while left > 0:
            count = reader.read()
            if count <= 0:
                raise ParseError(f"{what}: the points end {left} records early")
            for field, array in src_arrays.items():
                dst_arrays[field][:count] = array[:count]
            writer.write(count)
            left -= count
    finally:
        reader.close()
        writer.close()


def _copy_blob(source: Any, target: Any) -> None:
    chunk = 1 << 20
    buffer = np.empty(chunk, np.uint8)
    done, size = 0, source.byteCount()
    while done < size:
        count = min(chunk, size - done)
        source.read(buffer, done, count)
        target.write(buffer, done, count)
        done += count


def write_e57_poses(src: StrPath, dst: StrPath, poses: object) -> None:
    """Write a copy of the E57 file ``src`` to ``dst`` whose scans have the poses ``poses`` ((N, 4, 4) world <-
    scan, one per scan of ``src`` in its order, e.g. :func:`kissm.multiway.align`'s poses): every other element
    of the file (the points exactly as stored, names, images, extensions) is copied unchanged.

    Raises :class:`kissm.InvalidArgumentError` when ``poses`` is not (N, 4, 4) rigid transforms with N the scan
    count, or ``dst`` is ``src``; :class:`kissm.IoError` / :class:`kissm.ParseError` when a file cannot be
    opened, written or read; ``ModuleNotFoundError`` naming ``pip install kissm[e57]`` when pye57 is missing. A
    failed write leaves no ``dst`` behind.
    """
    pye57 = _pye57()
    libe57 = pye57.libe57
    array = check_poses(poses, "write_e57_poses")
    _check_rotations(array)
    src_name, dst_name = os.fspath(src), os.fspath(dst)
    _check_readable(src_name)
    if os.path.exists(dst_name) and os.path.samefile(src_name, dst_name):
        raise InvalidArgumentError(f"write_e57_poses: dst is src ({dst_name}); write the copy elsewhere")
    source = _open(pye57, src_name, "r")
    try:
        root = source.root()
        scans = libe57.VectorNode(root.get("data3D")) if root.isDefined("data3D") else None
        count = scans.childCount() if scans is not None else 0
        if len(array) != count:
            raise InvalidArgumentError(f"write_e57_poses: {len(array)} poses for the {count} scans of {src_name}")
        target = _open(pye57, dst_name, "w")
        try:
            _copy_tree(pye57, source, target, array, src_name)
        except BaseException:
            target.cancel()  # libE57 then removes the partial file
            raise
        target.close()
    except libe57.E57Exception as e:
        raise ParseError(f"{src_name} -> {dst_name}: E57: {e}") from e
    finally:
        source.close()


def _copy_tree(pye57: Any, source: Any, target: Any, poses: np.ndarray, what: str) -> None:
    libe57 = pye57.libe57
    copy_node = pye57.utils.copy_node
    get_node = pye57.utils.get_node
    for k in range(source.extensionsCount()):
        target.extensionsAdd(source.extensionsPrefix(k), source.extensionsUri(k))
    points: list[tuple[Any, Any]] = []
    blobs: list[tuple[Any, Any]] = []

    def copy(node: Any) -> Any:
        out, vectors, blob_pairs = copy_node(node, target)
        points.extend((pair["in"], pair["out"]) for pair in vectors)
        blobs.extend((pair["in"], pair["out"]) for pair in blob_pairs)
        return out

    root, out_root = source.root(), target.root()
    for k in range(root.childCount()):
        child = get_node(root, k)
        name = child.elementName()
        if name != "data3D":
            out_root.set(name, copy(child))
            continue
        scans = libe57.VectorNode(target, child.allowHeteroChildren())
        for s in range(child.childCount()):
            scan = get_node(child, s)
            out_scan = libe57.StructureNode(target)
            for c in range(scan.childCount()):
                element = get_node(scan, c)
                if element.elementName() != "pose":
                    out_scan.set(element.elementName(), copy(element))
            out_scan.set("pose", _pose_node(libe57, target, poses[s]))
            scans.append(out_scan)
        out_root.set(name, scans)
    for source_points, target_points in points:
        _copy_points(libe57, source_points, target_points, what)
    for source_blob, target_blob in blobs:
        _copy_blob(source_blob, target_blob)
