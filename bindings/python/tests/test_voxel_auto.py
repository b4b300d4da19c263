# SPDX-License-Identifier: MIT
"""voxel_size="auto": kissm.suggest_voxel_size (one cloud, a pair, a set), registration with the pair's suggestion
(the same bits as with that voxel given), features, and every real pair against its ground truth."""

from __future__ import annotations

import math

import numpy as np
import pytest

import kissm

from conftest import data_dir
from helpers import assert_same_result
from realdata import RealPair, pair_names, read_cached
from testdata import rotation_error_deg

NAMES = pair_names(data_dir()) or ["(no real data)"]


def test_suggestion_is_symmetric_and_a_rung(pair) -> None:
    v = kissm.suggest_voxel_size(pair.source, pair.target)
    assert v == kissm.suggest_voxel_size(pair.target, pair.source)
    assert v == min(kissm.suggest_voxel_size(pair.source), kissm.suggest_voxel_size(pair.target))
    assert v == kissm.suggest_voxel_size(pair.target, pair.source, pair.target)  # a set
    k = 8 * math.log2(v)
    assert abs(k - round(k)) < 1e-9  # 2^(k/8)


def test_suggestion_is_order_free_and_scales(pair) -> None:
    v = kissm.suggest_voxel_size(pair.source)
    rows = np.random.default_rng(3).permutation(len(pair.source))
    assert kissm.suggest_voxel_size(pair.source[rows]) == v
    assert kissm.suggest_voxel_size(pair.source * 8.0 + 1e4) == 8.0 * v
    with_nan = np.vstack([pair.source, [[np.nan, 0.0, 0.0]]])
    assert kissm.suggest_voxel_size(with_nan) == v  # non-finite points are ignored


def test_suggestion_bad_input() -> None:
    with pytest.raises(kissm.InvalidArgumentError, match="at least one cloud"):
        kissm.suggest_voxel_size()
    with pytest.raises(kissm.TooFewPointsError, match=r"clouds\[1\].*coincide"):
        kissm.suggest_voxel_size(np.random.default_rng(1).normal(size=(100, 3)), np.ones((50, 3)))
    with pytest.raises(kissm.EmptyInputError, match=r"clouds\[0\]"):
        kissm.suggest_voxel_size(np.full((10, 3), np.nan))
    with pytest.raises(ValueError):
        kissm.suggest_voxel_size(np.zeros((10, 2)))


def test_register_auto_is_register_at_the_suggestion(pair) -> None:
    v = kissm.suggest_voxel_size(pair.source, pair.target)
    auto = kissm.register(pair.source, pair.target, voxel_size="auto", num_threads=1)
    assert auto.voxel_size_used == v
    assert_same_result(auto, kissm.register(pair.source, pair.target, voxel_size=v, num_threads=2))
    assert_same_result(auto, kissm.register(pair.source, pair.target, voxel_size=0, num_threads=0))
    assert auto.valid and rotation_error_deg(auto.rotation, pair.rotation) < 2.0
    given = kissm.register(pair.source, pair.target, voxel_size=pair.voxel_size)
    assert given.voxel_size_used == pair.voxel_size


def test_features_under_auto(pair) -> None:
    """A matcher at 'auto' describes each cloud at its own suggestion; features of one voxel register at it, features
    of two voxels are refused by name."""
    v = kissm.suggest_voxel_size(pair.source, pair.target)
    with kissm.Matcher(voxel_size="auto") as auto, kissm.Matcher(voxel_size=v) as fixed:
        s, t = fixed.compute_features(pair.source), fixed.compute_features(pair.target)
        assert_same_result(auto.register_features(s, t), fixed.register(pair.source, pair.target))
        own_s, own_t = auto.compute_features(pair.source), auto.compute_features(pair.target)
        if kissm.suggest_voxel_size(pair.source) != kissm.suggest_voxel_size(pair.target):
            with pytest.raises(kissm.FeaturesMismatchError, match="voxel"):
                auto.register_features(own_s, own_t)


@pytest.mark.parametrize("name", NAMES)
def test_real_pair_with_auto_voxel(real_pairs: dict[str, RealPair], name: str) -> None:
    """Every real pair registers with 'auto' (docs/design/voxel_auto.md): right where the kind must succeed, and
    never valid and wrong."""
    pair = real_pairs[name]
    source, target = read_cached(pair.source, pair.source_format), read_cached(pair.target, pair.target_format)
    r = kissm.register(source, target, voxel_size="auto", num_threads=2)
    assert r.voxel_size_used == kissm.suggest_voxel_size(source, target)
    rre = rotation_error_deg(r.rotation, pair.gt[:3, :3]) if r.valid else math.nan
    rte = float(np.linalg.norm(r.translation - pair.gt[:3, 3])) if r.valid else math.nan
    right = r.valid and rre < pair.kind.max_rot_deg and rte < pair.kind.max_trans_m
    assert right or not r.valid, f"{name}: valid but wrong at voxel {r.voxel_size_used} ({rre:.2f} deg, {rte:.4f})"
    if pair.kind.must_succeed:
        assert right, f"{name}: {r!r}"


def test_batch_and_multiway_share_one_voxel(pair) -> None:
    """'auto' in a batch or an alignment is the suggestion of all its clouds together: one voxel for every pair."""
    clouds = {"target": pair.target, "source": pair.source}
    v = kissm.suggest_voxel_size(pair.target, pair.source)
    [done] = kissm.batch.register_many([("source", "target")], clouds, voxel_size="auto", threads_per_job=2)
    assert done.result is not None and done.result.voxel_size_used == v
    assert_same_result(done.result, kissm.register(pair.source, pair.target, voxel_size=v))
    described = kissm.batch.describe_many(clouds, voxel_size="auto")
    assert all(
        f.num_voxels == kissm.Matcher(voxel_size=v).compute_features(clouds[k]).num_voxels for k, f in described.items()
    )
    automatic = kissm.multiway.align(clouds, "auto", refine=None)
    assert np.array_equal(automatic.poses, kissm.multiway.align(clouds, v, refine=None).poses)
    with pytest.raises(kissm.InvalidArgumentError, match="auto"):
        kissm.batch.register_many([("source", "target")], described, voxel_size="auto")
