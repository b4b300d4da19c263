# SPDX-License-Identifier: MIT
"""kissm.Config: every C field as a keyword, library defaults, library validation, pickling, repr."""

from __future__ import annotations

import copy
import dataclasses
import pickle

import numpy as np
import pytest

import kissm
from kissm import _ffi
from kissm._errors import check

C_FIELDS = [name for name, _ in _ffi.ffi.typeof("kissm_config").fields]
PLUMBING = {"struct_size", "log_fn", "log_user_data", "progress_fn", "progress_user_data"}
#: Fields the library requires to be 0: no setting, zeroed by the binding.
RESERVED = {"reserved1", "reserved2"}


def c_defaults():
    c = _ffi.ffi.new("kissm_config *")
    assert _ffi.lib.kissm_config_init(c, _ffi.ffi.sizeof("kissm_config")) == 0
    return c


def test_every_c_field_is_a_keyword() -> None:
    python_fields = {f.name for f in dataclasses.fields(kissm.Config)}
    assert python_fields == set(C_FIELDS) - PLUMBING - RESERVED


def test_defaults_come_from_kissm_config_init() -> None:
    c = c_defaults()
    config = kissm.Config()
    for name in set(C_FIELDS) - PLUMBING - RESERVED:
        value = getattr(config, name)
        if name in kissm._config._VECTOR_FIELDS:  # double[3] in C, a tuple here
            assert value == tuple(getattr(c, name)), name
        elif name in kissm._config._ENUMS:  # a KISSM_* code in C, its name here
            assert kissm._config._ENUMS[name][value] == getattr(c, name), name
        elif name in kissm._config._BOOL_FIELDS:  # int32 0/1 in C, a bool here
            assert type(value) is bool and value == bool(getattr(c, name)), name
        else:
            assert value == getattr(c, name), name
    # and the struct handed to the library is byte for byte kissm_config_init's
    assert bytes(_ffi.ffi.buffer(config._to_c())) == bytes(_ffi.ffi.buffer(c))


def test_fields_round_trip_into_the_c_struct() -> None:
    config = kissm.Config(
        voxel_size=0.25,
        num_threads=3,
        normal_radius_gain=2.5,
        fpfh_radius_gain=6.0,
        max_linearity=0.95,
        ratio_test=1.0,
        prune_noise_bound_gain=1.5,
        solver_noise_bound_gain=0.5,
        noise_bound_max=0.4,
        viewpoint=(1, 2.5, -3),
        min_normal_neighbors=5,
        max_correspondences=3000,
        min_inliers=20,
        nonfinite_policy="drop",
        viewpoint_mode="cloud_center",
        log_level=0,
        refine_mode="point_to_plane",
        refine_max_iterations=12,
        refine_max_distance_gain=2.5,
        refine_kernel_gain=0.75,
        refine_rotation_epsilon=2e-4,
        refine_translation_epsilon_gain=5e-3,
        min_overlap=0.4,
        max_rotation_uncertainty=0.05,
        min_inlier_coverage=0.3,
        refine_min_inliers=25,
        min_refine_condition=0.05,
        refine_normal_radius_gain=1.5,
        max_refine_rmse_gain=0.6,
        allow_degenerate=True,
        max_ambiguity=0.9,
    )
    c = config._to_c()
    assert (c.voxel_size, c.num_threads, c.normal_radius_gain, c.fpfh_radius_gain) == (0.25, 3, 2.5, 6.0)
    assert (c.max_linearity, c.ratio_test, c.prune_noise_bound_gain) == (0.95, 1.0, 1.5)
    assert (c.solver_noise_bound_gain, c.noise_bound_max, tuple(c.viewpoint)) == (0.5, 0.4, (1.0, 2.5, -3.0))
    assert (c.min_normal_neighbors, c.max_correspondences, c.min_inliers, c.log_level) == (5, 3000, 20, 0)
    assert c.nonfinite_policy == _ffi.lib.KISSM_NONFINITE_DROP
    assert c.viewpoint_mode == _ffi.lib.KISSM_VIEWPOINT_CLOUD_CENTER
    assert (c.refine_mode, c.refine_max_iterations) == (_ffi.lib.KISSM_REFINE_POINT_TO_PLANE, 12)
    assert (c.refine_max_distance_gain, c.refine_kernel_gain, c.refine_rotation_epsilon) == (2.5, 0.75, 2e-4)
    assert (c.refine_translation_epsilon_gain, c.min_overlap) == (5e-3, 0.4)
    assert (c.max_rotation_uncertainty, c.min_inlier_coverage, c.refine_min_inliers) == (0.05, 0.3, 25)
    assert (c.min_refine_condition, c.refine_normal_radius_gain, c.max_refine_rmse_gain) == (0.05, 1.5, 0.6)
    assert c.allow_degenerate == 1
    assert c.max_ambiguity == 0.9
    assert c.reserved1 == c.reserved2 == 0
    assert c.log_fn == _ffi.ffi.NULL and c.progress_fn == _ffi.ffi.NULL
    # what the matcher got is what was asked for
    with kissm.Matcher(config) as matcher:
        out = _ffi.ffi.new("kissm_config *")
        out.struct_size = _ffi.ffi.sizeof("kissm_config")
        assert _ffi.lib.kissm_get_config(matcher._ptr, out) == 0
        assert bytes(_ffi.ffi.buffer(out)) == bytes(_ffi.ffi.buffer(c))


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("voxel_size", -0.5, "config.voxel_size is -0.5; it must be a finite length > 0, or 0 for a voxel suggested"),
        ("voxel_size", -1.0, "config.voxel_size is -1"),
        ("voxel_size", float("nan"), "config.voxel_size is nan"),
        ("voxel_size", float("inf"), "config.voxel_size is inf"),
        ("num_threads", -1, "config.num_threads is -1; it must be in [0, 1024]"),
        ("num_threads", 5000, "config.num_threads is 5000"),
        ("normal_radius_gain", 6.0, "config.normal_radius_gain is 6; it must be in (0, 5]"),
        ("fpfh_radius_gain", 1.0, "config.fpfh_radius_gain is 1; it must be in [1.5, 50]"),
        ("max_linearity", 0.0, "config.max_linearity is 0"),
        ("ratio_test", 1.5, "config.ratio_test is 1.5"),
        ("prune_noise_bound_gain", 0.0, "config.prune_noise_bound_gain is 0"),
        ("solver_noise_bound_gain", -2.0, "config.solver_noise_bound_gain is -2"),
        ("noise_bound_max", -1.0, "config.noise_bound_max is -1"),
        ("viewpoint", (0.0, float("nan"), 0.0), "config.viewpoint[1] is not finite"),
        ("min_normal_neighbors", 2, "config.min_normal_neighbors is 2; it must be in [3, 100000]"),
        ("max_correspondences", 2, "config.max_correspondences is 2"),
        ("min_inliers", 100001, "config.min_inliers is 100001"),
        ("nonfinite_policy", 7, "config.nonfinite_policy is 7; it must be in [0, 1]"),
        ("viewpoint_mode", -1, "config.viewpoint_mode is -1"),
        ("log_level", 5, "config.log_level is 5; it must be in [0, 4]"),
        ("refine_mode", 3, "config.refine_mode is 3; it must be in [0, 2]"),
        ("refine_mode", -1, "config.refine_mode is -1"),
        ("refine_max_iterations", 0, "config.refine_max_iterations is 0; it must be in [1, 1000]"),
        ("refine_max_iterations", 1001, "config.refine_max_iterations is 1001"),
        ("refine_max_distance_gain", 0.0, "config.refine_max_distance_gain is 0; it must be in (0, 100]"),
        ("refine_max_distance_gain", 101.0, "config.refine_max_distance_gain is 101"),
        ("refine_kernel_gain", -1.0, "config.refine_kernel_gain is -1; it must be in (0, 100]"),
        ("refine_kernel_gain", float("nan"), "config.refine_kernel_gain is nan"),
        ("refine_rotation_epsilon", 1.5, "config.refine_rotation_epsilon is 1.5; it must be in [0, 1]"),
        ("refine_rotation_epsilon", -1e-9, "config.refine_rotation_epsilon is -1e-09"),
        ("refine_translation_epsilon_gain", 2.0, "config.refine_translation_epsilon_gain is 2; it must be in [0, 1]"),
        ("min_overlap", 1.01, "config.min_overlap is 1.01; it must be in [0, 1]"),
        ("min_overlap", float("inf"), "config.min_overlap is inf"),
        ("max_rotation_uncertainty", 0.0, "config.max_rotation_uncertainty is 0; it must be in (0, 3.15]"),
        ("max_rotation_uncertainty", 3.2, "config.max_rotation_uncertainty is 3.2"),
        ("max_rotation_uncertainty", float("nan"), "config.max_rotation_uncertainty is nan"),
        ("min_inlier_coverage", -0.1, "config.min_inlier_coverage is -0.1; it must be in [0, 1]"),
        ("min_inlier_coverage", 1.5, "config.min_inlier_coverage is 1.5"),
        ("refine_min_inliers", 2, "config.refine_min_inliers is 2; it must be in [3, 100000]"),
        ("refine_min_inliers", 100001, "config.refine_min_inliers is 100001"),
        ("min_refine_condition", -0.1, "config.min_refine_condition is -0.1; it must be in [0, 1]"),
        ("min_refine_condition", float("nan"), "config.min_refine_condition is nan"),
        ("refine_normal_radius_gain", 0.0, "config.refine_normal_radius_gain is 0; it must be in (0, 50]"),
        ("refine_normal_radius_gain", 50.5, "config.refine_normal_radius_gain is 50.5"),
        ("refine_normal_radius_gain", float("inf"), "config.refine_normal_radius_gain is inf"),
        ("max_refine_rmse_gain", 0.0, "config.max_refine_rmse_gain is 0; it must be in (0, 100]"),
        ("max_refine_rmse_gain", 100.5, "config.max_refine_rmse_gain is 100.5"),
        ("max_refine_rmse_gain", float("nan"), "config.max_refine_rmse_gain is nan"),
        # a bool here; an int other than 0 or 1 reaches the library, which names the field
        ("allow_degenerate", 2, "config.allow_degenerate is 2; it must be in [0, 1]"),
        ("allow_degenerate", -1, "config.allow_degenerate is -1; it must be in [0, 1]"),
        ("max_ambiguity", -0.01, "config.max_ambiguity is -0.01; it must be in [0, 1]"),
        ("max_ambiguity", 1.5, "config.max_ambiguity is 1.5; it must be in [0, 1]"),
        ("max_ambiguity", float("nan"), "config.max_ambiguity is nan"),
    ],
)
def test_invalid_values_raise_valueerror_with_the_library_message(field: str, value: object, message: str) -> None:
    with pytest.raises(ValueError) as info:
        kissm.Config(**{field: value})
    assert isinstance(info.value, kissm.InvalidArgumentError)
    assert message in str(info.value)
    assert str(info.value).startswith("kissm_config_validate: ")  # the library's message, verbatim
    with pytest.raises(kissm.InvalidArgumentError, match=f"config.{field}"):
        kissm.Matcher(**{field: value})


def test_voxel_size_auto() -> None:
    """'auto' (and 0, the C spelling, which becomes it) reaches the C config as 0; other strings are TypeErrors."""
    for given in ("auto", 0, 0.0):
        c = kissm.Config(voxel_size=given)
        assert c.voxel_size == "auto" and c._to_c().voxel_size == 0.0
        assert c == kissm.Config(voxel_size="auto") and eval(repr(c), {"kissm": kissm}) == c
    assert kissm.Matcher(voxel_size="auto").config.voxel_size == "auto"
    with pytest.raises(TypeError, match="'auto'"):
        kissm.Config(voxel_size="Auto")


def test_max_correspondences_automatic(pair) -> None:
    """0, the default, is the automatic cap: 5000 for clouds this small, so the same result, bit for bit."""
    assert kissm.Config().max_correspondences == 0
    assert kissm.Config(max_correspondences=0)._to_c().max_correspondences == 0
    automatic = kissm.Matcher(voxel_size=pair.voxel_size, num_threads=2).register(pair.source, pair.target)
    fixed = kissm.Matcher(voxel_size=pair.voxel_size, num_threads=2, max_correspondences=5000).register(
        pair.source, pair.target
    )
    assert automatic.valid and automatic.num_initial_correspondences <= 5000
    assert automatic.transform.tobytes() == fixed.transform.tobytes()
    assert automatic.num_initial_correspondences == fixed.num_initial_correspondences
    few = kissm.Matcher(voxel_size=pair.voxel_size, num_threads=2, max_correspondences=50).register(
        pair.source, pair.target
    )
    assert few.num_initial_correspondences == 50


def test_out_of_int32_range_is_a_valueerror() -> None:
    with pytest.raises(ValueError, match="num_threads"):
        kissm.Config(num_threads=2**40)


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("voxel_size", "0.3"),
        ("voxel_size", None),
        ("num_threads", 2.0),
        ("num_threads", True),
        ("min_inliers", "15"),
        ("viewpoint", 3.0),
        ("viewpoint", ("a", 0, 0)),
        ("nonfinite_policy", 0.5),
        ("refine_mode", 1.0),
        ("refine_mode", True),
        ("refine_max_iterations", 10.0),
        ("refine_kernel_gain", "1"),
        ("min_overlap", None),
        ("max_rotation_uncertainty", "0.1"),
        ("min_inlier_coverage", True),
        ("refine_min_inliers", 10.0),
        ("min_refine_condition", None),
        ("refine_normal_radius_gain", "2"),
        ("max_refine_rmse_gain", "0.5"),
        ("allow_degenerate", "yes"),
        ("allow_degenerate", 1.0),
        ("allow_degenerate", None),
    ],
)
def test_wrong_types_raise_typeerror(field: str, value: object) -> None:
    with pytest.raises(TypeError, match=field):
        kissm.Config(**{field: value})


def test_reserved_fields_are_zeroed_and_not_settings() -> None:
    """The library refuses a non-zero reserved field; the binding always hands it 0 and takes no keyword for it."""
    for name in RESERVED:
        with pytest.raises(TypeError, match=name):
            kissm.Config(**{name: 0})
        with pytest.raises(TypeError, match=name):
            kissm.Matcher(voxel_size=0.3, **{name: 0})
        c = kissm.Config(voxel_size=0.3)._to_c()
        assert getattr(c, name) == 0
        setattr(c, name, 1)  # what a binding that left it to chance could send
        with pytest.raises(kissm.InvalidArgumentError, match=f"config.{name} is 1; it must be in \\[0, 0\\]"):
            check(_ffi.lib.kissm_config_validate(c))
        assert name not in kissm.Config().to_dict() and name not in repr(kissm.Config(voxel_size=0.3))


def test_allow_degenerate_is_a_bool() -> None:
    """Default False (kissm_config_init's 0); True, numpy bools and the C values 0 and 1 are accepted and kept
    as a bool, handed to the library as 0 or 1."""
    assert kissm.Config().allow_degenerate is False and c_defaults().allow_degenerate == 0
    for value, expected in [(True, True), (False, False), (1, True), (0, False), (np.bool_(True), True)]:
        config = kissm.Config(allow_degenerate=value)
        assert config.allow_degenerate is expected, value
        assert config._to_c().allow_degenerate == int(expected)
    assert kissm.Config(allow_degenerate=np.int32(1)) == kissm.Config(allow_degenerate=True)
    allowed = kissm.Config(allow_degenerate=True)
    assert repr(allowed) == "kissm.Config(allow_degenerate=True)" and eval(repr(allowed), {"kissm": kissm}) == allowed
    assert kissm.Config().replace(allow_degenerate=True) == allowed and allowed.to_dict()["allow_degenerate"] is True
    with kissm.Matcher(allow_degenerate=True) as matcher:
        assert matcher.config.allow_degenerate is True
        out = _ffi.ffi.new("kissm_config *")
        out.struct_size = _ffi.ffi.sizeof("kissm_config")
        assert _ffi.lib.kissm_get_config(matcher._ptr, out) == 0 and out.allow_degenerate == 1
    for name in kissm.PRESETS:
        assert kissm.Config.preset(name).allow_degenerate is False
        assert kissm.Config.preset(name, allow_degenerate=True).allow_degenerate is True


def test_viewpoint_needs_three_coordinates() -> None:
    with pytest.raises(ValueError, match="3 coordinates"):
        kissm.Config(viewpoint=(1.0, 2.0))


def test_numpy_scalars_and_sequences_are_accepted() -> None:
    config = kissm.Config(voxel_size=np.float32(0.5), num_threads=np.int64(2), viewpoint=np.array([1, 2, 3]))
    assert config.voxel_size == 0.5 and type(config.voxel_size) is float
    assert config.num_threads == 2 and type(config.num_threads) is int
    assert config.viewpoint == (1.0, 2.0, 3.0)


def test_enumerations_take_names_or_the_c_constants() -> None:
    assert kissm.Config(nonfinite_policy="drop") == kissm.Config(nonfinite_policy=_ffi.lib.KISSM_NONFINITE_DROP)
    assert kissm.Config(viewpoint_mode=1).viewpoint_mode == "cloud_center"
    assert kissm.Config(viewpoint_mode=_ffi.lib.KISSM_VIEWPOINT_SIGN_FREE).viewpoint_mode == "sign_free"
    assert kissm.Config(viewpoint_mode=3) == kissm.Config(viewpoint_mode="local")
    assert kissm.Config().nonfinite_policy == "reject" and kissm.Config().viewpoint_mode == "local"
    with pytest.raises(ValueError, match="'reject', 'drop'"):
        kissm.Config(nonfinite_policy="ignore")


def test_refine_mode_names() -> None:
    assert kissm._config.REFINE_MODES == {
        "none": _ffi.lib.KISSM_REFINE_NONE,
        "gicp": _ffi.lib.KISSM_REFINE_GICP,
        "point_to_plane": _ffi.lib.KISSM_REFINE_POINT_TO_PLANE,
    }
    assert kissm.Config().refine_mode == "none"
    for name, code in kissm._config.REFINE_MODES.items():
        assert kissm.Config(refine_mode=code).refine_mode == name
        assert kissm.Config(refine_mode=name)._to_c().refine_mode == code
    assert kissm.Config(refine_mode=np.int32(1)) == kissm.Config(refine_mode="gicp")
    with pytest.raises(
        ValueError, match="Config.refine_mode is 'point-to-plane'; use one of 'none', 'gicp', 'point_to_plane'"
    ):
        kissm.Config(refine_mode="point-to-plane")  # the CLI's spelling is not a Python name


def test_unknown_keywords_are_typeerrors() -> None:
    with pytest.raises(TypeError, match="voxel"):
        kissm.Config(voxel=0.3)
    with pytest.raises(TypeError, match="voxel"):
        kissm.Matcher(voxel=0.3)
    with pytest.raises(TypeError):
        kissm.Config(0.3)  # keyword-only


def test_configs_are_immutable_values() -> None:
    config = kissm.Config(voxel_size=0.5)
    with pytest.raises(dataclasses.FrozenInstanceError):
        config.voxel_size = 1.0  # type: ignore[misc]
    assert config == kissm.Config(voxel_size=0.5) and config != kissm.Config()
    assert hash(config) == hash(kissm.Config(voxel_size=0.5))
    assert config.replace(num_threads=2) == kissm.Config(voxel_size=0.5, num_threads=2)
    with pytest.raises(ValueError):
        config.replace(voxel_size=-1.0)
    assert kissm.Config(**config.to_dict()) == config


def test_pickle_and_copy() -> None:
    config = kissm.Config(
        voxel_size=0.45,
        num_threads=2,
        viewpoint=(0, 0, 1.7),
        nonfinite_policy="drop",
        refine_mode="gicp",
        refine_max_iterations=7,
        refine_kernel_gain=0.5,
        min_overlap=0.3,
        max_rotation_uncertainty=0.02,
        min_inlier_coverage=0.1,
        refine_min_inliers=12,
        min_refine_condition=0.02,
        refine_normal_radius_gain=2.5,
        max_refine_rmse_gain=0.5,
        allow_degenerate=True,
    )
    for protocol in range(2, pickle.HIGHEST_PROTOCOL + 1):
        assert pickle.loads(pickle.dumps(config, protocol)) == config
    assert copy.deepcopy(config) == config and copy.copy(config) == config


def test_repr_is_readable_and_evaluable() -> None:
    assert repr(kissm.Config()) == "kissm.Config()"
    config = kissm.Config(voxel_size=0.5, num_threads=2, viewpoint_mode="cloud_center")
    assert repr(config) == "kissm.Config(voxel_size=0.5, num_threads=2, viewpoint_mode='cloud_center')"
    assert eval(repr(config), {"kissm": kissm}) == config
    refined = kissm.Config(refine_mode="point_to_plane", refine_max_iterations=5, min_overlap=0.25)
    assert repr(refined) == "kissm.Config(refine_mode='point_to_plane', refine_max_iterations=5, min_overlap=0.25)"
    assert eval(repr(refined), {"kissm": kissm}) == refined
    validity = kissm.Config(max_rotation_uncertainty=0.05, min_inlier_coverage=0.5, refine_min_inliers=20)
    assert repr(validity) == (
        "kissm.Config(max_rotation_uncertainty=0.05, min_inlier_coverage=0.5, refine_min_inliers=20)"
    )
    assert eval(repr(validity), {"kissm": kissm}) == validity


def test_matcher_overrides_and_config() -> None:
    base = kissm.Config(voxel_size=0.5, min_inliers=10)
    with kissm.Matcher(base, num_threads=2) as matcher:
        assert matcher.config == base.replace(num_threads=2)
    with kissm.Matcher(voxel_size=0.4) as matcher:
        assert matcher.config == kissm.Config(voxel_size=0.4)
        assert "voxel_size=0.4" in repr(matcher)
    with pytest.raises(TypeError, match="kissm.Config"):
        kissm.Matcher({"voxel_size": 0.4})  # type: ignore[arg-type]


def test_a_mistyped_field_names_the_nearest() -> None:
    """Issue 36: errors that say what to type instead."""
    with pytest.raises(TypeError, match=r"unknown kissm.Config field 'voxel_sise' \(did you mean 'voxel_size'\?\)"):
        kissm.Matcher(voxel_sise=0.3)
    with pytest.raises(TypeError, match=r"'refine_mod' \(did you mean 'refine_mode'\?\)"):
        kissm.Config().replace(refine_mod="gicp")
    with pytest.raises(TypeError, match=r"unknown kissm.Config field 'frobnicate'$"):
        kissm.Config().replace(frobnicate=1)
