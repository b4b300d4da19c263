#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""kissm benchmark: kissm against the reference KISS-Matcher and Open3D, on real pairs and synthetic scenes.

Full run (normally through ``bash bench/run.sh``, which makes the venv with every peer installed)::

    python bench/bench.py --threads 1 2 --rotations 2 --repeats 3 --out docs

Smoke run (seconds; needs only numpy and kissm; any peer that happens to be importable is skipped unless
it is the reference)::

    python bench/bench.py --smoke --out /tmp/kissm-bench-smoke

How it measures (also written into the report):

* Every case (a pair of ``../shared/data``, raw or with its source turned by a large rotation with a fixed
  seed, ground truth composed accordingly) is loaded once, as float64 (N, 3) arrays, and saved to a
  temporary ``.npy``. Each method then runs in its **own fresh worker process** per (thread count, case):
  the worker pins itself to the first T CPUs (``sched_setaffinity``, like ``taskset``) before any library
  is imported, with ``OMP_NUM_THREADS=T``; kissm also gets ``num_threads=T``.
* The worker loads the arrays, returns freed heap to the OS (``malloc_trim``), resets its peak-RSS counter
  (``/proc/self/clear_refs``) and records the resident size as the baseline. Peak memory of a method is
  ``VmHWM - baseline`` after the warm-up and all timed runs: what the call adds on top of the input
  arrays and the imported libraries, including one-time initialisation in the first call.
* One warm-up call per method, then the timed calls interleaved method by method (A B C D, A B C D, ...).
  Every timed call starts from the raw numpy arrays: matcher construction, conversion, voxelisation,
  features, matching and solving are all inside the wall time. The median over the repeats is reported.
* Stage times: kissm's ``Result.time_*_ms``; the reference's own C++ getters (its matching time includes
  its pruning, which is shown separately); Open3D's stages timed around each call.
"""

from __future__ import annotations

import argparse
import contextlib
import ctypes
import datetime as _dt
import gc
import importlib.util
import json
import math
import os
import platform
import resource
import select
import shlex
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import traceback
import zlib
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
sys.path.insert(0, str(HERE))
from report_common import METHOD_LABEL, STAGE_ORDER as STAGES  # noqa: E402, I001  (one definition, shared with the report)

COARSE_METHODS = ("kissm", "reference", "o3d_ransac", "o3d_fgr")
REFINE_METHODS = ("kissm_gicp", "kissm_p2pl", "sgicp", "o3d_gicp", "o3d_p2pl", "ref_sgicp")
METHODS = COARSE_METHODS + REFINE_METHODS
# The Python modules each method needs (checked before a run).
METHOD_MODULES = {
    "kissm": ("kissm",),
    "reference": ("kiss_matcher",),
    "o3d_ransac": ("open3d",),
    "o3d_fgr": ("open3d",),
    "kissm_gicp": ("kissm",),
    "kissm_p2pl": ("kissm",),
    "sgicp": ("small_gicp",),
    "o3d_gicp": ("open3d",),
    "o3d_p2pl": ("open3d",),
    "ref_sgicp": ("kiss_matcher", "small_gicp"),
}
# Peers that refine from kissm's coarse pose (computed once per case by the parent, untimed).
FROM_KISSM_START = ("sgicp", "o3d_gicp", "o3d_p2pl")
KISSM_REFINE_MODE = {"kissm_gicp": "gicp", "kissm_p2pl": "point_to_plane"}
# The upstream loop-closure chain (KISS-Matcher's ROS module): its fine step's settings and acceptance gates.
UPSTREAM_CHAIN = {
    "corr_dist_gain": 5.0,
    "max_iterations": 10,
    "num_neighbors": 20,
    "min_inliers": 100,
    "min_overlap": 0.9,
}

# Voxel size and success thresholds per kind of data (SPEC §7; docs/design/accuracy.md).
KIND_SETTINGS = {
    "lidar_keyframe_downsampled": ("lidar", 0.5),
    "lidar_scan": ("lidar", 0.3),
    "indoor_rgbd_fragment": ("indoor", 0.05),
    "object_range_scan": ("object", 0.006),
}
THRESHOLDS = {"lidar": (5.0, 2.0), "indoor": (5.0, 0.3), "object": (5.0, 0.01), "synthetic": (5.0, 2.0)}
REFERENCE_MIN_INLIERS = 5  # "valid" for the reference: solution.valid and at least 5 final inliers
REFERENCE_MIN_VOXEL = 0.005  # the reference refuses smaller voxels


# ================================================================================================
# Worker side: one process per (method, thread count, case); JSON lines on a private pipe.
# ================================================================================================


def _proc_status() -> dict[str, int]:
    out = {}
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(("VmRSS:", "VmHWM:")):
                key, value = line.split(":", 1)
                out[key] = int(value.split()[0])  # kB
    return out


def _trim_heap() -> None:
    gc.collect()
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL("libc.so.6").malloc_trim(0)


def _reset_peak() -> None:
    # Writing 5 resets VmHWM to the current RSS (Linux >= 4.0). Without it the peak includes loading.
    with contextlib.suppress(OSError):
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")


class _Runner:
    """Runs one method on the loaded arrays; returns the per-call record."""

    def __init__(self, method: str, threads: int):
        import numpy as np

        self.np = np
        self.method = method
        self.threads = threads
        self.src = self.tgt = None
        self.voxel = None
        self.seed = 0
        self.init = None  # the coarse pose the refinement peers start from
        self.coarse_valid = False
        self.refine: dict = {}
        family = METHOD_MODULES[method]
        if family == ("kissm",):
            import kissm

            self.lib = kissm
            self.version = kissm.__version__
        elif family == ("kiss_matcher",):
            import kiss_matcher

            self.lib = kiss_matcher
            self.version = getattr(kiss_matcher, "__version__", "?")
        elif family == ("open3d",):
            import open3d as o3d

            o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
            self.lib = o3d
            self.version = o3d.__version__
        else:  # small_gicp, alone or after the reference
            from importlib import metadata

            import small_gicp

            self.sg = small_gicp
            self.version = metadata.version("small-gicp")
            if "kiss_matcher" in family:
                import kiss_matcher

                self.lib = kiss_matcher
                self.version = f"kiss-matcher {metadata.version('kiss-matcher')} + small_gicp {self.version}"

    def load(self, msg: dict) -> dict:
        np = self.np
        self.src = self.tgt = None
        _trim_heap()
        self.src = np.ascontiguousarray(np.load(msg["src"]), dtype=np.float64)
        self.tgt = np.ascontiguousarray(np.load(msg["tgt"]), dtype=np.float64)
        self.voxel = float(msg["voxel"])
        self.seed = int(msg.get("seed", 0))
        self.refine = dict(msg.get("refine") or {})
        start = msg.get("init")
        self.init = None if start is None else np.asarray(start["transform"], dtype=np.float64).reshape(4, 4)
        self.coarse_valid = bool(start and start["valid"])
        _trim_heap()
        _reset_peak()
        st = _proc_status()
        return {"baseline_kb": st.get("VmRSS", 0), "n_src": len(self.src), "n_tgt": len(self.tgt)}

    def run(self) -> dict:
        # CPU time of the whole process (every thread) and page faults during the call: wall time on a VM
        # includes the kernel's work for memory touched for the first time, which the user time does not.
        before = resource.getrusage(resource.RUSAGE_SELF)
        rec = getattr(self, "_run_" + self.method)()
        after = resource.getrusage(resource.RUSAGE_SELF)
        rec["cpu"] = {
            "user_ms": (after.ru_utime - before.ru_utime) * 1e3,
            "sys_ms": (after.ru_stime - before.ru_stime) * 1e3,
            "minflt": after.ru_minflt - before.ru_minflt,
        }
        return rec

    # ---- kissm: the Python binding, raw float64 arrays in, pose out --------------------------------------
    def _run_kissm(self, refine_mode: str | None = None) -> dict:
        kissm = self.lib
        config = {"refine_mode": refine_mode} if refine_mode else {}
        t0 = time.perf_counter()
        with kissm.Matcher(voxel_size=self.voxel, num_threads=self.threads, **config) as matcher:
            r = matcher.register(self.src, self.tgt)
        transform = r.transform
        wall = (time.perf_counter() - t0) * 1e3
        stages = {
            "voxelize": r.time_voxelize_ms,
            "features": r.time_features_ms,
            "matching": r.time_matching_ms,
            "pruning": r.time_pruning_ms,
            "solver": r.time_solver_ms,
        }
        stages["input"] = max(0.0, wall - r.time_total_ms)
        rec = {
            "wall_ms": wall,
            "engine_ms": r.time_total_ms,
            "stages": stages,
            "transform": transform.tolist(),
            "valid": bool(r.valid),
            "inliers": int(r.num_final_inliers),
            "info": {
                "reason": r.reason,
                "src_voxels": r.num_source_voxels,
                "tgt_voxels": r.num_target_voxels,
                "src_keypoints": r.num_source_keypoints,
                "tgt_keypoints": r.num_target_keypoints,
                "initial_corr": r.num_initial_correspondences,
                "pruned_corr": r.num_pruned_correspondences,
            },
        }
        if refine_mode:
            stages["refine"] = r.time_refine_ms
            rec["coarse_transform"] = r.coarse_transform.tolist()
            rec["info"].update(
                overlap=_finite(r.overlap),
                refine_rmse=_finite(r.refine_rmse),
                refine_condition=_finite(r.refine_condition),
                refine_iterations=int(r.refine_iterations),
                refine_converged=bool(r.refine_converged),
                refine_corr=int(r.num_refine_correspondences),
            )
        return rec

    def _run_kissm_gicp(self) -> dict:
        return self._run_kissm(KISSM_REFINE_MODE["kissm_gicp"])

    def _run_kissm_p2pl(self) -> dict:
        return self._run_kissm(KISSM_REFINE_MODE["kissm_p2pl"])

    # ---- the reference: PyPI kiss-matcher, its own C++ stage times -----------------------------------------
    def _run_reference(self) -> dict:
        km, np = self.lib, self.np
        if self.voxel < REFERENCE_MIN_VOXEL:
            raise ValueError(f"the reference refuses voxel sizes below {REFERENCE_MIN_VOXEL}")
        t0 = time.perf_counter()
        matcher = km.KISSMatcher(km.KISSMatcherConfig(self.voxel))
        solution = matcher.estimate(self.src, self.tgt)
        rotation = np.array(solution.rotation, dtype=np.float64).reshape(3, 3)
        translation = np.array(solution.translation, dtype=np.float64).reshape(3)
        wall = (time.perf_counter() - t0) * 1e3
        inliers = int(matcher.get_num_final_inliers())
        processing = matcher.get_processing_time() * 1e3
        extraction = matcher.get_extraction_time() * 1e3
        matching = matcher.get_matching_time() * 1e3  # includes the pruning (ROBIN) time
        rejection = matcher.get_rejection_time() * 1e3
        solver = matcher.get_solver_time() * 1e3
        engine = processing + extraction + matching + solver
        stages = {
            "voxelize": processing,
            "features": extraction,
            "matching": max(0.0, matching - rejection),
            "pruning": rejection,
            "solver": solver,
            "input": max(0.0, wall - engine),
        }
        transform = np.eye(4)
        transform[:3, :3] = rotation
        transform[:3, 3] = translation
        return {
            "wall_ms": wall,
            "engine_ms": engine,
            "stages": stages,
            "transform": transform.tolist(),
            "valid": bool(solution.valid) and inliers >= REFERENCE_MIN_INLIERS,
            "inliers": inliers,
            "info": {"solution_valid": bool(solution.valid)},
        }

    # ---- Open3D: the standard FPFH recipe, then RANSAC or FGR ---------------------------------------------
    def _o3d_prepare(self, points, times: dict):
        o3d = self.lib
        v = self.voxel
        t0 = time.perf_counter()
        cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
        t1 = time.perf_counter()
        down = cloud.voxel_down_sample(v)
        t2 = time.perf_counter()
        down.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=2 * v, max_nn=30))
        fpfh = o3d.pipelines.registration.compute_fpfh_feature(
            down, o3d.geometry.KDTreeSearchParamHybrid(radius=5 * v, max_nn=100)
        )
        t3 = time.perf_counter()
        times["input"] += (t1 - t0) * 1e3
        times["voxelize"] += (t2 - t1) * 1e3
        times["features"] += (t3 - t2) * 1e3
        return down, fpfh

    def _run_o3d(self, use_fgr: bool) -> dict:
        o3d, np = self.lib, self.np
        reg = o3d.pipelines.registration
        v = self.voxel
        o3d.utility.random.seed(self.seed)
        stages = {"input": 0.0, "voxelize": 0.0, "features": 0.0}
        t0 = time.perf_counter()
        src, src_f = self._o3d_prepare(self.src, stages)
        tgt, tgt_f = self._o3d_prepare(self.tgt, stages)
        t1 = time.perf_counter()
        if use_fgr:
            result = reg.registration_fgr_based_on_feature_matching(
                src, tgt, src_f, tgt_f, reg.FastGlobalRegistrationOption(maximum_correspondence_distance=0.5 * v)
            )
        else:
            result = reg.registration_ransac_based_on_feature_matching(
                src,
                tgt,
                src_f,
                tgt_f,
                True,
                1.5 * v,
                reg.TransformationEstimationPointToPoint(False),
                3,
                [reg.CorrespondenceCheckerBasedOnEdgeLength(0.9), reg.CorrespondenceCheckerBasedOnDistance(1.5 * v)],
                reg.RANSACConvergenceCriteria(100000, 0.999),
            )
        transform = np.asarray(result.transformation, dtype=np.float64)
        t2 = time.perf_counter()
        wall = (t2 - t0) * 1e3
        stages["registration"] = (t2 - t1) * 1e3
        accounted = sum(stages.values())
        stages["input"] += max(0.0, wall - accounted)
        return {
            "wall_ms": wall,
            "engine_ms": wall,
            "stages": stages,
            "transform": transform.tolist(),
            # Open3D has no validity decision; a result with no correspondences (fitness 0) counts as invalid.
            "valid": bool(result.fitness > 0),
            "inliers": len(result.correspondence_set),
            "info": {"fitness": float(result.fitness), "src_voxels": len(src.points), "tgt_voxels": len(tgt.points)},
        }

    def _run_o3d_ransac(self) -> dict:
        return self._run_o3d(False)

    def _run_o3d_fgr(self) -> dict:
        return self._run_o3d(True)

    # ---- refinement peers, from kissm's coarse pose (self.init) ---------------------------------------------
    def _start(self):
        if self.init is None:
            raise ValueError("no initial pose was loaded (a refinement peer needs kissm's coarse pose)")
        return self.init

    def _run_sgicp(self) -> dict:
        """small_gicp GICP: preprocess_points (voxel grid, kd-tree, covariances) of both clouds, then align."""
        sg = self.sg
        init = self._start()
        t0 = time.perf_counter()
        src, _ = sg.preprocess_points(self.src, self.voxel, num_threads=self.threads)
        tgt, tgt_tree = sg.preprocess_points(self.tgt, self.voxel, num_threads=self.threads)
        t1 = time.perf_counter()
        result = sg.align(
            tgt,
            src,
            tgt_tree,
            init,
            registration_type="GICP",
            max_correspondence_distance=self.refine["max_distance"],
            num_threads=self.threads,
            max_iterations=self.refine["max_iterations"],
        )
        transform = self.np.asarray(result.T_target_source, dtype=self.np.float64)
        t2 = time.perf_counter()
        wall = (t2 - t0) * 1e3
        stages = {"preprocess": (t1 - t0) * 1e3, "align": (t2 - t1) * 1e3}
        return {
            "wall_ms": wall,
            "engine_ms": wall,
            "stages": stages,
            "transform": transform.tolist(),
            "coarse_transform": init.tolist(),
            # small_gicp has no validity decision: its pose is reported when kissm's coarse pose was.
            "valid": self.coarse_valid,
            "inliers": int(result.num_inliers),
            "info": {
                "converged": bool(result.converged),
                "iterations": int(result.iterations),
                "src_points": src.size(),
                "tgt_points": tgt.size(),
            },
        }

    def _run_o3d_refine(self, gicp: bool) -> dict:
        """Open3D GICP or point-to-plane ICP from the coarse pose, with its own downsampling and covariances or
        normals."""
        o3d, np = self.lib, self.np
        reg = o3d.pipelines.registration
        v = self.voxel
        init = self._start()
        stages = {"input": 0.0, "voxelize": 0.0, "covariances": 0.0}
        t0 = time.perf_counter()
        clouds = []
        for points, needs_geometry in ((self.src, gicp), (self.tgt, True)):
            ta = time.perf_counter()
            cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
            tb = time.perf_counter()
            down = cloud.voxel_down_sample(v)
            tc = time.perf_counter()
            if needs_geometry and gicp:
                down.estimate_covariances(o3d.geometry.KDTreeSearchParamKNN(knn=30))  # GICP's own default
            elif needs_geometry:
                down.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=2 * v, max_nn=30))
            td = time.perf_counter()
            stages["input"] += (tb - ta) * 1e3
            stages["voxelize"] += (tc - tb) * 1e3
            stages["covariances"] += (td - tc) * 1e3
            clouds.append(down)
        t1 = time.perf_counter()
        criteria = reg.ICPConvergenceCriteria(max_iteration=self.refine["max_iterations"])
        if gicp:
            result = reg.registration_generalized_icp(
                clouds[0],
                clouds[1],
                self.refine["max_distance"],
                init,
                reg.TransformationEstimationForGeneralizedICP(),
                criteria,
            )
        else:
            result = reg.registration_icp(
                clouds[0],
                clouds[1],
                self.refine["max_distance"],
                init,
                reg.TransformationEstimationPointToPlane(),
                criteria,
            )
        transform = np.asarray(result.transformation, dtype=np.float64)
        t2 = time.perf_counter()
        wall = (t2 - t0) * 1e3
        stages["align"] = (t2 - t1) * 1e3
        return {
            "wall_ms": wall,
            "engine_ms": wall,
            "stages": stages,
            "transform": transform.tolist(),
            "coarse_transform": init.tolist(),
            "valid": self.coarse_valid and result.fitness > 0,
            "inliers": len(result.correspondence_set),
            "info": {
                "fitness": float(result.fitness),
                "inlier_rmse": float(result.inlier_rmse),
                "src_points": len(clouds[0].points),
                "tgt_points": len(clouds[1].points),
            },
        }

    def _run_o3d_gicp(self) -> dict:
        return self._run_o3d_refine(True)

    def _run_o3d_p2pl(self) -> dict:
        return self._run_o3d_refine(False)

    # ---- the upstream chain: reference coarse + small_gicp VGICP, as KISS-Matcher's ROS loop closure does -------
    def _run_ref_sgicp(self) -> dict:
        km, sg, np = self.lib, self.sg, self.np
        v, threads = self.voxel, self.threads
        chain = UPSTREAM_CHAIN
        if v < REFERENCE_MIN_VOXEL:
            raise ValueError(f"the reference refuses voxel sizes below {REFERENCE_MIN_VOXEL}")
        t0 = time.perf_counter()
        # 1. voxelised clouds (upstream voxelises its submaps before both steps)
        src = sg.voxelgrid_sampling(self.src, v, threads)
        tgt = sg.voxelgrid_sampling(self.tgt, v, threads)
        src_xyz = np.ascontiguousarray(src.points()[:, :3])
        tgt_xyz = np.ascontiguousarray(tgt.points()[:, :3])
        t1 = time.perf_counter()
        # 2. the coarse estimate
        matcher = km.KISSMatcher(km.KISSMatcherConfig(v))
        solution = matcher.estimate(src_xyz, tgt_xyz)
        coarse = reference_transform(solution)
        t2 = time.perf_counter()
        ref_engine = (
            matcher.get_processing_time()
            + matcher.get_extraction_time()
            + matcher.get_matching_time()
            + matcher.get_solver_time()
        ) * 1e3
        inliers = int(matcher.get_num_final_inliers())
        # 3. VGICP from the coarse pose: covariances of both clouds, the target's Gaussian voxel map. Upstream
        # skips this step when its gates reject the coarse pose; here it always runs, so its time is counted.
        sg.estimate_covariances(src, num_neighbors=chain["num_neighbors"], num_threads=threads)
        sg.estimate_covariances(tgt, num_neighbors=chain["num_neighbors"], num_threads=threads)
        voxelmap = sg.GaussianVoxelMap(v)
        voxelmap.insert(tgt)
        t3 = time.perf_counter()
        result = sg.align(
            voxelmap,
            src,
            coarse,
            max_correspondence_distance=chain["corr_dist_gain"] * v,
            num_threads=threads,
            max_iterations=chain["max_iterations"],
        )
        transform = np.asarray(result.T_target_source, dtype=np.float64)
        t4 = time.perf_counter()
        wall = (t4 - t0) * 1e3
        overlap = result.num_inliers / max(1, src.size())
        coarse_valid = bool(solution.valid) and inliers >= REFERENCE_MIN_INLIERS
        stages = {
            "voxelize": (t1 - t0) * 1e3,
            "reference": (t2 - t1) * 1e3,
            "preprocess": (t3 - t2) * 1e3,
            "align": (t4 - t3) * 1e3,
        }
        return {
            # engine: the Python wall minus the reference binding's copy of the points (its wall minus its C++)
            "wall_ms": wall,
            "engine_ms": wall - max(0.0, stages["reference"] - ref_engine),
            "stages": stages,
            "transform": transform.tolist(),
            "coarse_transform": coarse.tolist(),
            # valid: the reference's rule of the coarse comparison; gates_valid: upstream's own acceptance.
            "valid": coarse_valid,
            "inliers": inliers,
            "info": {
                "ref_engine_ms": ref_engine,
                "solution_valid": bool(solution.valid),
                "overlap": overlap,
                "converged": bool(result.converged),
                "iterations": int(result.iterations),
                "gates_valid": bool(solution.valid)
                and inliers > chain["min_inliers"]
                and overlap >= chain["min_overlap"],
                "src_points": src.size(),
                "tgt_points": tgt.size(),
            },
        }


def reference_transform(solution):
    """The reference's RegistrationSolution as a 4x4 transform (float64)."""
    import numpy as np

    t = np.eye(4)
    t[:3, :3] = np.array(solution.rotation, dtype=np.float64).reshape(3, 3)
    t[:3, 3] = np.array(solution.translation, dtype=np.float64).reshape(3)
    return t


def _finite(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None  # JSON has no NaN


def worker_main(method: str, threads: int, cpus: list[int]) -> int:
    # Pin before importing anything that starts threads (TBB and OpenMP size their pools from the mask).
    if cpus and hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, cpus)
    proto = os.fdopen(os.dup(1), "w", buffering=1)
    os.dup2(2, 1)  # anything a library prints goes to the log, never into the protocol
    sys.stdout = sys.stderr

    def send(obj: dict) -> None:
        proto.write(json.dumps(obj) + "\n")
        proto.flush()

    try:
        runner = _Runner(method, threads)
    except Exception as exc:  # noqa: BLE001 - reported to the parent
        send({"ok": False, "error": f"{type(exc).__name__}: {exc}"})
        return 1
    affinity = sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else []
    send({"ok": True, "version": runner.version, "affinity": affinity})
    for line in sys.stdin:
        msg = json.loads(line)
        cmd = msg.get("cmd")
        try:
            if cmd == "load":
                reply = runner.load(msg)
            elif cmd == "run":
                reply = runner.run()
            elif cmd == "mem":
                reply = _proc_status()
            elif cmd == "quit":
                send({"ok": True})
                return 0
            else:
                raise ValueError(f"unknown command {cmd!r}")
            reply["ok"] = True
        except Exception as exc:  # noqa: BLE001 - reported to the parent
            reply = {"ok": False, "error": f"{type(exc).__name__}: {exc}", "traceback": traceback.format_exc()}
        send(reply)
    return 0


# ================================================================================================
# Parent side
# ================================================================================================


class WorkerError(RuntimeError):
    pass


class WorkerTimeout(RuntimeError):
    pass


class Worker:
    """A method's worker process, pinned to ``cpus``; ``call`` sends one command and waits for its reply."""

    def __init__(self, method: str, threads: int, cpus: list[int], log, python: str):
        env = dict(os.environ)
        for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
            env[var] = str(threads)
        env["PYTHONUNBUFFERED"] = "1"
        self.method = method
        log.write(f"\n===== worker {method} threads={threads} cpus={cpus}\n")
        log.flush()
        self.proc = subprocess.Popen(
            [
                python,
                str(Path(__file__).resolve()),
                "--worker",
                method,
                "--threads",
                str(threads),
                "--cpus",
                ",".join(map(str, cpus)),
            ],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=log,
            env=env,
        )
        self._buf = b""
        self.hello = self._reply(120.0)
        if not self.hello.get("ok"):
            self.close()
            raise WorkerError(f"{method}: {self.hello.get('error')}")

    def _reply(self, timeout: float | None) -> dict:
        deadline = None if timeout is None else time.monotonic() + timeout
        fd = self.proc.stdout.fileno()
        while b"\n" not in self._buf:
            remaining = None if deadline is None else deadline - time.monotonic()
            if remaining is not None and remaining <= 0:
                self.kill()
                raise WorkerTimeout(f"{self.method}: no reply within {timeout:.0f} s")
            ready, _, _ = select.select([fd], [], [], remaining)
            if not ready:
                continue
            chunk = os.read(fd, 1 << 16)
            if not chunk:
                code = self.proc.wait()
                raise WorkerError(f"{self.method}: worker exited with status {code}")
            self._buf += chunk
        line, self._buf = self._buf.split(b"\n", 1)
        return json.loads(line)

    def call(self, msg: dict, timeout: float | None = None) -> dict:
        try:
            self.proc.stdin.write((json.dumps(msg) + "\n").encode())
            self.proc.stdin.flush()
        except BrokenPipeError as exc:
            raise WorkerError(f"{self.method}: worker is gone") from exc
        reply = self._reply(timeout)
        if not reply.get("ok"):
            raise WorkerError(f"{self.method}: {reply.get('error')}\n{reply.get('traceback', '')}")
        return reply

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()  # our own child, by its handle
            self.proc.wait()

    def close(self) -> None:
        if self.proc.poll() is None:
            try:
                self.call({"cmd": "quit"}, timeout=10)
            except (WorkerError, WorkerTimeout):
                pass
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.kill()
        for stream in (self.proc.stdin, self.proc.stdout):
            with contextlib.suppress(Exception):
                stream.close()


# ---- geometry -------------------------------------------------------------------------------------------


def rotation_about(axis, angle):
    import numpy as np

    axis = np.asarray(axis, dtype=np.float64)
    axis = axis / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * (k @ k)


def pose_errors(estimate, truth) -> tuple[float | None, float | None]:
    import numpy as np

    estimate = np.asarray(estimate, dtype=np.float64)
    if not np.all(np.isfinite(estimate)):
        return None, None
    r_est, r_gt = estimate[:3, :3], truth[:3, :3]
    cos = (np.trace(r_gt.T @ r_est) - 1.0) / 2.0
    rre = math.degrees(math.acos(max(-1.0, min(1.0, cos))))
    rte = float(np.linalg.norm(estimate[:3, 3] - truth[:3, 3]))
    return rre, rte


# ---- real data ------------------------------------------------------------------------------------------


def read_pair_txt(path: Path) -> dict[str, str]:
    out = {}
    for line in path.read_text().splitlines():
        if ":" in line:
            key, value = line.split(":", 1)
            out[key.strip()] = value.strip()
    return out


def list_pairs(data_dir: Path) -> list[dict]:
    rows = []
    lines = (data_dir / "index.tsv").read_text().splitlines()
    header = lines[0].split("\t")
    for line in lines[1:]:
        if not line.strip():
            continue
        row = dict(zip(header, line.split("\t"), strict=False))
        kind = row["kind"]
        if kind not in KIND_SETTINGS:
            raise SystemExit(f"bench: unknown kind {kind!r} in index.tsv; add it to KIND_SETTINGS")
        category, voxel = KIND_SETTINGS[kind]
        rows.append(
            {
                "dataset": row["dataset"],
                "pair": row["pair"],
                "pair_dir": row["pair_dir"],
                "kind": kind,
                "category": category,
                "voxel": voxel,
            }
        )
    return rows


def load_pair(data_dir: Path, row: dict):
    import kissm
    import numpy as np

    pair_dir = data_dir / row["pair_dir"]
    meta = read_pair_txt(pair_dir / "pair.txt")
    base = data_dir / row["dataset"]
    src = kissm.read_points(base / meta["source"], format=meta.get("source_format", "auto"))
    tgt = kissm.read_points(base / meta["target"], format=meta.get("target_format", "auto"))
    gt = np.loadtxt(pair_dir / "gt_T_target_source.txt", dtype=np.float64).reshape(4, 4)
    return src, tgt, gt


def make_cases(data_dir: Path, rows: list[dict], rotations: int, tmp: Path) -> list[dict]:
    """Loads each pair once and writes its raw and rotated variants as .npy files."""
    import numpy as np

    cases = []
    for row in rows:
        src, tgt, gt = load_pair(data_dir, row)
        name = f"{row['dataset']}/{row['pair']}"
        tgt_path = tmp / f"case{len(cases):03d}_tgt.npy"
        np.save(tgt_path, tgt)
        for r in range(rotations + 1):
            case = dict(row, name=name, index=len(cases), n_src=len(src), n_tgt=len(tgt), tgt_path=str(tgt_path))
            if r == 0:
                rot = np.eye(3)
                case.update(variant="raw", rot_deg=0.0)
            else:
                rng = np.random.default_rng(zlib.crc32(f"{name}#{r}".encode()))
                axis = rng.normal(size=3)
                angle = rng.uniform(0.3 * math.pi, math.pi)  # 54°..180° about a random axis
                rot = rotation_about(axis, angle)
                case.update(variant=f"rot{r}", rot_deg=math.degrees(angle))
            src_r = np.ascontiguousarray(src @ rot.T)
            truth = gt.copy()
            truth[:3, :3] = gt[:3, :3] @ rot.T  # p_t = R_gt p_s + t = (R_gt R^T)(R p_s) + t
            src_path = tmp / f"case{len(cases):03d}_src.npy"
            np.save(src_path, src_r)
            seed = zlib.crc32(f"{name}#{r}#ransac".encode()) & 0x7FFFFFFF  # Open3D takes an int32 seed
            case.update(src_path=str(src_path), gt=truth.tolist(), seed=seed)
            cases.append(case)
    return cases


# ---- synthetic scenes for the scaling runs ---------------------------------------------------------------


def _terrain(params, xy):
    import numpy as np

    z = np.zeros(len(xy))
    for amp, kx, ky, phase in params:
        z += amp * np.sin(kx * xy[:, 0] + ky * xy[:, 1] + phase)
    return z


SYN_TILE = 40.0  # objects are placed per 40 m tile, each tile from its own seed: a larger scene adds objects


def scene_layout(size: float, seed: int) -> dict:
    """The scene's geometry (shared by source and target): terrain waves, boxes (buildings), poles."""
    import numpy as np

    rng = np.random.default_rng(seed)
    waves = []
    for _ in range(6):
        wavelength = rng.uniform(15.0, 90.0)
        direction = rng.uniform(0, 2 * math.pi)
        k = 2 * math.pi / wavelength
        amplitude = rng.uniform(0.2, 0.8)
        waves.append((amplitude, k * math.cos(direction), k * math.sin(direction), rng.uniform(0, 2 * math.pi)))
    boxes, poles = [], []
    tiles = int(math.ceil(size / SYN_TILE))
    for i in range(tiles):
        for j in range(tiles):
            t = np.random.default_rng([seed, i, j])
            nb, npole = t.poisson(SYN_TILE**2 / 500.0), t.poisson(SYN_TILE**2 / 250.0)
            boxes.append(
                np.column_stack(
                    [
                        (i + t.uniform(0, 1, nb)) * SYN_TILE,
                        (j + t.uniform(0, 1, nb)) * SYN_TILE,  # centre
                        t.uniform(3.0, 18.0, nb),
                        t.uniform(3.0, 18.0, nb),  # width, depth
                        t.uniform(2.5, 14.0, nb),
                        t.uniform(0, math.pi, nb),  # height, yaw
                    ]
                )
            )
            poles.append(
                np.column_stack(
                    [
                        (i + t.uniform(0, 1, npole)) * SYN_TILE,
                        (j + t.uniform(0, 1, npole)) * SYN_TILE,
                        t.uniform(0.08, 0.35, npole),
                        t.uniform(3.0, 9.0, npole),  # radius, height
                    ]
                )
            )
    boxes, poles = np.concatenate(boxes), np.concatenate(poles)
    boxes = boxes[(boxes[:, 0] < size) & (boxes[:, 1] < size)]
    poles = poles[(poles[:, 0] < size) & (poles[:, 1] < size)]
    return {"size": size, "waves": waves, "boxes": boxes, "poles": poles}


def sample_scene(layout: dict, density: float, seed: int, x_range: tuple[float, float], noise: float = 0.02):
    """Samples the scene's surfaces uniformly (``density`` points per m²), keeping x within ``x_range``."""
    import numpy as np

    rng = np.random.default_rng(seed)
    size, waves = layout["size"], layout["waves"]
    parts = []
    # terrain
    n = rng.poisson(density * size * size)
    xy = rng.uniform(0, size, (n, 2))
    parts.append(np.column_stack([xy, _terrain(waves, xy)]))
    # boxes: four walls and a roof, sunk 0.5 m into the terrain
    b = layout["boxes"]
    w, d, h, yaw = b[:, 2], b[:, 3], b[:, 4], b[:, 5]
    face_area = np.column_stack([d * h, d * h, w * h, w * h, w * d])
    counts = rng.poisson(density * face_area.sum(axis=1))
    box = np.repeat(np.arange(len(b)), counts)
    cum = np.cumsum(face_area, axis=1)[box]
    u = rng.uniform(0, 1, len(box)) * cum[:, -1]
    face = (u[:, None] >= cum).sum(axis=1)
    a, c = rng.uniform(-0.5, 0.5, len(box)), rng.uniform(0, 1, len(box))
    bw, bd, bh = w[box], d[box], h[box]
    lx = np.where(face < 2, np.where(face == 0, -0.5, 0.5) * bw, a * bw)
    ly = np.where(face < 2, a * bd, np.where(face == 2, -0.5, 0.5) * bd)
    ly = np.where(face == 4, rng.uniform(-0.5, 0.5, len(box)) * bd, ly)
    lz = np.where(face == 4, bh, c * bh)
    cy, sy = np.cos(yaw[box]), np.sin(yaw[box])
    base = _terrain(waves, b[:, :2])[box] - 0.5
    parts.append(np.column_stack([b[box, 0] + cy * lx - sy * ly, b[box, 1] + sy * lx + cy * ly, base + lz]))
    # poles
    p = layout["poles"]
    counts = rng.poisson(density * 2 * math.pi * p[:, 2] * p[:, 3])
    pole = np.repeat(np.arange(len(p)), counts)
    theta = rng.uniform(0, 2 * math.pi, len(pole))
    base = _terrain(waves, p[:, :2])[pole]
    parts.append(
        np.column_stack(
            [
                p[pole, 0] + p[pole, 2] * np.cos(theta),
                p[pole, 1] + p[pole, 2] * np.sin(theta),
                base + rng.uniform(0, 1, len(pole)) * p[pole, 3],
            ]
        )
    )
    pts = np.concatenate(parts)
    pts = pts[(pts[:, 0] >= x_range[0] * size) & (pts[:, 0] <= x_range[1] * size)]
    pts += rng.normal(0, noise, pts.shape)
    return pts


def count_voxels(points, voxel: float) -> int:
    import numpy as np

    keys = np.floor(points / voxel).astype(np.int64)
    keys -= keys.min(axis=0)
    span = keys.max(axis=0) + 1
    flat = (keys[:, 0] * span[1] + keys[:, 1]) * span[2] + keys[:, 2]
    return int(len(np.unique(flat)))


SYN_DENSITY = 16.0  # points per m² of surface: about 4 points per 0.5 m voxel on flat ground
SYN_POSE = (math.radians(40.0), (0.3, 0.2, 1.0), (6.0, -4.0, 0.5))  # angle, axis, translation


def synthetic_pose():
    import numpy as np

    angle, axis, trans = SYN_POSE
    gt = np.eye(4)
    gt[:3, :3] = rotation_about(axis, angle)
    gt[:3, 3] = trans
    return gt


def make_synthetic(target_voxels: int, voxel: float, seed: int, tmp: Path, tag: str) -> dict:
    """Source/target clouds of one scene with about ``target_voxels`` voxels each (calibrated by size)."""
    import numpy as np

    size = math.sqrt(target_voxels / 1.3) * voxel  # first guess: ground voxels plus some walls
    for _ in range(6):
        layout = scene_layout(size, seed)
        # source and target overlap by about 70% (x in [0, 0.85] and [0.15, 1] of the extent)
        src_world = sample_scene(layout, SYN_DENSITY, seed + 1, (0.0, 0.85))
        n = count_voxels(src_world, voxel)
        if abs(n - target_voxels) <= 0.03 * target_voxels:
            break
        size *= math.sqrt(target_voxels / n)
    tgt = sample_scene(layout, SYN_DENSITY, seed + 2, (0.15, 1.0))
    gt = synthetic_pose()
    rot, trans = gt[:3, :3], gt[:3, 3]
    src = np.ascontiguousarray((src_world - trans) @ rot)  # R p_s + t = p_world
    src_path, tgt_path = tmp / f"syn_{tag}_src.npy", tmp / f"syn_{tag}_tgt.npy"
    np.save(src_path, src)
    np.save(tgt_path, tgt)
    return {
        "target_voxels": target_voxels,
        "extent_m": size,
        "n_src": len(src),
        "n_tgt": len(tgt),
        "voxels_numpy": n,
        "src_path": str(src_path),
        "tgt_path": str(tgt_path),
        "gt": gt.tolist(),
    }


# ---- running ---------------------------------------------------------------------------------------------


def median(values):
    values = [v for v in values if v is not None]
    return statistics.median(values) if values else None


def cpus_for(threads: int) -> list[int]:
    if hasattr(os, "sched_getaffinity"):
        available = sorted(os.sched_getaffinity(0))
    else:
        available = list(range(os.cpu_count() or 1))
    if threads > len(available):
        raise SystemExit(f"bench: {threads} threads asked for, but only CPUs {available} are available")
    return available[:threads]


def within(rre, rte, category: str) -> bool:
    max_rre, max_rte = THRESHOLDS[category]
    return rre is not None and rre < max_rre and rte < max_rte


def judge(record: dict, gt, category: str) -> None:
    import numpy as np

    rre, rte = pose_errors(record["transform"], np.asarray(gt))
    record["rre_deg"], record["rte_m"] = rre, rte
    record["success"] = bool(record["valid"] and within(rre, rte, category))
    if "coarse_transform" in record:  # a refining method: the errors of the pose it started from
        c_rre, c_rte = pose_errors(record["coarse_transform"], np.asarray(gt))
        record["coarse_rre_deg"], record["coarse_rte_m"] = c_rre, c_rte
        record["start_within"] = within(c_rre, c_rte, category)
        record["within"] = within(rre, rte, category)


def refine_settings() -> dict:
    """What the refinement peers share with kissm's refinement: its correspondence distance (as a gain on the
    voxel size) and its iteration cap, both kissm's defaults, read from the library."""
    import kissm

    config = kissm.Config()
    return {"max_distance_gain": config.refine_max_distance_gain, "max_iterations": config.refine_max_iterations}


def add_coarse_starts(cases: list[dict], threads: int) -> None:
    """kissm's coarse pose for each case (one untimed call in this process; kissm's result does not depend on
    the thread count): the start of the refinement peers, the same start kissm's own refinement has."""
    import kissm
    import numpy as np

    for case in cases:
        src, tgt = np.load(case["src_path"]), np.load(case["tgt_path"])
        with kissm.Matcher(voxel_size=case["voxel"], num_threads=threads) as matcher:
            r = matcher.register(src, tgt)
        rre, rte = pose_errors(r.transform, np.asarray(case["gt"]))
        case["coarse"] = {
            "transform": r.transform.tolist(),
            "valid": bool(r.valid),
            "rre_deg": rre,
            "rte_m": rte,
            "within": within(rre, rte, case["category"]),
        }


def slim(record: dict) -> dict:
    return {k: v for k, v in record.items() if k not in ("ok",)}


def run_real(args, cases, methods, threads_list, log, results) -> None:
    total = len(threads_list) * len(cases)
    done = 0
    refine = {}
    if any(m in REFINE_METHODS for m in methods):
        refine = refine_settings()
        results["meta"]["refine_settings"] = dict(refine, upstream_chain=UPSTREAM_CHAIN)
    if any(m in FROM_KISSM_START for m in methods):
        t0 = time.monotonic()
        add_coarse_starts(cases, max(threads_list))
        print(f"bench: kissm's coarse poses for {len(cases)} cases in {time.monotonic() - t0:.0f} s", flush=True)
        by_index = {c["index"]: c for c in cases}
        for c in results["cases"]:
            c["coarse"] = by_index[c["index"]]["coarse"]
    for threads in threads_list:
        cpus = cpus_for(threads)
        for case in cases:
            done += 1
            t_case = time.monotonic()
            workers: dict[str, Worker] = {}
            failed: dict[str, str] = {}
            for m in methods:
                try:
                    w = Worker(m, threads, cpus, log, args.python)
                    results["versions"].setdefault(m, w.hello.get("version"))
                    msg = {
                        "cmd": "load",
                        "src": case["src_path"],
                        "tgt": case["tgt_path"],
                        "voxel": case["voxel"],
                        "seed": case["seed"],
                    }
                    if m in REFINE_METHODS:
                        msg["init"] = case.get("coarse")
                        msg["refine"] = {
                            "max_distance": refine["max_distance_gain"] * case["voxel"],
                            "max_iterations": refine["max_iterations"],
                        }
                    load = w.call(msg, timeout=300)
                    w.baseline_kb = load["baseline_kb"]
                    workers[m] = w
                except (WorkerError, WorkerTimeout) as exc:
                    failed[m] = str(exc)
            base = {"threads": threads, "case": case["index"]}
            for rep in range(args.repeats + 1):  # rep 0 is the warm-up
                for m in methods:
                    if m in failed:
                        continue
                    try:
                        rec = workers[m].call({"cmd": "run"}, timeout=args.timeout)
                        judge(rec, case["gt"], case["category"])
                        if m in KISSM_REFINE_MODE and "coarse" in case:  # the peers' start, bit for bit?
                            rec["same_start"] = rec["coarse_transform"] == case["coarse"]["transform"]
                        rec["status"] = "ok"
                    except WorkerTimeout as exc:
                        failed[m] = "timeout"
                        rec = {"status": "timeout", "error": str(exc)}
                    except WorkerError as exc:
                        failed[m] = str(exc)
                        rec = {"status": "error", "error": str(exc)}
                    rec.update(base, method=m, rep=rep, warmup=rep == 0)
                    results["runs"].append(slim(rec))
            for m in methods:
                mem = {"threads": threads, "case": case["index"], "method": m}
                if m in workers and m not in failed:
                    st = workers[m].call({"cmd": "mem"}, timeout=30)
                    mem.update(
                        baseline_kb=workers[m].baseline_kb,
                        hwm_kb=st["VmHWM"],
                        peak_kb=max(0, st["VmHWM"] - workers[m].baseline_kb),
                    )
                else:
                    mem.update(error=failed.get(m, "not run"))
                    if m in failed and (failed[m] != "timeout" or args.smoke):
                        results["errors"].append(
                            f"{METHOD_LABEL[m]} on {case['name']} {case['variant']} ({threads}t): {failed[m]}"
                        )
                results["memory"].append(mem)
                if m in workers:
                    workers[m].close()
            line = []
            for m in methods:
                runs = [
                    r
                    for r in results["runs"]
                    if r["threads"] == threads
                    and r["case"] == case["index"]
                    and r["method"] == m
                    and not r["warmup"]
                    and r["status"] == "ok"
                ]
                if runs:
                    ok = sum(r["success"] for r in runs)
                    line.append(f"{m} {median([r['wall_ms'] for r in runs]):.0f}ms {ok}/{len(runs)}")
                else:
                    line.append(f"{m} {failed.get(m, '-')[:40]}")
            print(
                f"[{done}/{total}] {threads}t {case['name']} {case['variant']}: "
                + ", ".join(line)
                + f"  ({time.monotonic() - t_case:.0f} s, load {os.getloadavg()[0]:.1f})",
                flush=True,
            )


def _mem_available_kb() -> int | None:
    with contextlib.suppress(OSError, ValueError):
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1])
    return None


def projected_too_big(runs: list, sizes: list, method: str, target: int, timeout: float) -> str | None:
    """Why the next size should not be tried (projected memory or time from the smaller sizes), or None."""
    done = [r for r in runs if r["method"] == method and r["status"] == "ok"]
    if not done:
        return None
    last = done[-1]
    x_last = sizes[last["size"]]["voxels_numpy"]
    ratio = target / x_last
    exponent = 1.0
    if len(done) >= 2:
        prev = done[-2]
        x_prev = sizes[prev["size"]]["voxels_numpy"]
        if x_last > x_prev and prev["wall_ms"] > 0:
            exponent = max(1.0, math.log(last["wall_ms"] / prev["wall_ms"]) / math.log(x_last / x_prev))
    time_s = last["wall_ms"] / 1e3 * ratio**exponent
    if time_s > 2 * timeout:
        return f"projected {time_s:.0f} s per call from the smaller sizes, over twice the {timeout:.0f} s timeout"
    avail = _mem_available_kb()
    mem_kb = (last["peak_kb"] + last["baseline_kb"]) * ratio * 1.25
    if avail and mem_kb > 0.7 * avail:
        return (
            f"projected {mem_kb / 2**20:.1f} GB from the smaller sizes, over 70% of the "
            f"{avail / 2**20:.1f} GB available"
        )
    return None


def run_scaling(args, methods, threads, tmp, log, results) -> None:
    import numpy as np

    cpus = cpus_for(threads)
    voxel = args.scaling_voxel
    warm = make_synthetic(1000, voxel, 99, tmp, "warm")
    scaling = {
        "voxel": voxel,
        "threads": threads,
        "density": SYN_DENSITY,
        "timeout_s": args.scaling_timeout,
        "sizes": [],
        "runs": [],
    }
    results["scaling"] = scaling
    stopped: dict[str, str] = {}
    for i, target in enumerate(args.scaling_sizes):
        t_gen = time.monotonic()
        scene = make_synthetic(target, voxel, 1234, tmp, f"{i}")
        scene["gen_s"] = time.monotonic() - t_gen
        scene["index"] = i
        scaling["sizes"].append({k: v for k, v in scene.items() if not k.endswith("_path")})
        gt = np.asarray(scene["gt"])
        for m in methods:
            rec = {"size": i, "method": m}
            if m in stopped:
                rec.update(status="skipped", error=stopped[m])
                scaling["runs"].append(rec)
                continue
            why = projected_too_big(scaling["runs"], scaling["sizes"], m, target, args.scaling_timeout)
            if why:
                rec.update(status="skipped", error=why)
                stopped[m] = why
                scaling["runs"].append(rec)
                print(f"[scaling {threads}t] {target:>9} voxels {m}: skipped ({why})", flush=True)
                continue
            w = None
            try:
                w = Worker(m, threads, cpus, log, args.python)
                results["versions"].setdefault(m, w.hello.get("version"))
                w.call(
                    {"cmd": "load", "src": warm["src_path"], "tgt": warm["tgt_path"], "voxel": voxel, "seed": 7},
                    timeout=120,
                )
                w.call({"cmd": "run"}, timeout=args.scaling_timeout)  # warm-up on a small scene
                load = w.call(
                    {"cmd": "load", "src": scene["src_path"], "tgt": scene["tgt_path"], "voxel": voxel, "seed": 7},
                    timeout=600,
                )
                # The first call at a size is untimed: it is the first to touch that much memory in this
                # process, and on a VM whose balloon driver hands freed pages back to the host (this machine)
                # a first touch costs about 2.5 s per GB, which only the largest sizes, measured once, would
                # pay. Its time is kept as first_wall_ms.
                calls = []
                t_start = time.monotonic()
                while True:
                    r = w.call({"cmd": "run"}, timeout=args.scaling_timeout)
                    judge(r, gt, "synthetic")
                    calls.append(r)
                    runs = calls[1:]
                    if runs and (len(runs) >= args.scaling_repeats or time.monotonic() - t_start > 20.0):
                        break
                st = w.call({"cmd": "mem"}, timeout=30)
                rec.update(
                    status="ok",
                    n=len(runs),
                    walls_ms=[r["wall_ms"] for r in runs],
                    first_wall_ms=calls[0]["wall_ms"],
                    cpu={k: median([r["cpu"][k] for r in runs]) for k in ("user_ms", "sys_ms", "minflt")},
                    wall_ms=median([r["wall_ms"] for r in runs]),
                    engine_ms=median([r["engine_ms"] for r in runs]),
                    stages={
                        s: median([r["stages"].get(s) for r in runs])
                        for s in STAGES
                        if any(s in r["stages"] for r in runs)
                    },
                    success=runs[0]["success"],
                    valid=runs[0]["valid"],
                    rre_deg=runs[0]["rre_deg"],
                    rte_m=runs[0]["rte_m"],
                    info=runs[0].get("info", {}),
                    baseline_kb=load["baseline_kb"],
                    hwm_kb=st["VmHWM"],
                    peak_kb=max(0, st["VmHWM"] - load["baseline_kb"]),
                )
            except WorkerTimeout as exc:
                rec.update(status="timeout", error=str(exc))
                stopped[m] = f"timed out at {target} voxels"
            except WorkerError as exc:
                rec.update(status="error", error=str(exc))
                stopped[m] = f"failed at {target} voxels"
                results["errors"].append(f"scaling {METHOD_LABEL[m]} at {target} voxels: {exc}")
            finally:
                if w is not None:
                    w.close()
            scaling["runs"].append(rec)
            extra = (
                (f"{rec['wall_ms']:.0f} ms, +{rec['peak_kb'] / 1024:.0f} MB, {'ok' if rec['success'] else 'FAIL'}")
                if rec["status"] == "ok"
                else rec["status"]
            )
            print(
                f"[scaling {threads}t] {target:>9} voxels ({scene['n_src']} points) {m}: {extra}  "
                f"(load {os.getloadavg()[0]:.1f})",
                flush=True,
            )
        for path in (scene["src_path"], scene["tgt_path"]):
            with contextlib.suppress(OSError):
                os.unlink(path)


# ---- machine description --------------------------------------------------------------------------------


def package_versions(dists) -> dict[str, str | None]:
    """The installed version of each distribution, None where it is not installed (every bench's report)."""
    from importlib import metadata

    out: dict[str, str | None] = {}
    for dist in dists:
        try:
            out[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            out[dist] = None
    return out


def machine_info(python: str) -> dict:
    info = {"platform": platform.platform(), "python": platform.python_version(), "cpus_online": os.cpu_count()}
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                info["cpu"] = line.split(":", 1)[1].strip()
                break
    with contextlib.suppress(OSError):
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal"):
                info["mem_total_gb"] = round(int(line.split()[1]) / 2**20, 1)
    if hasattr(os, "sched_getaffinity"):
        info["cpus_allowed"] = sorted(os.sched_getaffinity(0))
    versions = package_versions(("kissm", "kiss-matcher", "open3d-cpu", "open3d", "small-gicp", "numpy", "matplotlib"))
    info["packages"] = {dist: version for dist, version in versions.items() if version is not None}
    with contextlib.suppress(Exception):
        head = subprocess.run(
            ["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"], capture_output=True, text=True, timeout=10
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "-C", str(REPO), "status", "--porcelain", "--untracked-files=no"],
            capture_output=True,
            text=True,
            timeout=10,
        ).stdout.strip()
        info["git"] = head + (" (with uncommitted changes)" if dirty else "")
    with contextlib.suppress(Exception):
        import kissm

        info["kissm_library"] = kissm.library_path
    return info


def available_methods(methods: list[str]) -> tuple[list[str], dict[str, str]]:
    ok, missing = [], {}
    for m in methods:
        absent = [mod for mod in METHOD_MODULES[m] if importlib.util.find_spec(mod) is None]
        if absent:
            missing[m] = "Python module " + " and ".join(repr(mod) for mod in absent) + " not installed"
        else:
            ok.append(m)
    return ok, missing


def parse_args(argv):
    p = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    p.add_argument("--threads", type=int, nargs="+", default=[1, 2], help="thread counts (default: 1 2)")
    p.add_argument("--rotations", type=int, default=2, help="rotated variants per pair besides the raw one (2)")
    p.add_argument("--repeats", type=int, default=3, help="timed calls per method and case after the warm-up (3)")
    p.add_argument(
        "--methods",
        nargs="+",
        choices=METHODS,
        default=list(METHODS),
        help="coarse: " + " ".join(COARSE_METHODS) + "; refinement: " + " ".join(REFINE_METHODS),
    )
    p.add_argument(
        "--refine-only",
        action="store_true",
        help="only the refinement comparison: kissm coarse and "
        "refined, small_gicp, Open3D GICP / point-to-plane, reference + small_gicp; no scaling",
    )
    p.add_argument("--pairs", nargs="*", default=None, help="only pairs whose dataset/pair contains one of these")
    p.add_argument("--data", type=Path, default=Path(os.environ.get("KISSM_DATA_DIR", REPO.parent / "shared" / "data")))
    p.add_argument("--out", type=Path, default=REPO / "docs" / "reports", help="writes OUT/benchmarks.md and OUT/img/*.png")
    p.add_argument(
        "--raw",
        type=Path,
        default=None,
        help="raw results JSON (default bench/results/latest.json with the default --out, else OUT/raw.json)",
    )
    p.add_argument("--timeout", type=float, default=600.0, help="seconds per call on real pairs (600)")
    p.add_argument("--no-real", action="store_true", help="skip the real pairs")
    p.add_argument("--no-scaling", action="store_true", help="skip the synthetic scaling runs")
    p.add_argument(
        "--scaling-sizes",
        type=int,
        nargs="+",
        default=[10_000, 30_000, 100_000, 300_000, 1_000_000, 3_000_000],
        help="target voxels per cloud",
    )
    p.add_argument(
        "--scaling-methods",
        nargs="+",
        choices=COARSE_METHODS,
        default=None,
        help="default: the coarse ones of --methods",
    )
    p.add_argument("--scaling-threads", type=int, default=None, help="default: the largest of --threads")
    p.add_argument("--scaling-voxel", type=float, default=0.5)
    p.add_argument(
        "--scaling-repeats",
        type=int,
        default=3,
        help="timed calls per size after one untimed call (fewer past 20 s) (3)",
    )
    p.add_argument(
        "--scaling-timeout",
        type=float,
        default=300.0,
        help="seconds per call; larger sizes are skipped for a method after a timeout (300)",
    )
    p.add_argument("--quick", action="store_true", help="1 rotation, 1 repeat, scaling up to 100K voxels")
    p.add_argument(
        "--smoke",
        action="store_true",
        help="seconds-long check of the harness: kissm (+ the reference "
        "if installed), one small real pair (or a synthetic one), tiny scaling, results in --out",
    )
    p.add_argument("--python", default=sys.executable, help=argparse.SUPPRESS)
    p.add_argument("--worker", default=None, help=argparse.SUPPRESS)
    p.add_argument("--cpus", default="", help=argparse.SUPPRESS)
    return p.parse_args(argv)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    args = parse_args(argv)
    if args.worker:
        return worker_main(args.worker, args.threads[0], [int(c) for c in args.cpus.split(",") if c])

    explicit = {a.split("=")[0] for a in argv if a.startswith("--")}
    if args.quick:
        if "--rotations" not in explicit:
            args.rotations = 1
        if "--repeats" not in explicit:
            args.repeats = 1
        if "--scaling-sizes" not in explicit:
            args.scaling_sizes = [10_000, 30_000, 100_000]
    if args.refine_only:
        if "--methods" not in explicit:  # the coarse ones for the coarse errors, times and success to compare
            args.methods = ["kissm", "reference", *REFINE_METHODS]
        args.no_scaling = True
    if args.smoke:
        if "--out" not in explicit:
            args.out = Path(tempfile.mkdtemp(prefix="kissm-bench-smoke-"))
        if "--methods" not in explicit:  # the fast methods; the peers among them only when installed
            args.methods = ["kissm", "reference", *REFINE_METHODS]
        if "--threads" not in explicit:
            args.threads = [1]
        if "--rotations" not in explicit:
            args.rotations = 1
        if "--repeats" not in explicit:
            args.repeats = 1
        if "--scaling-sizes" not in explicit:
            args.scaling_sizes = [10_000, 30_000]
        if "--scaling-methods" not in explicit:
            args.scaling_methods = ["kissm"]
        if "--pairs" not in explicit:
            args.pairs = ["kitti07_keyframes_gtsam_points/000002__000003"]
    if args.raw is None:  # the committed raw results only with the committed report
        committed = not args.smoke and args.out.resolve() == (REPO / "docs" / "reports").resolve()
        args.raw = HERE / "results" / "latest.json" if committed else args.out / "raw.json"

    methods, missing = available_methods(args.methods)
    if importlib.util.find_spec("kissm") is None:  # it reads the data and gives the refinement peers their start
        print("bench: the kissm Python package is not importable (pip install ./bindings/python)", file=sys.stderr)
        return 2
    if missing and not args.smoke:
        for m, why in missing.items():
            print(f"bench: {METHOD_LABEL[m]}: {why} (use bench/run.sh, or pass --methods)", file=sys.stderr)
        return 2
    if missing:
        print("bench: smoke run without " + ", ".join(METHOD_LABEL[m] for m in missing) + " (not installed)")
    scaling_methods = [m for m in (args.scaling_methods or methods) if m in methods and m in COARSE_METHODS]
    scaling_threads = args.scaling_threads or max(args.threads)
    for t in set(args.threads) | {scaling_threads}:
        cpus_for(t)

    command = "python bench/bench.py " + " ".join(shlex.quote(a) for a in argv)
    if os.environ.get("KISSM_BENCH_COMMAND"):
        command = os.environ["KISSM_BENCH_COMMAND"]
    results = {
        "meta": {
            "command": command,
            "args": {
                k: (str(v) if isinstance(v, Path) else v)
                for k, v in vars(args).items()
                if k not in ("worker", "cpus", "python")
            },
            "started": _dt.datetime.now().astimezone().isoformat(timespec="seconds"),
            "load_start": os.getloadavg(),
            "machine": machine_info(args.python),
            "methods": methods,
            "missing_methods": missing,
        },
        "versions": {},
        "cases": [],
        "runs": [],
        "memory": [],
        "scaling": None,
        "errors": [],
        "load_samples": [],
    }
    t0 = time.monotonic()
    args.out.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix="kissm-bench-"))
    log_path = args.out / "bench_workers.log" if args.smoke else tmp / "workers.log"
    print(
        f"bench: methods {', '.join(methods)}; threads {args.threads}; data {args.data}; "
        f"load {os.getloadavg()[0]:.1f}; worker log {log_path}",
        flush=True,
    )
    try:
        with open(log_path, "w") as log:
            if not args.no_real:
                if (args.data / "index.tsv").is_file():
                    rows = list_pairs(args.data)
                    if args.pairs is not None:
                        rows = [r for r in rows if any(s in f"{r['dataset']}/{r['pair']}" for s in args.pairs)]
                    cases = make_cases(args.data, rows, args.rotations, tmp)
                    results["cases"] = [{k: v for k, v in c.items() if not k.endswith("_path")} for c in cases]
                    run_real(args, cases, methods, args.threads, log, results)
                elif args.smoke:
                    print(f"bench: no data at {args.data}; the smoke run uses a synthetic pair instead")
                    scene = make_synthetic(5000, 0.5, 4321, tmp, "smoke")
                    case = {
                        "dataset": "synthetic",
                        "pair": "smoke",
                        "name": "synthetic/smoke",
                        "kind": "synthetic",
                        "category": "synthetic",
                        "voxel": 0.5,
                        "variant": "raw",
                        "rot_deg": 0.0,
                        "index": 0,
                        "n_src": scene["n_src"],
                        "n_tgt": scene["n_tgt"],
                        "src_path": scene["src_path"],
                        "tgt_path": scene["tgt_path"],
                        "gt": scene["gt"],
                        "seed": 1,
                    }
                    results["cases"] = [{k: v for k, v in case.items() if not k.endswith("_path")}]
                    run_real(args, [case], methods, args.threads, log, results)
                else:
                    print(f"bench: no data at {args.data} (set --data or KISSM_DATA_DIR)", file=sys.stderr)
                    return 2
            results["load_samples"].append(os.getloadavg())
            if not args.no_scaling:
                run_scaling(args, scaling_methods, scaling_threads, tmp, log, results)
    finally:
        results["meta"]["duration_s"] = time.monotonic() - t0
        results["meta"]["load_end"] = os.getloadavg()
        results["meta"]["finished"] = _dt.datetime.now().astimezone().isoformat(timespec="seconds")
        args.raw.parent.mkdir(parents=True, exist_ok=True)
        args.raw.write_text(json.dumps(results, indent=1))
        shutil.rmtree(tmp, ignore_errors=True)

    import report

    written = report.write_all(results, args.out, smoke=args.smoke)
    print(
        f"bench: wrote {', '.join(str(p) for p in written)} and {args.raw} in {results['meta']['duration_s']:.0f} s",
        flush=True,
    )
    if results["errors"]:
        print("bench: errors:\n  " + "\n  ".join(results["errors"]), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
