# SPDX-License-Identifier: MIT
"""docs/reports/ground.md and docs/reports/img/ground_*.png from the results of ground_bench.py
(kissm_bench.ground): the segmentation against Patchwork++, ground suppression in registration, the 4-DoF solver
against the reference's Quatro mode, with the targets' verdicts. The cases and targets the page states are
defined here and measured with by kissm_bench.ground.

``python bench/ground_bench.py --report-from bench/results/ground_latest.json.gz [--out DIR]`` rewrites the
page. The agreement plot (``img/ground_agreement.png``) needs the points and labels of a run, which no results
file keeps: a rewritten page shows the one already in ``DIR/img``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from ..common import med
from ..reference import REFERENCE_MIN_INLIERS
from ..results import pick, pose_digest

YAWS_DEG = (60.0, 120.0, 180.0, -90.0)  # source turned about up (z): fixed angles, no randomness needed
WRONG_UP_DEG = (30.0, 90.0)  # source turned about x with suppression on: its +z is no longer up
TILTS_DEG = (5.0, 10.0, 30.0)  # source turned about x under rotation_dof=1
SEG_VOXELS = (0.3, 0.5)
TILT_REASON = "the clouds' relative roll or pitch is not zero"
TILT_LIMIT_DEG = 2.0  # Config.max_rotation_uncertainty's default, the tilt limit of rotation_dof=1
ABOUT_UP_TOL = 1e-9
IOU_TARGET, SPEED_TARGET = 0.85, 2.0
LABEL = {
    "none": "kissm (3-DoF, no suppression)",
    "ground": "kissm, suppression='ground'",
    "dof1": "kissm, rotation_dof=1",
    "ref_quatro": "reference, use_quatro=True",
}


# ---- what the page reads ---------------------------------------------------------------------------------


RUN_FIELDS = (
    "pair",
    "variant",
    "group",
    "axis",
    "deg",
    "voxel",
    "method",
    "success",
    "valid",
    "wrong_valid",
    "reason",
    "rre_deg",
    "rte_m",
    "wall_ms",
    "features_ms",
    "matching_ms",
    "pruning_ms",
    "solver_ms",
    "suppression_ms",
    "inliers",
    "keypoints",
    "suppressed",
    "initial_corr",
    "inlier_ratio",
    "tilt_deg",
    "about_up_dev",
    "pose",
)
SEG_FIELDS = ("scan", "label", "points", "intensity", "pw_ground", "pw_second_call_same", "pw_ms", "kissm")
SEG_KISSM_FIELDS = ("iou", "precision", "recall", "iou_in_pw_range", "ms", "speedup", "deterministic")
#: A call that raised, as the run records it (and the page lists it).
ERROR_FIELDS = ("pair", "variant", "group", "axis", "deg", "voxel", "method", "rep", "error")
#: The agreement plot's points and labels: handed to the page by the run, never saved.
BevArrays = tuple[np.ndarray, np.ndarray, np.ndarray]


def _reduce_run(r: dict[str, Any]) -> dict[str, Any]:
    out = pick(r, RUN_FIELDS)
    if "transform" in r:  # the page asks only whether a case's repeated calls gave the same pose
        out["pose"] = pose_digest(r["transform"])
    return out


def _reduce_seg(rec: dict[str, Any]) -> dict[str, Any]:
    out = pick(rec, SEG_FIELDS)
    out["kissm"] = {v: pick(k, SEG_KISSM_FIELDS) for v, k in rec["kissm"].items()}
    return out


def reduce(results: dict[str, Any]) -> dict[str, Any]:
    """What the page is rendered from: the run's description and notes, per scan the segmentation's scores and
    times, per registration call its case, method, outcome, counts, times and a fingerprint of its pose, and the
    calls that raised. Reduced results reduce to themselves."""
    return {
        "meta": results["meta"],
        "notes": results["notes"],
        "seg": [_reduce_seg(rec) for rec in results["seg"]],
        "runs": [_reduce_run(r) for r in results["runs"]],
        "errors": results["errors"],
        **pick(results, ("bev",)),
    }


# ---- summary ---------------------------------------------------------------------------------------------


def fmp(r: dict[str, Any]) -> float:
    return float(r["features_ms"] + r["matching_ms"] + r["pruning_ms"])


def case_summary(runs: list[dict[str, Any]]) -> dict[str, Any] | None:
    """One method on one case: success count, median errors and counts, median times."""
    if not runs:
        return None
    ok = [r for r in runs if r["success"]]
    first = runs[0]
    out = {
        "calls": len(runs),
        "success": len(ok),
        "valid0": sum(not r["valid"] for r in runs),
        "wrong_valid": sum(r["wrong_valid"] for r in runs),
        "reasons": sorted({r["reason"] for r in runs if not r["valid"]}),
        "rre_deg": med(r["rre_deg"] for r in runs),
        "rte_m": med(r["rte_m"] for r in runs),
        "fmp_ms": med(fmp(r) for r in runs),
        "solver_ms": med(r["solver_ms"] for r in runs),
        "wall_ms": med(r["wall_ms"] for r in runs),
        "inliers": med(r["inliers"] for r in runs),
        "same_pose": len({r["pose"] for r in runs}) == 1,
        "about_up_dev": max((r["about_up_dev"] for r in runs if r["about_up_dev"] is not None), default=None),
    }
    for key in ("keypoints", "suppressed", "initial_corr", "inlier_ratio", "tilt_deg", "suppression_ms"):
        if key in first:
            out[key] = med(r[key] for r in runs)
    return out


def outcomes(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Calls, successes, valid = 0, wrong poses reported valid and the reasons of the invalid ones."""
    return {
        "calls": len(runs),
        "success": sum(r["success"] for r in runs),
        "valid0": sum(not r["valid"] for r in runs),
        "wrong_valid": sum(r["wrong_valid"] for r in runs),
        "reasons": sorted({r["reason"] for r in runs if not r["valid"]}),
    }


def summarise(results: dict[str, Any]) -> dict[str, Any]:
    runs = results["runs"]
    keys = list(dict.fromkeys((r["pair"], r["variant"], r["group"]) for r in runs))
    cases = []
    for pair, variant, group in keys:
        mine = [r for r in runs if r["pair"] == pair and r["variant"] == variant]
        row = {"pair": pair, "variant": variant, "group": group, "deg": mine[0]["deg"], "voxel": mine[0]["voxel"]}
        for m in ("none", "ground", "dof1", "ref_quatro"):
            row[m] = case_summary([r for r in mine if r["method"] == m])
        cases.append(row)
    yaw = [c for c in cases if c["group"] == "yaw"]

    def change(a: str, b: str, key: str) -> float | None:
        vals = [c[b][key] / c[a][key] for c in yaw if c[a] and c[b] and c[a].get(key) and c[b].get(key) is not None]
        return med(vals)

    supp = {
        "cases": len([c for c in yaw if c["ground"]]),
        "ground_success": sum(c["ground"]["success"] == c["ground"]["calls"] for c in yaw if c["ground"]),
        "none_success": sum(c["none"]["success"] == c["none"]["calls"] for c in yaw if c["none"]),
        "wrong_valid": sum(c["ground"]["wrong_valid"] for c in yaw if c["ground"]),
        **{f"change_{k}": change("none", "ground", k) for k in ("keypoints", "initial_corr", "inlier_ratio", "fmp_ms")},
        "fmp_faster_cases": sum(
            1 for c in yaw if c["ground"] and c["none"] and c["ground"]["fmp_ms"] < c["none"]["fmp_ms"]
        ),
    }
    dof = {
        "cases": len([c for c in yaw if c["dof1"]]),
        "dof1_success": sum(c["dof1"]["success"] == c["dof1"]["calls"] for c in yaw if c["dof1"]),
        "dof3_success": sum(c["none"]["success"] == c["none"]["calls"] for c in yaw if c["none"]),
        "ref_success": sum(c["ref_quatro"]["success"] == c["ref_quatro"]["calls"] for c in yaw if c["ref_quatro"]),
        "ref_cases": len([c for c in yaw if c["ref_quatro"]]),
        "dof1_wrong_valid": sum(c["dof1"]["wrong_valid"] for c in yaw if c["dof1"]),
        "ref_wrong_valid": sum(c["ref_quatro"]["wrong_valid"] for c in yaw if c["ref_quatro"]),
        "about_up_max_dev": max(
            (r["about_up_dev"] for r in runs if r["method"] == "dof1" and r["about_up_dev"] is not None), default=None
        ),
        "about_up_bad": sum(
            1
            for r in runs
            if r["method"] == "dof1" and (r["about_up_dev"] is None or r["about_up_dev"] >= ABOUT_UP_TOL)
        ),
        "dof1_calls": sum(1 for r in runs if r["method"] == "dof1"),
        "solver_ratio": change("dof1", "none", "solver_ms"),  # 3-DoF solver time over 1-DoF
        "solver_faster_cases": sum(
            1 for c in yaw if c["dof1"] and c["none"] and c["dof1"]["solver_ms"] < c["none"]["solver_ms"]
        ),
    }

    def about_x(method: str, deg: float) -> list[dict[str, Any]]:  # the calls of a case turned about x
        return [r for r in runs if r["method"] == method and r["axis"] == "x" and r["deg"] == deg]

    wrong_up = []
    for d in sorted({c["deg"] for c in cases if "wrong_up" in c["group"]}):
        sel = [c for c in cases if "wrong_up" in c["group"] and c["deg"] == d]
        entry: dict[str, Any] = {"deg": d}
        for m in ("none", "ground"):
            entry[m] = outcomes(about_x(m, d))
        entry["cases"] = len(sel)
        wrong_up.append(entry)
    tilt = []
    for d in sorted({c["deg"] for c in cases if "tilt" in c["group"]}):
        entry = {"deg": d}
        for m in ("dof1", "ref_quatro"):
            rs = about_x(m, d)
            entry[m] = {
                **outcomes(rs),
                "valid0_tilt": sum(not r["valid"] and TILT_REASON in r["reason"] for r in rs),
                "tilt_deg": med(r.get("tilt_deg") for r in rs),
            }
        tilt.append(entry)
    seg = results["seg"]
    segsum = {}
    for v in SEG_VOXELS:
        ks = [s["kissm"][str(v)] for s in seg]
        full = [s["kissm"][str(v)] for s in seg if "keyframe" not in s["label"]]
        segsum[str(v)] = {
            "min_iou": min((k["iou"] for k in ks if k["iou"] is not None), default=None),
            "min_iou_raw": min((k["iou"] for k in full if k["iou"] is not None), default=None),
            "iou_pass": sum(1 for k in ks if k["iou"] is not None and k["iou"] >= IOU_TARGET),
            "min_speedup": min((k["speedup"] for k in ks if k["speedup"]), default=None),
            "speed_pass": sum(1 for k in ks if k["speedup"] and k["speedup"] >= SPEED_TARGET),
            "speed_pass_raw": sum(1 for k in full if k["speedup"] and k["speedup"] >= SPEED_TARGET),
            "scans_raw": len(full),
            "scans": len(ks),
        }
    kissm_wrong = sum(1 for r in runs if r["wrong_valid"] and r["method"] != "ref_quatro")
    return {
        "cases": cases,
        "supp": supp,
        "dof": dof,
        "wrong_up": wrong_up,
        "tilt": tilt,
        "seg": segsum,
        "kissm_wrong_valid": kissm_wrong,
    }


# ---- report ----------------------------------------------------------------------------------------------


def f2(v: float | None, nd: int = 2) -> str:
    return "–" if v is None else f"{v:.{nd}f}"


def fms(v: float | None) -> str:
    if v is None:
        return "–"
    return f"{v:,.0f}" if v >= 100 else f"{v:.1f}" if v >= 1 else f"{v:.2f}" if v >= 0.1 else f"{v:.3f}"


def fe(v: float | None) -> str:
    return "–" if v is None else f"{v:.1e}"


def fx(v: float | None) -> str:
    return "–" if v is None else f"{v:.2f}x"


def pct(v: float | None) -> str:
    return "–" if v is None else f"{100 * (v - 1):+.0f}%"


def ferr(s: dict[str, Any] | None) -> str:
    if not s or s["rre_deg"] is None:
        return "–"
    return f"{s['rre_deg']:.2f}°, {100 * s['rte_m']:.0f} cm"


def fok(s: dict[str, Any] | None) -> str:
    """Successes / calls, and the wrong valid poses or else the invalid ones."""
    if not s:
        return "–"
    wrong, invalid = s["wrong_valid"], s["valid0"]
    note = f" **{wrong} WRONG VALID**" if wrong else f" ({invalid} valid=0)" if invalid else ""
    return f"{s['success']}/{s['calls']}{note}"


def short_pair(name: str) -> str:
    ds, _, pair = name.partition("/pairs/")
    short = {
        "small_gicp_lidar": "small_gicp",
        "kitti07_keyframes_gtsam_points": "KITTI 07 kf",
        "kitti_demo_scans_unverified": "KITTI sweeps",
    }.get(ds, ds)
    return f"{short} {pair}"


def verdict(ok: bool) -> str:
    return "**met**" if ok else "**MISSED**"


def write_report(results: dict[str, Any], out_dir: Path, bev: BevArrays | None = None) -> list[Path]:
    """Writes ``out_dir``/ground.md and its plots from a run's results (raw or reduced) and, from the run itself,
    the points and labels of the agreement plot."""
    results = reduce(results)
    s = summarise(results)
    meta = results["meta"]
    cmd = meta["command"]
    mach = meta["machine"]
    pk = meta["versions"]
    written: list[Path] = []
    img = out_dir / "img"
    plot_paths = make_plots(results, s, img, bev)
    written += plot_paths
    L = [
        "# Ground-vehicle mode: ground suppression and the 4-DoF solver",
        "",
        f"Measured by `bench/ground_bench.py` (the command: `{cmd}`; this page is its output). The machine "
        f"has {mach.get('cpus_online', '?')} CPUs shared with other work, so the timings are noisy: the "
        "methods are interleaved call by call and medians are reported; ratios are of medians from the same run. "
        "Rewrite this page from the saved results with `python bench/ground_bench.py --report-from "
        f"{meta['raw']}`.",
        "",
    ]
    for note in results["notes"]:
        L.append(f"> {note}")
    if results["notes"]:
        L.append("")
    # --- 1
    L += ["## 1. Ground segmentation against Patchwork++", ""]
    seg = results["seg"]
    if seg:
        sv = s["seg"]
        L += [
            f"kissm's `ground_mask(points, voxel, num_threads={meta['threads']})` at voxel 0.3 m and 0.5 m against "
            "Patchwork++ (`pypatchworkpp` "
            f"{pk.get('pypatchworkpp', '?')}, `Parameters()` = its KITTI defaults: sensor height 1.723 m, range "
            "2.7–80 m), fed the file's intensity (1.0 for the keyframes, which have none). Patchwork++'s labels "
            "are the truth for precision (share of kissm's ground that Patchwork++ calls ground) and recall; its "
            "labels come from the first call of a fresh instance. Time: median of "
            f"{meta['args']['seg_repeats']} interleaved calls after one warm-up, kissm's whole call (a Matcher, "
            "voxelisation, the ground model, the per-point labels) against Patchwork++'s `estimateGround` (one "
            f"instance reused, as in a stream); 1 CPU{'s' if meta['threads'] > 1 else ''} pinned.",
            "",
            "| scan | points | PW++ ground | IoU 0.3 | P / R 0.3 | IoU 0.5 | P / R 0.5 | IoU 0.3 in 2.7–80 m | "
            "kissm 0.3 ms | kissm 0.5 ms | PW++ ms | speed-up 0.3 | speed-up 0.5 |",
            "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
        ]
        for r in seg:
            a, b = r["kissm"]["0.3"], r["kissm"]["0.5"]
            label = r["label"] + ("" if r["intensity"] else " (no intensity)")
            L.append(
                f"| {label} | {r['points']:,d} | {r['pw_ground']:,d} | {f2(a['iou'], 3)} | "
                f"{f2(a['precision'])} / {f2(a['recall'])} | {f2(b['iou'], 3)} | {f2(b['precision'])} / "
                f"{f2(b['recall'])} | {f2(a['iou_in_pw_range'], 3)} | {fms(a['ms'])} | {fms(b['ms'])} | "
                f"{fms(r['pw_ms'])} | {fx(a['speedup'])} | {fx(b['speedup'])} |"
            )
        L.append("")
        for v in SEG_VOXELS:
            x = sv[str(v)]
            L.append(
                f"- Voxel {v} m: IoU >= {IOU_TARGET} on {x['iou_pass']}/{x['scans']} scans (lowest "
                f"{f2(x['min_iou'], 3)}; lowest on the full sweeps and small_gicp scans {f2(x['min_iou_raw'], 3)}): "
                f"{verdict(x['iou_pass'] == x['scans'])}. At least {SPEED_TARGET:g}x faster on "
                f"{x['speed_pass']}/{x['scans']} scans (lowest {fx(x['min_speedup'])}): "
                f"{verdict(x['speed_pass'] == x['scans'])}; on the raw scans (the full sweeps and small_gicp's, the "
                f"issue's measure) {x.get('speed_pass_raw', '?')}/{x.get('scans_raw', '?')}: "
                f"{verdict(x.get('speed_pass_raw') == x.get('scans_raw'))}."
            )
        unstable = [r["label"] for r in seg if not r["pw_second_call_same"]]
        nondet = [r["label"] for r in seg if not all(k["deterministic"] for k in r["kissm"].values())]
        L.append(
            "- kissm's labels were the same on a second call on every scan."
            if not nondet
            else f"- **kissm's labels changed between two calls on: {', '.join(nondet)}.**"
        )
        if unstable:
            L.append(
                f"- Patchwork++'s labels differ between its first and second call on the same scan for "
                f"{len(unstable)}/{len(seg)} scans ({', '.join(unstable)}): it carries per-frame history (its "
                "adaptive elevation and flatness thresholds), so the IoU above uses the fresh instance's labels."
            )
        L.append(
            "- The KITTI 07 keyframes are pre-thinned (0.27 m median spacing), so every voxel holds a point or "
            "two; Patchwork++ is tuned for raw sweeps. The small_gicp scans are from an unnamed sensor at an "
            "unknown height (Patchwork++ assumes KITTI's 1.723 m); judge the target on the KITTI sweeps first."
        )
        inside = suppression_inside(results)
        if inside:
            L += [
                "",
                "Not the target's measurement, but what registration pays: inside `register(..., "
                "suppression='ground')` the ground model runs on the voxels the features use anyway, so its cost "
                "(`Result.time_suppression_ms`, both clouds, median over the raw case's calls) is far below a "
                "standalone `ground_mask` call:",
                "",
                "| pair | voxel | suppression inside register, both clouds, ms | Patchwork++ on the same two scans, ms "
                "| ratio |",
                "|---|---:|---:|---:|---:|",
            ]
            for row in inside:
                L.append(
                    f"| {short_pair(row['pair'])} | {row['voxel']:g} | {fms(row['supp_ms'])} | {fms(row['pw_ms'])} "
                    f"| {fx(row['pw_ms'] / row['supp_ms'] if row['supp_ms'] else None)} |"
                )
        if (img / "ground_agreement.png").is_file():
            L += ["", "![agreement](img/ground_agreement.png)", ""]
        L.append("")
    else:
        L += ["Not measured in this run (Patchwork++ missing or no scan).", ""]
    # --- 2
    cases = s["cases"]
    yaw = [c for c in cases if c["group"] == "yaw"]
    sp = s["supp"]
    L += [
        "## 2. Ground suppression in registration",
        "",
        "Every LiDAR pair of `../shared/data` (voxel 0.3 m for the sweeps and small_gicp scans, 0.5 m for the "
        f"keyframes), raw and with the source turned about up (z) by {', '.join(f'{d:g}°' for d in YAWS_DEG)}; "
        f"`kissm.register(src, tgt, voxel, num_threads={meta['threads']})` with `suppression='none'` and "
        f"`'ground'`, {meta['args']['repeats']} timed calls each after a warm-up, interleaved. Success: valid "
        "within 5° and 2 m. Keypoints: source + target; F+M+P: features (suppression included) + matching + "
        "pruning, median ms.",
        "",
        "| pair | variant | success none / ground | error none / ground | suppressed voxels | keypoints none → ground "
        "| initial corr. | inlier ratio | F+M+P ms none → ground | suppression ms |",
        "|---|---|---|---|---:|---|---|---|---|---:|",
    ]
    for c in yaw:
        a, b = c["none"], c["ground"]
        if not a or not b:
            continue
        L.append(
            f"| {short_pair(c['pair'])} | {c['variant']} | {fok(a)} / {fok(b)} | {ferr(a)} / {ferr(b)} | "
            f"{b['suppressed']:,.0f} | {a['keypoints']:,.0f} → {b['keypoints']:,.0f} | "
            f"{a['initial_corr']:,.0f} → {b['initial_corr']:,.0f} | {f2(a['inlier_ratio'], 3)} → "
            f"{f2(b['inlier_ratio'], 3)} | {fms(a['fmp_ms'])} → {fms(b['fmp_ms'])} | {fms(b['suppression_ms'])} |"
        )
    L += [
        "",
        f"- Median change with suppression over the {sp['cases']} cases: keypoints {pct(sp['change_keypoints'])}, "
        f"initial correspondences {pct(sp['change_initial_corr'])}, inlier ratio {pct(sp['change_inlier_ratio'])}, "
        f"features + matching + pruning time {pct(sp['change_fmp_ms'])} (faster in {sp['fmp_faster_cases']}/"
        f"{sp['cases']} cases).",
        f'- Target "every LiDAR pair, raw and yaw-turned, still succeeds": {sp["ground_success"]}/{sp["cases"]} '
        f"cases succeed on every call with suppression ({sp['none_success']}/{sp['cases']} without): "
        f"{verdict(sp['ground_success'] == sp['cases'])}. Wrong poses reported valid with suppression: "
        f"{sp['wrong_valid']}.",
        "",
        "### Wrong up",
        "",
        "The source turned about x (a horizontal axis), so its +z is not up and the ground model looks for a "
        "ground in the wrong direction; one call per pair. Success / valid = 0 / WRONG VALID (a valid pose "
        "outside the thresholds; must be 0).",
        "",
        "| source turned about x | pairs | suppression 'ground': ok / valid=0 / WRONG VALID | reasons | "
        "'none' (baseline): ok / valid=0 / WRONG VALID |",
        "|---|---:|---|---|---|",
    ]
    for w in s["wrong_up"]:
        g, n = w["ground"], w["none"]
        L.append(
            f"| {w['deg']:g}° | {w['cases']} | {g['success']} / {g['valid0']} / "
            f"{'**' + str(g['wrong_valid']) + '**' if g['wrong_valid'] else 0} | {'; '.join(g['reasons']) or '–'} | "
            f"{n['success']} / {n['valid0']} / {'**' + str(n['wrong_valid']) + '**' if n['wrong_valid'] else 0} |"
        )
    wu = sum(w["ground"]["wrong_valid"] for w in s["wrong_up"])
    L += ["", f"- Wrong-up wrong valids with suppression: **{wu}** ({verdict(wu == 0)}).", ""]
    # --- 3
    dof = s["dof"]
    L += [
        "## 3. 4-DoF (yaw-only) solver",
        "",
        f"The same raw and yaw-turned cases, `rotation_dof` 3 (default) against 1, and the reference "
        f"(`kiss-matcher` {pk.get('kiss-matcher', 'not installed')}) with `KISSMatcherConfig(voxel, "
        "use_quatro=True)` (its config has that flag), in its own helper process per voxel size, interleaved "
        "with kissm's calls. Solver: `Result.time_solver_ms` and the reference's `get_solver_time()`, median ms. "
        "Tilt: `Result.tilt` of the 1-DoF call. About z: the largest of |R22 − 1|, |R02|, |R12|, |R20|, |R21| "
        "of the returned rotation over the calls.",
        "",
        "| pair | variant | success 3-DoF / 1-DoF / ref Quatro | error 1-DoF | error ref Quatro | solver ms 3-DoF "
        "→ 1-DoF | ref Quatro solver ms | tilt ° | about z (1-DoF) | about z (ref) |",
        "|---|---|---|---|---|---|---:|---:|---:|---:|",
    ]
    for c in yaw:
        a, b, q = c["none"], c["dof1"], c["ref_quatro"]
        if not a or not b:
            continue
        L.append(
            f"| {short_pair(c['pair'])} | {c['variant']} | {fok(a)} / {fok(b)} / {fok(q)} | {ferr(b)} | {ferr(q)} | "
            f"{fms(a['solver_ms'])} → {fms(b['solver_ms'])} | {fms(q['solver_ms']) if q else '–'} | "
            f"{f2(b.get('tilt_deg'))} | {fe(b['about_up_dev'])} | "
            f"{fe(q['about_up_dev'] if q else None)} |"
        )
    ref_txt = (
        f"{dof['ref_success']}/{dof['ref_cases']} cases for the reference's Quatro mode "
        f"({dof['ref_wrong_valid']} wrong valid)"
        if dof["ref_cases"]
        else "the reference was not run"
    )
    L += [
        "",
        f'- Target "every run succeeds": {dof["dof1_success"]}/{dof["cases"]} cases succeed on every 1-DoF call '
        f"({dof['dof3_success']}/{dof['cases']} with 3-DoF; {ref_txt}): "
        f"{verdict(dof['dof1_success'] == dof['cases'])}.",
        f'- Target "the rotation is exactly about up": {dof["dof1_calls"] - dof["about_up_bad"]}/{dof["dof1_calls"]} '
        f"1-DoF calls within {ABOUT_UP_TOL:g} (largest deviation {fe(dof['about_up_max_dev'])}): "
        f"{verdict(dof['about_up_bad'] == 0)}.",
        f'- Target "the solver is faster than the 3-DoF one": faster in {dof["solver_faster_cases"]}/{dof["cases"]} '
        f"cases, median 3-DoF / 1-DoF solver time {fx(dof['solver_ratio'])}: "
        f"{verdict(dof['solver_faster_cases'] == dof['cases'])}"
        + (
            " (the slower cases differ by a few ms on a shared machine, possibly noise; the target is judged per case)."
            if 0 < dof["cases"] - dof["solver_faster_cases"] <= 2
            else "."
        ),
    ]
    vs = [
        (c["dof1"]["solver_ms"] / c["ref_quatro"]["solver_ms"], c["dof1"]["wall_ms"] / c["ref_quatro"]["wall_ms"])
        for c in yaw
        if c["dof1"] and c["ref_quatro"] and c["ref_quatro"]["solver_ms"] and c["ref_quatro"]["wall_ms"]
    ]
    if vs:
        L.append(
            "- Against the reference's Quatro mode: kissm's 1-DoF solver stage takes a median "
            f"{fx(med(v[0] for v in vs))} the reference's `get_solver_time()` (the two timers need not cover the same "
            f"work), while kissm's whole call takes {fx(med(v[1] for v in vs))} "
            "the reference's wall time."
        )
    L += [
        "- Where the pair itself has some relative roll or pitch (KITTI 07 000000__000001: `tilt` about 1.3°), the "
        "yaw-only pose keeps that much rotation error in every variant (both kissm and the reference), within the "
        "5° success threshold and under the 2° tilt limit.",
        "",
        "### Tilted pairs under rotation_dof=1",
        "",
        "The source turned about x, so the pair's relative roll is that angle: the yaw-only model cannot "
        'express it. Right: valid = 0 (reason "' + TILT_REASON + '"), or a valid pose within the '
        "thresholds. One call per pair.",
        "",
        "| turned about x | kissm 1-DoF: valid=0 (tilt reason) / ok / WRONG VALID | median tilt ° | other reasons | "
        "ref Quatro: ok / valid=0 / WRONG VALID |",
        "|---|---|---:|---|---|",
    ]
    for t in s["tilt"]:
        k, q = t["dof1"], t["ref_quatro"]
        others = [r for r in k["reasons"] if TILT_REASON not in r]
        L.append(
            f"| {t['deg']:g}° | {k['valid0']} ({k['valid0_tilt']}) / {k['success']} / "
            f"{'**' + str(k['wrong_valid']) + '**' if k['wrong_valid'] else 0} of {k['calls']} | {f2(k['tilt_deg'])} | "
            f"{'; '.join(others) or '–'} | "
            + (f"{q['success']} / {q['valid0']} / {q['wrong_valid']} of {q['calls']} |" if q["calls"] else "– |")
        )
    tw = sum(t["dof1"]["wrong_valid"] for t in s["tilt"])
    L += [
        "",
        f"- kissm tilted wrong valids: **{tw}** ({verdict(tw == 0)}). The reference has no such check: its "
        "Quatro mode reports what it finds.",
        "",
        "## Wrong poses reported valid",
        "",
        f"kissm, every call of this run: **{s['kissm_wrong_valid']}**"
        + (" — **NOT ZERO: a wrong pose was reported valid.**" if s["kissm_wrong_valid"] else "."),
        "",
    ]
    for r in results["runs"]:
        if r["wrong_valid"] and r["method"] != "ref_quatro":
            L.append(
                f"- **{LABEL[r['method']]}, {short_pair(r['pair'])}, {r['variant']}** (voxel {r['voxel']:g}): valid "
                f"with {r['rre_deg']:.2f}° / {r['rte_m']:.2f} m error; {r['inliers']} final inliers of "
                f"{r['initial_corr']:,d} initial correspondences (inlier ratio {f2(r['inlier_ratio'], 4)}), "
                f"`Result.tilt` {f2(r.get('tilt_deg'))}° against the {TILT_LIMIT_DEG:g}° limit "
                f"(`max_rotation_uncertainty`): the tilt measured on so few inliers missed the {r['deg']:g}° the "
                "source was turned by."
            )
    if s["kissm_wrong_valid"]:
        L.append("")
    if any(p.name == "ground_times.png" for p in plot_paths):
        L += ["![times](img/ground_times.png)", ""]
    # --- how
    L += [
        "## How it was measured",
        "",
        f"- Machine: {mach.get('cpu', '?')}, {mach.get('cpus_online', '?')} CPUs online (allowed "
        f"{mach.get('cpus_allowed', '?')}), {mach.get('mem_total_gb', '?')} GB, {mach.get('platform', '?')}, "
        f"Python {mach.get('python', '?')}; kissm {pk.get('kissm') or 'from the checkout'} "
        f"(`{mach.get('kissm_library', '?')}`), kiss-matcher {pk.get('kiss-matcher', 'not installed')}, "
        f"pypatchworkpp {pk.get('pypatchworkpp', 'not installed')}, numpy {pk.get('numpy', '?')}; git "
        f"{mach.get('git', '?')}.",
        f"- Run: {meta['started']} to {meta.get('finished', '?')} ({meta.get('duration_s', 0) / 60:.1f} min); load "
        f"average {meta['load_start'][0]:.2f} at the start, {meta.get('load_end', [math.nan])[0]:.2f} at the end. "
        "Other work shared the 2 CPUs during the run.",
        f"- Pinning: the process (and the reference's helpers) to CPUs {meta['cpus']} with `sched_setaffinity`, "
        f"`OMP_NUM_THREADS={meta['threads']}`; kissm `num_threads={meta['threads']}`; Patchwork++ is "
        "single-threaded.",
        "- Cases: each pair's source read once (`kissm.read_points`), turned about its own origin (the sensor) by "
        "the variant's rotation R, ground truth `R_gt R^T`; success, errors and validity as in "
        "`bindings/python/tests/realdata.py` (LiDAR: 5° and 2 m). The reference is valid when `solution.valid` "
        f"and it has at least {REFERENCE_MIN_INLIERS} final inliers (as in `bench/bench.py`).",
        "- Timed registration cases (raw and yaw): one untimed warm-up call per method (the reference's helper "
        "once per voxel size), then the methods in turn, repeated. Wrong-up and tilted cases: one call each "
        "(kissm is deterministic: `same pose` held on every repeated case"
        + (
            ""
            if all(c[m]["same_pose"] for c in yaw for m in ("none", "ground", "dof1") if c[m])
            else " — **except some; see the raw results**"
        )
        + ").",
        f"- Raw results: `{meta['raw']}`.",
    ]
    if results["errors"]:
        L += ["", "## Calls that raised", ""]
        for e in results["errors"]:
            L.append(f"- {pick(e, ERROR_FIELDS)}")  # in the run's order (saved results sort their keys)
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / "ground.md"
    path.write_text("\n".join(L) + "\n")
    return [path, *written]


def suppression_inside(results: dict[str, Any]) -> list[dict[str, Any]]:
    """Per pair: suppression's time inside register (raw case, both clouds) and Patchwork++ on its two scans."""
    rows = []
    pairs = list(dict.fromkeys(r["pair"] for r in results["runs"]))
    for pair in pairs:
        runs = [r for r in results["runs"] if r["pair"] == pair and r["variant"] == "raw" and r["method"] == "ground"]
        dataset, names = pair.split("/")[0], pair.split("/")[-1].split("__")
        scans = [
            s
            for s in results["seg"]
            if s["scan"].startswith(dataset + "/")
            and any(Path(s["scan"]).stem == n or Path(s["scan"]).parent.name == n for n in names)
        ]
        if not runs or len(scans) != 2:
            continue
        rows.append(
            {
                "pair": pair,
                "voxel": runs[0]["voxel"],
                "supp_ms": med(r["suppression_ms"] for r in runs),
                "pw_ms": sum(s["pw_ms"] for s in scans),
            }
        )
    return rows


def make_plots(results: dict[str, Any], s: dict[str, Any], img: Path, bev: BevArrays | None) -> list[Path]:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return []
    img.mkdir(parents=True, exist_ok=True)
    out = []
    if bev is not None:
        xyz, mask, truth = bev
        fig, ax = plt.subplots(figsize=(7, 7))
        keep = np.linalg.norm(xyz[:, :2], axis=1) < 50
        cats = [
            (~mask & ~truth, "#c8c8c8", "neither"),
            (mask & truth, "#2ca02c", "both ground"),
            (mask & ~truth, "#d62728", "kissm only"),
            (~mask & truth, "#1f77b4", "Patchwork++ only"),
        ]
        for sel, color, label in cats:
            sel = sel & keep
            ax.scatter(xyz[sel, 0], xyz[sel, 1], s=0.3, c=color, label=f"{label} ({sel.sum():,d})", linewidths=0)
        ax.set_aspect("equal")
        ax.set_title(
            f"{results['bev']['scan']}: kissm ground_mask (voxel {results['bev']['voxel']}) vs Patchwork++", fontsize=9
        )
        ax.legend(markerscale=20, fontsize=8, loc="upper right")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        fig.tight_layout()
        p = img / "ground_agreement.png"
        fig.savefig(p, dpi=110)
        plt.close(fig)
        out.append(p)
    seg = results["seg"]
    yaw = [c for c in s["cases"] if c["group"] == "yaw" and c["none"] and c["ground"]]
    if seg or yaw:
        fig, axes = plt.subplots(1, 2, figsize=(12, 4.6))
        if seg:
            ax = axes[0]
            x = np.arange(len(seg))
            for i, (key, label, color) in enumerate(
                (("0.3", "kissm 0.3", "#d62728"), ("0.5", "kissm 0.5", "#ff7f0e"), ("pw", "Patchwork++", "#1f77b4"))
            ):
                vals = [r["pw_ms"] if key == "pw" else r["kissm"][key]["ms"] for r in seg]
                ax.bar(x + (i - 1) * 0.27, vals, 0.27, label=label, color=color)
            ax.set_xticks(x)
            ax.set_xticklabels(
                [r["label"].replace("KITTI-style sweep", "sweep").replace("KITTI 07 keyframe", "kf") for r in seg],
                rotation=35,
                ha="right",
                fontsize=7,
            )
            ax.set_ylabel("ms per scan (median, 1 thread)")
            ax.set_title("Ground segmentation time", fontsize=10)
            ax.legend(fontsize=8)
        if yaw:
            ax = axes[1]
            x = np.arange(len(yaw))
            ax.bar(x - 0.2, [c["none"]["fmp_ms"] for c in yaw], 0.4, label="suppression none", color="#7f7f7f")
            ax.bar(x + 0.2, [c["ground"]["fmp_ms"] for c in yaw], 0.4, label="suppression ground", color="#2ca02c")
            ax.set_xticks(x)
            ax.set_xticklabels(
                [f"{short_pair(c['pair'])} {c['variant']}" for c in yaw], rotation=60, ha="right", fontsize=6
            )
            ax.set_ylabel("features + matching + pruning ms (median)")
            ax.set_title("Registration front end with and without suppression", fontsize=10)
            ax.legend(fontsize=8)
        fig.tight_layout()
        p = img / "ground_times.png"
        fig.savefig(p, dpi=110)
        plt.close(fig)
        out.append(p)
    return out
