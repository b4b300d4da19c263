# SPDX-License-Identifier: MIT
"""``kissm.Config``: every setting of ``kissm_config``, validated by the library at construction."""

from __future__ import annotations

import dataclasses
import difflib
import numbers
from collections.abc import Mapping
from typing import Any, Literal

import numpy as np

from ._errors import check
from ._ffi import ffi, lib

NonFinitePolicy = Literal["reject", "drop"]
ViewpointMode = Literal["fixed", "cloud_center", "sign_free", "local"]
RefineMode = Literal["none", "gicp", "point_to_plane"]
Suppression = Literal["none", "ground"]

#: Python names of the C enumerations (the fields hold the names; the ints are accepted too).
NONFINITE_POLICIES: dict[str, int] = {"reject": lib.KISSM_NONFINITE_REJECT, "drop": lib.KISSM_NONFINITE_DROP}
VIEWPOINT_MODES: dict[str, int] = {
    "fixed": lib.KISSM_VIEWPOINT_FIXED,
    "cloud_center": lib.KISSM_VIEWPOINT_CLOUD_CENTER,
    "sign_free": lib.KISSM_VIEWPOINT_SIGN_FREE,
    "local": lib.KISSM_VIEWPOINT_LOCAL,
}
REFINE_MODES: dict[str, int] = {
    "none": lib.KISSM_REFINE_NONE,
    "gicp": lib.KISSM_REFINE_GICP,
    "point_to_plane": lib.KISSM_REFINE_POINT_TO_PLANE,
}
SUPPRESSIONS: dict[str, int] = {"none": lib.KISSM_SUPPRESS_NONE, "ground": lib.KISSM_SUPPRESS_GROUND}
#: Names of the ``KISSM_PRESET_*`` settings (:meth:`Config.preset`).
PRESETS: dict[str, int] = {
    "lidar-vehicle": lib.KISSM_PRESET_LIDAR_VEHICLE,
    "lidar-handheld": lib.KISSM_PRESET_LIDAR_HANDHELD,
    "indoor-rgbd": lib.KISSM_PRESET_INDOOR_RGBD,
    "object": lib.KISSM_PRESET_OBJECT,
}
_ENUMS: dict[str, dict[str, int]] = {
    "nonfinite_policy": NONFINITE_POLICIES,
    "viewpoint_mode": VIEWPOINT_MODES,
    "refine_mode": REFINE_MODES,
    "suppression": SUPPRESSIONS,
}
_VECTOR_FIELDS = ("viewpoint", "up")
VoxelSize = float | Literal["auto"]
#: The C value of voxel_size "auto": the library suggests the voxel from each call's clouds.
_AUTO_VOXEL = 0.0

_FLOAT_FIELDS = (
    "voxel_size",
    "normal_radius_gain",
    "fpfh_radius_gain",
    "max_linearity",
    "ratio_test",
    "prune_noise_bound_gain",
    "solver_noise_bound_gain",
    "noise_bound_max",
    "refine_max_distance_gain",
    "refine_kernel_gain",
    "refine_rotation_epsilon",
    "refine_translation_epsilon_gain",
    "max_rotation_uncertainty",
    "min_overlap",
    "min_inlier_coverage",
    "min_refine_condition",
    "refine_normal_radius_gain",
    "sensor_height",
    "max_refine_rmse_gain",
    "max_ambiguity",
)
_INT_FIELDS = (
    "num_threads",
    "min_normal_neighbors",
    "max_correspondences",
    "min_inliers",
    "log_level",
    "refine_max_iterations",
    "refine_min_inliers",
    "rotation_dof",
)
#: int32 0/1 in C, bool here.
_BOOL_FIELDS = ("allow_degenerate",)


def _new_c_config() -> Any:
    c = ffi.new("kissm_config *")
    check(lib.kissm_config_init(c, ffi.sizeof("kissm_config")))
    return c


def _enum_name(field: str, value: int) -> str | int:
    for name, number in _ENUMS[field].items():
        if number == value:
            return name
    return value


def _values_of(c: Any) -> dict[str, Any]:
    """The settings of a C ``kissm_config *`` as Config fields."""
    values: dict[str, Any] = {name: float(getattr(c, name)) for name in _FLOAT_FIELDS}
    if values["voxel_size"] == _AUTO_VOXEL:
        values["voxel_size"] = "auto"
    values.update({name: int(getattr(c, name)) for name in _INT_FIELDS})
    values.update({name: bool(getattr(c, name)) for name in _BOOL_FIELDS})
    for name in _VECTOR_FIELDS:
        values[name] = tuple(float(v) for v in getattr(c, name))
    for field in _ENUMS:
        values[field] = _enum_name(field, int(getattr(c, field)))
    return values


_DEFAULTS = _values_of(_new_c_config())


def _as_int(field: str, value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"Config.{field} must be an int, not {type(value).__name__}")
    return int(value)


def _as_float(field: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"Config.{field} must be a real number, not {type(value).__name__}")
    return float(value)


def _as_bool(field: str, value: Any) -> bool | int:
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if not isinstance(value, numbers.Integral):
        raise TypeError(f"Config.{field} must be a bool, not {type(value).__name__}")
    # 0 and 1 are the C values; any other int is kept: the library rejects it with its own message.
    return bool(value) if value in (0, 1) else int(value)


def _as_enum(field: str, value: Any) -> str | int:
    choices = _ENUMS[field]
    if isinstance(value, str):
        if value not in choices:
            raise ValueError(f"Config.{field} is {value!r}; use one of {', '.join(map(repr, choices))}")
        return value
    # An int that names no choice is kept: the library rejects it with its own message.
    return _enum_name(field, _as_int(field, value))


@dataclasses.dataclass(frozen=True, kw_only=True, repr=False)
class Config:
    """Settings of a :class:`Matcher`: the fields of the C ``kissm_config``, with the library's defaults.

    Lengths are in the clouds' unit (metres for LiDAR); every radius and noise bound is a gain times
    ``voxel_size``. Invalid values raise :class:`ValueError` (a :class:`kissm.InvalidArgumentError`) with
    the library's message when the Config is made. Configs are immutable, hashable and picklable; derive
    one from another with :meth:`replace`.
    """

    voxel_size: VoxelSize = _DEFAULTS["voxel_size"]
    """Voxel edge length, > 0, or ``"auto"``: the voxel :func:`kissm.suggest_voxel_size` gives for each call's clouds
    together (features computed apart: each cloud's own; ``Result.voxel_size_used`` reports the voxel a call used; 0
    is the C spelling of ``"auto"`` and becomes it). Otherwise the one setting to choose per data set (0.3-0.5 m for
    outdoor LiDAR, about 0.05 m for indoor RGB-D fragments)."""
    num_threads: int = _DEFAULTS["num_threads"]
    """Worker threads per call, 0..1024; 0 = all hardware threads. Results never depend on it."""
    normal_radius_gain: float = _DEFAULTS["normal_radius_gain"]
    """Normal-estimation radius = gain * voxel_size; in (0, fpfh_radius_gain]."""
    fpfh_radius_gain: float = _DEFAULTS["fpfh_radius_gain"]
    """FPFH radius = gain * voxel_size; in [1.5, 50]."""
    max_linearity: float = _DEFAULTS["max_linearity"]
    """Voxels with (l1 - l2) / l1 above this get no normal; in (0, 1]."""
    ratio_test: float = _DEFAULTS["ratio_test"]
    """Lowe ratio on squared descriptor distances; in (0, 1]; 1 = off."""
    prune_noise_bound_gain: float = _DEFAULTS["prune_noise_bound_gain"]
    """Graph-pruning bound = gain * voxel_size; in (0, 1e6]."""
    solver_noise_bound_gain: float = _DEFAULTS["solver_noise_bound_gain"]
    """Solver inlier bound = gain * voxel_size; in (0, 1e6]."""
    noise_bound_max: float = _DEFAULTS["noise_bound_max"]
    """Cap on both bounds, in the clouds' unit, >= 0, finite; 0 = no cap."""
    viewpoint: tuple[float, float, float] = _DEFAULTS["viewpoint"]
    """Sensor position (x, y, z) toward which normals point, under viewpoint_mode='fixed'."""
    min_normal_neighbors: int = _DEFAULTS["min_normal_neighbors"]
    """Neighbours needed for a normal and a descriptor; 3..100000."""
    max_correspondences: int = _DEFAULTS["max_correspondences"]
    """Cap on the mutual matches kept, best ratio first; 3..100000, or 0 (the default) for automatic: one per 20
    keypoints of the smaller cloud, at least 5000 and at most 100000 (so 5000 for clouds of up to 100,000 keypoints)."""
    min_inliers: int = _DEFAULTS["min_inliers"]
    """Final inliers needed for ``Result.valid`` without refinement (``refine_min_inliers`` with it); 3..100000."""
    nonfinite_policy: NonFinitePolicy = _DEFAULTS["nonfinite_policy"]
    """'reject' (a NaN/Inf coordinate raises NonFiniteError) or 'drop' (such points are skipped and counted)."""
    viewpoint_mode: ViewpointMode = _DEFAULTS["viewpoint_mode"]
    """How normals are oriented. With no viewpoint at all, so that features depend on no cloud's frame (scans in
    any frame, maps; docs/design/frames.md): 'local' (the default: each normal turned away from its neighbours'
    centroid, its sign ignored where that centroid is too close to the surface to say) or 'sign_free'
    (descriptors blind to every normal's sign). With a viewpoint: 'fixed' (toward ``viewpoint``, in each cloud's
    frame: single scans in their sensor frame) or 'cloud_center' (toward each cloud's bounding-box centre)."""
    log_level: int = _DEFAULTS["log_level"]
    """Most verbose level passed to a log callback (0..4); kept for completeness: the Python package installs no log
    callback, and the library itself never prints."""
    refine_mode: RefineMode = _DEFAULTS["refine_mode"]
    """Fine registration of the solver's pose in the same call, on the voxelised clouds: 'none' (the solver's pose
    as it is), 'gicp' (Generalized ICP, plane to plane) or 'point_to_plane'. :meth:`Matcher.refine` uses this
    cost too ('gicp' when it is 'none'). With refinement, ``Result.transform`` is the refined pose and
    ``Result.coarse_transform`` the solver's."""
    refine_max_iterations: int = _DEFAULTS["refine_max_iterations"]
    """Refinement iteration cap, 1..1000."""
    refine_max_distance_gain: float = _DEFAULTS["refine_max_distance_gain"]
    """Refinement's correspondence distance (and ``Result.overlap``'s) = gain * voxel_size; in (0, 100]."""
    refine_kernel_gain: float = _DEFAULTS["refine_kernel_gain"]
    """Scale of refinement's Cauchy kernel = gain * voxel_size; in (0, 100]."""
    refine_rotation_epsilon: float = _DEFAULTS["refine_rotation_epsilon"]
    """Refinement has converged when a step turns the pose by less than this (radians) and moves it by less than
    ``refine_translation_epsilon_gain * voxel_size``; in [0, 1]."""
    refine_translation_epsilon_gain: float = _DEFAULTS["refine_translation_epsilon_gain"]
    """Convergence threshold on a refinement step's translation = gain * voxel_size; in [0, 1]."""
    max_rotation_uncertainty: float = _DEFAULTS["max_rotation_uncertainty"]
    """Without refinement, ``Result.valid`` needs ``Result.rotation_uncertainty`` <= this (radians; else reason "the
    inliers leave the rotation uncertain": too few inliers, or all on one compact object; a valid pose with twice
    it above this is refined to confirm it, and returned refined when the refined rule accepts it); in (0, 3.15]. With
    refinement it bounds 2 times the rotation's 1-sigma that ``Result.information`` states (the square root of the
    largest eigenvalue of its inverse's rotation block), with the same reason."""
    min_overlap: float = _DEFAULTS["min_overlap"]
    """With refinement, ``Result.valid`` needs ``Result.overlap`` >= this (else reason "the refined pose overlaps
    too little"); in [0, 1]."""
    min_inlier_coverage: float = _DEFAULTS["min_inlier_coverage"]
    """With refinement, ``Result.valid`` needs ``Result.inlier_coverage`` >= this (else reason "the inliers cover
    too little of the overlap": one object may match itself in several poses); in [0, 1]."""
    refine_min_inliers: int = _DEFAULTS["refine_min_inliers"]
    """With refinement, the final inliers ``Result.valid`` needs (``min_inliers`` applies without refinement);
    3..100000."""
    min_refine_condition: float = _DEFAULTS["min_refine_condition"]
    """With refinement (and :meth:`Matcher.refine`), ``Result.valid`` needs ``Result.refine_condition`` >= this
    (else reason "the refined pose is not constrained in every direction": a direction carrying less than this
    share of the strongest one's information slides, as along a corridor); in [0, 1]."""
    refine_normal_radius_gain: float = _DEFAULTS["refine_normal_radius_gain"]
    """Refinement aligns planes fitted to the neighbours within gain * voxel_size (at least 5 of them; a value above
    ``normal_radius_gain`` acts as it); in (0, 50]. The planes are computed with the features, so :class:`Features`
    of a Config with another value do not match (:class:`kissm.FeaturesMismatchError`)."""
    suppression: Suppression = _DEFAULTS["suppression"]
    """Geometric suppression before keypoints: 'none', or 'ground' (the ground voxels around the sensor at
    ``viewpoint``, perpendicular to ``up``, get no keypoint; they stay in the clouds refinement aligns;
    docs/reports/ground.md). Computed with the features."""
    rotation_dof: int = _DEFAULTS["rotation_dof"]
    """Rotational degrees of freedom: 3, or 1 (yaw about ``up`` only; a clearly tilted pair ends ``valid`` False
    with reason "the clouds' relative roll or pitch is not zero")."""
    up: tuple[float, float, float] = _DEFAULTS["up"]
    """The up direction in each cloud's own frame (finite, length above 1e-9; normalised), for suppression and
    ``rotation_dof=1``."""
    sensor_height: float = _DEFAULTS["sensor_height"]
    """Height of the sensor (``viewpoint``) above the ground along ``up``, metres, for suppression; 0 = estimate;
    in [0, 1000]."""
    max_refine_rmse_gain: float = _DEFAULTS["max_refine_rmse_gain"]
    """With refinement (and :meth:`Matcher.refine`), ``Result.valid`` needs ``Result.refine_rmse`` <= gain *
    ``voxel_size`` (else reason "the refined clouds stay apart": a local optimum beside the right pose, as a
    refinement from a prior outside its convergence basin reaches); in (0, 100]."""
    allow_degenerate: bool = _DEFAULTS["allow_degenerate"]
    """With refinement (and :meth:`Matcher.refine`): whether a refined pose that leaves directions free
    (``Result.degenerate``: a corridor leaves one, a tunnel two, a plane three; directions carrying less than
    ``min_refine_condition`` of the strongest one's information) may be valid. False (the default): such a pose
    ends ``valid`` False with reason "the refined pose is not constrained in every direction". True: it is judged
    by the other rules and, if valid, flagged ``Result.degenerate`` with its free directions in
    ``Result.weak_directions``, for callers who constrain those from elsewhere (odometry, a motion model). Stored
    in [0, 1] as an integer: False or True."""
    max_ambiguity: float = _DEFAULTS["max_ambiguity"]
    """``Result.valid`` needs ``Result.ambiguity`` <= this (else reason "a second, distinct pose has nearly as much
    support": a repetitive or symmetric scene, such as a street of identical facades, that matches as well one
    period along or turned onto its own symmetry); 1 never refuses a pose for it; in [0, 1]."""

    def __post_init__(self) -> None:
        set_field = object.__setattr__  # frozen: normalise through object
        if isinstance(self.voxel_size, str) and self.voxel_size != "auto":
            raise TypeError(f"Config.voxel_size must be a real number or 'auto', not {self.voxel_size!r}")
        for name in _FLOAT_FIELDS:
            if name != "voxel_size" or self.voxel_size != "auto":
                set_field(self, name, _as_float(name, getattr(self, name)))
        if self.voxel_size == _AUTO_VOXEL:
            set_field(self, "voxel_size", "auto")
        for name in _INT_FIELDS:
            set_field(self, name, _as_int(name, getattr(self, name)))
        for name in _BOOL_FIELDS:
            set_field(self, name, _as_bool(name, getattr(self, name)))
        for name in _ENUMS:
            set_field(self, name, _as_enum(name, getattr(self, name)))
        for name in _VECTOR_FIELDS:
            given = getattr(self, name)
            try:
                vector = tuple(_as_float(name, v) for v in given)
            except TypeError:
                raise TypeError(f"Config.{name} must be 3 real numbers, not {given!r}") from None
            if len(vector) != 3:
                raise ValueError(f"Config.{name} must have 3 coordinates, not {len(vector)}")
            set_field(self, name, vector)
        check(lib.kissm_config_validate(self._to_c()))

    @classmethod
    def preset(cls, name: str, **changes: Any) -> Config:
        """The settings for a common kind of data (``kissm_config_preset``), then ``changes``: 'lidar-vehicle'
        (outdoor LiDAR on a car or ground robot: 0.3 m voxels, ground suppression), 'lidar-handheld' (handheld,
        backpack or drone LiDAR: 0.3 m voxels, frame-free normals), 'indoor-rgbd' (0.05 m voxels) or 'object'
        (0.006 m voxels). docs/parameters.md, "Presets", has the evidence."""
        if name not in PRESETS:
            raise ValueError(f"unknown preset {name!r}; use one of {', '.join(map(repr, PRESETS))}")
        c = _new_c_config()
        check(lib.kissm_config_preset(c, PRESETS[name]))
        return cls(**{**_values_of(c), **changes})

    def _to_c(self) -> Any:
        """A fresh ``kissm_config *`` holding these settings (no callbacks)."""
        c = _new_c_config()
        for name in _FLOAT_FIELDS:
            value = getattr(self, name)
            setattr(c, name, _AUTO_VOXEL if value == "auto" else value)
        for name in _INT_FIELDS + _BOOL_FIELDS + tuple(_ENUMS):
            value = getattr(self, name)
            if isinstance(value, str):
                value = _ENUMS[name][value]
            elif isinstance(value, bool):
                value = int(value)
            try:
                setattr(c, name, value)
            except OverflowError:
                raise ValueError(f"config.{name} is {value}; it does not fit in a 32-bit int") from None
        for name in _VECTOR_FIELDS:
            target = getattr(c, name)
            for i in range(3):
                target[i] = getattr(self, name)[i]
        c.reserved1 = 0  # not settings: the library refuses anything else (kept for future fields)
        c.reserved2 = 0
        return c

    def replace(self, **changes: Any) -> Config:
        """A copy with some fields changed (validated like a new Config)."""
        unknown = sorted(set(changes) - {f.name for f in dataclasses.fields(self)})
        if unknown:
            raise TypeError(f"unknown kissm.Config field {unknown[0]!r}{did_you_mean(unknown[0])}")
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict[str, Any]:
        """Every field as a plain dict (``Config(**config.to_dict()) == config``)."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}

    def __repr__(self) -> str:
        changed = [f"{name}={value!r}" for name, value in self.to_dict().items() if value != _DEFAULTS[name]]
        return f"kissm.Config({', '.join(changed)})"

    def __reduce__(self) -> tuple[Any, tuple[Mapping[str, Any]]]:
        return (_config_from_dict, (self.to_dict(),))


def _config_from_dict(values: Mapping[str, Any]) -> Config:
    return Config(**values)


def default_config() -> Config:
    """The library's defaults (``kissm_config_init``)."""
    return Config()


def did_you_mean(name: str) -> str:
    """ " (did you mean 'voxel_size'?)" for a mistyped Config field, or "" when none is near."""
    near = difflib.get_close_matches(name, [f.name for f in dataclasses.fields(Config)], n=1)
    return f" (did you mean {near[0]!r}?)" if near else ""
