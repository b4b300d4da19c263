# SPDX-License-Identifier: MIT
"""What the sections of the benchmark page share: the methods', stages' and datasets' labels and colours, the
results' index (:class:`Results`) and the cell and table formatting. The benchmark (kissm_bench.benchmark and its
workers) and the page (kissm_bench.reports.benchmarks) import it; it imports neither."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from ..common import med

METHOD_LABEL = {
    "kissm": "kissm",
    "reference": "KISS-Matcher (reference)",
    "o3d_ransac": "Open3D FPFH+RANSAC",
    "o3d_fgr": "Open3D FPFH+FGR",
    "kissm_gicp": "kissm + GICP refinement",
    "kissm_p2pl": "kissm + point-to-plane refinement",
    "sgicp": "small_gicp GICP from kissm's coarse pose",
    "o3d_gicp": "Open3D GICP from kissm's coarse pose",
    "o3d_p2pl": "Open3D point-to-plane ICP from kissm's coarse pose",
    "ref_sgicp": "reference + small_gicp VGICP (upstream chain)",
}
SHORT = {
    "kissm": "kissm",
    "reference": "reference",
    "o3d_ransac": "O3D RANSAC",
    "o3d_fgr": "O3D FGR",
    "kissm_gicp": "kissm GICP",
    "kissm_p2pl": "kissm P2PL",
    "sgicp": "small_gicp",
    "o3d_gicp": "O3D GICP",
    "o3d_p2pl": "O3D P2PL",
    "ref_sgicp": "ref + small_gicp",
}
COARSE = ("kissm", "reference", "o3d_ransac", "o3d_fgr")
REFINING = ("kissm_gicp", "kissm_p2pl", "sgicp", "o3d_gicp", "o3d_p2pl", "ref_sgicp")
STAGE_LABEL = {
    "input": "input / binding / other",
    "voxelize": "voxelise",
    "features": "normals + FPFH",
    "matching": "descriptor matching",
    "pruning": "pruning",
    "solver": "solver",
    "registration": "RANSAC / FGR (matching + solve)",
    "refine": "refinement",
    "reference": "reference estimate",
    "preprocess": "small_gicp preprocess (voxel grid, kd-tree, covariances)",
    "covariances": "covariances / normals",
    "align": "alignment",
}
STAGE_COLOR = {
    "input": "#9e9e9e",
    "voxelize": "#4e79a7",
    "features": "#f28e2b",
    "matching": "#59a14f",
    "pruning": "#e15759",
    "solver": "#b07aa1",
    "registration": "#edc948",
    "refine": "#d62728",
    "reference": "#1f77b4",
    "preprocess": "#ff9da7",
    "covariances": "#f1ce63",
    "align": "#76b7b2",
}
STAGE_ORDER = (
    "input",
    "voxelize",
    "features",
    "matching",
    "pruning",
    "solver",
    "registration",
    "refine",
    "reference",
    "preprocess",
    "covariances",
    "align",
)
METHOD_COLOR = {"kissm": "#d62728", "reference": "#1f77b4", "o3d_ransac": "#2ca02c", "o3d_fgr": "#9467bd"}
DATASET_LABEL = {
    "small_gicp_lidar": "small_gicp LiDAR",
    "stanford_bunny_scans": "Stanford bunny",
    "3dmatch_geotransformer_demo": "3DMatch (indoor)",
    "kitti07_keyframes_gtsam_points": "KITTI 07 keyframes",
    "kitti_demo_scans_unverified": "KITTI HDL-64E full scans",
    "synthetic": "synthetic",
}


def fmt(value: float | None, digits: int = 0, unit: str = "") -> str:
    if value is None:
        return "–"
    if isinstance(value, float) and not math.isfinite(value):
        return "–"
    return f"{value:,.{digits}f}{unit}"


def fmt_ms(value: float | None) -> str:
    if value is None:
        return "–"
    if value >= 100:
        return f"{value:,.0f}"
    if value >= 10:
        return f"{value:.1f}"
    return f"{value:.2f}"


def fmt_ratio(value: float | None) -> str:
    return "–" if value is None else f"{value:.1f}x"


def slope(xs: Sequence[float], ys: Sequence[float | None]) -> float | None:
    """The least-squares slope of log y against log x over the positive points (None under two)."""
    pts = [(math.log(x), math.log(y)) for x, y in zip(xs, ys, strict=False) if x and y and x > 0 and y > 0]
    if len(pts) < 2:
        return None
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    if sxx == 0:
        return None
    return sum((p[0] - mx) * (p[1] - my) for p in pts) / sxx


class Results:
    """Indexes the results (raw or reduced) for the tables."""

    def __init__(self, raw: dict[str, Any]):
        self.raw = raw
        self.cases = {c["index"]: c for c in raw["cases"]}
        self.all_methods = raw["meta"]["methods"]
        self.methods = [m for m in self.all_methods if m in COARSE]  # the coarse comparison's sections
        self.refining = [m for m in self.all_methods if m in REFINING]
        self.threads = sorted({r["threads"] for r in raw["runs"]})
        self.runs: dict[tuple[int, int, str], list[dict[str, Any]]] = {}
        self.status: dict[tuple[int, int, str], list[str]] = {}
        for r in raw["runs"]:
            if r.get("warmup"):
                continue
            key = (r["threads"], r["case"], r["method"])
            self.status.setdefault(key, []).append(r["status"])
            if r["status"] == "ok":
                self.runs.setdefault(key, []).append(r)
        self.memory = {(m["threads"], m["case"], m["method"]): m for m in raw["memory"]}
        self.pairs: list[str] = []
        for c in raw["cases"]:
            if c["name"] not in self.pairs:
                self.pairs.append(c["name"])

    def case_ids(self, pair: str | None = None, category: str | None = None, dataset: str | None = None) -> list[int]:
        return [
            i
            for i, c in self.cases.items()
            if (pair is None or c["name"] == pair)
            and (category is None or c["category"] == category)
            and (dataset is None or c["dataset"] == dataset)
        ]

    def collect(self, threads: int, case_ids: list[int], method: str) -> list[dict[str, Any]]:
        out: list[dict[str, Any]] = []
        for i in case_ids:
            out += self.runs.get((threads, i, method), [])
        return out

    def summary(self, threads: int, case_ids: list[int], method: str) -> dict[str, Any]:
        runs = self.collect(threads, case_ids, method)
        statuses = [s for i in case_ids for s in self.status.get((threads, i, method), [])]
        good = [r for r in runs if r["success"]]
        peaks = [self.memory.get((threads, i, method), {}).get("peak_kb") for i in case_ids]
        stages = {}
        for s in STAGE_ORDER:
            vals = [r["stages"].get(s) for r in runs if s in r["stages"]]
            if vals:
                stages[s] = med(vals)
        return {
            "n": len(statuses),
            "ok": len(runs),
            "success": len(good),
            "timeouts": statuses.count("timeout"),
            "errors": statuses.count("error"),
            "wall": med([r["wall_ms"] for r in runs]),
            "engine": med([r["engine_ms"] for r in runs]),
            "stages": stages,
            "rre": med([r["rre_deg"] for r in good]),
            "rte": med([r["rte_m"] for r in good]),
            "peak_mb": (max(p for p in peaks if p is not None) / 1024) if any(p is not None for p in peaks) else None,
            "valid": sum(r["valid"] for r in runs),
            "wrong_valid": sum(r["valid"] and not r["success"] for r in runs),
        }


def machine_busy(meta: dict[str, Any]) -> bool:
    """Whether the load average at the start or the end of the run was over half the CPUs."""
    ls, le = meta.get("load_start"), meta.get("load_end")
    return bool(ls and le and max(ls[0], le[0]) > 0.5 * (meta["machine"].get("cpus_online") or 1))


def success_cell(s: dict[str, Any]) -> str:
    if s["n"] == 0:
        return "–"
    cell = f"{s['success']}/{s['n']}"
    if s["timeouts"]:
        cell += f" ({s['timeouts']} timeout)"
    if s["errors"]:
        cell += f" ({s['errors']} error)"
    return cell


def rte_cell(value: float | None, category: str) -> str:
    if value is None:
        return "–"
    if category == "object":
        return f"{value * 1000:.2f} mm"
    if category == "indoor":
        return f"{value * 100:.1f} cm"
    return f"{value:.3f} m"


# ---- tables -----------------------------------------------------------------------------------------------


def table(header: Sequence[str], rows: Sequence[Sequence[Any]], align: Sequence[str] | None = None) -> str:
    align = align or ["---"] + ["--:"] * (len(header) - 1)
    out = ["| " + " | ".join(header) + " |", "|" + "|".join(align) + "|"]
    out += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(out)
