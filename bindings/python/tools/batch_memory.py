# SPDX-License-Identifier: MIT
"""The memory numbers of docs/batch.md: per cloud, the features' size in memory (Features.memory_bytes) and as
bytes (Features.to_bytes); per job, the peak resident memory a describe job and a pair job add to a process.

    python bindings/python/tools/batch_memory.py VOXEL FORMAT CLOUD [CLOUD...]

Each job runs in a fresh process (so one job's peak is not hidden by another's): the peak is the process's
maximum resident set size after the job minus the one just before it (both from /proc/self/status VmHWM,
reset in between through /proc/self/clear_refs), with the job's inputs already in memory. Linux only.
"""

from __future__ import annotations

import itertools
import json
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

CHILD = r"""
import json, sys
import kissm

def high_water_kib():
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM:"):
            return int(line.split()[1])
    raise RuntimeError("no VmHWM")

def reset_high_water():
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")

job, voxel, fmt, *paths = sys.argv[1:]
matcher = kissm.Matcher(voxel_size=float(voxel), num_threads=1)
if job == "describe":
    points = kissm.read_points(paths[0], fmt)
    reset_high_water()
    before = high_water_kib()
    features = matcher.compute_features(points)
else:
    source, target = (kissm.Features.from_bytes(open(p, "rb").read()) for p in paths)
    reset_high_water()
    before = high_water_kib()
    matcher.register_features(source, target)
print(json.dumps({"peak_kib": high_water_kib() - before}))
"""


def child(*args: str) -> dict[str, Any]:
    out = subprocess.run([sys.executable, "-c", CHILD, *args], check=True, capture_output=True, text=True)
    result: dict[str, Any] = json.loads(out.stdout)
    return result


def main() -> None:
    import kissm

    voxel, fmt, *paths = sys.argv[1:]
    saved: list[str] = []
    scratch = tempfile.TemporaryDirectory()  # the features' bytes, for the pair jobs to load
    with scratch, kissm.Matcher(voxel_size=float(voxel), num_threads=1) as matcher:
        for path in paths:
            features = matcher.compute_features(kissm.read_points(path, fmt))
            data = features.to_bytes()
            saved.append(str(Path(scratch.name) / f"{len(saved)}.features"))
            Path(saved[-1]).write_bytes(data)
            describe = child("describe", voxel, fmt, path)
            keypoints = features.num_keypoints
            print(
                f"{path}: {features.num_points} points, {keypoints} keypoints, "
                f"memory_bytes {features.memory_bytes} ({features.memory_bytes / keypoints:.0f}/keypoint), "
                f"to_bytes {len(data)} ({len(data) / keypoints:.0f}/keypoint), "
                f"describe job peak {describe['peak_kib'] / 1024:.1f} MiB"
            )
        for (i, earlier), (j, later) in itertools.combinations(enumerate(saved), 2):
            pair = child("register", voxel, fmt, later, earlier)
            print(f"pair {paths[j]} -> {paths[i]}: pair job peak {pair['peak_kib'] / 1024:.1f} MiB")


if __name__ == "__main__":
    main()
