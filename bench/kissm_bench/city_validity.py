# SPDX-License-Identifier: MIT
"""Can a validity rule refuse the wrong poses that loop registrations on a simulated city report valid, without
losing right ones? (docs/design/accuracy.md, "Confidence", "The simulated city's wrong poses: a rule that refuses
them".)

Two steps:

``drive``: on a drive of ``kissm simulate`` (scans.tsv, gt_poses.txt), the pairs a loop search tries, chosen by
the ground-truth positions: ``kissm._candidates.loop_candidates`` with a radius of 30 voxels, ``loop_gap`` 10, 5
per scan and a drift allowance of 5% of the path between (the setting under which docs/reports/multiway-drive.md
saw its 9 wrong poses: pairs up to about 90 m apart), plus ``--far`` random pairs 30-80 m apart and at least 50
scans apart (half of them with headings more than 45 degrees apart: crossings), plus ``--extra`` pairs. Each pair
(the later scan as source, into the earlier) is registered with ``kissm.Matcher(voxel_size=0.5,
refine_mode="gicp")`` (``--refine``) on features computed once per scan; every result's numbers go to a JSON line
with its error against the exact relative pose (wrong: more than 2 degrees or 2 voxels off).

``sets``: every pair of the shared multi-scan sets (the later scan into the earlier), raw and with the source turned
and moved ``--turns`` times, recorded the same way (``how`` is the set's name): what a rule costs the multiway
job's pairs.

``rules``: reads those lines and the validity study's records (``bench/validity_study.py --priors --records``:
the real data raw, turned and moved, GICP and coarse, refinement from priors, the synthetic scenes), compares the
numbers of the wrong and right valid drive results, and lists the single thresholds and pairs of thresholds that
refuse every wrong valid drive result, with the right valid results each would lose per drive and per data set of
the study; ``--rule`` costs a rule of one's own. Rules are applied after the fact to the recorded numbers (a
field that is NaN, e.g. the residual of an unrefined pose, leaves the rule silent).

    python bench/city_validity_study.py drive DRIVE --out d.jsonl [--scans N] [--far 400] [--extra I,J ...]
    python bench/city_validity_study.py sets --turns 3 [--refine none] --out sets.jsonl
    python bench/validity_study.py --threads 1 --priors --records study.jsonl
    python bench/city_validity_study.py rules d1.jsonl d2.jsonl ... --real study.jsonl \\
        [--rule "refuse if refine_rmse_voxels > 0.35 and refine_condition < 0.09"]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .common import DATA_HELP, default_data

MAX_ANGLE_DEG, MAX_VOXELS = 2.0, 2.0
VOXEL = 0.5

#: The numbers of a valid result the rules may read (kissm.Result fields; overlap_spread derived).
FIELDS = (
    "num_final_inliers",
    "num_rotation_inliers",
    "inlier_ratio",
    "overlap",
    "refine_rmse",
    "refine_condition",
    "rotation_uncertainty",
    "inlier_coverage",
    "ambiguity",
    "confidence",
    "num_refine_correspondences",
    "max_core_number",
    "num_pruned_correspondences",
    "num_initial_correspondences",
    "residual_rms",
    "noise_bound",
)


# ---- the drive -----------------------------------------------------------------------------------------------


def angle_deg(rotation: np.ndarray) -> float:
    return math.degrees(math.acos(max(-1.0, min(1.0, (float(np.trace(rotation)) - 1.0) / 2.0))))


def pose_error(estimate: np.ndarray, truth: np.ndarray) -> tuple[float, float]:
    difference = np.linalg.inv(truth) @ estimate
    return angle_deg(difference[:3, :3]), float(np.linalg.norm(difference[:3, 3]))


def choose_pairs(
    poses: np.ndarray, far: int, seed: int, extra: Sequence[tuple[int, int]]
) -> dict[tuple[int, int], str]:
    """(i, j) -> how the pair was chosen: "loop" (loop_candidates on the truth, 5% drift), "far", "extra"."""
    from kissm._candidates import loop_candidates

    n = len(poses)
    positions = poses[:, :3, 3]
    path = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(positions, axis=0), axis=1))])
    piece = np.zeros(n, dtype=np.int64)
    pairs: dict[tuple[int, int], str] = {}
    for i, j in loop_candidates((positions, path, piece), 30 * VOXEL, 10, 5, drift=0.05):
        pairs[(i, j)] = "loop"
    rng = np.random.default_rng(seed)
    heading = np.arctan2(poses[:, 1, 0], poses[:, 0, 0])
    ii, jj = np.triu_indices(n, k=50)
    d = np.linalg.norm(positions[ii] - positions[jj], axis=1)
    keep = (d >= 30.0) & (d <= 80.0)
    ii, jj = ii[keep], jj[keep]
    turn = np.abs((heading[ii] - heading[jj] + np.pi) % (2 * np.pi) - np.pi)
    for crossing in (True, False):
        pool = [
            k for k in np.flatnonzero((turn > math.radians(45)) == crossing) if (int(ii[k]), int(jj[k])) not in pairs
        ]
        for k in rng.choice(pool, size=min(far // 2, len(pool)), replace=False) if pool else []:
            pairs[(int(ii[k]), int(jj[k]))] = "far, crossing" if crossing else "far"
    for i, j in extra:
        if max(i, j) < n:
            pairs.setdefault((min(i, j), max(i, j)), "extra")
    return pairs


def row(
    result: Any, i: int, j: int, how: str, truth: np.ndarray, distance: float, voxel: float = VOXEL
) -> dict[str, Any]:
    out: dict[str, Any] = {"target": i, "source": j, "how": how, "distance_m": distance}
    out["valid"] = bool(result.valid)
    out["reason"] = result.reason
    transform = np.asarray(result.transform)
    if np.isfinite(transform).all():
        deg, m = pose_error(transform, truth)
        out["error_deg"], out["error_m"] = deg, m
        out["right"] = deg <= MAX_ANGLE_DEG and m <= MAX_VOXELS * voxel
    else:
        out["error_deg"] = out["error_m"] = None
        out["right"] = False
    for name in FIELDS:
        v = getattr(result, name)
        out[name] = float(v) if isinstance(v, float) else int(v)
    extent = np.asarray(result.inlier_extent, dtype=float)
    out["inlier_extent"] = extent.tolist()
    cov = float(result.inlier_coverage)
    out["overlap_spread"] = float(extent[0] / cov) if cov > 0 and math.isfinite(cov) else math.nan
    return out


def drive_main(args: argparse.Namespace) -> int:
    import kissm

    from .data import read_scan_set

    names, files, formats, poses_by_name = read_scan_set(args.drive)
    n = min(args.scans or len(names), len(names))
    poses = np.array([poses_by_name[name] for name in names[:n]])
    extra = [tuple(int(x) for x in e.split(",")) for e in args.extra]
    pairs = choose_pairs(poses, args.far, args.seed, extra)  # type: ignore[arg-type]
    used = sorted({k for p in pairs for k in p})
    print(f"{args.drive}: {n} scans, {len(pairs)} pairs over {len(used)} scans", file=sys.stderr, flush=True)
    t0 = time.monotonic()
    with kissm.Matcher(voxel_size=VOXEL, refine_mode=args.refine, num_threads=args.threads) as m:
        features = {}
        for count, k in enumerate(used):
            features[k] = m.compute_features(kissm.read_points(files[k], format=formats[k]))
            if count % 100 == 99:
                print(f"  features {count + 1}/{len(used)} {time.monotonic() - t0:.0f} s", file=sys.stderr)
        with open(args.out, "w", encoding="utf-8") as out:
            for count, ((i, j), how) in enumerate(sorted(pairs.items())):
                r = m.register_features(features[j], features[i])
                truth = np.linalg.inv(poses[i]) @ poses[j]
                distance = float(np.linalg.norm(poses[i][:3, 3] - poses[j][:3, 3]))
                out.write(json.dumps(row(r, i, j, how, truth, distance)) + "\n")
                if count % 200 == 199:
                    print(f"  pairs {count + 1}/{len(pairs)} {time.monotonic() - t0:.0f} s", file=sys.stderr)
    print(f"  done in {time.monotonic() - t0:.0f} s", file=sys.stderr)
    return 0


def random_motion(rng: np.random.Generator, reach: float) -> np.ndarray:
    """A rigid motion with a uniformly random rotation and a translation of up to ``reach`` per axis."""
    q = rng.normal(size=4)
    w, x, y, z = q / np.linalg.norm(q)
    t = np.eye(4)
    t[:3, :3] = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ]
    t[:3, 3] = rng.uniform(-reach, reach, size=3)
    return t


def sets_main(args: argparse.Namespace) -> int:
    """Every pair of every shared multi-scan set, the later scan into the earlier (``kissm.multiway.align``'s
    "all"), each result recorded as the drive step records its pairs (``how`` is the set's name)."""
    import kissm

    from .data import SCAN_SETS, read_scan_set

    root = args.data
    with open(args.out, "w", encoding="utf-8") as out:
        for scan_set in SCAN_SETS:
            names, files, formats, poses = read_scan_set(root / scan_set.folder)
            clouds = [kissm.read_points(f, format=k) for f, k in zip(files, formats, strict=True)]
            rng = np.random.default_rng(args.seed)
            with kissm.Matcher(voxel_size=scan_set.voxel, refine_mode=args.refine, num_threads=args.threads) as m:
                targets = [m.compute_features(c) for c in clouds]
                for turn in range(args.turns + 1):
                    # Turned: every source moved by a random rigid motion T (the sources' frames no longer near the
                    # targets'), so the relative pose is truth @ inv(T).
                    motions = [np.eye(4) if turn == 0 else random_motion(rng, 10 * scan_set.voxel) for _ in clouds]
                    sources = (
                        targets
                        if turn == 0
                        else [
                            m.compute_features(c @ t[:3, :3].T + t[:3, 3]) for c, t in zip(clouds, motions, strict=True)
                        ]
                    )
                    for j in range(len(names)):
                        for i in range(j):
                            r = m.register_features(sources[j], targets[i])
                            truth = np.linalg.inv(poses[names[i]]) @ poses[names[j]] @ np.linalg.inv(motions[j])
                            record = row(r, i, j, scan_set.label, truth, 0.0, scan_set.voxel)
                            record["turn"] = turn
                            out.write(json.dumps(record) + "\n")
            print(f"  {scan_set.label}: {len(names)} scans", file=sys.stderr, flush=True)
    return 0


# ---- the rules -----------------------------------------------------------------------------------------------

#: (field, direction): a rule refuses a result whose field is below (">=": it must be at least) or above ("<=")
#: the threshold.
DIRECTIONS = {
    "refine_rmse_voxels": "<=",
    "num_final_inliers": ">=",
    "num_rotation_inliers": ">=",
    "inlier_ratio": ">=",
    "overlap": ">=",
    "refine_condition": ">=",
    "rotation_uncertainty": "<=",
    "inlier_coverage": ">=",
    "ambiguity": "<=",
    "confidence": ">=",
    "num_refine_correspondences": ">=",
    "max_core_number": ">=",
}


def value(r: dict[str, Any], field: str) -> float:
    if field == "refine_rmse_voxels":  # the residual in voxels: the solver's bound is 0.75 voxel at the defaults
        rmse, bound = r.get("refine_rmse"), r.get("noise_bound")
        voxel = bound / 0.75 if bound else VOXEL
        return math.nan if rmse is None else float(rmse) / voxel
    v = r.get(field)
    return math.nan if v is None else float(v)


def passes(r: dict[str, Any], field: str, threshold: float) -> bool:
    """Whether the result keeps its validity under "field >= / <= threshold" (a NaN field passes: the rule does
    not apply to it, e.g. overlap of an unrefined result)."""
    v = value(r, field)
    if math.isnan(v):
        return True
    return v >= threshold if DIRECTIONS[field] == ">=" else v <= threshold


def threshold_rule(field: str, threshold: float) -> Callable[[dict[str, Any]], bool]:
    """Whether a result keeps its validity under "field >= / <= threshold" (passes)."""
    return lambda r: passes(r, field, threshold)


def pair_rule(a: str, ta: float, b: str, tb: float) -> Callable[[dict[str, Any]], bool]:
    """Whether a result keeps its validity under both thresholds (refused when either fails)."""
    return lambda r: passes(r, a, ta) and passes(r, b, tb)


def tightest(wrong: list[dict[str, Any]], field: str) -> float | None:
    """The loosest threshold on field that refuses every wrong result (None when some has no value)."""
    values = [value(r, field) for r in wrong]
    if any(math.isnan(v) for v in values):
        return None
    if DIRECTIONS[field] == ">=":
        return float(np.nextafter(max(values), math.inf))
    return float(np.nextafter(min(values), -math.inf))


def load(path: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


DATASETS = (  # the validity study's families, by the start of their name, as the tables list them
    ("kitti07_keyframes", "KITTI 07 keyframes"),
    ("kitti07 keyframes 2-4", "KITTI 07 keyframes 2-4 apart"),
    ("scan to map", "scan to map (KITTI 07)"),
    ("kitti_demo", "KITTI demo scans"),
    ("small_gicp", "small_gicp LiDAR"),
    ("ground suppressed", "ground suppressed LiDAR"),
    ("3dmatch", "3DMatch"),
    ("stanford_bunny", "bunny pairs"),
    ("bunny multi-scan", "bunny multi-scan neighbours"),
    ("happy multi-scan", "happy multi-scan neighbours"),
    ("synthetic pair", "synthetic pair"),
    ("unrelated", "unrelated scans"),
)


def real_group(r: dict[str, Any]) -> tuple[str, str, str] | None:
    """A validity study record's (data set, raw / turned / moved, GICP / coarse); None for point-to-plane and the
    features entry point (the same bits)."""
    mode = r["mode"]
    if "(features)" in mode or mode not in ("none", "gicp"):
        return None
    fam, name = r["family"], r["name"]
    if fam == "refine from a prior":  # kissm.refine from the truth disturbed (validity_study --priors)
        return ("refined from a prior", "all", "GICP")
    mode = "GICP" if mode == "gicp" else "coarse"
    dataset = next((label for key, label in DATASETS if fam.startswith(key)), None)
    if dataset is None:  # the repetitive scenes, their controls, the objects of symmetric parts
        return ("synthetic scenes", "all", mode)
    if "(moved frame)" in fam:
        variant = "moved"
    elif "_variant" in r:
        variant = r["_variant"]
    elif name.endswith(" raw") or name.endswith("of the others") and "turned" not in name:
        variant = "raw"
    else:
        variant = "turned"
    return (dataset, variant, mode)


def load_study(path: Path, rotations: int = 6) -> list[dict[str, Any]]:
    """The validity study's records, each real pair's marked raw or turned (its names are cut at 48 characters, so
    the " raw" / " rotN" suffix may be gone): per family and mode a pair's runs come raw first, then its
    ``rotations`` turns (validity_study.real_pairs)."""
    rows = load(path)
    seen: dict[tuple[str, str], int] = {}
    for r in rows:
        if "/pairs/" in r["name"] and "(moved frame)" not in r["family"] and r["family"] != "refine from a prior":
            k = seen.get((r["family"], r["mode"]), 0)
            seen[(r["family"], r["mode"])] = k + 1
            r["_variant"] = "raw" if k % (1 + rotations) == 0 else "turned"
    return rows


def rules_main(args: argparse.Namespace) -> int:
    drives = {Path(p).stem: load(Path(p)) for p in args.drives}
    valid = [(d, r) for d, rs in drives.items() for r in rs if r["valid"]]
    wrong = [r for _, r in valid if not r["right"]]
    right = [r for _, r in valid if r["right"]]
    groups: dict[tuple[str, str, str], list[dict[str, Any]]] = {}
    for r in (r for path in args.real for r in load_study(path)):
        g = real_group(r)
        if g is not None and r.get("valid"):
            groups.setdefault(g, []).append(r)
    print("drives:")
    for d, rs in drives.items():
        v = [r for r in rs if r["valid"]]
        w = [r for r in v if not r["right"]]
        hows = sorted({r["how"] for r in rs})
        print(
            f"  {d}: {len(rs)} pairs ("
            + ", ".join(f"{h} {sum(r['how'] == h for r in rs)}" for h in hows)
            + f"), {len(v)} valid, {len(w)} wrong valid ("
            + ", ".join(f"{h} {sum(r['how'] == h for r in w)}" for h in hows)
            + f"), {sum(1 for r in rs if r['right'] and not r['valid'])} right invalid"
        )
        unrefined = [r for r in v if math.isnan(value(r, "refine_rmse"))]
        if unrefined:
            sigma = [math.degrees(value(r, "rotation_uncertainty")) for r in unrefined if r["right"]]
            print(
                f"    unrefined valid: {len(unrefined)}, {sum(not r['right'] for r in unrefined)} wrong; the right "
                f"ones' rotation uncertainty at most {max(sigma, default=math.nan):.3f} deg"
            )
        for r in sorted(w, key=lambda r: (r["source"], r["target"])):
            print(
                f"    {r['source']:4d} -> {r['target']:4d} {r['how']:14s} {r['distance_m']:5.1f} m: "
                f"{r['error_deg']:7.2f} deg {r['error_m']:6.2f} m  "
                + " ".join(f"{f}={value(r, f):.4g}" for f in ("refine_rmse_voxels",) + FIELDS + ("overlap_spread",))
            )
    print("\nreal data: valid results per group, right / wrong")
    for g, rs in sorted(groups.items()):
        print(f"  {' / '.join(g):50s} {sum(r['right'] for r in rs):5d} / {sum(not r['right'] for r in rs):3d}")

    real_gicp_right = [
        r for g, rs in groups.items() if g[0] != "synthetic scenes" and g[2] == "GICP" for r in rs if r["right"]
    ]
    print(
        "\nvalid drive results, wrong [min, max] | right [p1, p5, median] | real data's right GICP results "
        "[min, p1, p99, max]"
    )
    for f in ("refine_rmse_voxels",) + FIELDS + ("overlap_spread",):
        wv = [value(r, f) for r in wrong]
        rr = [value(r, f) for r in right if not math.isnan(value(r, f))]
        rg = [value(r, f) for r in real_gicp_right if not math.isnan(value(r, f))]
        if not wv or not rr or any(math.isnan(x) for x in wv):
            continue
        q = np.percentile(rr, [1, 5, 50])
        q2 = np.percentile(rg, [0, 1, 99, 100]) if rg else [math.nan] * 4
        print(
            f"  {f:28s} wrong [{min(wv):.4g}, {max(wv):.4g}] | right p1 {q[0]:.4g} p5 {q[1]:.4g} med {q[2]:.4g}"
            f" | real [{q2[0]:.4g}, {q2[1]:.4g}, {q2[2]:.4g}, {q2[3]:.4g}]"
        )

    def cost(rule: Callable[[dict[str, Any]], bool]) -> tuple[int, dict[str, int], dict[tuple[str, str, str], int]]:
        caught = sum(not rule(r) for r in wrong)
        lost = {d: sum(1 for r in rs if r["valid"] and r["right"] and not rule(r)) for d, rs in drives.items()}
        real_lost = {g: sum(1 for r in rs if r["right"] and not rule(r)) for g, rs in groups.items()}
        return caught, lost, real_lost

    def show(label: str, rule: Callable[[dict[str, Any]], bool]) -> None:
        caught, lost, real_lost = cost(rule)
        real_total = sum(n for g, n in real_lost.items())
        print(
            f"\n  {label}: refuses {caught} of {len(wrong)} wrong valid; right valid lost: drives "
            + ", ".join(f"{d} {n}/{sum(1 for r in drives[d] if r['valid'] and r['right'])}" for d, n in lost.items())
            + f"; validity study {real_total}/{sum(sum(r['right'] for r in rs) for rs in groups.values())}"
        )
        for g, n in sorted(real_lost.items()):
            if n:
                print(f"    {' / '.join(g)}: {n} of {sum(r['right'] for r in groups[g])}")

    def real_cost(rule: Callable[[dict[str, Any]], bool]) -> int:
        return sum(cost(rule)[2].values())

    print("\nsingle thresholds that refuse every wrong valid drive result (drive loss, study loss):")
    singles = []
    for f in DIRECTIONS:
        t = tightest(wrong, f)
        if t is None:
            continue
        rule = threshold_rule(f, t)
        _, lost, _ = cost(rule)
        singles.append((sum(lost.values()) + real_cost(rule), f, t))
    for _, f, t in sorted(singles):
        show(f"{f} {DIRECTIONS[f]} {t:.5g}", threshold_rule(f, t))

    print("\ntwo thresholds, a result refused when either fails (every wrong one fails one), the least loss first:")
    best = []
    names = list(DIRECTIONS)
    for a in names:
        for b in names:
            if a == b:
                continue
            wa = sorted({value(r, a) for r in wrong if not math.isnan(value(r, a))})
            for va in wa:
                ta = float(np.nextafter(va, math.inf if DIRECTIONS[a] == ">=" else -math.inf))
                left = [r for r in wrong if passes(r, a, ta)]
                if not left:
                    continue
                tb = tightest(left, b)
                if tb is None:
                    continue
                rule = pair_rule(a, ta, b, tb)
                _, lost, _ = cost(rule)
                best.append((sum(lost.values()) + real_cost(rule), sum(lost.values()), a, ta, b, tb))
    best.sort()
    for _, _, a, ta, b, tb in best[: args.top]:
        show(f"{a} {DIRECTIONS[a]} {ta:.5g} and {b} {DIRECTIONS[b]} {tb:.5g}", pair_rule(a, ta, b, tb))
    for text in args.rule:
        show(f"given: {text}", parse_rule(text))
    return 0


def parse_rule(text: str) -> Callable[[dict[str, Any]], bool]:
    """ "a >= 1 and b <= 2" (a result keeps its validity when every part holds); "refuse if a > 0.3 and b < 0.9"
    (refused when every part holds)."""
    ops: dict[str, Callable[[float, float], bool]] = {
        ">=": lambda v, t: v >= t,
        "<=": lambda v, t: v <= t,
        ">": lambda v, t: v > t,
        "<": lambda v, t: v < t,
    }
    refuse = text.startswith("refuse if ")
    parts = [p.split() for p in text.removeprefix("refuse if ").split(" and ")]
    checks = [(f, ops[o], float(t)) for f, o, t in parts]

    def keeps(r: dict[str, Any]) -> bool:
        values = [value(r, f) for f, _, _ in checks]
        if any(math.isnan(v) for v in values):
            return True
        held = all(op(v, t) for v, (_, op, t) in zip(values, checks, strict=True))
        return not held if refuse else held

    return keeps


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    d = sub.add_parser("drive", help="register a drive's loop-search pairs and record every result")
    d.add_argument("drive", type=Path, help="kissm simulate's OUTDIR")
    d.add_argument("--scans", type=int, help="the first N scans only (all)")
    d.add_argument("--far", type=int, default=400, help="random pairs 30-80 m apart (400)")
    d.add_argument("--seed", type=int, default=7, help="the far pairs' draw (7)")
    d.add_argument("--extra", nargs="*", default=[], help="more pairs, as I,J")
    d.add_argument("--threads", type=int, default=1)
    d.add_argument("--refine", default="gicp", help="the Matcher's refine_mode (gicp)")
    d.add_argument("--out", type=Path, required=True, help="JSON lines, one per pair")
    s = sub.add_parser("sets", help="register every pair of the shared multi-scan sets and record every result")
    s.add_argument("--data", type=Path, default=default_data(), help=DATA_HELP)
    s.add_argument("--threads", type=int, default=1)
    s.add_argument("--refine", default="gicp", help="the Matcher's refine_mode (gicp)")
    s.add_argument("--turns", type=int, default=0, help="also each pair with its source turned and moved, N times (0)")
    s.add_argument("--seed", type=int, default=7, help="the turns' draw (7)")
    s.add_argument("--out", type=Path, required=True, help="JSON lines, one per pair")
    r = sub.add_parser("rules", help="compare wrong and right valid results; rules that refuse every wrong one")
    r.add_argument("drives", nargs="+", type=Path, help="the drive step's JSON lines")
    r.add_argument(
        "--real",
        type=Path,
        action="append",
        default=[],
        help="bench/validity_study.py --records output (--priors included), repeatable",
    )
    r.add_argument("--top", type=int, default=12, help="two-field rules shown (12)")
    r.add_argument(
        "--rule",
        action="append",
        default=[],
        help='a rule to cost: "overlap >= 0.85 and ambiguity <= 0.45" (kept when all hold) or "refuse if ..."',
    )
    args = parser.parse_args(argv)
    return {"drive": drive_main, "sets": sets_main, "rules": rules_main}[args.command](args)
