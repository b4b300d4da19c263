# SPDX-License-Identifier: MIT
"""Bitwise equality with the C library as the kissm CLI runs it, on inputs that need no real data."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import kissm
from kissm import _ffi

import testdata
from cli_json import assert_matches_cli, run_cli, write_transform


def test_demo_clouds_bitwise_equal_cli(cli: Path, demo_clouds: tuple[Path, Path]) -> None:
    """The CLI's demo scans (float64 PLY), read by kissm.read_points and registered from Python."""
    source_path, target_path = demo_clouds
    expected = run_cli(cli, source_path, target_path, 0.3)
    assert expected["valid"]
    source, target = kissm.read_points(source_path), kissm.read_points(target_path)
    for threads in (1, 2):
        with kissm.Matcher(voxel_size=0.3, num_threads=threads) as matcher:
            assert_matches_cli(matcher.register(source, target), expected)
            assert_matches_cli(
                matcher.register_features(matcher.compute_features(source), matcher.compute_features(target)), expected
            )


def test_python_arrays_bitwise_equal_cli_on_the_same_values(cli: Path, pair, tmp_path: Path) -> None:
    """Arrays made in Python, registered in place, against the CLI reading them from .npy (exact float64)."""
    np.save(tmp_path / "source.npy", pair.source)
    np.save(tmp_path / "target.npy", pair.target)
    expected = run_cli(cli, tmp_path / "source.npy", tmp_path / "target.npy", pair.voxel_size)
    assert expected["valid"]
    assert_matches_cli(kissm.register(pair.source, pair.target, voxel_size=pair.voxel_size), expected)
    strided = np.zeros((len(pair.source), 4))
    strided[:, :3] = pair.source
    assert_matches_cli(
        kissm.register(strided[:, :3], np.asfortranarray(pair.target), voxel_size=pair.voxel_size), expected
    )


def test_float32_arrays_bitwise_equal_cli(cli: Path, pair, tmp_path: Path) -> None:
    """float32 arrays passed in place against the CLI reading raw float32 triples (bin_xyz)."""
    source, target = pair.source.astype("<f4"), pair.target.astype("<f4")
    source.tofile(tmp_path / "source.bin")
    target.tofile(tmp_path / "target.bin")
    expected = run_cli(cli, tmp_path / "source.bin", tmp_path / "target.bin", pair.voxel_size, ["--format", "bin_xyz"])
    assert_matches_cli(kissm.register(source, target, voxel_size=pair.voxel_size), expected)


def test_xyz_text_with_python_repr_is_exact(cli: Path, pair, tmp_path: Path) -> None:
    """Shortest round-trip text written by Python reads back to the same doubles in C."""
    for name, xyz in (("source.xyz", pair.source), ("target.xyz", pair.target)):
        (tmp_path / name).write_text("".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in xyz.tolist()))
    expected = run_cli(cli, tmp_path / "source.xyz", tmp_path / "target.xyz", pair.voxel_size)
    assert_matches_cli(kissm.register(pair.source, pair.target, voxel_size=pair.voxel_size), expected)


def test_invalid_result_matches_cli(cli: Path, tmp_path: Path) -> None:
    """A degenerate input (a plane): valid = 0, the same reason and NaN/null fields in both."""
    plane = np.c_[np.random.default_rng(3).random((3000, 2)) * 8.0, np.zeros(3000)]
    np.save(tmp_path / "plane.npy", plane)
    expected = run_cli(cli, tmp_path / "plane.npy", tmp_path / "plane.npy", 0.3)
    assert not expected["valid"]
    assert_matches_cli(kissm.register(plane, plane, voxel_size=0.3), expected)


def test_cli_config_flags_match_config_fields(cli: Path, pair, tmp_path: Path) -> None:
    np.save(tmp_path / "s.npy", pair.source)
    np.save(tmp_path / "t.npy", pair.target)
    expected = run_cli(
        cli,
        tmp_path / "s.npy",
        tmp_path / "t.npy",
        0.35,
        ["--min-inliers", "12", "--max-correspondences", "800", "--viewpoint-center"],
    )
    result = kissm.register(
        pair.source,
        pair.target,
        voxel_size=0.35,
        min_inliers=12,
        max_correspondences=800,
        viewpoint_mode="cloud_center",
    )
    assert_matches_cli(result, expected)


@pytest.mark.parametrize("mode", ["fixed", "cloud_center", "sign_free", "local"])
def test_cli_viewpoint_option_matches_config(cli: Path, pair_files, pair, mode: str) -> None:
    expected = run_cli(cli, *pair_files, pair.voxel_size, ["--viewpoint", mode.replace("_", "-")])
    assert expected["valid"]
    assert_matches_cli(kissm.register(pair.source, pair.target, pair.voxel_size, viewpoint_mode=mode), expected)


@pytest.mark.parametrize("threads", [0, 3])
def test_cli_threads_do_not_matter(cli: Path, demo_clouds: tuple[Path, Path], threads: int) -> None:
    source_path, target_path = demo_clouds
    expected = run_cli(cli, source_path, target_path, 0.3, threads=threads)
    assert_matches_cli(
        kissm.register(kissm.read_points(source_path), kissm.read_points(target_path), voxel_size=0.3, num_threads=1),
        expected,
    )


# ---- refinement: `register --refine` and `kissm refine` ------------------------------------------------------


@pytest.fixture()
def pair_files(pair, tmp_path: Path) -> tuple[Path, Path]:
    np.save(tmp_path / "source.npy", pair.source)
    np.save(tmp_path / "target.npy", pair.target)
    return tmp_path / "source.npy", tmp_path / "target.npy"


@pytest.mark.parametrize("mode", ["none", "gicp", "point_to_plane"])
def test_refined_registration_bitwise_equals_cli(cli: Path, pair, pair_files, mode: str) -> None:
    cli_mode = mode.replace("_", "-")
    expected = run_cli(cli, *pair_files, pair.voxel_size, ["--refine", cli_mode])
    assert expected["valid"] and (expected["information"] is None) == (mode == "none")
    assert_matches_cli(kissm.register(pair.source, pair.target, pair.voxel_size, refine=mode), expected, mode)


@pytest.mark.parametrize("mode", [None, "gicp", "point_to_plane"])
def test_refine_command_bitwise_equals_cli(cli: Path, pair, pair_files, tmp_path: Path, mode: str | None) -> None:
    """`kissm refine SRC TGT --initial T.txt` (GICP by default) against kissm.refine from the same prior."""
    initial = testdata.pose(testdata.rotation_zyx(3.0), [0.2, -0.15, 0.05]) @ pair.transform
    write_transform(tmp_path / "initial.txt", initial)
    extra = ["--initial", str(tmp_path / "initial.txt")] + (["--refine", mode.replace("_", "-")] if mode else [])
    expected = run_cli(cli, *pair_files, pair.voxel_size, extra, command_name="refine")
    assert expected["valid"]
    keys = list(expected)
    assert keys.index("initial_transform") == keys.index("transform") - 1
    assert np.array(expected["initial_transform"], dtype=float).tobytes() == initial.tobytes()
    result = kissm.refine(pair.source, pair.target, initial, pair.voxel_size, refine=mode)
    assert_matches_cli(result, expected, mode or "gicp")
    assert testdata.rotation_error_deg(result.rotation, pair.rotation) < 0.05


#: Each validity setting, whether its rule is the refined one, and the reason it gives one step past the value
#: the committed pair measures.
VALIDITY_SETTINGS = {
    "max_rotation_uncertainty": (False, "KISSM_REASON_UNCERTAIN_ROTATION"),
    "min_inlier_coverage": (True, "KISSM_REASON_CLUSTERED_INLIERS"),
    "refine_min_inliers": (True, "KISSM_REASON_TOO_FEW_INLIERS"),
    "min_refine_condition": (True, "KISSM_REASON_UNCONSTRAINED"),
}


@pytest.mark.parametrize("setting", list(VALIDITY_SETTINGS))
def test_cli_validity_flags_match_config_fields(cli: Path, pair, pair_files, setting: str) -> None:
    """`--max-rotation-uncertainty`, `--min-inlier-coverage`, `--refine-min-inliers`, `--min-refine-condition` are
    the Config fields: set one step past what the pair measures, both refuse the pose for the same reason, with the
    same numbers."""
    refined, reason = VALIDITY_SETTINGS[setting]
    mode = "gicp" if refined else "none"
    measured = kissm.register(pair.source, pair.target, pair.voxel_size, refine=mode)
    assert measured.valid
    value: float | int = {
        "max_rotation_uncertainty": float(np.nextafter(measured.rotation_uncertainty, 0.0)),
        "min_inlier_coverage": float(np.nextafter(measured.inlier_coverage, 1.0)),
        "refine_min_inliers": measured.num_final_inliers + 1,
        "min_refine_condition": float(np.nextafter(measured.refine_condition, 1.0)),
    }[setting]
    flags = ["--refine", mode, "--" + setting.replace("_", "-"), repr(value)]
    extra: dict[str, float] = {}
    if setting == "max_rotation_uncertainty":
        # A pose declined for its rotation's uncertainty is verified by refinement; held to a coverage no inlier
        # set reaches, the verification fails and the coarse decision stands.
        flags += ["--min-inlier-coverage", "1"]
        extra["min_inlier_coverage"] = 1.0
    expected = run_cli(cli, *pair_files, pair.voxel_size, flags)
    result = kissm.register(pair.source, pair.target, pair.voxel_size, refine=mode, **{setting: value}, **extra)
    assert not result.valid and result.reason_code == getattr(_ffi.lib, reason)
    assert_matches_cli(result, expected, mode)


def test_cli_refine_normal_radius_is_the_config_field(cli: Path, pair, pair_files, tmp_path: Path) -> None:
    """`--refine-normal-radius GAIN` is Config.refine_normal_radius_gain, for `register --refine` and `kissm refine`
    alike: the same refined pose, bit for bit, and not the default's."""
    gain = 0.75 * kissm.Config().refine_normal_radius_gain
    flags = ["--refine", "gicp", "--refine-normal-radius", repr(gain)]
    expected = run_cli(cli, *pair_files, pair.voxel_size, flags)
    result = kissm.register(pair.source, pair.target, pair.voxel_size, refine="gicp", refine_normal_radius_gain=gain)
    assert result.valid
    assert_matches_cli(result, expected, "gicp")
    default = kissm.register(pair.source, pair.target, pair.voxel_size, refine="gicp")
    assert not np.array_equal(result.transform, default.transform)
    initial = testdata.pose(testdata.rotation_zyx(3.0), [0.2, -0.15, 0.05]) @ pair.transform
    write_transform(tmp_path / "initial.txt", initial)
    extra = ["--initial", str(tmp_path / "initial.txt"), "--refine-normal-radius", repr(gain)]
    expected = run_cli(cli, *pair_files, pair.voxel_size, extra, command_name="refine")
    refined = kissm.refine(pair.source, pair.target, initial, pair.voxel_size, refine_normal_radius_gain=gain)
    assert_matches_cli(refined, expected, "gicp")
