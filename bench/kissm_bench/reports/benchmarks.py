# SPDX-License-Identifier: MIT
"""docs/reports/benchmarks.md and its plots in docs/reports/img/, from the results of bench.py: the coarse
comparison, the refinement part (issue 14: kissm's refinement against small_gicp and Open3D from the same coarse
pose, and kissm coarse + refine against the upstream chain, reference + small_gicp, with the targets' verdicts)
and the scaling runs.

``python bench/report.py RESULTS --out DIR`` rewrites the page from saved results: the reduced ones of
bench/results/latest.json.gz, or a raw results file.
"""

from __future__ import annotations

import argparse
import importlib.util
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

from .. import results as results_io
from ..common import REPORTS, med, ordered_packages
from ..results import pick
from .common import (
    DATASET_LABEL,
    METHOD_COLOR,
    METHOD_LABEL,
    SHORT,
    STAGE_COLOR,
    STAGE_LABEL,
    STAGE_ORDER,
    Results,
    fmt,
    fmt_ms,
    fmt_ratio,
    machine_busy,
    rte_cell,
    slope,
    success_cell,
    table,
)


def make_plots(res: Results, img_dir: Path) -> dict[str, Path]:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return {}
    img_dir.mkdir(parents=True, exist_ok=True)
    plots = {}
    lidar_pairs = [p for p in res.pairs if res.cases[res.case_ids(pair=p)[0]]["category"] == "lidar"]
    show_pairs = (lidar_pairs or res.pairs) if res.methods else []
    for threads in res.threads:
        if not show_pairs:
            break
        n = len(show_pairs)
        cols = 2 if n > 1 else 1
        rows = math.ceil(n / cols)
        fig, axes = plt.subplots(
            rows, cols, figsize=(7.0 * cols, 0.55 * len(res.methods) * rows + 1.0 * rows + 0.8), squeeze=False
        )
        used = set()
        for ax, pair in zip(axes.flat, show_pairs, strict=False):
            ids = res.case_ids(pair=pair)
            c = res.cases[ids[0]]
            labels, y = [], 0
            for m in reversed(res.methods):
                s = res.summary(threads, ids, m)
                left = 0.0
                for st in STAGE_ORDER:
                    v = s["stages"].get(st)
                    if not v:
                        continue
                    ax.barh(
                        y,
                        v,
                        left=left,
                        color=STAGE_COLOR[st],
                        edgecolor="white",
                        linewidth=0.4,
                        hatch="//" if st == "input" and m == "reference" else None,
                        label=STAGE_LABEL[st] if st not in used else None,
                    )
                    used.add(st)
                    left += v
                if s["wall"] is not None:
                    text = f" {s['wall']:,.0f} ms"
                    if m == "reference" and s["engine"] is not None:
                        text = f" {s['wall']:,.0f} ms (C++ {s['engine']:,.0f})"
                    ax.text(left, y, text, va="center", fontsize=8)
                else:
                    ax.text(0, y, " not run / timeout", va="center", fontsize=8)
                labels.append(SHORT[m])
                y += 1
            ax.set_yticks(range(len(labels)), labels)
            ax.set_title(f"{pair} (v = {c['voxel']} m, {c['n_src'] // 1000}K/{c['n_tgt'] // 1000}K pts)", fontsize=9)
            ax.set_xlabel("median wall time per call [ms]")
            ax.margins(x=0.28)
            ax.grid(axis="x", alpha=0.3)
        for ax in list(axes.flat)[n:]:
            ax.axis("off")
        fig.legend(loc="lower center", ncol=4, fontsize=8, frameon=False)
        fig.suptitle(
            f"Per-stage time, {_threads_title(threads)} (median over raw + rotated variants and repeats)",
            fontsize=11,
        )
        fig.tight_layout(rect=(0, 0.07 if rows > 1 else 0.12, 1, 0.97))
        path = img_dir / f"stage_times_{threads}t.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        plots[f"stage_times_{threads}t"] = path

    plots.update(refine_plot(res, img_dir, plt))

    sc = res.raw.get("scaling")
    if sc and any(r["status"] == "ok" for r in sc["runs"]):
        xs = scaling_x(sc)
        for kind in ("time", "memory"):
            fig, ax = plt.subplots(figsize=(7.5, 5.2))
            for m in res.methods:
                pts = [
                    (xs[r["size"]], r["wall_ms"] / 1e3 if kind == "time" else r["peak_kb"] / 1024)
                    for r in sc["runs"]
                    if r["method"] == m and r["status"] == "ok"
                ]
                if not pts:
                    continue
                _loglog_fit(ax, pts, "o-", METHOD_COLOR[m], 2, METHOD_LABEL[m])
                stops = [r for r in sc["runs"] if r["method"] == m and r["status"] == "timeout"]
                if stops and kind == "time":  # a timed-out call: drawn at the timeout, "more than this"
                    ax.plot([xs[stops[0]["size"]]], [sc["timeout_s"]], "x", color=METHOD_COLOR[m], ms=10, mew=2)
                    ax.annotate(
                        "timeout",
                        (xs[stops[0]["size"]], sc["timeout_s"]),
                        textcoords="offset points",
                        xytext=(6, -3),
                        fontsize=7,
                        color=METHOD_COLOR[m],
                    )
            if kind == "time":
                for st in ("voxelize", "features", "matching", "pruning", "solver"):
                    pts = [
                        (xs[r["size"]], r["stages"].get(st, 0) / 1e3)
                        for r in sc["runs"]
                        if r["method"] == "kissm" and r["status"] == "ok"
                    ]
                    pts = [p for p in pts if p[1] > 0]
                    if len(pts) < 2:
                        continue
                    _loglog_fit(ax, pts, "--", STAGE_COLOR[st], 1.2, f"kissm {STAGE_LABEL[st]}")
                ax.set_ylabel("median wall time per call [s]")
                ax.set_title(f"Time vs size, synthetic scenes, {sc['threads']} thread(s), v = {sc['voxel']} m")
            else:
                ax.set_ylabel("peak memory above the input arrays [MB]")
                ax.set_title(f"Peak memory vs size, synthetic scenes, v = {sc['voxel']} m")
            lo, hi = min(xs.values()), max(xs.values())
            ref = [lo, hi]
            ax.set_xlabel("voxels per cloud (source, as counted by kissm)")
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=7.5, loc="upper left")
            ax.set_xlim(lo / 1.5, hi * 1.5)
            del ref
            fig.tight_layout()
            path = img_dir / f"scaling_{kind}.png"
            fig.savefig(path, dpi=110)
            plt.close(fig)
            plots[f"scaling_{kind}"] = path
    return plots


def _loglog_fit(ax: Any, pts: list[tuple[float, float]], style: str, color: str, lw: float, label: str) -> None:
    """``pts`` on log-log axes, labelled with their least-squares slope."""
    xs, ys = [p[0] for p in pts], [p[1] for p in pts]
    k = slope(xs, ys)
    ax.loglog(xs, ys, style, color=color, lw=lw, label=f"{label} (slope {k:.2f})" if k is not None else label)


def scaling_x(sc: dict[str, Any]) -> dict[int, float]:
    """Each scaling size's x: the source voxels kissm counted, else numpy's count."""
    xs = {}
    for size in sc["sizes"]:
        i = size["index"]
        k = [r for r in sc["runs"] if r["size"] == i and r["method"] == "kissm" and r["status"] == "ok"]
        xs[i] = (
            float(k[0]["info"]["src_voxels"])
            if k and k[0].get("info", {}).get("src_voxels")
            else float(size["voxels_numpy"])
        )
    return xs


# ---- markdown ---------------------------------------------------------------------------------------------

#: The per-pair tables' stage columns and their headers.
PER_PAIR_STAGES = {
    "voxelize": "voxelise",
    "features": "features",
    "matching": "matching",
    "pruning": "pruning",
    "solver": "solver",
    "registration": "RANSAC/FGR",
    "input": "input/other",
}


def render(raw: dict[str, Any], plots: dict[str, Path], out_dir: Path, smoke: bool) -> str:
    res = Results(raw)
    meta = raw["meta"]
    mach = meta["machine"]
    methods = res.methods
    peers = [m for m in methods if m != "kissm"]
    L = []
    L.append("# Benchmarks")
    L.append("")
    if smoke:
        L.append("**Smoke run** (a seconds-long check of the harness, not a measurement).")
        L.append("")
    L.append(
        "Generated by `bench/bench.py` (do not edit by hand; rerun it). kissm against the reference "
        "implementation (PyPI `kiss-matcher`), Open3D FPFH + RANSAC and Open3D FPFH + FGR, and kissm's "
        "refinement against small_gicp, Open3D GICP / point-to-plane ICP and the reference + small_gicp chain, "
        "in one run on one machine, interleaved, with the same voxel size and thread count for every method."
    )
    L.append("")
    L.append(f"- Command: `{meta['command']}`")
    L.append(f"- Run: {meta['started']} to {meta.get('finished', '?')} ({meta.get('duration_s', 0) / 60:.0f} min)")
    ls, le = meta.get("load_start"), meta.get("load_end")
    if ls and le:
        busy = machine_busy(meta)
        L.append(
            f"- Load average (1/5/15 min) at the start {ls[0]:.2f} / {ls[1]:.2f} / {ls[2]:.2f}, at the end "
            f"{le[0]:.2f} / {le[1]:.2f} / {le[2]:.2f} on {mach.get('cpus_online')} CPUs"
            + (
                " — **the machine was busy with other work: absolute times are noisy; ratios come from "
                "interleaved calls and are more robust**"
                if busy
                else ""
            )
        )
    L.append(
        f"- Machine: {mach.get('cpu', '?')}, {mach.get('cpus_online')} CPUs (allowed: "
        f"{mach.get('cpus_allowed')}), {mach.get('mem_total_gb', '?')} GB RAM, {mach.get('platform')}, "
        f"Python {mach.get('python')}"
    )
    pk = mach.get("packages", {})
    L.append(
        "- Versions: "
        + ", ".join(f"{k} {v}" for k, v in ordered_packages(pk))
        + (f"; kissm build {mach['git']}" if mach.get("git") else "")
    )
    if meta.get("missing_methods"):
        missing = sorted(meta["missing_methods"], key=list(METHOD_LABEL).index)  # saved results sort their keys
        L.append("- Not run (not installed): " + ", ".join(METHOD_LABEL[m] for m in missing))
    L.append("")

    L.append("## How it is measured")
    L.append("")
    L.append("""- **Data**: every pair of `../shared/data` (SPEC §7), raw and with the source turned about its origin by
  large random rotations (54°–180° about a random axis, fixed seeds; ground truth composed accordingly). Voxel
  sizes: LiDAR keyframes 0.5 m, full LiDAR scans 0.3 m, 3DMatch 0.05 m, bunny 0.006 m. Success: a pose reported
  valid within 5° and 2 m (LiDAR), 0.3 m (indoor) or 0.01 m (bunny) of the ground truth. RRE/RTE are medians over
  the successful calls.
- **Same input for everyone**: each case is read once (kissm's readers), kept as float64 (N, 3) numpy arrays, and
  every timed call starts from those raw arrays: matcher construction, conversion, voxelisation, features,
  matching and solving are all inside the wall time.
- **Threads**: each method runs in its own worker process per (thread count, case), pinned to the first T CPUs
  with `sched_setaffinity` (what `taskset` does) before any library is loaded, with `OMP_NUM_THREADS=T`
  (the reference's TBB and OpenMP pools and Open3D's OpenMP size themselves from the mask); kissm also gets
  `num_threads=T`.
- **Order**: one warm-up call per method, then the timed calls interleaved (A B C D, A B C D, …); the median
  over the repeats (and, in the per-pair tables, over the variants) is reported.
- **Stage times**: kissm's own `Result.time_*_ms` (\"input\" = the Python call minus the library's total); the
  reference's own C++ getters (voxelisation, extraction, matching minus its ROBIN pruning, pruning, solver;
  \"input\" = its Python wall time minus the sum of its C++ stages, i.e. the binding copying the points);
  Open3D's stages timed around each call (\"input\" = numpy to `PointCloud`).
- **Reference times**: \"C++\" is the sum of the reference's own stage times (processing + extraction +
  matching + solver; its matching includes the pruning), the number the 3x target is judged against;
  \"wall\" is its Python call. The reference's pose counts as reported valid when `solution.valid` and it has at
  least 5 final inliers (its examples' threshold); kissm uses its default `min_inliers`; Open3D has no validity
  decision, so its pose counts as reported unless its fitness is 0.
- **Peak memory**: `VmHWM` of the worker after the warm-up and the timed calls, minus its resident size just
  before the first call (after imports and loading the arrays, with `malloc_trim` and the peak counter reset
  through `/proc/self/clear_refs`): what the calls add on top of the input, including one-time initialisation.
- **Open3D recipe**: `voxel_down_sample(v)`, normals with `KDTreeSearchParamHybrid(2v, 30)`, FPFH with
  `(5v, 100)`; RANSAC: mutual filter, max correspondence distance 1.5v, point-to-point, `ransac_n = 3`, edge
  length 0.9 and distance 1.5v checkers, `RANSACConvergenceCriteria(100000, 0.999)`, seeded per case; FGR:
  `FastGlobalRegistrationOption(maximum_correspondence_distance = 0.5v)`.
- **small_gicp** and Open3D's ICP variants only register locally, from an initial guess: they are the peers
  of kissm's refinement stage, from kissm's coarse pose, in [Refinement](#refinement).""")
    L.append("")

    lidar_pairs = [p for p in res.pairs if res.cases[res.case_ids(pair=p)[0]]["category"] == "lidar"]

    # ---- speed-up ----
    if res.runs and methods:
        L.append("## Speed-up of kissm")
        L.append("")
        L.append(
            "Median wall time of one call per LiDAR pair (over its raw and rotated variants and the repeats), "
            "and the speed-up of kissm = peer time / kissm time from the same interleaved run. "
            '"min" is the smallest per-variant ratio. Target (SPEC §8): kissm\'s end-to-end Python call at least '
            "3x faster than the reference's own C++ stage times on every LiDAR pair, at every thread count."
        )
        L.append("")
        for threads in res.threads:
            header = ["pair (LiDAR)", "kissm [ms]"]
            if "reference" in methods:
                header += ["ref C++ [ms]", "ref wall [ms]", "vs ref C++ (min)", "≥ 3x", "vs ref wall"]
            for m in peers:
                if m != "reference":
                    header += [f"{SHORT[m]} [ms]", f"vs {SHORT[m]}"]
            rows = []
            for pair in lidar_pairs or res.pairs:
                ids = res.case_ids(pair=pair)
                k = res.summary(threads, ids, "kissm")
                row = [pair, fmt_ms(k["wall"])]
                if "reference" in methods:
                    r = res.summary(threads, ids, "reference")
                    ratio = r["engine"] / k["wall"] if r["engine"] and k["wall"] else None
                    per_case = []
                    for i in ids:
                        kk = med([x["wall_ms"] for x in res.runs.get((threads, i, "kissm"), [])])
                        rr = med([x["engine_ms"] for x in res.runs.get((threads, i, "reference"), [])])
                        if kk and rr:
                            per_case.append(rr / kk)
                    lo = min(per_case) if per_case else None
                    verdict = "–" if lo is None else ("yes" if lo >= 3 else "**no**")
                    rw = r["wall"] / k["wall"] if r["wall"] and k["wall"] else None
                    row += [
                        fmt_ms(r["engine"]),
                        fmt_ms(r["wall"]),
                        f"{fmt_ratio(ratio)} ({fmt_ratio(lo)})",
                        verdict,
                        fmt_ratio(rw),
                    ]
                for m in peers:
                    if m == "reference":
                        continue
                    p = res.summary(threads, ids, m)
                    note = ""
                    if p["timeouts"]:
                        note = " (timeouts)"
                    row += [
                        fmt_ms(p["wall"]) + note,
                        fmt_ratio(p["wall"] / k["wall"] if p["wall"] and k["wall"] else None),
                    ]
                rows.append(row)
            L.append(f"### {_threads_title(threads)}")
            L.append("")
            L.append(table(header, rows))
            L.append("")
            if "reference" in methods:
                L += _speed_target_lines(res, threads, lidar_pairs or res.pairs)
        L += _stage_scaling_table(res, lidar_pairs or res.pairs)

    # ---- success per dataset ----
    if res.runs and methods:
        L.append("## Success per dataset")
        L.append("")
        L.append(
            "Successful calls / timed calls, over raw and rotated variants and repeats; median RRE / RTE over "
            'the successes. "wrong valid" counts poses reported valid but outside the thresholds.'
        )
        L.append("")
        datasets = _datasets(res)
        for threads in res.threads:
            header = ["dataset (cases)"] + [f"{SHORT[m]}" for m in methods]
            rows = []
            totals = {m: [0, 0, 0] for m in methods}
            for ds in datasets:
                ids = res.case_ids(dataset=ds)
                cat = res.cases[ids[0]]["category"]
                row = [f"{DATASET_LABEL.get(ds, ds)} ({len(ids)})"]
                for m in methods:
                    s = res.summary(threads, ids, m)
                    totals[m][0] += s["success"]
                    totals[m][1] += s["n"]
                    totals[m][2] += s["wrong_valid"]
                    cell = success_cell(s)
                    if s["success"]:
                        cell += f"; {fmt(s['rre'], 2)}° / {rte_cell(s['rte'], cat)}"
                    if s["wrong_valid"]:
                        cell += f"; {s['wrong_valid']} wrong valid"
                    row.append(cell)
                rows.append(row)
            rows.append(
                ["**total**"]
                + [
                    f"**{t[0]}/{t[1]}**" + (f" ({t[2]} wrong valid)" if t[2] else "")
                    for t in (totals[m] for m in methods)
                ]
            )
            L.append(f"### {_threads_title(threads)}")
            L.append("")
            L.append(table(header, rows, ["---"] + ["---"] * len(methods)))
            L.append("")

    # ---- refinement (issue 14) ----

    L += refine_section(res, plots, out_dir)

    # ---- stage plots ----
    stage_plots = [k for k in plots if k.startswith("stage_times_")]
    # Without matplotlib the section keeps its text and says why its plots are missing (the page's tables are the
    # same either way: bench/check_pages.py compares them on machines without it).
    no_matplotlib = importlib.util.find_spec("matplotlib") is None
    if stage_plots or (no_matplotlib and res.methods and res.pairs):
        L.append("## Where the time goes")
        L.append("")
        L.append(
            "Per-stage median times per method on each LiDAR pair (hatched: the reference's Python binding "
            "copying the points, outside its own C++ stage times)."
        )
        L.append("")
        for name in sorted(stage_plots):
            L.append(f"![{name}]({plots[name].relative_to(out_dir).as_posix()})")
            L.append("")
        if not stage_plots:
            L += ["(No plot: matplotlib is not installed.)", ""]

    # ---- per pair tables ----
    if res.runs and methods:
        L.append("## Per pair")
        L.append("")
        L.append(
            "Aggregated over each pair's variants (raw + rotated) and repeats. Times in ms (medians); "
            "peak memory is the largest over the pair's variants."
        )
        L.append("")
        for threads in res.threads:
            L.append(f"### {_threads_title(threads)}")
            L.append("")
            header = ["pair", "method", "success", "RRE", "RTE", "wall", *PER_PAIR_STAGES.values(), "peak MB"]
            rows = []
            for pair in res.pairs:
                ids = res.case_ids(pair=pair)
                cat = res.cases[ids[0]]["category"]
                for m in methods:
                    s = res.summary(threads, ids, m)
                    st = s["stages"]
                    rows.append(
                        [
                            pair if m == methods[0] else "",
                            SHORT[m],
                            success_cell(s),
                            fmt(s["rre"], 2, "°"),
                            rte_cell(s["rte"], cat),
                            fmt_ms(s["wall"]),
                            *(fmt_ms(st.get(x)) for x in PER_PAIR_STAGES),
                            fmt(s["peak_mb"], 0),
                        ]
                    )
            L.append(table(header, rows, ["---", "---", "---"] + ["--:"] * (len(header) - 3)))
            L.append("")

        L.append("<details><summary>Every case (pair × variant)</summary>")
        L.append("")
        for threads in res.threads:
            L.append(f"#### {_threads_title(threads)}")
            L.append("")
            header = ["case", "rotation", "method", "success", "RRE", "RTE", "inliers"]
            header += ["wall [ms]", "engine [ms]", "peak MB"]
            rows = []
            for i, c in res.cases.items():
                for m in methods:
                    s = res.summary(threads, [i], m)
                    runs = res.runs.get((threads, i, m), [])
                    rows.append(
                        [
                            f"{c['name']} {c['variant']}" if m == methods[0] else "",
                            f"{c['rot_deg']:.0f}°" if m == methods[0] else "",
                            SHORT[m],
                            success_cell(s),
                            fmt(med([r["rre_deg"] for r in runs]), 2, "°"),
                            rte_cell(med([r["rte_m"] for r in runs]), c["category"]),
                            fmt(med([r["inliers"] for r in runs]), 0),
                            fmt_ms(s["wall"]),
                            fmt_ms(s["engine"]),
                            fmt(s["peak_mb"], 0),
                        ]
                    )
            L.append(table(header, rows, ["---", "--:", "---", "---"] + ["--:"] * 6))
            L.append("")
        L.append("(RRE/RTE here are medians over all calls, successful or not.)")
        L.append("")
        L.append("</details>")
        L.append("")

    # ---- scaling ----
    sc = raw.get("scaling")
    if sc and sc["runs"]:
        xs = scaling_x(sc)
        sm = [m for m in methods if any(r["method"] == m for r in sc["runs"])]
        L.append("## Scaling (synthetic scenes)")
        L.append("")
        L.append(
            f"Synthetic outdoor scenes (seeded): wavy terrain, box buildings and poles, sampled at "
            f"{sc['density']:.0f} points/m² with 2 cm noise; source and target are independent samplings "
            f"overlapping by about 70% with a known pose (40° about a tilted axis, 7 m). Voxel size "
            f"{sc['voxel']} m, {sc['threads']} thread(s), one fresh worker per (method, size) with a warm-up on a "
            f"small scene and one untimed call at the size itself, then the median of up to 3 calls (1 past "
            f"20 s); a call over {sc['timeout_s']:.0f} s is a timeout and the method's larger sizes are "
            f"skipped. Peak memory as above. The untimed call is the first to touch that much memory in its "
            f"process: on this machine (a VM whose balloon driver hands freed memory back to the host) a first "
            f"touch costs about 2.5 s per GB, which only the largest sizes, measured once, would otherwise "
            f"pay; kissm's first-call times are listed below the table."
        )
        L.append("")
        header = ["voxels / cloud", "points (src + tgt)"]
        for m in sm:
            header += [f"{SHORT[m]} [s]", f"{SHORT[m]} MB"]
        header += ["kissm success"]
        rows = []
        for size in sc["sizes"]:
            i = size["index"]
            row = [f"{xs[i]:,.0f}", f"{size['n_src'] + size['n_tgt']:,}"]
            ksucc = "–"
            for m in sm:
                run = next((r for r in sc["runs"] if r["size"] == i and r["method"] == m), None)
                if run is None:
                    row += ["–", "–"]
                elif run["status"] == "ok":
                    row += [fmt(run["wall_ms"] / 1e3, 2), fmt(run["peak_kb"] / 1024, 0)]
                    if m == "kissm":
                        ksucc = "yes" if run["success"] else f"no (RRE {fmt(run['rre_deg'], 1)}°)"
                else:
                    row += [run["status"], "–"]
            row.append(ksucc)
            rows.append(row)
        L.append(table(header, rows))
        L.append("")
        firsts = [
            (sc["sizes"][r["size"]], r)
            for r in sc["runs"]
            if r["method"] == "kissm" and r["status"] == "ok" and r.get("first_wall_ms") is not None
        ]
        if firsts:
            L.append(
                "kissm's untimed first call per size [s]: "
                + ", ".join(f"{xs[size['index']]:,.0f} voxels {fmt(r['first_wall_ms'] / 1e3, 2)}" for size, r in firsts)
                + "."
            )
            L.append("")
        for r in sc["runs"]:
            if r["status"] != "ok":
                size = sc["sizes"][r["size"]]
                L.append(
                    f"- {METHOD_LABEL[r['method']]} at {size['target_voxels']:,} voxels: {r['status']} "
                    f"({(r.get('error') or '').splitlines()[0] if r.get('error') else ''})"
                )
        if any(r["status"] != "ok" for r in sc["runs"]):
            L.append("")
        # slopes
        L.append(
            "Log–log slopes (1.0 = linear): over every size the method finished (least squares), and between "
            "its two largest sizes (local, where superlinear growth shows first):"
        )
        L.append("")
        rows = []
        superlinear = []
        for m in sm:
            ok = [r for r in sc["runs"] if r["method"] == m and r["status"] == "ok"]
            if len(ok) < 2:
                continue
            x = [xs[r["size"]] for r in ok]

            def add(
                quantity: str, ys: list[float | None], note: str, label: str = METHOD_LABEL[m], x: list[float] = x
            ) -> None:
                whole, local = slope(x, ys), slope(x[-2:], ys[-2:])
                rows.append([label, quantity, fmt(whole, 2), fmt(local, 2), note])
                if quantity != "peak memory" and local is not None and local > 1.15 and ys[-1] and ys[-1] > 50:
                    superlinear.append(f"{label} {quantity} (local slope {local:.2f})")
                if quantity == "peak memory" and local is not None and local > 1.15:
                    superlinear.append(f"{label} peak memory (local slope {local:.2f})")

            add("total wall time", [r["wall_ms"] for r in ok], f"{fmt(min(x), 0)}–{fmt(max(x), 0)} voxels")
            if all(r.get("cpu") for r in ok):
                add("CPU time, user", [r["cpu"]["user_ms"] for r in ok], "all threads, outside the kernel")
            if m == "kissm":
                for st in ("voxelize", "features", "matching", "pruning", "solver"):
                    ys = [r["stages"].get(st) for r in ok]
                    add(f"stage: {STAGE_LABEL[st]}", ys, f"{fmt_ms(ys[-1])} ms at the largest", "kissm")
            add("peak memory", [r["peak_kb"] for r in ok], f"{fmt(ok[-1]['peak_kb'] / 1024, 0)} MB at the largest")
        L.append(
            table(
                ["method", "quantity", "slope (all)", "slope (two largest)", "note"],
                rows,
                ["---", "---", "--:", "--:", "---"],
            )
        )
        L.append("")
        if superlinear:
            L.append(
                "**Superlinear** (local slope above 1.15, ignoring parts under 50 ms): " + "; ".join(superlinear) + "."
            )
        else:
            L.append("No time or memory grows superlinearly (every local slope at most 1.15).")
        L.append("")
        cpu_rows = []
        for m in sm:
            for r in sc["runs"]:
                if r["method"] != m or r["status"] != "ok" or not r.get("cpu"):
                    continue
                c = r["cpu"]
                cpu_rows.append(
                    [
                        METHOD_LABEL[m],
                        f"{xs[r['size']]:,.0f}",
                        fmt(r["wall_ms"] / 1e3, 2),
                        fmt(c["user_ms"] / 1e3, 2),
                        fmt(c["sys_ms"] / 1e3, 2),
                        f"{c['minflt']:,.0f}",
                        fmt(c["sys_ms"] * 1e3 / c["minflt"], 1) if c["minflt"] else "–",
                    ]
                )
        if cpu_rows:
            L.append(
                "CPU time of the calls (all threads) and the page faults they took: the kernel's share (sys) is "
                "mostly the first touch of fresh memory, whose cost per fault depends on the machine (on a VM, "
                "on whether the host still backs the page):"
            )
            L.append("")
            L.append(
                table(
                    ["method", "voxels / cloud", "wall [s]", "user [s]", "sys [s]", "page faults", "sys µs / fault"],
                    cpu_rows,
                )
            )
            L.append("")
        k_ok = [r for r in sc["runs"] if r["method"] == "kissm" and r["status"] == "ok"]
        if k_ok:
            L.append(
                "kissm memory per input point (peak above the input arrays / (source + target points)), and per "
                "voxel (/ (source + target voxels)):"
            )
            L.append("")
            rows = []
            for r in k_ok:
                size = sc["sizes"][r["size"]]
                npts = size["n_src"] + size["n_tgt"]
                nvox = (r["info"].get("src_voxels") or 0) + (r["info"].get("tgt_voxels") or 0)
                rows.append(
                    [
                        f"{xs[r['size']]:,.0f}",
                        f"{npts:,}",
                        fmt(r["peak_kb"] / 1024, 1),
                        fmt(r["peak_kb"] * 1024 / npts, 0),
                        fmt(r["peak_kb"] * 1024 / nvox, 0) if nvox else "–",
                    ]
                )
            L.append(table(["voxels / cloud", "points", "peak MB", "bytes / point", "bytes / voxel"], rows))
            L.append("")
            # the input itself, for scale
            L.append("(For scale: the float64 input itself is 24 bytes per point.)")
            L.append("")
        for name in ("scaling_time", "scaling_memory"):
            if name in plots:
                L.append(f"![{name}]({plots[name].relative_to(out_dir).as_posix()})")
                L.append("")

    if raw.get("errors"):
        L.append("## Errors during the run")
        L.append("")
        for e in raw["errors"]:
            L.append(f"- {e.splitlines()[0]}")
        L.append("")
    L.append("## Reproduce")
    L.append("")
    L.append("```sh")
    L.append("bash bench/run.sh            # the full run (about an hour on 2 cores); see bench/README.md")
    L.append("bash bench/run.sh --refine-only --out /tmp/refine   # the refinement comparison alone (15 minutes)")
    L.append("bash bench/run.sh --smoke    # seconds: a check of the harness")
    L.append("```")
    L.append("")
    return "\n".join(L)


# ---- refinement (issue 14) ------------------------------------------------------------------------------


FROM_KISSM = ("kissm_gicp", "kissm_p2pl", "sgicp", "o3d_gicp", "o3d_p2pl")  # start from kissm's coarse pose
ERROR_COLUMNS = ("kissm_gicp", "kissm_p2pl", "sgicp", "o3d_gicp", "o3d_p2pl", "ref_sgicp")


#: The speed targets of the default coarse path against the reference's C++ time: a geometric mean over the LiDAR
#: pairs, and the slowest pair; and the 1 -> 2 thread scaling under which a stage is flagged.
GEOMEAN_TARGET, SLOWEST_TARGET, SCALING_TARGET = 6.0, 4.5, 1.6


def _speed_target_lines(res: Results, threads: int, pairs: list[str]) -> list[str]:
    """The geometric mean of kissm's speed-up over the reference's C++ time across ``pairs`` and the slowest pair's,
    against GEOMEAN_TARGET and SLOWEST_TARGET."""
    ratios = {}
    for pair in pairs:
        ids = res.case_ids(pair=pair)
        k, r = res.summary(threads, ids, "kissm"), res.summary(threads, ids, "reference")
        if k["wall"] and r["engine"]:
            ratios[pair] = r["engine"] / k["wall"]
    if not ratios:
        return []
    geomean = math.exp(sum(math.log(v) for v in ratios.values()) / len(ratios))
    slowest = min(ratios, key=lambda p: ratios[p])
    met = geomean >= GEOMEAN_TARGET and ratios[slowest] >= SLOWEST_TARGET
    return [
        f"Over the {len(ratios)} LiDAR pairs: geometric mean {fmt_ratio(geomean)} (target {GEOMEAN_TARGET:g}x), "
        f"slowest {slowest} {fmt_ratio(ratios[slowest])} (target {SLOWEST_TARGET:g}x): "
        + ("**met**." if met else "**not met**."),
        "",
    ]


def _stage_scaling_table(res: Results, pairs: list[str]) -> list[str]:
    """kissm's stage times at one thread over those at two, per LiDAR pair; a stage under SCALING_TARGET in bold."""
    if not {1, 2} <= set(res.threads) or "kissm" not in res.methods:
        return []
    stages = ("voxelize", "features", "matching", "pruning", "solver")
    rows = []
    for pair in pairs:
        ids = res.case_ids(pair=pair)
        one, two = res.summary(1, ids, "kissm"), res.summary(2, ids, "kissm")
        row = [pair]
        for stage in (*stages, "total"):
            a = one["wall"] if stage == "total" else one["stages"].get(stage)
            b = two["wall"] if stage == "total" else two["stages"].get(stage)
            x = a / b if a and b else None
            cell = fmt_ratio(x)
            row.append(f"**{cell}**" if x is not None and x < SCALING_TARGET else cell)
        rows.append(row)
    return [
        "### Two threads: scaling per stage",
        "",
        "kissm's median stage time at one thread over that at two, per LiDAR pair (the same runs as above); a stage "
        f"under {SCALING_TARGET:g}x is in bold. Stages of a few milliseconds are noisy here.",
        "",
        table(["pair (LiDAR)", *stages, "whole call"], rows),
        "",
    ]


def _threads_title(threads: int) -> str:
    return f"{threads} thread{'s' if threads > 1 else ''}"


def _datasets(res: Results) -> list[str]:
    out: list[str] = []
    for c in res.raw["cases"]:
        if c["dataset"] not in out:
            out.append(c["dataset"])
    return out


def _errors(
    runs: list[dict[str, Any]], key_rre: str = "rre_deg", key_rte: str = "rte_m"
) -> tuple[float | None, float | None, int, int]:
    """Median RRE and RTE of the calls whose start pose was within the success thresholds."""
    good = [r for r in runs if r.get("start_within")]
    return med([r[key_rre] for r in good]), med([r[key_rte] for r in good]), len(good), len(runs)


def _err_cell(rre: float | None, rte: float | None, category: str) -> str:
    return "–" if rre is None else f"{fmt(rre, 3)}° / {rte_cell(rte, category)}"


def _stage(runs: list[dict[str, Any]], name: str) -> float | None:
    return med([r["stages"].get(name) for r in runs])


#: A method's value in one call, of which a ratio takes the median per case.
CallValue = Callable[[dict[str, Any]], float | None]
#: The refinement's time targets: (numerator's method, its value) / (denominator's method, its value) per case.
Ratio = tuple[tuple[str, CallValue], tuple[str, CallValue]]
STAGE_RATIO: Ratio = (("sgicp", lambda x: x["wall_ms"]), ("kissm_gicp", lambda x: x["stages"].get("refine")))
END_TO_END_RATIO: Ratio = (("ref_sgicp", lambda x: x["engine_ms"]), ("kissm_gicp", lambda x: x["wall_ms"]))


def _case_median(res: Results, threads: int, method: str, value: CallValue) -> Callable[[int], float | None]:
    return lambda i: med([value(r) for r in res.runs.get((threads, i, method), [])])


def _per_case_ratios(res: Results, threads: int, ids: list[int], ratio: Ratio) -> list[float]:
    """The ratio of the medians of every case where both are known."""
    (num_method, num_value), (den_method, den_value) = ratio
    num, den = _case_median(res, threads, num_method, num_value), _case_median(res, threads, den_method, den_value)
    out = []
    for i in ids:
        a, b = num(i), den(i)
        if a and b:
            out.append(a / b)
    return out


def _ratio_verdict(res: Results, threads: int, ratio: Ratio, target: float, title: str) -> str | None:
    """``title`` and whether every pair's smallest per-case ratio reaches ``target``; None when none is known."""
    lows = []
    for pair in res.pairs:
        ratios = _per_case_ratios(res, threads, res.case_ids(pair=pair), ratio)
        if ratios:
            lows.append((min(ratios), pair))
    if not lows:
        return None
    lo = min(lows)
    short = [p for v, p in lows if v < target]
    return (
        title
        + ("yes" if not short else "**no**")
        + f" (smallest per-case ratio {fmt_ratio(lo[0])}, {lo[1]})"
        + (f"; under {target:g}x: {', '.join(short)}" if short else "")
    )


def refine_verdicts(res: Results) -> list[str]:
    """One line per target of issue 14, from this run."""
    lines = []
    datasets = _datasets(res)
    m = res.refining
    for threads in res.threads:
        worse = []
        if "kissm_gicp" in m and "sgicp" in m:
            for ds in datasets:
                ids = res.case_ids(dataset=ds)
                k = _errors(res.collect(threads, ids, "kissm_gicp"))
                s = _errors(res.collect(threads, ids, "sgicp"))
                if k[0] is None or k[1] is None or s[0] is None or s[1] is None:  # (RRE and RTE: both or neither)
                    continue
                cat = res.cases[ids[0]]["category"]
                if k[0] > s[0] or k[1] > s[1]:
                    worse.append(
                        f"{DATASET_LABEL.get(ds, ds)} (kissm {_err_cell(k[0], k[1], cat)} vs small_gicp "
                        f"{_err_cell(s[0], s[1], cat)})"
                    )
            lines.append(
                f"**Errors, {_threads_title(threads)}**: kissm GICP's median RRE and RTE at least as good as "
                f"small_gicp's on every dataset: " + ("yes" if not worse else "**no** — " + "; ".join(worse))
            )
        time_targets = (
            (
                "sgicp",
                STAGE_RATIO,
                2,
                f"**Refinement stage, {_threads_title(threads)}**: small_gicp preprocess + align / "
                f"kissm's refinement stage ≥ 2x on every pair: ",
            ),
            (
                "ref_sgicp",
                END_TO_END_RATIO,
                3,
                f"**End to end, {_threads_title(threads)}**: (reference + small_gicp) / (kissm coarse + "
                f"GICP) ≥ 3x on every pair: ",
            ),
        )
        for peer, ratio, target, title in time_targets:
            if "kissm_gicp" not in m or peer not in m:
                continue
            verdict = _ratio_verdict(res, threads, ratio, target, title)
            if verdict is not None:
                lines.append(verdict)
        ref = "reference" if "reference" in res.methods else ("ref_sgicp" if "ref_sgicp" in m else None)
        for km in ("kissm_gicp", "kissm_p2pl"):
            if km not in m:
                continue
            behind, bunny, wrong = [], None, 0
            for ds in datasets:
                ids = res.case_ids(dataset=ds)
                ours = res.summary(threads, ids, km)
                wrong += ours["wrong_valid"]
                if ref is None:
                    continue
                theirs = res.summary(threads, ids, ref)
                if ours["success"] < theirs["success"]:
                    label = DATASET_LABEL.get(ds, ds)
                    behind.append(f"{label} {ours['success']}/{ours['n']} vs {theirs['success']}/{theirs['n']}")
                if ds == "stanford_bunny_scans":
                    bunny = (ours["success"], theirs["success"], ours["n"])
            text = f"**Success, {SHORT[km]}, {_threads_title(threads)}**: "
            if ref is not None:
                text += f"at least {SHORT[ref]}'s on every dataset: " + (
                    "yes" if not behind else "**no** — " + "; ".join(behind)
                )
                if bunny:
                    text += (
                        f"; bunny strictly better: {'yes' if bunny[0] > bunny[1] else '**no**'} "
                        f"({bunny[0]}/{bunny[2]} vs {bunny[1]}/{bunny[2]})"
                    )
                text += "; "
            text += "wrong poses reported valid: " + ("none" if wrong == 0 else f"**{wrong}**")
            lines.append(text)
    return lines


def refine_section(res: Results, plots: dict[str, Path], out_dir: Path) -> list[str]:
    m = res.refining
    if not m or not any(res.collect(t, list(res.cases), x) for t in res.threads for x in m):
        return []
    settings = res.raw["meta"].get("refine_settings", {})
    chain = settings.get("upstream_chain", {})
    gain, iters = settings.get("max_distance_gain"), settings.get("max_iterations")
    L = ["## Refinement", ""]
    L.append(f"""kissm's refinement stage (`refine_mode` = `gicp` or `point_to_plane`, kissm's defaults) against
fine registration peers that start from **kissm's coarse pose** (the solver's pose kissm's own refinement starts
from; computed once per case, untimed, and identical at every thread count), and the upstream chain end to end.
Same cases, workers, pinning and interleaving as above; every method is its own worker, timed calls alternate.

- **kissm GICP / P2PL**: one `Matcher(voxel_size=v, num_threads=T, refine_mode=...)` call from the raw arrays;
  its wall time is kissm coarse + refine end to end, and `Result.time_refine_ms` is "kissm's refinement stage"
  (it reuses the voxels, normals and kd-tree of the features stage, so that time is not in it).
- **small_gicp** 1.0.1 GICP: `preprocess_points(points, v, num_threads=T)` for both clouds (voxel grid, kd-tree,
  covariances from 10 neighbours: "preprocess") then `align(target, source, target_tree, start, 'GICP', ...)`
  ("align"), with kissm's correspondence distance ({fmt(gain, 1)} v) and iteration cap ({iters}); its own
  convergence epsilons.
- **Open3D** 0.20: `voxel_down_sample(v)`; GICP: `estimate_covariances` (KNN 30, its default) of both clouds and
  `registration_generalized_icp`; point-to-plane: the target's normals (`KDTreeSearchParamHybrid(2v, 30)`) and
  `registration_icp` with `TransformationEstimationPointToPlane`; the same distance and iteration cap. Times
  include the conversion from numpy, downsampling and covariances / normals.
- **reference + small_gicp** (KISS-Matcher's ROS loop-closure module): both clouds voxelised
  (`small_gicp.voxelgrid_sampling(v)`), the reference's `estimate` on them, covariances of both
  ({chain.get("num_neighbors", "?")} neighbours), the target's Gaussian voxel map, and VGICP from the reference's
  pose with correspondence distance {fmt(chain.get("corr_dist_gain"), 0)} v and {chain.get("max_iterations", "?")}
  iterations (the module's configured cap is never applied, so its wrapper's default runs). Upstream skips the
  fine step when its gates reject the coarse pose (valid with more than {chain.get("min_inliers", "?")} final
  inliers, then overlap = inliers / source points ≥ {fmt((chain.get("min_overlap") or 0) * 100, 0)}%); here the
  fine step always runs so its time is counted, and the gates are reported separately. "C++" is its wall time
  minus the reference binding's copy of the points (its Python wall minus its own stage times), the number the
  3x target is judged against.
- **Validity**: kissm's refined `valid` (its rule with refinement); small_gicp and Open3D have no validity
  decision, so their pose counts as reported when kissm's coarse pose was reported valid (Open3D also needs a
  fitness above 0); the chain's pose counts as reported by the reference's rule of the coarse comparison (valid
  and at least 5 final inliers). Success and "wrong valid" as above.
- **Errors** are medians over the calls whose start pose was within the success thresholds (for the peers and
  kissm the same cases; the chain starts from the reference's pose, so its set can differ: its count is shown).""")
    starts = [
        r["same_start"]
        for t in res.threads
        for x in ("kissm_gicp", "kissm_p2pl")
        for r in res.collect(t, list(res.cases), x)
        if "same_start" in r
    ]
    if starts:
        L.append(
            f"- **Same start, checked**: kissm's refined calls started from the peers' start pose bit for bit in "
            f"{sum(starts)} of {len(starts)} calls"
            + ("." if all(starts) else " — **the comparison is not from one start where it differs**.")
        )
    if machine_busy(res.raw["meta"]) and max(res.threads) > 1:
        L.append(
            "- **Busy machine**: the peers' OpenMP threads spin at their barriers, so while another program "
            "holds a CPU a 2-thread call of small_gicp or Open3D can take many times its 1-thread time (not so "
            "with `OMP_WAIT_POLICY=passive`). In this run the peers' 2-thread times, and kissm's ratios against "
            "them, are inflated; only a quiet run settles the 2-thread targets."
        )
    L.append("")
    lines = refine_verdicts(res)
    if lines:
        L.append("### Targets")
        L.append("")
        L += [f"- {x}" for x in lines]
        L.append("")
    L += _error_tables(res)
    L += _time_tables(res)
    L += _success_tables(res)
    for k in sorted(x for x in plots if x.startswith("refine_times")):
        L.append(f"![{k}]({plots[k].relative_to(out_dir).as_posix()})")
        L.append("")
    L += _case_details(res)
    return L


def _error_tables(res: Results) -> list[str]:
    m = res.refining
    cols = [x for x in ERROR_COLUMNS if x in m]
    start_from = next((x for x in FROM_KISSM if x in m), None)
    L = ["### Errors from the same start", ""]
    L.append(
        'Median RRE / RTE per dataset; "kissm coarse" is the pose every peer but the chain starts from. '
        "(n) = calls from a start within the thresholds / all timed calls."
    )
    L.append("")
    for threads in res.threads:
        compare = "kissm_gicp" in cols and "sgicp" in cols
        header = ["dataset", "kissm coarse"] + [SHORT[x] for x in cols]
        header += ["kissm GICP ≤ small_gicp"] if compare else []
        rows = []
        for ds in _datasets(res):
            ids = res.case_ids(dataset=ds)
            cat = res.cases[ids[0]]["category"]
            row = [DATASET_LABEL.get(ds, ds)]
            if start_from:
                c = _errors(res.collect(threads, ids, start_from), "coarse_rre_deg", "coarse_rte_m")
                row.append(f"{_err_cell(c[0], c[1], cat)} ({c[2]}/{c[3]})")
            else:
                row.append("–")
            found = {}
            for x in cols:
                e = _errors(res.collect(threads, ids, x))
                found[x] = e
                cell = _err_cell(e[0], e[1], cat)
                if x == "ref_sgicp" or not start_from:
                    cell += f" ({e[2]}/{e[3]})"
                row.append(cell)
            if compare:
                k, s = found["kissm_gicp"], found["sgicp"]
                if k[0] is None or k[1] is None or s[0] is None or s[1] is None:  # (RRE and RTE: both or neither)
                    row.append("–")
                else:
                    ok_r, ok_t = k[0] <= s[0], k[1] <= s[1]
                    row.append(
                        "yes"
                        if ok_r and ok_t
                        else "**no**: " + ", ".join(x for x, ok in (("RRE", ok_r), ("RTE", ok_t)) if not ok)
                    )
            rows.append(row)
        L.append(f"#### {_threads_title(threads)}")
        L.append("")
        L.append(table(header, rows, ["---"] * len(header)))
        L.append("")
    return L


def _time_tables(res: Results) -> list[str]:
    m = res.refining
    L = []
    if "kissm_gicp" in m or "sgicp" in m:
        L += ["### Refinement time", ""]
        L.append(
            "Median ms per call per pair (over its variants and repeats). kissm: its refinement stage "
            "(`time_refine_ms`); \"kissm GICP − coarse\" is kissm + GICP's wall time minus plain kissm's, "
            "everything refinement adds (normals it keeps, the kd-tree, the stage), a difference of two noisy "
            'medians ("vs GICP − coarse" takes at least the stage itself). small_gicp: preprocess '
            '(both clouds) + align. Ratio = small_gicp total / kissm\'s GICP stage ("min": smallest per-case '
            "ratio). Target: ≥ 2x."
        )
        L.append("")
        for threads in res.threads:
            header = [
                "pair",
                "kissm GICP stage",
                "kissm P2PL stage",
                "kissm GICP − coarse",
                "small_gicp preprocess",
                "small_gicp align",
                "small_gicp total",
                "ratio (min)",
                "≥ 2x",
                "vs GICP − coarse",
                "O3D GICP",
                "O3D P2PL",
            ]
            rows = []
            for pair in res.pairs:
                ids = res.case_ids(pair=pair)
                kg = res.collect(threads, ids, "kissm_gicp")
                kp = res.collect(threads, ids, "kissm_p2pl")
                sg = res.collect(threads, ids, "sgicp")
                kc = res.collect(threads, ids, "kissm")
                k_stage = _stage(kg, "refine")
                s_total = med([r["wall_ms"] for r in sg])
                added = None
                kg_wall, kc_wall = med([r["wall_ms"] for r in kg]), med([r["wall_ms"] for r in kc])
                if kg_wall is not None and kc_wall is not None:
                    added = kg_wall - kc_wall
                added_cell = fmt_ms(added) if added is None or added > 0 else "< 0 (noise)"
                if added is not None and k_stage:
                    added = max(added, k_stage)  # refinement adds at least its own stage: less is noise
                ratios = _per_case_ratios(res, threads, ids, STAGE_RATIO)
                lo = min(ratios) if ratios else None
                rows.append(
                    [
                        pair,
                        fmt_ms(k_stage),
                        fmt_ms(_stage(kp, "refine")),
                        added_cell,
                        fmt_ms(_stage(sg, "preprocess")),
                        fmt_ms(_stage(sg, "align")),
                        fmt_ms(s_total),
                        f"{fmt_ratio(s_total / k_stage if s_total and k_stage else None)} ({fmt_ratio(lo)})",
                        "–" if lo is None else ("yes" if lo >= 2 else "**no**"),
                        fmt_ratio(s_total / added if s_total and added and added > 0 else None),
                        fmt_ms(med([r["wall_ms"] for r in res.collect(threads, ids, "o3d_gicp")])),
                        fmt_ms(med([r["wall_ms"] for r in res.collect(threads, ids, "o3d_p2pl")])),
                    ]
                )
            L.append(f"#### {_threads_title(threads)}")
            L.append("")
            L.append(table(header, rows))
            L.append("")
    if "kissm_gicp" in m and "ref_sgicp" in m:
        L += ["### End to end: kissm coarse + refine against reference + small_gicp", ""]
        L.append(
            "Median ms per call from the raw arrays. The chain's \"C++\" leaves out the reference binding's "
            'copy of the points; ratio = chain C++ / kissm + GICP ("min": smallest per-case ratio). '
            "Target: ≥ 3x."
        )
        L.append("")
        for threads in res.threads:
            header = [
                "pair",
                "kissm + GICP",
                "kissm + P2PL",
                "chain wall",
                "chain C++",
                "of which VGICP",
                "ratio (min)",
                "≥ 3x",
                "vs chain wall",
            ]
            rows = []
            for pair in res.pairs:
                ids = res.case_ids(pair=pair)
                kg_ms = med([r["wall_ms"] for r in res.collect(threads, ids, "kissm_gicp")])
                kp_ms = med([r["wall_ms"] for r in res.collect(threads, ids, "kissm_p2pl")])
                ch = res.collect(threads, ids, "ref_sgicp")
                cw, ce = med([r["wall_ms"] for r in ch]), med([r["engine_ms"] for r in ch])
                fine = med([(r["stages"].get("preprocess") or 0) + (r["stages"].get("align") or 0) for r in ch])
                ratios = _per_case_ratios(res, threads, ids, END_TO_END_RATIO)
                lo = min(ratios) if ratios else None
                rows.append(
                    [
                        pair,
                        fmt_ms(kg_ms),
                        fmt_ms(kp_ms),
                        fmt_ms(cw),
                        fmt_ms(ce),
                        fmt_ms(fine),
                        f"{fmt_ratio(ce / kg_ms if ce and kg_ms else None)} ({fmt_ratio(lo)})",
                        "–" if lo is None else ("yes" if lo >= 3 else "**no**"),
                        fmt_ratio(cw / kg_ms if cw and kg_ms else None),
                    ]
                )
            L.append(f"#### {_threads_title(threads)}")
            L.append("")
            L.append(table(header, rows))
            L.append("")
    return L


def _success_tables(res: Results) -> list[str]:
    cols = [x for x in ("kissm", "reference") if x in res.methods] + res.refining
    L = ["### Success and validity", ""]
    L.append(
        'Successful calls / timed calls per dataset (raw and rotated variants, repeats); "wrong valid": '
        'reported valid but outside the thresholds. For the chain, "gates" counts the calls upstream\'s '
        "own gates would accept (and how many of those are wrong)."
    )
    L.append("")
    for threads in res.threads:
        rows = []
        totals = {x: [0, 0, 0] for x in cols}
        for ds in _datasets(res):
            ids = res.case_ids(dataset=ds)
            row = [f"{DATASET_LABEL.get(ds, ds)} ({len(ids)})"]
            for x in cols:
                s = res.summary(threads, ids, x)
                for j, key in enumerate(("success", "n", "wrong_valid")):
                    totals[x][j] += s[key]
                cell = f"{s['success']}/{s['n']}" if s["n"] else "–"
                if s["wrong_valid"]:
                    cell += f"; **{s['wrong_valid']} wrong valid**"
                if x == "ref_sgicp" and s["n"]:
                    runs = res.collect(threads, ids, x)
                    gated = [r for r in runs if r["info"].get("gates_valid")]
                    bad = sum(not r["within"] for r in gated)
                    cell += f"; gates {len(gated)}" + (f" ({bad} wrong)" if bad else "")
                row.append(cell)
            rows.append(row)
        rows.append(
            ["**total**"]
            + [f"**{t[0]}/{t[1]}**" + (f" ({t[2]} wrong valid)" if t[2] else "") for t in (totals[x] for x in cols)]
        )
        L.append(f"#### {_threads_title(threads)}")
        L.append("")
        L.append(table(["dataset (cases)"] + [SHORT[x] for x in cols], rows, ["---"] * (len(cols) + 1)))
        L.append("")
    return L


def _note(r: dict[str, Any]) -> str:
    info = r.get("info", {})
    if "refine_iterations" in info:
        ov = info.get("overlap")
        why = "" if r["valid"] else f"{info.get('reason')}; "  # why kissm reported the pose invalid
        return (
            f"{why}overlap {fmt(ov, 2) if ov is not None else '–'}, "
            f"{info['refine_iterations']} it{'' if info.get('refine_converged') else ' (cap)'}"
        )
    if "gates_valid" in info:
        return (
            f"{r['inliers']} inliers, overlap {fmt(info['overlap'] * 100, 0)}%, gates "
            f"{'accept' if info['gates_valid'] else 'reject'}"
        )
    if "fitness" in info:
        return f"fitness {fmt(info['fitness'], 2)}"
    if "iterations" in info:
        return f"{info['iterations']} it{'' if info.get('converged') else ' (not converged)'}"
    return ""


def _case_details(res: Results) -> list[str]:
    L = ["<details><summary>Refinement, every case (pair × variant)</summary>", ""]
    for threads in res.threads:
        L.append(f"#### {_threads_title(threads)}")
        L.append("")
        header = ["case", "method", "start RRE / RTE", "refined RRE / RTE", "valid", "success", "ms", "notes"]
        rows = []
        for i, c in res.cases.items():
            first = True
            for x in res.refining:
                runs = res.runs.get((threads, i, x), [])
                if not runs:
                    continue
                r = runs[len(runs) // 2]  # the errors do not change between repeats; times are medians
                cat = c["category"]
                rows.append(
                    [
                        f"{c['name']} {c['variant']}" if first else "",
                        SHORT[x],
                        _err_cell(r.get("coarse_rre_deg"), r.get("coarse_rte_m"), cat),
                        _err_cell(r["rre_deg"], r["rte_m"], cat),
                        "yes" if r["valid"] else "no",
                        f"{sum(q['success'] for q in runs)}/{len(runs)}",
                        fmt_ms(med([q["wall_ms"] for q in runs])),
                        _note(r),
                    ]
                )
                first = False
        L.append(table(header, rows, ["---"] * len(header)))
        L.append("")
    L.append("</details>")
    L.append("")
    return L


def refine_plot(res: Results, img_dir: Path, plt: Any) -> dict[str, Path]:
    """Per-pair refinement time: kissm's stage against the peers' preprocessing and alignment."""
    shown = [x for x in ("kissm_gicp", "kissm_p2pl", "sgicp", "o3d_gicp", "o3d_p2pl") if x in res.refining]
    if not shown or not res.pairs:
        return {}
    parts = {
        "kissm_gicp": ("refine",),
        "kissm_p2pl": ("refine",),
        "sgicp": ("preprocess", "align"),
        "o3d_gicp": ("input", "voxelize", "covariances", "align"),
        "o3d_p2pl": ("input", "voxelize", "covariances", "align"),
    }
    n = len(res.pairs)
    fig, axes = plt.subplots(
        1, len(res.threads), figsize=(6.5 * len(res.threads), 0.32 * n * len(shown) + 1.6), squeeze=False
    )
    used = set()
    for ax, threads in zip(axes.flat, res.threads, strict=False):
        labels: list[str] = []
        y = 0.0
        for pair in reversed(res.pairs):
            ids = res.case_ids(pair=pair)
            for x in reversed(shown):
                runs = res.collect(threads, ids, x)
                left = 0.0
                for st in parts[x]:
                    v = _stage(runs, st)
                    if not v:
                        continue
                    label = "kissm's refinement stage" if st == "refine" else STAGE_LABEL[st]
                    ax.barh(
                        y,
                        v,
                        left=left,
                        color=STAGE_COLOR[st],
                        edgecolor="white",
                        linewidth=0.4,
                        label=label if label not in used else None,
                    )
                    used.add(label)
                    left += v
                if left:
                    ax.text(left, y, f" {left:,.0f}" if left >= 10 else f" {left:.1f}", va="center", fontsize=6.5)
                labels.append(f"{pair.split('/')[-1]} {SHORT[x]}")
                y += 1
            y += 0.6
        ax.set_yticks(_tick_positions(n, len(shown)), labels, fontsize=6.5)
        ax.set_xlabel("median ms per call")
        ax.set_title(f"{_threads_title(threads)}", fontsize=10)
        ax.margins(x=0.15)
        ax.grid(axis="x", alpha=0.3)
    fig.legend(loc="lower center", ncol=5, fontsize=7.5, frameon=False)
    fig.suptitle(
        "Refinement from kissm's coarse pose: kissm's stage vs the peers' preprocessing + alignment", fontsize=10
    )
    fig.tight_layout(rect=(0, 0.06, 1, 0.96))
    path = img_dir / "refine_times.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return {"refine_times": path}


def _tick_positions(pairs: int, per_pair: int) -> list[float]:
    out, y = [], 0.0
    for _ in range(pairs):
        for _ in range(per_pair):
            out.append(y)
            y += 1
        y += 0.6
    return out


# ---- the page ----------------------------------------------------------------------------------------------

# What the page reads of a run's results (reduce keeps these; the rest of a record is the raw file's).
CASE_FIELDS = ("index", "name", "dataset", "category", "voxel", "n_src", "n_tgt", "variant", "rot_deg")
RUN_FIELDS = (
    "threads",
    "case",
    "method",
    "status",
    "wall_ms",
    "engine_ms",
    "stages",
    "valid",
    "success",
    "inliers",
    "rre_deg",
    "rte_m",
    "coarse_rre_deg",
    "coarse_rte_m",
    "start_within",
    "within",
    "same_start",
    "info",
)
#: Of a call's ``info``: what the refinement's notes read (which of them a record has tells its kind).
INFO_FIELDS = (
    "reason",
    "overlap",
    "refine_iterations",
    "refine_converged",
    "gates_valid",
    "fitness",
    "iterations",
    "converged",
)
MEMORY_FIELDS = ("threads", "case", "method", "peak_kb")
SCALING_FIELDS = ("voxel", "threads", "density", "timeout_s")
SIZE_FIELDS = ("index", "target_voxels", "voxels_numpy", "n_src", "n_tgt")
SCALING_RUN_FIELDS = (
    "size",
    "method",
    "status",
    "error",
    "wall_ms",
    "peak_kb",
    "stages",
    "success",
    "rre_deg",
    "first_wall_ms",
    "cpu",
    "info",
)
SCALING_INFO_FIELDS = ("src_voxels", "tgt_voxels")


def _with_info(record: dict[str, Any], fields: tuple[str, ...], info_fields: tuple[str, ...]) -> dict[str, Any]:
    out = pick(record, fields)
    if "info" in out:
        out["info"] = pick(out["info"], info_fields)
    return out


def reduce(raw: dict[str, Any]) -> dict[str, Any]:
    """What the page is rendered from: the run's description, the cases, the timed calls' results (no poses, no
    warm-up calls), the memory peaks, the scaling runs and the errors. Reduced results reduce to themselves."""
    timed = [r for r in raw["runs"] if not r.get("warmup")]
    runs = [_with_info(r, RUN_FIELDS, INFO_FIELDS) for r in timed]
    # The page has a section per thread count of the run, one with warm-up calls only (--repeats 0) too.
    only_warm = {r["threads"] for r in raw["runs"]} - {r["threads"] for r in timed}
    runs += [{"threads": t, "warmup": True} for t in sorted(only_warm)]
    sc = raw.get("scaling")
    scaling = (
        None
        if sc is None
        else {
            **pick(sc, SCALING_FIELDS),
            "sizes": [pick(size, SIZE_FIELDS) for size in sc["sizes"]],
            "runs": [_with_info(r, SCALING_RUN_FIELDS, SCALING_INFO_FIELDS) for r in sc["runs"]],
        }
    )
    return {
        "meta": raw["meta"],
        "cases": [pick(c, CASE_FIELDS) for c in raw["cases"]],
        "runs": runs,
        "memory": [pick(m, MEMORY_FIELDS) for m in raw["memory"]],
        "scaling": scaling,
        "errors": raw.get("errors", []),
    }


def write_all(raw: dict[str, Any], out_dir: Path, smoke: bool = False) -> list[Path]:
    """Writes ``out_dir``/benchmarks.md and its plots in ``out_dir``/img/ from a run's results (raw or reduced)."""
    reduced = reduce(raw)
    res = Results(reduced)
    plots = make_plots(res, out_dir / "img")
    md = out_dir / "benchmarks.md"
    out_dir.mkdir(parents=True, exist_ok=True)  # make_plots makes it only when it draws
    md.write_text(render(reduced, plots, out_dir, smoke))
    return [md, *plots.values()]


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        description="Regenerate the benchmark report from saved results (bench/results/latest.json.gz or a raw file)."
    )
    p.add_argument("raw", type=Path)
    p.add_argument("--out", type=Path, default=REPORTS)
    p.add_argument("--smoke", action="store_true")
    args = p.parse_args(argv)
    written = write_all(results_io.read(args.raw), args.out, args.smoke)
    print("wrote " + ", ".join(map(str, written)))
    return 0
