# SPDX-License-Identifier: MIT
"""Writes docs/reports/benchmarks.md and the plots in docs/reports/img/ from the results of bench.py.

``python bench/report.py RAW.json --out DIR`` regenerates the report from a saved raw results file.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import refine_report
from report_common import (
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
    med,
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
            f"Per-stage time, {threads} thread{'s' if threads > 1 else ''} "
            f"(median over raw + rotated variants and repeats)",
            fontsize=11,
        )
        fig.tight_layout(rect=(0, 0.07 if rows > 1 else 0.12, 1, 0.97))
        path = img_dir / f"stage_times_{threads}t.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        plots[f"stage_times_{threads}t"] = path

    plots.update(refine_report.make_plot(res, img_dir, plt))

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
                k = slope([p[0] for p in pts], [p[1] for p in pts])
                ax.loglog(
                    [p[0] for p in pts],
                    [p[1] for p in pts],
                    "o-",
                    color=METHOD_COLOR[m],
                    lw=2,
                    label=f"{METHOD_LABEL[m]} (slope {k:.2f})" if k is not None else METHOD_LABEL[m],
                )
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
                    k = slope([p[0] for p in pts], [p[1] for p in pts])
                    ax.loglog(
                        [p[0] for p in pts],
                        [p[1] for p in pts],
                        "--",
                        color=STAGE_COLOR[st],
                        lw=1.2,
                        label=f"kissm {STAGE_LABEL[st]} (slope {k:.2f})",
                    )
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


def scaling_x(sc) -> dict[int, float]:
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


def render(raw: dict, plots: dict[str, Path], out_dir: Path, smoke: bool) -> str:
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
        + ", ".join(f"{k} {v}" for k, v in pk.items())
        + (f"; kissm build {mach['git']}" if mach.get("git") else "")
    )
    if meta.get("missing_methods"):
        L.append("- Not run (not installed): " + ", ".join(METHOD_LABEL[m] for m in meta["missing_methods"]))
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
            L.append(f"### {threads} thread{'s' if threads > 1 else ''}")
            L.append("")
            L.append(table(header, rows))
            L.append("")

    # ---- success per dataset ----
    if res.runs and methods:
        L.append("## Success per dataset")
        L.append("")
        L.append(
            "Successful calls / timed calls, over raw and rotated variants and repeats; median RRE / RTE over "
            'the successes. "wrong valid" counts poses reported valid but outside the thresholds.'
        )
        L.append("")
        datasets = []
        for c in raw["cases"]:
            if c["dataset"] not in datasets:
                datasets.append(c["dataset"])
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
            L.append(f"### {threads} thread{'s' if threads > 1 else ''}")
            L.append("")
            L.append(table(header, rows, ["---"] + ["---"] * len(methods)))
            L.append("")

    # ---- refinement (issue 14) ----

    L += refine_report.render_section(res, plots, out_dir)

    # ---- stage plots ----
    stage_plots = [k for k in plots if k.startswith("stage_times_")]
    if stage_plots:
        L.append("## Where the time goes")
        L.append("")
        L.append(
            "Per-stage median times per method on each LiDAR pair (hatched: the reference's Python binding "
            "copying the points, outside its own C++ stage times)."
        )
        L.append("")
        for k in sorted(stage_plots):
            L.append(f"![{k}]({plots[k].relative_to(out_dir).as_posix()})")
            L.append("")

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
            L.append(f"### {threads} thread{'s' if threads > 1 else ''}")
            L.append("")
            header = [
                "pair",
                "method",
                "success",
                "RRE",
                "RTE",
                "wall",
                "voxelise",
                "features",
                "matching",
                "pruning",
                "solver",
                "RANSAC/FGR",
                "input/other",
                "peak MB",
            ]
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
                            *(
                                fmt_ms(st.get(x))
                                for x in (
                                    "voxelize",
                                    "features",
                                    "matching",
                                    "pruning",
                                    "solver",
                                    "registration",
                                    "input",
                                )
                            ),
                            fmt(s["peak_mb"], 0),
                        ]
                    )
            L.append(table(header, rows, ["---", "---", "---"] + ["--:"] * (len(header) - 3)))
            L.append("")

        L.append("<details><summary>Every case (pair × variant)</summary>")
        L.append("")
        for threads in res.threads:
            L.append(f"#### {threads} thread{'s' if threads > 1 else ''}")
            L.append("")
            header = [
                "case",
                "rotation",
                "method",
                "success",
                "RRE",
                "RTE",
                "inliers",
                "wall [ms]",
                "engine [ms]",
                "peak MB",
            ]
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
                r = next((r for r in sc["runs"] if r["size"] == i and r["method"] == m), None)
                if r is None:
                    row += ["–", "–"]
                elif r["status"] == "ok":
                    row += [fmt(r["wall_ms"] / 1e3, 2), fmt(r["peak_kb"] / 1024, 0)]
                    if m == "kissm":
                        ksucc = "yes" if r["success"] else f"no (RRE {fmt(r['rre_deg'], 1)}°)"
                else:
                    row += [r["status"], "–"]
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

            def add(quantity, ys, note, label=METHOD_LABEL[m], x=x):
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
        for k in ("scaling_time", "scaling_memory"):
            if k in plots:
                L.append(f"![{k}]({plots[k].relative_to(out_dir).as_posix()})")
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


def write_all(raw: dict, out_dir: Path, smoke: bool = False) -> list[Path]:
    out_dir = Path(out_dir)
    res = Results(raw)
    plots = make_plots(res, out_dir / "img")
    md = out_dir / "benchmarks.md"
    md.write_text(render(raw, plots, out_dir, smoke))
    return [md, *plots.values()]


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description="Regenerate the benchmark report from a raw results file.")
    p.add_argument("raw", type=Path)
    p.add_argument("--out", type=Path, default=Path(__file__).resolve().parent.parent / "docs" / "reports")
    p.add_argument("--smoke", action="store_true")
    args = p.parse_args(argv)
    written = write_all(json.loads(args.raw.read_text()), args.out, args.smoke)
    print("wrote " + ", ".join(map(str, written)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
