# SPDX-License-Identifier: MIT
"""The correspondence cap on very large clouds: success, inliers and time of the synthetic scaling scenes.

For each scene size (and seed) the benchmark's generator builds a pair, and one matcher registers it under
each ``max_correspondences`` asked for (0 is the library's automatic cap). One line per run: the voxels and
keypoints per cloud, the cap that was used (the initial correspondences), the core number, the final inliers,
valid, the rotation error against the generator's pose, and the stage times.

    KISSM_LIBRARY=build/libkissm.so PYTHONPATH=bindings/python/src:bench \\
        bench/.venv/bin/python bench/scale_cap_study.py --sizes 300000 1000000 --caps 0 5000 20000
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from pathlib import Path

import kissm
import numpy as np
from kissm_bench.scenes import make_synthetic


def rotation_error_deg(a: np.ndarray, b: np.ndarray) -> float:
    c = (np.trace(a[:3, :3].T @ b[:3, :3]) - 1.0) / 2.0
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", type=int, nargs="+", default=[100_000, 300_000, 1_000_000])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1234])
    ap.add_argument("--caps", type=int, nargs="+", default=[0, 5000])
    ap.add_argument("--voxel", type=float, default=0.5)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--viewpoint", default="local")
    args = ap.parse_args()

    print("voxels_src kp_src kp_tgt seed cap initial core inliers valid rre_deg wall_ms matching pruning solver")
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        for size in args.sizes:
            for seed in args.seeds:
                scene = make_synthetic(size, args.voxel, seed, tmp, f"{size}_{seed}")
                src = np.load(scene["src_path"])
                tgt = np.load(scene["tgt_path"])
                gt = np.asarray(scene["gt"])
                for cap in args.caps:
                    m = kissm.Matcher(
                        voxel_size=args.voxel,
                        num_threads=args.threads,
                        max_correspondences=cap,
                        viewpoint_mode=args.viewpoint,
                    )
                    t0 = time.perf_counter()
                    r = m.register(src, tgt)
                    wall = (time.perf_counter() - t0) * 1e3
                    err = rotation_error_deg(r.transform, gt) if r.has_pose else float("nan")
                    print(
                        f"{r.num_source_voxels} {r.num_source_keypoints} {r.num_target_keypoints} {seed} {cap} "
                        f"{r.num_initial_correspondences} {r.max_core_number} {r.num_final_inliers} "
                        f"{int(r.valid)} {err:.3f} {wall:.0f} {r.time_matching_ms:.0f} {r.time_pruning_ms:.0f} "
                        f"{r.time_solver_ms:.0f}",
                        flush=True,
                    )


if __name__ == "__main__":
    main()
