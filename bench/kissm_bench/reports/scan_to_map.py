# SPDX-License-Identifier: MIT
"""docs/reports/scan_to_map.md and docs/reports/img/scan_to_map_time.png from the results of map_bench.py
(kissm_bench.scan_to_map): per thread count and map size the medians over the scans, the target's verdict,
and how the run was made. The settings the page states (the distractor tiles, the success thresholds, the
methods) are defined here and measured with by kissm_bench.scan_to_map.

``python bench/map_bench.py --report-from bench/results/map_latest.json.gz [--out DIR]`` rewrites the page.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from ..common import med
from ..data import KEYFRAMES_DIR
from ..reference import REFERENCE_MIN_INLIERS
from ..results import pick, pose_digest

# The distractor tiles: the other real LiDAR clouds of the data, never the KITTI 07 keyframes (path, format).
TILE_SOURCES = (
    ("kitti_demo_scans_unverified/000000.bin", "kitti_bin_xyzi_f32"),
    ("kitti_demo_scans_unverified/000015.bin", "kitti_bin_xyzi_f32"),
    ("small_gicp_lidar/target.ply", "ply"),
    ("small_gicp_lidar/source.ply", "ply"),
)
TILE_KEEP = 0.7  # share of a source cloud's points in one tile (a random subset)
TILE_JITTER_M = 0.02  # Gaussian noise added to every tile point (sigma)
TILE_SHIFT_M = 30.0  # a tile's random shift from its grid cell's centre, in x and in y (uniform, +-)
TILE_Z_SHIFT_M = 1.0  # and in z, from the base map's median height
MAX_ROT_DEG, MAX_TRANS_M = 2.0, 0.5  # success: valid and within these of the ground truth
METHODS = ("kissm_reuse", "kissm_full", "reference")
LABEL = {
    "kissm_reuse": "kissm, map features reused",
    "kissm_full": "kissm, full register per scan",
    "reference": "reference KISS-Matcher",
    "prep": "kissm map preparation (once per map)",
}
COLOR = {"kissm_reuse": "#d62728", "kissm_full": "#ff7f0e", "reference": "#1f77b4", "prep": "#7f7f7f"}
TARGET_TEXT = "the target: per-scan time at 5M map points at most 2x the time at 100K"


# ---- what the page reads ---------------------------------------------------------------------------------


MAP_FIELDS = ("threads", "size", "points", "tiles")
PREP_FIELDS = (
    "threads",
    "size",
    "keyframe",
    "prep_ms",
    "map_voxels",
    "map_keypoints",
    "memory_bytes",
    "rss_growth_bytes",
)
RUN_FIELDS = (
    "threads",
    "size",
    "keyframe",
    "method",
    "rep",
    "wall_ms",
    "features_ms",
    "register_ms",
    "matching_ms",
    "cxx_ms",
    "valid",
    "success",
    "rot_err_deg",
    "trans_err_m",
    "inliers",
    "pose",
)
LAYOUT_FIELDS = ("spacing_m", "base_radius_m", "tile_radius_m", "first_ring_m", "tile_count")


def _reduce_run(r: dict[str, Any]) -> dict[str, Any]:
    out = pick(r, RUN_FIELDS)
    if "transform" in r:  # the page asks only whether the reused-map and the full register's poses are equal
        out["pose"] = pose_digest(r["transform"])
    return out


def _reduce_layout(layout: dict[str, Any] | None) -> dict[str, Any] | None:
    if not layout:
        return layout
    out = pick(layout, LAYOUT_FIELDS)
    if "tiles" in layout:  # the page counts the tiles; the raw results describe each
        out["tile_count"] = len(layout["tiles"])
    return out


def reduce(results: dict[str, Any]) -> dict[str, Any]:
    """What the page is rendered from: the run's description, per map its size and tiles, per map preparation its
    time and counts, per timed call its times, counts, errors and a fingerprint of its pose, the calls that raised
    and the distractor layout's figures. Reduced results reduce to themselves."""
    return {
        "meta": results["meta"],
        "maps": [pick(m, MAP_FIELDS) for m in results["maps"]],
        "prep": [pick(p, PREP_FIELDS) for p in results["prep"]],
        "runs": [_reduce_run(r) for r in results["runs"]],
        "errors": results["errors"],
        "layout": _reduce_layout(results.get("layout")),
    }


# ---- summary --------------------------------------------------------------------------------------------


def summarise(results: dict[str, Any], threads: int, size: int) -> dict[str, Any]:
    """One table row: medians over the keyframes of each scan's median over its timed calls."""
    runs = [r for r in results["runs"] if r["threads"] == threads and r["size"] == size]
    prep = [p for p in results["prep"] if p["threads"] == threads and p["size"] == size]
    maps = [m for m in results["maps"] if m["threads"] == threads and m["size"] == size]
    row: dict[str, Any] = {
        "size": size,
        "points": med([m["points"] for m in maps]),
        "points_range": (min(m["points"] for m in maps), max(m["points"] for m in maps)) if maps else None,
        "tiles": med([m["tiles"] for m in maps]),
        "voxels": med([p["map_voxels"] for p in prep]),
        "keypoints": med([p["map_keypoints"] for p in prep]),
        "prep_ms": med([p["prep_ms"] for p in prep]),
        "bytes_per_keypoint": med(
            [
                p["memory_bytes"] / p["map_keypoints"]
                for p in prep
                if p["memory_bytes"] is not None and p["map_keypoints"]
            ]
        ),
        "rss_per_keypoint": med([p["rss_growth_bytes"] / p["map_keypoints"] for p in prep if p["map_keypoints"]]),
    }
    keyframes = sorted({p["keyframe"] for p in prep} | {r["keyframe"] for r in runs})
    for m in METHODS:
        mine = [r for r in runs if r["method"] == m]
        per_scan: dict[str, list[float | None]] = {
            k: [] for k in ("wall_ms", "features_ms", "register_ms", "matching_ms", "cxx_ms")
        }
        for k in keyframes:
            calls = [r for r in mine if r["keyframe"] == k]
            for key in per_scan:
                per_scan[key].append(med([r.get(key) for r in calls]))
        ok = [r for r in mine if r["success"]]
        row[m] = {
            "calls": len(mine),
            "success": len(ok),
            "valid_wrong": sum(1 for r in mine if r["valid"] and not r["success"]),
            **{key: med(vals) for key, vals in per_scan.items()},
            "rot_err_deg": med([r["rot_err_deg"] for r in ok]),
            "trans_err_m": med([r["trans_err_m"] for r in ok]),
            "inliers": med([r["inliers"] for r in mine]),
        }
    reuse = {(r["keyframe"], r["rep"]): r["pose"] for r in runs if r["method"] == "kissm_reuse"}
    full = {(r["keyframe"], r["rep"]): r["pose"] for r in runs if r["method"] == "kissm_full"}
    both = [key for key in reuse if key in full]
    row["same_pose"] = (sum(1 for key in both if reuse[key] == full[key]), len(both))
    return row


def ratio(a: float | None, b: float | None) -> float | None:
    return a / b if a is not None and b else None


def fmt_ms(v: float | None) -> str:
    if v is None:
        return "–"
    return f"{v:,.0f}" if v >= 100 else f"{v:.1f}" if v >= 10 else f"{v:.2f}"


def fmt_count(v: float | None) -> str:
    return "–" if v is None else f"{v:,.0f}"


def fmt_x(v: float | None) -> str:
    return "–" if v is None else f"{v:.1f}x" if v >= 10 else f"{v:.2f}x"


def fmt_err(rot: float | None, trans: float | None) -> str:
    return "–" if rot is None or trans is None else f"{rot:.2f}° / {100 * trans:.1f} cm"


def short_points(n: float) -> str:
    return f"{n / 1e6:.3g}M" if n >= 1e6 else f"{n / 1e3:.0f}K" if n >= 1e3 else f"{n:.0f}"


def verdict(rows: list[dict[str, Any]]) -> tuple[str, float | None]:
    """The target's verdict for one thread count: per-scan time at the largest map against the smallest."""
    if len(rows) < 2:
        return "not judged (one map size)", None
    first, last = rows[0], rows[-1]
    growth = ratio(last["kissm_reuse"]["wall_ms"], first["kissm_reuse"]["wall_ms"])
    if growth is None:
        return "not judged (no per-scan time)", None
    pts0, pts1 = first["points"], last["points"]
    judgeable = pts1 >= 5e6 and pts0 <= 1.5e5
    what = f"{growth:.2f}x from {short_points(pts0)} to {short_points(pts1)} map points"
    if not judgeable:
        return f"{what} (not judged: the run's sizes do not span 100K to 5M)", growth
    return f"{what}: {'met' if growth <= 2.0 else 'NOT met'}", growth


def headline(threads: int, rows: list[dict[str, Any]]) -> str:
    if not rows:
        return f"{threads} thread(s): no results."
    first, last = rows[0], rows[-1]
    reuse, full, ref = last["kissm_reuse"], last["kissm_full"], last["reference"]
    plural = "s" if threads > 1 else ""
    text = (
        f"At {threads} thread{plural}, a scan against the {short_points(last['points'])}-point map "
        f"({fmt_count(last['voxels'])} voxels) takes {fmt_ms(reuse['wall_ms'])} ms with the map's features reused "
        f"({fmt_x(ratio(reuse['wall_ms'], first['kissm_reuse']['wall_ms']))} its time against the "
        f"{short_points(first['points'])}-point map; preparing the map once took {fmt_ms(last['prep_ms'])} ms), "
        f"{fmt_ms(full['wall_ms'])} ms with a full register per scan"
    )
    if ref["wall_ms"] is not None:
        text += (
            f" and {fmt_ms(ref['wall_ms'])} ms with the reference, which describes the whole map on every call "
            f"({fmt_x(ratio(ref['wall_ms'], reuse['wall_ms']))} the reused-map time)"
        )
    else:
        text += "; the reference did not run at this size"
    text += (
        f". Successes there: kissm {reuse['success']}/{reuse['calls']} (reused map), "
        f"{full['success']}/{full['calls']} (full)"
    )
    if ref["calls"]:
        text += f", reference {ref['success']}/{ref['calls']}"
    return text + "."


def write_report(results: dict[str, Any], out_dir: Path) -> list[Path]:
    """Writes ``out_dir``/scan_to_map.md and its plot from a run's results (raw or reduced)."""
    results = reduce(results)
    out_dir.mkdir(parents=True, exist_ok=True)
    meta = results["meta"]
    threads_list = sorted({m["threads"] for m in results["maps"]})
    sizes = sorted({m["size"] for m in results["maps"]})
    table = {
        t: [
            summarise(results, t, s)
            for s in sizes
            if any(m["threads"] == t and m["size"] == s for m in results["maps"])
        ]
        for t in threads_list
    }
    written = []
    plot = make_plot(table, out_dir / "img" / "scan_to_map_time.png")
    if plot is not None:
        written.append(plot)

    mach = meta["machine"]
    pk = mach.get("packages", {})
    lay = results.get("layout") or {}
    kfs = meta["args"]["keyframes"]
    L = [
        "# Scan to map: per-scan time against growing maps",
        "",
        "<!-- Generated by bench/map_bench.py from its raw results; rerun the command below, do not edit. -->",
        "",
        "One LiDAR scan registered against maps of growing size (issue 15): kissm with the map described once "
        "(`Matcher.compute_features(map)`) and reused for every scan (`compute_features(scan)` + "
        "`register_features`), kissm's full `register(scan, map)` per scan, and the reference KISS-Matcher "
        f"(PyPI kiss-matcher {pk.get('kiss-matcher', 'not installed')}), which has no reusable map side and "
        "describes the whole map on every call.",
        "",
        f"**{TARGET_TEXT[0].upper() + TARGET_TEXT[1:]}.**",
        "",
    ]
    for t in threads_list:
        text, _ = verdict(table[t])
        L.append(f"- {t} thread{'s' if t > 1 else ''}: {text}.")
    L.append("")
    for t in threads_list:
        L += [headline(t, table[t]), ""]
    if results["errors"]:
        L += [f"**{len(results['errors'])} call(s) raised** (listed at the end); their rows are incomplete.", ""]

    L += ["## Results", ""]
    L += [
        "Times are wall times from Python (numpy arrays in, pose out), in ms: per scan the median over its timed "
        "calls, then the median over the scans. *kissm per scan* is `compute_features(scan)` + "
        "`register_features` (in brackets: the two parts, and the matching stage of the second, *m*); *map prep* "
        "is `compute_features(map)`, paid once per map; *reference* is the call's wall time (in brackets: the "
        "sum of its own C++ stage times). *vs smallest* is kissm's per-scan time against the smallest map's. "
        "Success: calls reported valid within "
        f"{MAX_ROT_DEG:g}° and {MAX_TRANS_M:g} m of the ground truth, out of all timed calls (kissm reused · kissm "
        "full · reference); errors are medians over the successes, inliers over all calls. *Bytes / keypoint*: "
        "the map features' `memory_bytes` per map keypoint (in brackets the resident memory the process grew by "
        "while computing them, per keypoint).",
        "",
    ]
    for t in threads_list:
        rows = table[t]
        L += [
            f"### {t} thread{'s' if t > 1 else ''}",
            "",
            "| map points | voxels | keypoints | map prep | kissm per scan | vs smallest | kissm full | reference "
            "| ref / kissm per scan | success | median error: kissm · ref | median inliers: kissm · ref "
            "| bytes / keypoint |",
            "|---:|---:|---:|---:|---:|---:|---:|---:|---:|:---:|---|---|---:|",
        ]
        for row in rows:
            reuse, full, ref = row["kissm_reuse"], row["kissm_full"], row["reference"]
            lo, hi = row["points_range"]
            points = f"{lo:,d}" if lo == hi else f"{lo:,d}–{hi:,d}"
            per_scan = (
                f"{fmt_ms(reuse['wall_ms'])} ({fmt_ms(reuse['features_ms'])} + {fmt_ms(reuse['register_ms'])}, "
                f"m {fmt_ms(reuse['matching_ms'])})"
            )
            ref_ms = f"{fmt_ms(ref['wall_ms'])} ({fmt_ms(ref['cxx_ms'])})" if ref["calls"] else "not run"
            success = f"{reuse['success']}/{reuse['calls']} · {full['success']}/{full['calls']} · " + (
                f"{ref['success']}/{ref['calls']}" if ref["calls"] else "–"
            )
            mem = "n/a" if row["bytes_per_keypoint"] is None else f"{row['bytes_per_keypoint']:,.0f}"
            if row["rss_per_keypoint"] is not None:
                mem += f" ({row['rss_per_keypoint']:,.0f})"
            L.append(
                f"| {points} | {fmt_count(row['voxels'])} | {fmt_count(row['keypoints'])} | {fmt_ms(row['prep_ms'])} "
                f"| {per_scan} | {fmt_x(ratio(reuse['wall_ms'], rows[0]['kissm_reuse']['wall_ms']))} "
                f"| {fmt_ms(full['wall_ms'])} | {ref_ms} | {fmt_x(ratio(ref['wall_ms'], reuse['wall_ms']))} "
                f"| {success} | {fmt_err(reuse['rot_err_deg'], reuse['trans_err_m'])} · "
                f"{fmt_err(ref['rot_err_deg'], ref['trans_err_m'])} | {fmt_count(reuse['inliers'])} · "
                f"{fmt_count(ref['inliers'])} | {mem} |"
            )
        same = [row["same_pose"] for row in rows]
        wrong = {m: sum(row[m]["valid_wrong"] for row in rows) for m in METHODS}
        L += [
            "",
            f"kissm's reused-map pose equals its full register's bit for bit in {sum(s for s, _ in same)} of "
            f"{sum(n for _, n in same)} calls. Wrong poses reported valid: kissm reused {wrong['kissm_reuse']}, "
            f"kissm full {wrong['kissm_full']}, reference {wrong['reference']}.",
            "",
        ]
    if plot is not None:
        L += [f"![per-scan time against map points]({plot.relative_to(out_dir).as_posix()})", ""]
    else:
        L += ["(No plot: matplotlib is not installed.)", ""]

    L += ["## How it was measured", ""]
    L += [
        f"- Command: `{meta['command']}`; seed {meta['args']['seed']}, voxel {meta['args']['voxel']} m, "
        f"viewpoint mode `{meta['args']['viewpoint']}`, {meta['args']['repeats']} timed call(s) per method and scan "
        "after one warm-up call.",
        f"- Machine: {mach.get('cpu', '?')}, {mach.get('cpus_online', '?')} CPUs online (allowed "
        f"{mach.get('cpus_allowed', '?')}), {mach.get('mem_total_gb', '?')} GB, {mach.get('platform', '?')}, "
        f"Python {mach.get('python', '?')}; kissm {pk.get('kissm', '?')}, kiss-matcher "
        f"{pk.get('kiss-matcher', 'not installed')}, numpy {pk.get('numpy', '?')}, matplotlib "
        f"{pk.get('matplotlib', 'not installed')}; git {mach.get('git', '?')}.",
        f"- Run: {meta['started']} to {meta.get('finished', '?')} ({meta.get('duration_s', 0) / 60:.1f} min); load "
        f"average {meta['load_start'][0]:.2f} at the start, {meta.get('load_end', [math.nan])[0]:.2f} at the end.",
        f"- Scans: the KITTI 07 keyframes {', '.join(map(str, kfs))} of `../shared/data/{KEYFRAMES_DIR}`, each in "
        "its own sensor frame; ground truth: its world pose, chained through the pairs' `gt_T_target_source.txt` "
        "from keyframe 0 (as `bench/frame_study.py`).",
        "- Maps, in the world frame: the other four keyframes merged (the base map), then distractor tiles up to "
        "the map size: tile after tile, one of " + ", ".join(f"`{rel}`" for rel, _ in TILE_SOURCES) + " in turn, "
        f"a random {TILE_KEEP:.0%} of its points under a random yaw, {100 * TILE_JITTER_M:g} cm Gaussian jitter, "
        f"shifted up to {TILE_SHIFT_M:g} m from the centre of its cell of a grid with {lay.get('spacing_m', 0):g} m "
        f"spacing, nearest cells first, at least {meta['args']['min_gap']:g} m from every base map point; the last "
        "tile a random part of one. The maps of one seed are nested and the same on every run and thread count.",
        "- Each thread count runs in its own worker process pinned to that many CPUs (`sched_setaffinity`) with "
        "`OMP_NUM_THREADS` set before the reference is imported; kissm gets `num_threads`. Per map size and scan: "
        "one untimed warm-up call of each method, the map features computed once (timed: map prep), then the "
        "timed calls interleaved (kissm reused, kissm full, reference, and again). One kissm Matcher per worker.",
        f"- The reference runs as in `bench/bench.py` (a fresh `KISSMatcher(KISSMatcherConfig(voxel))` and "
        f"`estimate(scan, map)` per call; valid when `solution.valid` and at least {REFERENCE_MIN_INLIERS} final "
        f"inliers). Above {meta['args']['reference_once_above']:,d} map points it is called once per scan, "
        "without a warm-up of its own (it has run on the smaller maps in the same process)"
        + (
            f"; above {meta['args']['reference_max_points']:,d} map points it is not run."
            if meta["args"]["reference_max_points"] is not None
            else "."
        ),
        "- Memory: `memory_bytes` of the map's Features object when the kissm build offers it (else n/a), and "
        "the growth of the worker's resident set while computing them (after `malloc_trim`; a rough cross-check).",
    ]
    if lay:
        L.append(
            f"- Layout: base map radius {lay['base_radius_m']:.0f} m around its centre, tile radius up to "
            f"{lay['tile_radius_m']:.0f} m, nearest tile cell centre {lay['first_ring_m']:.0f} m from the base "
            f"map's centre; {lay['tile_count']} tile(s) made for the largest map. Raw results: `{meta['raw']}`."
        )
    if results["errors"]:
        L += ["", "## Calls that raised", ""]
        for e in results["errors"]:
            where = ", ".join(f"{key} {e[key]}" for key in ("threads", "size", "keyframe", "method", "rep") if key in e)
            L.append(f"- {where}: `{e['error']}`")
    path = out_dir / "scan_to_map.md"
    path.write_text("\n".join(L) + "\n")
    written.insert(0, path)
    return written


def make_plot(table: dict[int, list[dict[str, Any]]], path: Path) -> Path | None:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter
    except ImportError:
        return None
    path.parent.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    styles = ["-", "--", ":", "-."]
    for i, (threads, rows) in enumerate(sorted(table.items())):
        tag = f", {threads} thread{'s' if threads > 1 else ''}" if len(table) > 1 else ""
        for m in (*METHODS, "prep"):
            pts = [
                (row["points"], row["prep_ms"] if m == "prep" else row[m]["wall_ms"])
                for row in rows
                if (row["prep_ms"] if m == "prep" else row[m]["wall_ms"]) is not None
            ]
            if not pts:
                continue
            xs, ys = zip(*pts, strict=True)
            ax.plot(
                xs,
                ys,
                styles[i % len(styles)],
                marker="o" if m != "prep" else "s",
                ms=4,
                color=COLOR[m],
                alpha=0.6 if m == "prep" else 1.0,
                label=LABEL[m] + tag,
            )
    ax.set_xscale("log")
    ax.set_yscale("log")
    for axis, label in ((ax.xaxis, short_points), (ax.yaxis, lambda v: f"{v:,.0f}")):
        axis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
        axis.set_major_formatter(FuncFormatter(lambda v, _pos, label=label: label(v)))
        axis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("map points")
    ax.set_ylabel("wall time per scan [ms] (map prep: per map)")
    ax.set_title("Scan to map: time against map size (median over scans)", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    legend_rows = math.ceil(len(ax.get_lines()) / 2)
    if legend_rows:
        fig.legend(fontsize=7, loc="lower center", ncol=2, frameon=False)
    fig.tight_layout(rect=(0.0, 0.035 * legend_rows + 0.02, 1.0, 1.0))
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
