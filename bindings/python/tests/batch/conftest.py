# SPDX-License-Identifier: MIT
"""Fixtures of the kissm.batch tests: the batches and their serial results, computed once per module."""

from __future__ import annotations

from pathlib import Path

import pytest

import kissm

from batchcases import Batch, kitti_batch, serial, synthetic_batch


@pytest.fixture(scope="module")
def synthetic() -> Batch:
    return synthetic_batch()


@pytest.fixture(scope="module")
def synthetic_serial(synthetic: Batch) -> list[kissm.Result]:
    return serial(synthetic)


@pytest.fixture(scope="module")
def kitti(real_data: Path) -> Batch:
    return kitti_batch(real_data)


@pytest.fixture(scope="module")
def kitti_serial(kitti: Batch) -> list[kissm.Result]:
    return serial(kitti)
