# SPDX-License-Identifier: MIT
"""The fit behind ``kissm_result.confidence`` (src/core/confidence.cpp; docs/design/accuracy.md, "Confidence"): a
logistic model per kind of result, fitted on half of the validity study's runs (``bench/validity_study.py --priors
--records FILE``) and judged on the other half, split by run name, so that no variant of the fit is judged.

    python3 bench/validity_study.py --priors --records /tmp/records.jsonl
    python3 bench/confidence_fit.py /tmp/records.jsonl

Prints each model's coefficients (to be copied into src/core/confidence.cpp), the reliability table of the runs it
did not fit (per bin of predicted confidence: runs, mean prediction, observed success), how far the library's own
``Result.confidence`` is from the fitted model, and what thresholds give: per threshold, the runs above it and the
wrong poses among them.

A registration's confidence is the evidence model's probability times a factor for the ambiguity: 1 below 0.6,
the share of right poses among the ambiguous runs of its kind (0.8 and more) from 0.8 on, linear between (the kinds
differ: 4 of 46 unrefined, 30 of 110 refined): with a competitor as good, the pose is a pick among equals whatever
its inliers (logistic models with the ambiguity as an input, additive or with the inliers, let 45 inliers outweigh
a competitor at 0.8, where the repetitive scenes are mostly wrong). The
evidence models are fitted on the runs below 0.6. Their inputs, and the sign each weight must have (a model with a
wrong-signed weight is refused: the confidence must rise with the evidence for the pose):
  * registered without refinement: ln(1 + final inliers) (+);
  * registered with refinement: the same, the refined overlap (+) and refine_rmse in voxels (-) (without the residual,
    a GICP pose that slid off a part of a symmetric object, 0.52 voxel apart, read 1.0; the inliers' coverage came out
    with a negative weight: the repetitive scenes' wrong poses cover as much as right ones);
  * refined from a prior (kissm_refine): the overlap (+) and refine_rmse in voxels (-); no ambiguity factor.
"""

from __future__ import annotations

import argparse
import json
import math
import zlib
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

SOLVER_NOISE_BOUND_GAIN = 0.75  # the study runs the defaults: noise_bound = 0.75 voxel
#: The ambiguity from which a competitor counts (every valid right pose of the real data is below it) and from which
#: the pose is a pick among equals (every run of the repetitive scenes is above it).
AMBIGUITY_FROM, AMBIGUITY_FULL = 0.6, 0.8

Features = Callable[[dict[str, Any]], "list[float] | None"]


def coarse(r: dict[str, Any]) -> list[float] | None:
    if not math.isfinite(r["ambiguity"]):
        return None  # no pose: confidence 0 by definition
    return [1.0, math.log1p(r["num_final_inliers"])]


def rmse_voxels(r: dict[str, Any]) -> float:
    """refine_rmse in voxels, at most 10 (10 when it is not a number)."""
    voxel = r["noise_bound"] / SOLVER_NOISE_BOUND_GAIN
    return min(r["refine_rmse"] / voxel, 10.0) if math.isfinite(r["refine_rmse"]) else 10.0


def refined(r: dict[str, Any]) -> list[float] | None:
    base = coarse(r)
    if base is None or not math.isfinite(r["overlap"]):
        return None
    return [*base, r["overlap"], rmse_voxels(r)]


def prior(r: dict[str, Any]) -> list[float] | None:
    if not math.isfinite(r["overlap"]):
        return None
    return [1.0, r["overlap"], rmse_voxels(r)]


def competed(a: float) -> float:
    """0 below AMBIGUITY_FROM, 1 from AMBIGUITY_FULL, linear between."""
    return min(max((a - AMBIGUITY_FROM) / (AMBIGUITY_FULL - AMBIGUITY_FROM), 0.0), 1.0)


#: name, which runs, inputs, the signs of the weights after the intercept, whether the ambiguity factor applies, and
#: the L2 weight of the fit. Unrefined registrations between 1 and 10 final inliers are a few runs (a pose that few
#: inliers support is confirmed by GICP, and then counts as refined): unregularised, their fit is a step at 2.5
#: inliers that held-out runs with 5 and 8 wrong inliers cross at confidence 1, so it is damped. The others have
#: runs across their range and are left almost free.
MODELS: list[tuple[str, Callable[[dict[str, Any]], bool], Features, tuple[int, ...], bool, float]] = [
    (
        "registered",
        lambda r: r["family"] != "refine from a prior" and not math.isfinite(r["overlap"]),
        coarse,
        (1,),
        True,
        1.0,
    ),
    (
        "registered and refined",
        lambda r: r["family"] != "refine from a prior" and math.isfinite(r["overlap"]),
        refined,
        (1, 1, -1),
        True,
        1e-3,
    ),
    ("refined from a prior", lambda r: r["family"] == "refine from a prior", prior, (1, -1), False, 1e-3),
]


def held_out(r: dict[str, Any]) -> bool:
    """Half of the runs by name (a pair's variant, a prior's start): the fit never sees them."""
    return zlib.crc32(r["name"].encode()) % 2 == 1


def logistic_fit(x: np.ndarray, y: np.ndarray, l2: float) -> np.ndarray:
    """Newton's method on the log-likelihood with an L2 penalty on the weights (the intercept left free)."""
    w = np.zeros(x.shape[1])
    penalty = np.full(x.shape[1], l2)
    penalty[0] = 0.0
    for _ in range(200):
        p = 1.0 / (1.0 + np.exp(-x @ w))
        hessian = x.T @ (x * (p * (1 - p) + 1e-9)[:, None]) + np.diag(penalty) + 1e-9 * np.eye(len(w))
        step = np.linalg.solve(hessian, x.T @ (p - y) + penalty * w)
        w -= step
        if np.abs(step).max() < 1e-12:
            break
    return w


def reliability(p: np.ndarray, y: np.ndarray) -> list[str]:
    lines = ["    bin          runs  predicted  observed"]
    edges = np.linspace(0.0, 1.0, 11)
    for i in range(10):
        m = (p >= edges[i]) & ((p < edges[i + 1]) | (i == 9))
        if m.any():
            gap = abs(p[m].mean() - y[m].mean())
            verdict = "" if m.sum() < 20 else ("  within 0.1" if gap <= 0.1 else f"  OFF by {gap:.2f}")
            row = f"    [{edges[i]:.1f}, {edges[i + 1]:.1f})  {m.sum():5d}  {p[m].mean():9.3f}  {y[m].mean():8.3f}"
            lines.append(row + verdict)
    return lines


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("records", type=Path, help="bench/validity_study.py --records output (JSON lines)")
    args = parser.parse_args()
    rows = [json.loads(line) for line in args.records.read_text().splitlines() if line.strip()]
    for name, selects, features, signs, ambiguous, l2 in MODELS:
        data = [(features(r), r["right"], held_out(r), r.get("confidence", math.nan), r) for r in rows if selects(r)]
        data = [d for d in data if d[0] is not None]
        x = np.array([d[0] for d in data])
        y = np.array([float(d[1]) for d in data])
        test = np.array([d[2] for d in data])
        print(f"\n{name}: {len(data)} runs with a pose ({(~test).sum()} fitted, {test.sum()} held out)")
        # A pose with a competitor as good is a pick among equals: the share of right poses among this kind's fitted
        # runs whose ambiguity is AMBIGUITY_FULL or more.
        picks = [d[1] for d in data if not d[2] and d[4]["ambiguity"] >= AMBIGUITY_FULL] if ambiguous else []
        pick = sum(picks) / len(picks) if picks else 1.0
        if ambiguous:
            print(
                f"  a pick among equals (ambiguity >= {AMBIGUITY_FULL}): {sum(picks)} of {len(picks)} right: {pick:.6g}"
            )
        factor = np.array([1.0 - (1.0 - pick) * competed(d[4]["ambiguity"]) if ambiguous else 1.0 for d in data])
        # The evidence model is fitted where no competitor counts; the factor carries the rest.
        fit = ~test & (factor == 1.0)
        w = logistic_fit(x[fit], y[fit], l2)
        print("  weights (intercept first): " + ", ".join(f"{v:.6g}" for v in w))
        wrong_sign = [i for i, s in enumerate(signs) if np.sign(w[i + 1]) != s]
        if wrong_sign:
            print(f"  REFUSED: weights {wrong_sign} have the wrong sign")
        p = factor[test] / (1.0 + np.exp(-x[test] @ w))
        print("  held out:")
        print("\n".join(reliability(p, y[test])))
        library = np.array([d[3] for d in data])[test]
        if np.isfinite(library).all():
            print(f"  the library's confidence against this fit: max |difference| {np.abs(library - p).max():.2e}")
        print("  thresholds, held out: runs at or above it, wrong poses among them, right poses below it")
        judged = y[test]
        for t in (0.5, 0.9, 0.95, 0.99):
            above = p >= t
            print(
                f"    {t:4.2f}: {above.sum():4d} runs, {int((above & (judged == 0)).sum()):3d} wrong, "
                f"{int((~above & (judged == 1)).sum()):3d} right below"
            )
    return 0
