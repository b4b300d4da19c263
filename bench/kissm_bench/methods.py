# SPDX-License-Identifier: MIT
"""bench.py's methods: what each one calls, from the raw float64 arrays to a pose, and the record of one call
(wall time, stage times, pose, validity, counts). One :class:`Runner` lives in each worker process
(kissm_bench.workers), which imports this module before it pins itself: the libraries are imported by the
runner, after pinning."""

from __future__ import annotations

import resource
import time
from typing import TYPE_CHECKING, Any

from .common import finite, proc_status, reset_peak, trim_heap
from .reference import REFERENCE_MIN_VOXEL, estimate
from .reports.common import COARSE, REFINING

if TYPE_CHECKING:
    import numpy as np

COARSE_METHODS = COARSE
REFINE_METHODS = REFINING
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


def record(
    wall: float,
    engine: float,
    stages: dict[str, float],
    transform: np.ndarray,
    valid: bool,
    inliers: int,
    info: dict[str, Any],
    start: np.ndarray | None = None,
) -> dict[str, Any]:
    """One call's record: wall and engine time (ms), stage times, the pose, validity, inliers, the method's own
    details, and for a refining method the pose it started from."""
    rec = {
        "wall_ms": wall,
        "engine_ms": engine,
        "stages": stages,
        "transform": transform.tolist(),
        "valid": valid,
        "inliers": inliers,
        "info": info,
    }
    if start is not None:
        rec["coarse_transform"] = start.tolist()
    return rec


class Runner:
    """Runs one method on the loaded arrays; returns the per-call record."""

    def __init__(self, method: str, threads: int):
        import numpy as np

        self.np = np
        self.method = method
        self.threads = threads
        self.src: np.ndarray | None = None
        self.tgt: np.ndarray | None = None
        self.voxel = 0.0
        self.seed = 0
        self.init: np.ndarray | None = None  # the coarse pose the refinement peers start from
        self.coarse_valid = False
        self.refine: dict[str, Any] = {}
        self.lib: Any = None
        self.sg: Any = None
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

    def load(self, msg: dict[str, Any]) -> dict[str, Any]:
        np = self.np
        self.src = self.tgt = None
        trim_heap()
        self.src = np.ascontiguousarray(np.load(msg["src"]), dtype=np.float64)
        self.tgt = np.ascontiguousarray(np.load(msg["tgt"]), dtype=np.float64)
        self.voxel = float(msg["voxel"])
        self.seed = int(msg.get("seed", 0))
        self.refine = dict(msg.get("refine") or {})
        start = msg.get("init")
        self.init = None if start is None else np.asarray(start["transform"], dtype=np.float64).reshape(4, 4)
        self.coarse_valid = bool(start and start["valid"])
        trim_heap()
        reset_peak()
        st = proc_status()
        return {"baseline_kb": st.get("VmRSS", 0), "n_src": len(self.src), "n_tgt": len(self.tgt)}

    def _pair(self) -> tuple[np.ndarray, np.ndarray]:
        if self.src is None or self.tgt is None:
            raise ValueError("no case was loaded")
        return self.src, self.tgt

    def run(self) -> dict[str, Any]:
        # CPU time of the whole process (every thread) and page faults during the call: wall time on a VM
        # includes the kernel's work for memory touched for the first time, which the user time does not.
        before = resource.getrusage(resource.RUSAGE_SELF)
        rec: dict[str, Any] = getattr(self, "_run_" + self.method)()
        after = resource.getrusage(resource.RUSAGE_SELF)
        rec["cpu"] = {
            "user_ms": (after.ru_utime - before.ru_utime) * 1e3,
            "sys_ms": (after.ru_stime - before.ru_stime) * 1e3,
            "minflt": after.ru_minflt - before.ru_minflt,
        }
        return rec

    # ---- kissm: the Python binding, raw float64 arrays in, pose out --------------------------------------
    def _run_kissm(self, refine_mode: str | None = None) -> dict[str, Any]:
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
        info: dict[str, Any] = {
            "reason": r.reason,
            "src_voxels": r.num_source_voxels,
            "tgt_voxels": r.num_target_voxels,
            "src_keypoints": r.num_source_keypoints,
            "tgt_keypoints": r.num_target_keypoints,
            "initial_corr": r.num_initial_correspondences,
            "pruned_corr": r.num_pruned_correspondences,
        }
        if refine_mode:
            stages["refine"] = r.time_refine_ms
            info.update(
                overlap=finite(r.overlap),
                refine_rmse=finite(r.refine_rmse),
                refine_condition=finite(r.refine_condition),
                refine_iterations=int(r.refine_iterations),
                refine_converged=bool(r.refine_converged),
                refine_corr=int(r.num_refine_correspondences),
            )
        start = r.coarse_transform if refine_mode else None  # the solver's pose, which the refinement started from
        return record(wall, r.time_total_ms, stages, transform, bool(r.valid), int(r.num_final_inliers), info, start)

    def _run_kissm_gicp(self) -> dict[str, Any]:
        return self._run_kissm(KISSM_REFINE_MODE["kissm_gicp"])

    def _run_kissm_p2pl(self) -> dict[str, Any]:
        return self._run_kissm(KISSM_REFINE_MODE["kissm_p2pl"])

    # ---- the reference: PyPI kiss-matcher, its own C++ stage times -----------------------------------------
    def _run_reference(self) -> dict[str, Any]:
        if self.voxel < REFERENCE_MIN_VOXEL:
            raise ValueError(f"the reference refuses voxel sizes below {REFERENCE_MIN_VOXEL}")
        src, tgt = self._pair()
        e = estimate(self.lib, self.voxel, src, tgt)
        stages = {
            "voxelize": e.processing_ms,
            "features": e.extraction_ms,
            "matching": max(0.0, e.matching_ms - e.rejection_ms),
            "pruning": e.rejection_ms,
            "solver": e.solver_ms,
            "input": max(0.0, e.wall_ms - e.cxx_ms),
        }
        info = {"solution_valid": e.solution_valid}
        return record(e.wall_ms, e.cxx_ms, stages, e.transform, e.valid, e.inliers, info)

    # ---- Open3D: the standard FPFH recipe, then RANSAC or FGR ---------------------------------------------
    def _o3d_prepare(self, points: np.ndarray | None, times: dict[str, float]) -> tuple[Any, Any]:
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

    def _run_o3d(self, use_fgr: bool) -> dict[str, Any]:
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
        info = {"fitness": float(result.fitness), "src_voxels": len(src.points), "tgt_voxels": len(tgt.points)}
        # Open3D has no validity decision; a result with no correspondences (fitness 0) counts as invalid.
        return record(wall, wall, stages, transform, bool(result.fitness > 0), len(result.correspondence_set), info)

    def _run_o3d_ransac(self) -> dict[str, Any]:
        return self._run_o3d(False)

    def _run_o3d_fgr(self) -> dict[str, Any]:
        return self._run_o3d(True)

    # ---- refinement peers, from kissm's coarse pose (self.init) ---------------------------------------------
    def _start(self) -> np.ndarray:
        if self.init is None:
            raise ValueError("no initial pose was loaded (a refinement peer needs kissm's coarse pose)")
        return self.init

    def _run_sgicp(self) -> dict[str, Any]:
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
        info = {
            "converged": bool(result.converged),
            "iterations": int(result.iterations),
            "src_points": src.size(),
            "tgt_points": tgt.size(),
        }
        # small_gicp has no validity decision: its pose is reported when kissm's coarse pose was.
        return record(wall, wall, stages, transform, self.coarse_valid, int(result.num_inliers), info, start=init)

    def _run_o3d_refine(self, gicp: bool) -> dict[str, Any]:
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
        info = {
            "fitness": float(result.fitness),
            "inlier_rmse": float(result.inlier_rmse),
            "src_points": len(clouds[0].points),
            "tgt_points": len(clouds[1].points),
        }
        valid = self.coarse_valid and result.fitness > 0
        return record(wall, wall, stages, transform, valid, len(result.correspondence_set), info, start=init)

    def _run_o3d_gicp(self) -> dict[str, Any]:
        return self._run_o3d_refine(True)

    def _run_o3d_p2pl(self) -> dict[str, Any]:
        return self._run_o3d_refine(False)

    # ---- the upstream chain: reference coarse + small_gicp VGICP, as KISS-Matcher's ROS loop closure does -------
    def _run_ref_sgicp(self) -> dict[str, Any]:
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
        ref = estimate(km, v, src_xyz, tgt_xyz)
        coarse = ref.transform
        t2 = time.perf_counter()
        ref_engine, inliers = ref.cxx_ms, ref.inliers
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
        coarse_valid = ref.valid
        stages = {
            "voxelize": (t1 - t0) * 1e3,
            "reference": (t2 - t1) * 1e3,
            "preprocess": (t3 - t2) * 1e3,
            "align": (t4 - t3) * 1e3,
        }
        info = {
            "ref_engine_ms": ref_engine,
            "solution_valid": ref.solution_valid,
            "overlap": overlap,
            "converged": bool(result.converged),
            "iterations": int(result.iterations),
            "gates_valid": ref.solution_valid and inliers > chain["min_inliers"] and overlap >= chain["min_overlap"],
            "src_points": src.size(),
            "tgt_points": tgt.size(),
        }
        # engine: the Python wall minus the reference binding's copy of the points (its wall minus its C++).
        engine = wall - max(0.0, stages["reference"] - ref_engine)
        # valid: the reference's rule of the coarse comparison; gates_valid: upstream's own acceptance.
        return record(wall, engine, stages, transform, coarse_valid, inliers, info, start=coarse)
