/* SPDX-License-Identifier: MIT */
/**
 * @file kissm.h
 * @brief kissm: fast, robust, deterministic global 3D point cloud registration.
 *
 * The only public header of the library. C99 and C++ compatible; fixed-width types only; no enum types,
 * no bool and no compiler-specific types cross this boundary (constants are \#defines on int32_t values).
 *
 * Conventions
 *  - Every fallible function returns an int32_t status: #KISSM_OK (0) or a negative KISSM_ERR_* code.
 *    Codes are never renumbered. kissm_status_string() gives a static description of a code and
 *    kissm_last_error_message() the detailed message of the last failure on the calling thread.
 *  - Output parameters come last. On failure nothing is written to them, except that a kissm_result
 *    passed to a registration call is always fully overwritten (valid = 0, NaN pose) so that a failed or
 *    invalid call can never hand back an older pose.
 *  - The library never prints, never aborts, never keeps a caller's pointer after a call returns, and
 *    creates no thread outside a call.
 *  - Structs that may grow (kissm_config, kissm_result) start with struct_size; fields are only appended.
 *
 * Every fallible function can also fail with #KISSM_ERR_OUT_OF_MEMORY (an allocation failed; nothing was
 * changed) and #KISSM_ERR_INTERNAL (a bug in kissm); the lists of return values below name them too.
 */
#ifndef KISSM_H
#define KISSM_H

#include <stddef.h>
#include <stdint.h>

/** @cond KISSM_INTERNAL */
#if defined(_WIN32)
#  if defined(KISSM_BUILDING_DLL)
#    define KISSM_API __declspec(dllexport)
#  elif defined(KISSM_DLL)
#    define KISSM_API __declspec(dllimport)
#  else
#    define KISSM_API
#  endif
#elif defined(__GNUC__) || defined(__clang__)
#  define KISSM_API __attribute__((visibility("default")))
#else
#  define KISSM_API
#endif
/** @endcond */

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------------------------------ */
/* Version                                                                                          */
/* ------------------------------------------------------------------------------------------------ */

/**
 * @defgroup version Version
 * @brief The header's version macros and their runtime twins, which bindings compare with the header they
 *        were built from.
 * @{
 */

/** Major version of this header. */
#define KISSM_VERSION_MAJOR 0
/** Minor version of this header. */
#define KISSM_VERSION_MINOR 1
/** Patch version of this header. */
#define KISSM_VERSION_PATCH 0
/** The header's version as one number: major * 10000 + minor * 100 + patch. */
#define KISSM_VERSION_NUMBER (KISSM_VERSION_MAJOR * 10000 + KISSM_VERSION_MINOR * 100 + KISSM_VERSION_PATCH)
/** The header's version as "major.minor.patch". */
#define KISSM_VERSION_STRING "0.1.0"
/** Bumped only when the ABI breaks; equals the shared library's SOVERSION. */
#define KISSM_ABI_VERSION 0

/**
 * @brief Runtime twin of #KISSM_VERSION_NUMBER: the version of the library actually loaded.
 * @return major * 10000 + minor * 100 + patch of the library.
 */
KISSM_API uint32_t kissm_version_number(void);
/**
 * @brief Runtime twin of #KISSM_VERSION_STRING.
 * @return The library's version, "major.minor.patch": a static string, never NULL.
 */
KISSM_API const char *kissm_version_string(void);
/**
 * @brief Runtime twin of #KISSM_ABI_VERSION: a program compiled against this header may use the library
 *        only when the two are equal.
 * @return The library's ABI version (its SOVERSION).
 */
KISSM_API uint32_t kissm_abi_version(void);

/** @} */

/* ------------------------------------------------------------------------------------------------ */
/* Status codes (values are pinned forever)                                                        */
/* ------------------------------------------------------------------------------------------------ */

/**
 * @defgroup status Status codes and error messages
 * @brief What every fallible function returns: #KISSM_OK or a negative code. The values are pinned
 *        forever.
 * @{
 */

#define KISSM_OK 0                       /**< Success. */
#define KISSM_ERR_INVALID_ARGUMENT -1    /**< A config value or argument is out of its documented range. */
#define KISSM_ERR_NULL_ARGUMENT -2       /**< A required pointer is NULL. */
#define KISSM_ERR_EMPTY_INPUT -3         /**< A cloud has no points (or none left after dropping non-finite ones). */
#define KISSM_ERR_TOO_FEW_POINTS -4      /**< A cloud has fewer than #KISSM_MIN_POINTS points. */
#define KISSM_ERR_NONFINITE -5           /**< A NaN or infinite coordinate under #KISSM_NONFINITE_REJECT. */
#define KISSM_ERR_VOXEL_RANGE -6         /**< The voxel size is too small for the cloud's extent. */
#define KISSM_ERR_STRUCT_SIZE -7         /**< struct_size too small, above 65536, or with a non-zero unknown tail. */
#define KISSM_ERR_OUT_OF_MEMORY -8       /**< An allocation failed; nothing was changed. */
#define KISSM_ERR_CANCELLED -9           /**< kissm_cancel() or the progress callback stopped the call. */
#define KISSM_ERR_FEATURES_MISMATCH -10  /**< Features computed under a different configuration. */
#define KISSM_ERR_IO -11                 /**< A file could not be opened or read. */
#define KISSM_ERR_PARSE -12              /**< A file is malformed, truncated or of an unsupported layout. */
#define KISSM_ERR_UNSUPPORTED_FORMAT -13 /**< A file's format is not recognised (or not built in: LAZ). */
#define KISSM_ERR_INTERNAL -14           /**< A bug in kissm: please report it with the message. */

/**
 * @brief Describes a status code.
 * @param[in] status A status returned by a kissm_* function (any value is accepted).
 * @return A static, never-NULL description of @p status; "unknown status" for unknown values.
 */
KISSM_API const char *kissm_status_string(int32_t status);
/**
 * @brief Detailed message of the last failing kissm_* call on this thread, naming the offending argument.
 * @return A library-owned string, valid until the next kissm_* call on this thread; "" when the last call
 *         succeeded. Never NULL.
 */
KISSM_API const char *kissm_last_error_message(void);

/** Fewest points a cloud may have before kissm_register() refuses it with #KISSM_ERR_TOO_FEW_POINTS. */
#define KISSM_MIN_POINTS 4

/** @} */

/* ------------------------------------------------------------------------------------------------ */
/* Reasons for valid = 0 (a well-formed input that gives no trustworthy pose is not an error)       */
/* ------------------------------------------------------------------------------------------------ */

/**
 * @defgroup reasons Reasons for valid = 0
 * @brief Why kissm_result.valid is 0 after a call that returned #KISSM_OK: a well-formed input that gives
 *        no trustworthy pose is not an error.
 * @{
 */

#define KISSM_REASON_NONE 0                    /**< valid = 1, or the call failed (see its status). */
#define KISSM_REASON_TOO_FEW_VOXELS 1          /**< A cloud has too few occupied voxels to describe. */
#define KISSM_REASON_TOO_FEW_FEATURES 2        /**< A cloud has too few points with a reliable descriptor. */
#define KISSM_REASON_TOO_FEW_CORRESPONDENCES 3 /**< Matching or pruning left too few correspondences. */
#define KISSM_REASON_SOLVER_FAILED 4           /**< The robust solver found no consistent rotation. */
/** Final inliers below kissm_config.min_inliers (with refinement: refine_min_inliers); without refinement a pose
 * with at least refine_min_inliers is verified by GICP first, and returned refined and valid when the refined rule
 * accepts it. */
#define KISSM_REASON_TOO_FEW_INLIERS 5
#define KISSM_REASON_DEGENERATE 6 /**< The inliers are collinear or planar: the pose is ambiguous. */
/** Refinement ran and its pose lays too little of the source onto the target (kissm_result.overlap below
 * kissm_config.min_overlap, or fewer than 6 correspondences). */
#define KISSM_REASON_LOW_OVERLAP 7
/** Refinement ran and the aligned clouds leave a direction of the pose free (a plane, a corridor, a tunnel):
 * kissm_result.degenerate = 1, the free directions in kissm_result.weak_directions; kissm_config.allow_degenerate
 * = 1 accepts such a pose. */
#define KISSM_REASON_UNCONSTRAINED 8
/** Without refinement: the inliers pin the rotation down no better than kissm_config.max_rotation_uncertainty
 * (kissm_result.rotation_uncertainty): too few of them, or all on one compact object; and the pose, refined with
 * GICP to verify it, did not pass the refined rule either (when it does, the refined pose is returned valid). A
 * valid coarse pose with 2 times kissm_result.rotation_uncertainty above the bound is refined the same way to
 * confirm it, and returned refined when the refined rule accepts it (unchanged otherwise).
 * With refinement: 2 times the rotation's 1-sigma that kissm_result.information states (the square root of the
 * largest eigenvalue of the inverse's rotation block) exceeds kissm_config.max_rotation_uncertainty. */
#define KISSM_REASON_UNCERTAIN_ROTATION 9
/** With refinement: the inliers cover less than kissm_config.min_inlier_coverage of the aligned overlap
 * (kissm_result.inlier_coverage): one object may match itself in several poses. */
#define KISSM_REASON_CLUSTERED_INLIERS 10
/** Refinement was still moving the pose at kissm_config.refine_max_iterations (kissm_result.refine_converged
 * = 0): it was crossing from one basin to another, as refinements from a wrong start do. */
#define KISSM_REASON_NOT_CONVERGED 11
/** kissm_config.rotation_dof = 1 and the clouds' relative roll or pitch is not zero, so the yaw-only pose would
 * be off by at least that much: the best rotation on the yaw solution's inliers turns kissm_config.up by more
 * than kissm_config.max_rotation_uncertainty (kissm_result.tilt), or the yaw rotation explains under a quarter
 * of the matches that pruning found mutually consistent (kissm_result.num_rotation_inliers against
 * num_pruned_correspondences). */
#define KISSM_REASON_TILTED 12
/** Refinement ran and the aligned clouds stay apart by more than kissm_config.max_refine_rmse_gain voxels
 * (kissm_result.refine_rmse): a local optimum beside the right pose, as refinements from a prior outside the
 * convergence basin reach (a road shifted along itself, a scene turned onto its own symmetry). */
#define KISSM_REASON_LOOSE_ALIGNMENT 13
/** The scene holds a second pose, distinct from the one returned, with nearly as much support
 * (kissm_result.ambiguity above kissm_config.max_ambiguity): a repetitive or symmetric scene (a street of identical
 * facades, pillars at a regular spacing, a symmetric object) that matches as well one period along or turned onto
 * its own symmetry. The pose returned is one of them; a prior or a check from elsewhere must choose. */
#define KISSM_REASON_AMBIGUOUS 14
/** Refinement ran and the aligned clouds stay more than 0.37 voxel apart (kissm_result.refine_rmse) while the pose
 * is weakly constrained (kissm_result.refine_condition below 0.09): a partial match of repeated structure (the
 * ground and one facade of a street lined up, the rest apart, the pose free to slide). Right poses measured are
 * either tighter or better conditioned (docs/design/accuracy.md, "The simulated city's wrong poses"). */
#define KISSM_REASON_LOOSE_AND_WEAK 15

/**
 * @brief Describes a reason code.
 * @param[in] reason A KISSM_REASON_* value, as in kissm_result.reason (any value is accepted).
 * @return A static, never-NULL description of @p reason; "unknown reason" for unknown values.
 */
KISSM_API const char *kissm_reason_string(int32_t reason);

/** @} */

/* ------------------------------------------------------------------------------------------------ */
/* Configuration                                                                                    */
/* ------------------------------------------------------------------------------------------------ */

/**
 * @defgroup config Configuration
 * @brief kissm_config, its defaults (kissm_config_init()) and checks (kissm_config_validate()), and the
 *        constants and callbacks its fields use.
 * @{
 */

/** @name Non-finite policy (kissm_config.nonfinite_policy) */
/** @{ */
#define KISSM_NONFINITE_REJECT 0 /**< A NaN/Inf coordinate fails the call with #KISSM_ERR_NONFINITE. */
#define KISSM_NONFINITE_DROP 1   /**< Such points are skipped and counted in the result. */
/** @} */

/** @name How normals are oriented (kissm_config.viewpoint_mode) */
/** @{ */
#define KISSM_VIEWPOINT_FIXED 0        /**< kissm_config.viewpoint, in each cloud's own input frame (the sensor). */
#define KISSM_VIEWPOINT_CLOUD_CENTER 1 /**< Each cloud's bounding-box centre. */
/** No viewpoint: the descriptors do not depend on the normals' signs at all, so features depend on no cloud's
 * coordinate frame (docs/design/frames.md). */
#define KISSM_VIEWPOINT_SIGN_FREE 2
/** No viewpoint (the default): each normal turned away from the centroid of its neighbours within the FPFH
 * radius, a rule of the local shape alone, so features depend on no cloud's coordinate frame; where that
 * centroid lies too close to the surface to say, the descriptors ignore the normal's sign (docs/design/frames.md). */
#define KISSM_VIEWPOINT_LOCAL 3
/** @} */

/** @name Geometric suppression before keypoints (kissm_config.suppression) */
/** @{ */
#define KISSM_SUPPRESS_NONE 0 /**< Every voxel may become a keypoint. */
/** Ground voxels get no keypoint: a region-wise ground model around the sensor (kissm_config.viewpoint),
 * perpendicular to kissm_config.up (docs/reports/ground.md). They stay in the clouds refinement aligns. */
#define KISSM_SUPPRESS_GROUND 1
/** @} */

/** @name Settings for common sensors (kissm_config_preset()) */
/** @{ */
/** Outdoor LiDAR on a car or ground robot, scans in the sensor frame: 0.3 m voxels, ground suppression. */
#define KISSM_PRESET_LIDAR_VEHICLE 1
/** Handheld, backpack or drone LiDAR (no ground assumption, any orientation): 0.3 m voxels, frame-free normals. */
#define KISSM_PRESET_LIDAR_HANDHELD 2
/** Indoor RGB-D fragments (rooms, metres across): 0.05 m voxels. */
#define KISSM_PRESET_INDOOR_RGBD 3
/** Objects on a turntable or scanned by hand (decimetres across): 0.006 m voxels. */
#define KISSM_PRESET_OBJECT 4
/** @} */

/** @name Fine registration after the solver (kissm_config.refine_mode) */
/** @{ */
#define KISSM_REFINE_NONE 0           /**< The solver's pose as it is. */
#define KISSM_REFINE_GICP 1           /**< Generalized ICP (plane-to-plane) on the voxelised clouds. */
#define KISSM_REFINE_POINT_TO_PLANE 2 /**< Point-to-plane ICP on the voxelised clouds. */
/** @} */

/** @name Log levels for kissm_log_fn (kissm_config.log_level) */
/** @{ */
#define KISSM_LOG_ERROR 1 /**< Errors. */
#define KISSM_LOG_WARN 2  /**< Warnings (the default level). */
#define KISSM_LOG_INFO 3  /**< Progress information. */
#define KISSM_LOG_DEBUG 4 /**< Details for debugging. */
/** @} */

/** @name Pipeline stages, as reported to kissm_progress_fn */
/** @{ */
#define KISSM_STAGE_VOXELIZE 1 /**< Input checks, recentring and voxelisation. */
#define KISSM_STAGE_FEATURES 2 /**< Neighbour search, normals, FPFH. */
#define KISSM_STAGE_MATCHING 3 /**< Descriptor matching. */
#define KISSM_STAGE_PRUNING 4  /**< Compatibility graph and max k-core. */
#define KISSM_STAGE_SOLVER 5   /**< GNC-TLS rotation, translation, inliers, validity. */
#define KISSM_STAGE_REFINE 6   /**< Fine registration (kissm_config.refine_mode, kissm_refine()). */
/** @} */

/**
 * @brief Log callback (kissm_config.log_fn). Called on the calling thread only, never concurrently; must not
 *        call back into the same matcher.
 * @param[in] user_data kissm_config.log_user_data, as given.
 * @param[in] level A KISSM_LOG_* level, at most kissm_config.log_level.
 * @param[in] message The message; valid during the call only.
 */
typedef void (*kissm_log_fn)(void *user_data, int32_t level, const char *message);
/**
 * @brief Progress callback (kissm_config.progress_fn). Called on the calling thread at stage boundaries and
 *        within long stages.
 *
 * Stages never go back within a call and fractions never decrease within a stage; the last call of a
 * registration that ran to the end is (#KISSM_STAGE_SOLVER, 1.0), or (#KISSM_STAGE_REFINE, 1.0) when it
 * refined its pose.
 * @param[in] user_data kissm_config.progress_user_data, as given.
 * @param[in] stage The KISSM_STAGE_* stage running.
 * @param[in] fraction How much of that stage is done, in [0, 1].
 * @return 0 to go on; non-zero to cancel (the call then fails with #KISSM_ERR_CANCELLED).
 */
typedef int32_t (*kissm_progress_fn)(void *user_data, int32_t stage, double fraction);

/**
 * @brief Settings of a matcher. Fill it with kissm_config_init(), then change what you need.
 *
 * Each field's comment gives its unit, its valid range and its default (the value kissm_config_init()
 * writes).
 */
typedef struct kissm_config {
    /** sizeof(kissm_config) as the caller knows it; set by kissm_config_init(). */
    uint32_t struct_size;
    /** Worker threads, 0..1024; 0 = all hardware threads. Results do not depend on it. Default 0. */
    int32_t num_threads;

    /** Metres (or the cloud's unit); > 0, or 0 for automatic: each call then describes its clouds with the voxel
     * kissm_suggest_voxel_size() gives for them together (kissm_result.voxel_size_used reports it; features
     * computed apart get their own cloud's suggestion; its errors are the call's). Every length below scales with
     * it. Default 0.3. */
    double voxel_size;
    /** Normal radius = gain * voxel_size; in (0, fpfh_radius_gain]. Default 3.5 (paper). */
    double normal_radius_gain;
    /** FPFH radius = gain * voxel_size; in [1.5, 50] and >= normal gain. Default 5.0. */
    double fpfh_radius_gain;
    /** tau_lin: (l1 - l2) / l1 above this gets no normal; in (0, 1]. Default 0.99. */
    double max_linearity;
    /** Lowe ratio on squared descriptor distances, in (0, 1]; 1 = off. Default 0.9. */
    double ratio_test;
    /** Graph edge when length mismatch <= gain * voxel_size; in (0, 1e6]. Default 1.0. */
    double prune_noise_bound_gain;
    /** Solver inlier bound = gain * voxel_size; in (0, 1e6]. Default 0.75. */
    double solver_noise_bound_gain;
    /** Cap on both noise bounds in metres, >= 0, finite; 0 = no cap. Default 0. */
    double noise_bound_max;
    /** For #KISSM_VIEWPOINT_FIXED: the sensor position, finite. Default (0, 0, 0). */
    double viewpoint[3];

    /** tau_num: neighbours needed for a normal and a descriptor; 3..100000. Default 3. */
    int32_t min_normal_neighbors;
    /** Cap on mutual matches kept (best ratio first); 3..100000, or 0 for automatic: one per 20 keypoints of the
     * smaller cloud, at least 5000 and at most 100000 (5000 for every cloud of up to 100,000 keypoints). Default 0. */
    int32_t max_correspondences;
    /** Without refinement, valid needs at least this many final inliers (refine_min_inliers applies with it);
     * 3..100000. Default 15. */
    int32_t min_inliers;
    /** KISSM_NONFINITE_*. Default #KISSM_NONFINITE_REJECT. */
    int32_t nonfinite_policy;
    /** KISSM_VIEWPOINT_*: how normals are oriented. Default #KISSM_VIEWPOINT_LOCAL (features that depend on no
     * cloud's frame); #KISSM_VIEWPOINT_FIXED for scans in their sensor frame when kissm_config.viewpoint is
     * known (docs/design/frames.md). */
    int32_t viewpoint_mode;
    /** Most verbose level passed to log_fn, 0 (none)..4. Default #KISSM_LOG_WARN. */
    int32_t log_level;

    /** Log callback; NULL = silent. */
    kissm_log_fn log_fn;
    /** Passed to log_fn as it is. */
    void *log_user_data;
    /** Progress and cancellation callback; NULL = none. */
    kissm_progress_fn progress_fn;
    /** Passed to progress_fn as it is. */
    void *progress_user_data;

    /** KISSM_REFINE_*: refine the solver's pose on the voxelised clouds in the same call. kissm_refine()
     * uses this cost too (GICP when it is #KISSM_REFINE_NONE). Default #KISSM_REFINE_NONE. */
    int32_t refine_mode;
    /** Refinement iteration cap, 1..1000. Default 30. */
    int32_t refine_max_iterations;
    /** Refinement's correspondence distance, and kissm_result.overlap's, = gain * voxel_size; in (0, 100].
     * Default 3.0. */
    double refine_max_distance_gain;
    /** Scale of refinement's Cauchy kernel = gain * voxel_size; in (0, 100]. Default 1.0. */
    double refine_kernel_gain;
    /** Refinement has converged when a step turns the pose by less than this (radians) ...; in [0, 1].
     * Default 5e-4. */
    double refine_rotation_epsilon;
    /** ... and moves it by less than gain * voxel_size; in [0, 1]. Default 5e-3. */
    double refine_translation_epsilon_gain;
    /** Without refinement, valid needs kissm_result.rotation_uncertainty <= this (radians); in (0, 3.15].
     * Default 0.0349 (2 degrees). */
    double max_rotation_uncertainty;
    /** With refinement, valid needs kissm_result.overlap >= this; in [0, 1]. Default 0.2. */
    double min_overlap;
    /** With refinement, valid needs kissm_result.inlier_coverage >= this; in [0, 1]. Default 0.25. */
    double min_inlier_coverage;
    /** With refinement, valid needs at least this many final inliers (min_inliers applies without
     * refinement); 3..100000. Default 10. */
    int32_t refine_min_inliers;
    /** Must be 0. */
    int32_t reserved1;
    /** With refinement, valid needs kissm_result.refine_condition >= this (a direction carrying less than this
     * share of the strongest one's information slides); in [0, 1]. Default 0.01. */
    double min_refine_condition;
    /** Refinement aligns planes fitted to the neighbours within gain * voxel_size (at least 5 of them; at most
     * normal_radius_gain: a larger value acts as normal_radius_gain); in (0, 50]. Computed with the features,
     * so features of another value do not match (#KISSM_ERR_FEATURES_MISMATCH). Default 2.0. */
    double refine_normal_radius_gain;
    /** #KISSM_SUPPRESS_NONE or #KISSM_SUPPRESS_GROUND. Computed with the features, so features of another value
     * do not match (#KISSM_ERR_FEATURES_MISMATCH). Default #KISSM_SUPPRESS_NONE. */
    int32_t suppression;
    /** Rotational degrees of freedom the solver estimates: 3, or 1 (yaw about kissm_config.up only, roll and
     * pitch taken as zero; a pair that is clearly tilted ends valid = 0 with #KISSM_REASON_TILTED). Default 3. */
    int32_t rotation_dof;
    /** The up direction in each cloud's own frame (the same vector for both clouds; any finite vector of length
     * above 1e-9, normalised), for suppression and rotation_dof = 1. Computed with the features when
     * suppression is on. Default (0, 0, 1). */
    double up[3];
    /** Height of the sensor (kissm_config.viewpoint) above the ground along up, metres, for suppression; 0 =
     * estimate it from the cloud; in [0, 1000]. Default 0. */
    double sensor_height;
    /** With refinement, valid needs kissm_result.refine_rmse <= gain * voxel_size: right alignments of
     * voxelised clouds stay within a fraction of a voxel, wrong local optima do not; in (0, 100].
     * Default 0.45. */
    double max_refine_rmse_gain;
    /** 1: a refined pose that leaves a direction free (kissm_result.degenerate: a corridor, a tunnel, a plane) may
     * be valid, flagged, for callers who fuse its weak directions from elsewhere (odometry); 0: such a pose ends
     * valid = 0 with #KISSM_REASON_UNCONSTRAINED; in [0, 1]. Default 0. */
    int32_t allow_degenerate;
    /** Reserved; must be 0. */
    int32_t reserved2;
    /** A solved pose whose best distinct competitor reaches more than this share of its support
     * (kissm_result.ambiguity) ends valid = 0 with #KISSM_REASON_AMBIGUOUS; 1 never refuses a pose for it; in
     * [0, 1]. Default 0.7. */
    double max_ambiguity;
    /* New fields are only ever appended here. */
} kissm_config;

/**
 * @brief Writes the documented defaults into the first struct_size bytes of *config and sets
 *        config->struct_size = struct_size.
 * @param[out] config The struct to fill.
 * @param[in] struct_size Pass sizeof(kissm_config).
 * @retval KISSM_OK Done.
 * @retval KISSM_ERR_NULL_ARGUMENT @p config is NULL.
 * @retval KISSM_ERR_STRUCT_SIZE @p struct_size is smaller than the first published layout, or above 65536.
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_config_init(kissm_config *config, uint32_t struct_size);
/**
 * @brief Checks every field, with a message (kissm_last_error_message()) naming the field.
 *
 * kissm_create() performs the same checks.
 * @param[in] config The configuration to check.
 * @retval KISSM_OK Every field is in its range.
 * @retval KISSM_ERR_NULL_ARGUMENT @p config is NULL.
 * @retval KISSM_ERR_INVALID_ARGUMENT A field is out of its documented range.
 * @retval KISSM_ERR_STRUCT_SIZE config->struct_size is too small, above 65536, or the bytes this library
 *         does not know are not all zero.
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_config_validate(const kissm_config *config);
/**
 * @brief Applies the settings of a common kind of data on top of *config: the voxel size and the options
 *        that kind wants (docs/parameters.md, "Presets"); every other field keeps its value.
 *
 * Call it after kissm_config_init() and before your own changes. On error *config is unchanged.
 * @param[in,out] config A config filled by kissm_config_init().
 * @param[in] preset A KISSM_PRESET_* value.
 * @retval KISSM_OK Done.
 * @retval KISSM_ERR_NULL_ARGUMENT @p config is NULL.
 * @retval KISSM_ERR_STRUCT_SIZE config->struct_size is too small or above 65536.
 * @retval KISSM_ERR_INVALID_ARGUMENT @p preset is not a KISSM_PRESET_* value.
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_config_preset(kissm_config *config, int32_t preset);

/** @} */

/* ------------------------------------------------------------------------------------------------ */
/* Points: a borrowed, zero-copy view of the caller's xyz coordinates                               */
/* ------------------------------------------------------------------------------------------------ */

/**
 * @defgroup points Points
 * @brief kissm_points: a borrowed, zero-copy view of the caller's xyz coordinates.
 * @{
 */

#define KISSM_SCALAR_FLOAT32 1 /**< Coordinates are float. */
#define KISSM_SCALAR_FLOAT64 2 /**< Coordinates are double. */

/** @brief A borrowed, zero-copy view of the caller's xyz coordinates. */
typedef struct kissm_points {
    /** First point's x; y and z follow contiguously. Read during the call only. */
    const void *data;
    /** Number of points, at most 4294967295. */
    uint64_t count;
    /** Bytes from one point to the next; 0 = packed (3 scalars). */
    uint64_t stride_bytes;
    /** #KISSM_SCALAR_FLOAT32 or #KISSM_SCALAR_FLOAT64. */
    int32_t scalar_type;
    /** Must be 0. */
    int32_t reserved;
} kissm_points;

/** @} */

/* ------------------------------------------------------------------------------------------------ */
/* Result                                                                                           */
/* ------------------------------------------------------------------------------------------------ */

/**
 * @defgroup result Result
 * @brief kissm_result: the pose, its validity and what each stage found.
 * @{
 */

/**
 * @brief What a registration call found: the pose, whether it can be trusted, and the counts and timings
 *        of every stage. Always fully overwritten by kissm_register(), kissm_register_features(), kissm_refine()
 *        and kissm_refine_features().
 *
 * The time_*_ms fields are wall-clock milliseconds per stage; time_total_ms is their sum. Stages not run
 * are 0. Timings are the only fields that differ between identical calls.
 */
typedef struct kissm_result {
    /** Set by the caller to sizeof(kissm_result). */
    uint32_t struct_size;
    /** 1 when the pose can be trusted (see reason and the counts). */
    int32_t valid;
    /** KISSM_REASON_* when valid = 0. */
    int32_t reason;
    /** Reserved; written as 0. */
    int32_t reserved0;

    /** Maps source points into the target frame: p_t = R p_s + t. Row-major. NaN when no pose was
     * estimated; when valid = 0 but a pose was estimated it is kept here for inspection. */
    double transform[16];
    /** R of transform, row-major (NaN when no pose was estimated). */
    double rotation[9];
    /** t of transform (NaN when no pose was estimated). */
    double translation[3];

    /** Points given. */
    uint64_t num_source_points;
    /** Points given. */
    uint64_t num_target_points;
    /** Points dropped under #KISSM_NONFINITE_DROP. */
    uint64_t num_source_nonfinite;
    /** Points dropped under #KISSM_NONFINITE_DROP. */
    uint64_t num_target_nonfinite;
    /** Occupied voxels. */
    uint64_t num_source_voxels;
    /** Occupied voxels. */
    uint64_t num_target_voxels;
    /** Voxels with a descriptor. */
    uint64_t num_source_keypoints;
    /** Voxels with a descriptor. */
    uint64_t num_target_keypoints;
    /** Mutual, ratio-tested, capped matches. */
    uint64_t num_initial_correspondences;
    /** The maximum k-core. */
    uint64_t num_pruned_correspondences;
    /** Pruned correspondences the rotation solver kept. */
    uint64_t num_rotation_inliers;
    /** Pruned correspondences within the solver bound after R, t. */
    uint64_t num_final_inliers;
    /** k of the maximum k-core. */
    uint64_t max_core_number;

    /** num_final_inliers / num_initial_correspondences (0 when none). */
    double inlier_ratio;
    /** RMS of |R a + t - b| over final inliers, metres (NaN when none). */
    double residual_rms;
    /** Solver inlier bound used, metres. */
    double noise_bound;
    /** sqrt of the eigenvalues (descending) of the inliers' source covariance. */
    double inlier_extent[3];

    /** Wall-clock ms: input checks, recentring and voxelisation (0 if not run). */
    double time_voxelize_ms;
    /** Wall-clock ms: neighbour search, normals, FPFH (0 if not run). */
    double time_features_ms;
    /** Wall-clock ms: descriptor matching (0 if not run). */
    double time_matching_ms;
    /** Wall-clock ms: compatibility graph and max k-core (0 if not run). */
    double time_pruning_ms;
    /** Wall-clock ms: GNC-TLS rotation, translation, inliers, validity (0 if not run). */
    double time_solver_ms;
    /** Sum of the stage times (time_refine_ms included). Timings are the only fields that differ between
     * identical calls. */
    double time_total_ms;

    /** The solver's pose, row-major as transform; for kissm_refine() the initial transform with its rotation
     * block made exactly rigid (the nearest rotation). transform is the refined pose when refinement ran and this
     * one otherwise. NaN when no pose was estimated. */
    double coarse_transform[16];
    /** 6x6 information matrix of the refined pose, row-major, symmetric: the inverse covariance of the error
     * xi in T_true = T exp(xi), xi = (rotation [rad], translation [m]) in the source's frame (the perturbation
     * GTSAM's Pose3 uses; g2o orders translation first). The Gauss-Newton information of the point-to-plane
     * distances of the final correspondences (in both modes: GICP's along-plane weights are a regularisation,
     * not a measurement), divided by a calibrated variance: 12 times the square of the residuals' robust spread
     * (1.4826 times their median absolute value), as neighbouring voxels are not independent measurements. Its
     * NEES against the truth is measured on simulated and real scans (docs/design/accuracy.md); use it as it is in
     * a pose graph. A small eigenvalue shows a direction the data leaves free. NaN when refinement did not run. */
    double information[36];
    /** Share of the source's voxels that the refined pose lays within the refinement's correspondence distance
     * of a target voxel, in [0, 1]. NaN when refinement did not run. */
    double overlap;
    /** Weighted (Cauchy) RMS distance of the final correspondences to the target's planes, metres. NaN when
     * refinement did not run or found no correspondence. A valid refined pose has it at most
     * kissm_config.max_refine_rmse_gain * voxel_size. */
    double refine_rmse;
    /** Weakest over strongest direction of the information, with rotations as displacements at the matched
     * points' radius, in [0, 1]: near 0 the pose slides. NaN when refinement did not run. */
    double refine_condition;
    /** 1-sigma uncertainty (radians) of the solver's rotation about its worst axis if every inlier were off by
     * the noise bound: noise_bound / sqrt(N (e1^2 + e2^2)) with e1, e2 the two smaller inlier_extent values.
     * Infinite when e1 = e2 = 0 (no inliers, or all on one point); NaN when no pose was estimated and after
     * kissm_refine() / kissm_refine_features() (no solver ran). */
    double rotation_uncertainty;
    /** Principal standard deviation of the inliers over that of the source voxels the refined pose overlaps:
     * how much of the overlap the solver's matches span (above 1 when they reach beyond it). NaN unless a
     * registration was refined. */
    double inlier_coverage;
    /** Wall-clock ms: refinement (0 if not run). */
    double time_refine_ms;
    /** Correspondences of the refinement at its final pose (0 if not run). */
    uint64_t num_refine_correspondences;
    /** Refinement iterations run (0 if not run). */
    int32_t refine_iterations;
    /** 1 when refinement stopped on its convergence test rather than its iteration cap. */
    int32_t refine_converged;
    /** Source voxels kissm_config.suppression kept from becoming keypoints (0 when it is off). */
    uint64_t num_source_suppressed;
    /** Target voxels kissm_config.suppression kept from becoming keypoints (0 when it is off). */
    uint64_t num_target_suppressed;
    /** Wall-clock ms: suppression, both clouds (part of time_features_ms; 0 when it is off). */
    double time_suppression_ms;
    /** With rotation_dof = 1: the angle (radians) by which the best unconstrained rotation on the yaw
     * solution's inliers turns kissm_config.up, the evidence for #KISSM_REASON_TILTED. NaN otherwise. */
    double tilt;
    /** 1 when refinement ran and the aligned clouds leave num_weak_directions directions of the pose free:
     * their share of the information, with rotations as displacements at the matched points' radius, is below
     * kissm_config.min_refine_condition of the strongest direction's (refine_condition is the weakest share).
     * A corridor leaves one, a tunnel two, a plane three. Not valid (#KISSM_REASON_UNCONSTRAINED) unless
     * kissm_config.allow_degenerate = 1. 0 when refinement did not run: without it no dense information
     * exists to tell. */
    int32_t degenerate;
    /** Rows of weak_directions in use, 0 to 6 (0 unless degenerate). */
    int32_t num_weak_directions;
    /** The free directions, weakest first, row-major 6x6: row i < num_weak_directions is a unit 6-vector
     * xi = (rotation [rad], translation [m]) in the order and frame of information (T exp(xi), source frame),
     * its largest component positive; a pose moved along it changes the alignment by almost nothing. Rows
     * beyond num_weak_directions are NaN. */
    double weak_directions[36];
    /** When the robust solver found a pose: the support of the best competing pose, distinct from it (moving the
     * matched points by more than 8 noise bounds), over its own, in [0, 1]. Support is the inliers among every
     * match after the same polish, and from one half on the smaller of that ratio and the dense one (source
     * voxels landing beside target voxels). Near 0 in a scene with one answer; near 1 in a repetitive or
     * symmetric one. Above kissm_config.max_ambiguity: #KISSM_REASON_AMBIGUOUS. NaN when the solver did not run
     * (and from kissm_refine()). */
    double ambiguity;
    /** The probability that the pose is within the success tolerance (5 degrees, and 2 m for LiDAR, 0.3 m indoors,
     * 1 cm on small objects: about 4 to 7 voxels at the suggested sizes), in [0, 1]: a fixed logistic function of the
     * final inliers (with refinement also of the overlap and refine_rmse), times a factor falling with the ambiguity
     * (1 up to 0.6, a pick among equals from 0.8); from kissm_refine() of the overlap and refine_rmse
     * (docs/design/accuracy.md, "Confidence"). 0 without a pose; NaN when the call failed. It reads none of
     * kissm_config's thresholds. Runs its fit did not see held no wrong pose at 0.95 or above. */
    double confidence;
    /** The voxel size the clouds were described with (metres): kissm_config.voxel_size, or under voxel_size 0
     * (automatic) the one suggested for both clouds (kissm_suggest_voxel_size()); from features, theirs. 0 when
     * the call failed. */
    double voxel_size_used;
    /* New fields are only ever appended here. */
} kissm_result;

/**
 * @brief Prepares a result for a registration call: sets result->struct_size = struct_size and leaves the
 *        rest as a failed call does (valid = 0, reason #KISSM_REASON_NONE, counts 0, NaN pose).
 *
 * Optional: setting struct_size by hand is enough, since every registration call overwrites the whole
 * result. A newer caller's larger struct gets its unknown tail zeroed.
 * @param[out] result The struct to prepare.
 * @param[in] struct_size Pass sizeof(kissm_result).
 * @retval KISSM_OK Done.
 * @retval KISSM_ERR_NULL_ARGUMENT @p result is NULL.
 * @retval KISSM_ERR_STRUCT_SIZE @p struct_size is smaller than the first published layout, or above 65536;
 *         nothing is written.
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_result_init(kissm_result *result, uint32_t struct_size);

/** @} */

/* ------------------------------------------------------------------------------------------------ */
/* Matcher                                                                                          */
/* ------------------------------------------------------------------------------------------------ */

/**
 * @defgroup matcher Matcher
 * @brief Create a matcher from a configuration, register pairs of clouds, cancel a running call.
 * @{
 */

/** @brief Mutable; used by one thread at a time (kissm_cancel() excepted). Distinct matchers run
 *         concurrently. */
typedef struct kissm_matcher kissm_matcher;

/**
 * @brief Creates a matcher. The config is validated (as by kissm_config_validate()) and copied.
 * @param[in] config The settings; NULL = defaults.
 * @param[out] out_matcher The new matcher, for kissm_destroy().
 * @retval KISSM_OK Done.
 * @retval KISSM_ERR_NULL_ARGUMENT @p out_matcher is NULL.
 * @retval KISSM_ERR_INVALID_ARGUMENT, KISSM_ERR_STRUCT_SIZE @p config fails kissm_config_validate().
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_create(const kissm_config *config, kissm_matcher **out_matcher);
/**
 * @brief Destroys a matcher.
 * @param[in] matcher A matcher from kissm_create(); NULL is fine.
 */
KISSM_API void kissm_destroy(kissm_matcher *matcher);
/**
 * @brief Copies the matcher's config into *out_config (whose struct_size the caller sets).
 * @param[in] matcher The matcher.
 * @param[in,out] out_config Its struct_size is read (sizeof(kissm_config)); then it is overwritten.
 * @retval KISSM_OK Done.
 * @retval KISSM_ERR_NULL_ARGUMENT @p matcher or @p out_config is NULL.
 * @retval KISSM_ERR_STRUCT_SIZE out_config->struct_size is too small or above 65536.
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_get_config(const kissm_matcher *matcher, kissm_config *out_config);

/**
 * @brief Global registration of source against target. The result is always fully overwritten.
 *
 * Returns #KISSM_OK whenever the inputs were acceptable, including when result->valid is 0.
 * @param[in,out] matcher The matcher (its settings; one call at a time).
 * @param[in] source The cloud to move; read during the call only.
 * @param[in] target The cloud it is registered against; read during the call only.
 * @param[in,out] result Its struct_size is read (sizeof(kissm_result)); then it is fully overwritten.
 * @retval KISSM_OK The inputs were acceptable; result->valid says whether the pose can be trusted.
 * @retval KISSM_ERR_NULL_ARGUMENT A pointer argument, or source->data or target->data, is NULL.
 * @retval KISSM_ERR_STRUCT_SIZE result->struct_size is smaller than sizeof(kissm_result) or above 65536.
 * @retval KISSM_ERR_INVALID_ARGUMENT A kissm_points field is out of range (scalar_type, reserved, count,
 *         stride_bytes).
 * @retval KISSM_ERR_EMPTY_INPUT A cloud has no points (or none left after dropping non-finite ones).
 * @retval KISSM_ERR_TOO_FEW_POINTS A cloud has fewer than #KISSM_MIN_POINTS points.
 * @retval KISSM_ERR_NONFINITE A NaN or infinite coordinate under #KISSM_NONFINITE_REJECT.
 * @retval KISSM_ERR_VOXEL_RANGE The voxel size is too small for a cloud's extent.
 * @retval KISSM_ERR_CANCELLED kissm_cancel() or the progress callback stopped the call.
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_register(kissm_matcher *matcher, const kissm_points *source, const kissm_points *target,
                                 kissm_result *result);

/**
 * @brief Requests that the call running on matcher stop with #KISSM_ERR_CANCELLED. Safe from any thread.
 *
 * A request made while no call is running is cleared when the next call starts.
 * @param[in] matcher The matcher; NULL is ignored.
 */
KISSM_API void kissm_cancel(kissm_matcher *matcher);

/**
 * @brief Fine registration from a known pose (tracking, re-localisation from a prior): voxelises both clouds,
 *        estimates their normals and refines @p initial_transform with kissm_config.refine_mode (GICP when it
 *        is #KISSM_REFINE_NONE). No descriptors, no global search.
 *
 * result->coarse_transform is the initial transform; result->transform the refined pose; valid = 1 when the
 * refined pose passes the refined rule (overlap, conditioning, convergence) and otherwise 0 with a reason; it
 * trusts the prior (docs/refinement.md: from priors within about 10 degrees and 3 voxels it is right). Keypoint counts
 * are 0 (no descriptors are computed) and time_features_ms is the time of the normals. The result is always
 * fully overwritten.
 * @param[in,out] matcher The matcher (its settings; one call at a time).
 * @param[in] source The cloud to move; read during the call only.
 * @param[in] target The cloud it is registered against; read during the call only.
 * @param[in] initial_transform 4x4 row-major, p_target = R p_source + t: finite, R a rotation (orthonormal to
 *            1e-3, det +1), last row (0, 0, 0, 1), |t| at most 1e9.
 * @param[in,out] result Its struct_size is read (sizeof(kissm_result)); then it is fully overwritten.
 * @retval KISSM_OK The inputs were acceptable; result->valid says whether the refined pose can be trusted.
 * @retval KISSM_ERR_NULL_ARGUMENT A pointer argument, or source->data or target->data, is NULL.
 * @retval KISSM_ERR_STRUCT_SIZE result->struct_size is smaller than sizeof(kissm_result) or above 65536.
 * @retval KISSM_ERR_INVALID_ARGUMENT @p initial_transform is not finite or not rigid, or a kissm_points field
 *         is out of range.
 * @retval KISSM_ERR_EMPTY_INPUT, KISSM_ERR_TOO_FEW_POINTS, KISSM_ERR_NONFINITE, KISSM_ERR_VOXEL_RANGE As
 *         for kissm_register().
 * @retval KISSM_ERR_CANCELLED kissm_cancel() or the progress callback stopped the call.
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_refine(kissm_matcher *matcher, const kissm_points *source, const kissm_points *target,
                               const double initial_transform[16], kissm_result *result);

/**
 * @brief Which points of a cloud the ground model of #KISSM_SUPPRESS_GROUND labels ground, under the matcher's
 *        voxel_size, up, viewpoint (the sensor) and sensor_height, whatever its kissm_config.suppression.
 *
 * The model runs on the voxels, so every point of a voxel gets the voxel's label; points dropped as
 * non-finite (#KISSM_NONFINITE_DROP) get 0. Deterministic: the same bytes for any num_threads. On error
 * @p out_mask is unchanged.
 * @param[in,out] matcher The matcher (its settings; one call at a time).
 * @param[in] points The cloud, in its own frame; read during the call only.
 * @param[out] out_mask points->count bytes: 1 for a ground point, else 0.
 * @retval KISSM_OK Done (a cloud without ground gets all zeros).
 * @retval KISSM_ERR_NULL_ARGUMENT @p matcher, @p points, points->data or @p out_mask is NULL.
 * @retval KISSM_ERR_INVALID_ARGUMENT A kissm_points field is out of range.
 * @retval KISSM_ERR_EMPTY_INPUT, KISSM_ERR_TOO_FEW_POINTS, KISSM_ERR_NONFINITE, KISSM_ERR_VOXEL_RANGE As
 *         for kissm_register().
 * @retval KISSM_ERR_CANCELLED kissm_cancel() or the progress callback stopped the call.
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_ground_mask(kissm_matcher *matcher, const kissm_points *points, uint8_t *out_mask);

/** @} */

/**
 * @brief Suggests a voxel size for clouds that are to be described alike: one cloud, a pair (source and target,
 *        in either order) or a set of scans.
 *
 * Each cloud's own voxel is the smallest of 2^(k/8) metres (k an integer) at which its grid holds at most 3000
 * occupied voxels, or 2000 for a compact cloud (an object scan or an indoor fragment: one whose 3000 voxels cover
 * the area of their two largest principal spreads densely); a quarter of its points when it has fewer than 4 times
 * as many. The suggestion is the clouds' own lower median (the smaller of a pair), raised if needed to keep every
 * cloud within the voxel grid's range. It depends on the points
 * alone, not on their order nor the clouds' order, and not on any thread count. Non-finite points are ignored.
 * The rule and its evidence: docs/design/voxel_auto.md. kissm_config.voxel_size = 0 applies it in every call.
 * @param[in] clouds @p num_clouds clouds; read during the call only.
 * @param[in] num_clouds 1 to 65536.
 * @param[out] out_voxel_size The suggestion, > 0; written only on success.
 * @retval KISSM_OK Done.
 * @retval KISSM_ERR_NULL_ARGUMENT @p clouds, a cloud's data or @p out_voxel_size is NULL.
 * @retval KISSM_ERR_INVALID_ARGUMENT @p num_clouds is 0 or above 65536, or a kissm_points field is out of range.
 * @retval KISSM_ERR_EMPTY_INPUT A cloud has no finite point.
 * @retval KISSM_ERR_TOO_FEW_POINTS A cloud has fewer than 4 finite points, or they all coincide.
 * @retval KISSM_ERR_VOXEL_RANGE A cloud's finite points span more than a double holds, or so little that no voxel
 *         grid fits them.
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_suggest_voxel_size(const kissm_points *clouds, uint64_t num_clouds, double *out_voxel_size);

/* ------------------------------------------------------------------------------------------------ */
/* Features: a cloud described once, matched against many                                           */
/* ------------------------------------------------------------------------------------------------ */

/**
 * @defgroup features Features
 * @brief A cloud described once, matched against many.
 * @{
 */

/** @brief Immutable once created; may be used from several threads at once and outlive the matcher. */
typedef struct kissm_features kissm_features;

/**
 * @brief Voxelises and describes one cloud under the matcher's configuration.
 * @param[in,out] matcher The matcher (its settings; one call at a time).
 * @param[in] cloud The cloud; read during the call only.
 * @param[out] out_features The features, for kissm_features_destroy().
 * @retval KISSM_OK Done.
 * @retval KISSM_ERR_NULL_ARGUMENT @p matcher, @p cloud, cloud->data or @p out_features is NULL.
 * @retval KISSM_ERR_INVALID_ARGUMENT A kissm_points field is out of range.
 * @retval KISSM_ERR_EMPTY_INPUT, KISSM_ERR_TOO_FEW_POINTS, KISSM_ERR_NONFINITE, KISSM_ERR_VOXEL_RANGE As
 *         for kissm_register().
 * @retval KISSM_ERR_CANCELLED kissm_cancel() or the progress callback stopped the call.
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_features_compute(kissm_matcher *matcher, const kissm_points *cloud,
                                         kissm_features **out_features);
/**
 * @brief Destroys features.
 * @param[in] features Features from kissm_features_compute(); NULL is fine.
 */
KISSM_API void kissm_features_destroy(kissm_features *features);
/**
 * @brief Points of the cloud the features were computed from.
 * @param[in] features The features.
 * @return The number of points; 0 for NULL.
 */
KISSM_API uint64_t kissm_features_num_points(const kissm_features *features);
/**
 * @brief Occupied voxels of the described cloud.
 * @param[in] features The features.
 * @return The number of voxels; 0 for NULL.
 */
KISSM_API uint64_t kissm_features_num_voxels(const kissm_features *features);
/**
 * @brief Voxels with a descriptor.
 * @param[in] features The features.
 * @return The number of keypoints; 0 for NULL.
 */
KISSM_API uint64_t kissm_features_num_keypoints(const kissm_features *features);
/**
 * @brief Memory the features hold: voxels, normals, descriptors and their search index (and the voxels'
 *        index when the matcher refines), in bytes.
 * @param[in] features The features.
 * @return The number of bytes; 0 for NULL.
 */
KISSM_API uint64_t kissm_features_memory_bytes(const kissm_features *features);
/**
 * @brief Registration of two described clouds: same pose, counts and validity as kissm_register() on the
 *        clouds the features were computed from.
 *
 * Voxelisation and feature times are reported as 0. The result is always fully overwritten. Features carry
 * the search index of their descriptors, so a large cloud described once (a map) is not indexed again: the
 * call costs about in proportion to the side with fewer keypoints, times the log of the other side's
 * (docs/design/frames.md, "Scan-to-map cost").
 * @param[in,out] matcher The matcher (its settings; one call at a time).
 * @param[in] source Features of the cloud to move.
 * @param[in] target Features of the cloud it is registered against.
 * @param[in,out] result Its struct_size is read (sizeof(kissm_result)); then it is fully overwritten.
 * @retval KISSM_OK The inputs were acceptable; result->valid says whether the pose can be trusted.
 * @retval KISSM_ERR_NULL_ARGUMENT A pointer argument is NULL.
 * @retval KISSM_ERR_STRUCT_SIZE result->struct_size is smaller than sizeof(kissm_result) or above 65536.
 * @retval KISSM_ERR_FEATURES_MISMATCH Either was computed under a config whose descriptor parameters differ
 *         from matcher's.
 * @retval KISSM_ERR_CANCELLED kissm_cancel() or the progress callback stopped the call.
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_register_features(kissm_matcher *matcher, const kissm_features *source,
                                          const kissm_features *target, kissm_result *result);
/**
 * @brief kissm_refine() on described clouds: the same result as kissm_refine() on the clouds the features were
 *        computed from (keypoint counts 0 as there), bit for bit but for the times. Features computed with
 *        refinement enabled carry the index refinement searches, so a map described once is not indexed again.
 *
 * Voxelisation and feature times are reported as 0. The result is always fully overwritten.
 * @param[in,out] matcher The matcher (its settings; one call at a time).
 * @param[in] source Features of the cloud to move.
 * @param[in] target Features of the cloud it is registered against.
 * @param[in] initial_transform As for kissm_refine().
 * @param[in,out] result Its struct_size is read (sizeof(kissm_result)); then it is fully overwritten.
 * @retval KISSM_OK The inputs were acceptable; result->valid says whether the refined pose can be trusted.
 * @retval KISSM_ERR_NULL_ARGUMENT A pointer argument is NULL.
 * @retval KISSM_ERR_STRUCT_SIZE result->struct_size is smaller than sizeof(kissm_result) or above 65536.
 * @retval KISSM_ERR_INVALID_ARGUMENT @p initial_transform is not finite or not rigid.
 * @retval KISSM_ERR_FEATURES_MISMATCH Either was computed under a config whose descriptor parameters differ
 *         from matcher's.
 * @retval KISSM_ERR_CANCELLED kissm_cancel() or the progress callback stopped the call.
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_refine_features(kissm_matcher *matcher, const kissm_features *source,
                                        const kissm_features *target, const double initial_transform[16],
                                        kissm_result *result);
/**
 * @brief Writes features as bytes that kissm_features_deserialize() reads back on any machine: a versioned,
 *        little-endian format with a checksum (docs/features-format.md).
 *
 * The bytes hold the voxels, normals, descriptors and counts, and the descriptor settings they were computed
 * under (so features loaded elsewhere still fail with #KISSM_ERR_FEATURES_MISMATCH against a matcher of other
 * settings); the search indexes are not stored but rebuilt on load. The same features always give the same
 * bytes. Call it first with @p buffer NULL to learn the size.
 * @param[in] features The features.
 * @param[out] buffer Where the bytes go, or NULL to ask for the size only (then @p capacity is ignored).
 * @param[in] capacity Bytes available at @p buffer.
 * @param[out] out_size The size of the bytes, written or needed. Also written when @p capacity is too small,
 *             so that the caller can grow the buffer (the one exception to "nothing is written on failure").
 * @retval KISSM_OK The bytes were written (or, for a NULL @p buffer, *out_size is the size they need).
 * @retval KISSM_ERR_NULL_ARGUMENT @p features or @p out_size is NULL.
 * @retval KISSM_ERR_INVALID_ARGUMENT @p capacity is smaller than the size needed; nothing is written to
 *         @p buffer and *out_size is the size needed.
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_features_serialize(const kissm_features *features, void *buffer, uint64_t capacity,
                                           uint64_t *out_size);
/**
 * @brief Features from bytes written by kissm_features_serialize(), possibly by another process or machine.
 *
 * The bytes are not trusted: everything is bounds-checked and validated (magic, version, checksum, counts,
 * indices, finite values), so truncated, corrupted or forged input fails with a message and is never read
 * beyond @p size. The features' search indexes are rebuilt (on the calling thread), so registering the loaded
 * features gives bit for bit the result of the original ones.
 * @param[in] bytes The bytes; read during the call only.
 * @param[in] size Their number: exactly what kissm_features_serialize() wrote (trailing bytes are refused).
 * @param[out] out_features The features, for kissm_features_destroy(); untouched on failure.
 * @retval KISSM_OK Done.
 * @retval KISSM_ERR_NULL_ARGUMENT @p bytes or @p out_features is NULL.
 * @retval KISSM_ERR_PARSE The bytes are not features of this format version, are truncated or corrupted
 *         (checksum), or hold a value the library cannot have written; the message names it and its byte
 *         offset.
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_features_deserialize(const void *bytes, uint64_t size, kissm_features **out_features);

/** @brief Numbers in a signature (kissm_features_signature()). */
#define KISSM_SIGNATURE_SIZE 82
/**
 * @brief A fixed-length summary of the features for finding scans that see the same place: the Euclidean
 *        distance between two clouds' signatures is small when they overlap (loop candidates among thousands
 *        of scans, docs/multiway.md "Loop candidates by similarity").
 *
 * Three blocks, each of unit length: the mean of the keypoints' FPFH descriptors (33 numbers), their standard
 * deviation per bin (33), and the square roots of the shares of keypoints per band of 12 voxels of distance from
 * the keypoints' centroid (16, the last band open). It depends on no coordinate frame (a rotated or moved cloud
 * gives nearly the same numbers; voxelisation differs a little), is computed from what the features serialise
 * (loaded features give the same bits), on the calling thread in a fixed order (the same bits whatever the
 * matcher's threads), and costs a pass over the keypoints. Features without keypoints give all zeros. Compare
 * signatures of features computed with the same voxel size only.
 * @param[in] features The features.
 * @param[out] out_signature #KISSM_SIGNATURE_SIZE numbers; untouched on failure.
 * @retval KISSM_OK Done.
 * @retval KISSM_ERR_NULL_ARGUMENT @p features or @p out_signature is NULL.
 * @retval KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_features_signature(const kissm_features *features, double *out_signature);

/** @} */

/* ------------------------------------------------------------------------------------------------ */
/* Point files: PLY (ascii, binary), PCD (ascii, binary), KITTI .bin (float32 xyzi), .npy (float32 /  */
/* float64, shape (N, 3) or (N, >=3)), whitespace xyz text (.xyz, .txt, .pts, .asc)                   */
/* ------------------------------------------------------------------------------------------------ */

/**
 * @defgroup files Point files
 * @brief Reading clouds: PLY (ascii, binary), PCD (ascii, binary), KITTI .bin (float32 xyzi), .npy
 *        (float32 / float64, shape (N, 3) or (N, >=3)), whitespace xyz text (.xyz, .txt, .pts, .asc), LAS 1.0-1.4
 *        (.las; .laz when built with KISSM_WITH_LAZ).
 * @{
 */

#define KISSM_FORMAT_AUTO 0      /**< By extension, then by content. */
#define KISSM_FORMAT_PLY 1       /**< PLY, ascii or binary. */
#define KISSM_FORMAT_PCD 2       /**< PCD, ascii or binary. */
#define KISSM_FORMAT_KITTI_BIN 3 /**< float32 x y z intensity. */
#define KISSM_FORMAT_NPY 4       /**< .npy, float32 or float64, shape (N, 3) or (N, >=3). */
#define KISSM_FORMAT_XYZ 5       /**< Whitespace-separated xyz text. */
#define KISSM_FORMAT_BIN_XYZ 6   /**< float32 x y z, no intensity. */
/**
 * ASPRS LAS 1.0-1.4, point data record formats 0-10: x y z only, scale and offset applied in double
 * precision; points flagged withheld are left out. LAZ (LASzip-compressed LAS, the same header) is read when
 * the library was built with the CMake option KISSM_WITH_LAZ (off by default); otherwise it fails with
 * #KISSM_ERR_UNSUPPORTED_FORMAT ("LAZ support was not built in").
 */
#define KISSM_FORMAT_LAS 7

/** @brief A cloud owned by the library, as read from a file: float64 xyz, packed. */
typedef struct kissm_cloud kissm_cloud;

/**
 * @brief Reads a point file. Non-finite points are kept as they are (the registration policy decides).
 * @param[in] path The file, UTF-8.
 * @param[in] format A KISSM_FORMAT_* value; #KISSM_FORMAT_AUTO detects it.
 * @param[out] out_cloud The cloud, for kissm_cloud_destroy().
 * @retval KISSM_OK Done.
 * @retval KISSM_ERR_NULL_ARGUMENT @p path or @p out_cloud is NULL.
 * @retval KISSM_ERR_INVALID_ARGUMENT @p format is not a KISSM_FORMAT_* value.
 * @retval KISSM_ERR_IO The file could not be opened or read.
 * @retval KISSM_ERR_PARSE The file is malformed, truncated or of an unsupported layout.
 * @retval KISSM_ERR_UNSUPPORTED_FORMAT The file's format is not recognised, or it is LAZ and this library
 *         was built without LAZ support.
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_read_points(const char *path, int32_t format, kissm_cloud **out_cloud);
/**
 * @brief Destroys a cloud.
 * @param[in] cloud A cloud from kissm_read_points(); NULL is fine.
 */
KISSM_API void kissm_cloud_destroy(kissm_cloud *cloud);
/**
 * @brief Number of points of a cloud.
 * @param[in] cloud The cloud.
 * @return The number of points; 0 for NULL.
 */
KISSM_API uint64_t kissm_cloud_count(const kissm_cloud *cloud);
/**
 * @brief Number of points the reader left out of the cloud on purpose: for LAS and LAZ, the points flagged
 *        withheld (not in kissm_cloud_count()); 0 for every other format, which leaves nothing out.
 * @param[in] cloud The cloud.
 * @return The number of points left out; 0 for NULL.
 */
KISSM_API uint64_t kissm_cloud_num_withheld(const kissm_cloud *cloud);
/**
 * @brief The cloud's coordinates.
 * @param[in] cloud The cloud.
 * @return Pointer to count * 3 doubles (x, y, z per point), valid until kissm_cloud_destroy(); NULL for
 *         NULL or an empty cloud.
 */
KISSM_API const double *kissm_cloud_data(const kissm_cloud *cloud);
/**
 * @brief Fills a kissm_points view of the cloud (float64, packed), valid until kissm_cloud_destroy().
 * @param[in] cloud The cloud.
 * @param[out] out_points The view.
 * @retval KISSM_OK Done.
 * @retval KISSM_ERR_NULL_ARGUMENT @p cloud or @p out_points is NULL.
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_cloud_points(const kissm_cloud *cloud, kissm_points *out_points);

/** @} */

/* ------------------------------------------------------------------------------------------------ */
/* Pose graphs: many relative poses made into one consistent set of absolute ones                     */
/* ------------------------------------------------------------------------------------------------ */

/**
 * @defgroup pose_graph Pose graphs
 * @brief Nodes are scans, edges relative poses between them (a registration's transform and information, an
 *        odometry step, a user's constraint). kissm_pose_graph_optimize() finds every node's pose in the frame of
 *        an anchor node: Levenberg-Marquardt on SE(3) over the sparse normal equations, and for the edges added as
 *        robust, graduated non-convexity with a truncated least-squares cost, so that a wrong loop closure ends
 *        rejected instead of bending the map (docs/pose-graph.md).
 *
 * An edge from source s to target t with transform T and information I states T = inv(X_t) X_s for the nodes'
 * world-from-node poses X, with the error xi = Log(inv(T) inv(X_t) X_s), rotation first, in the source's frame
 * (kissm_result's convention, and GTSAM's BetweenFactor<Pose3>(t, s, T) with I as its information). A
 * graph is used by one thread at a time (kissm_pose_graph_cancel() excepted).
 * @{
 */

/** @brief A pose graph: nodes, edges, and the solution of its last optimisation. */
typedef struct kissm_pose_graph kissm_pose_graph;

/** Most nodes a graph may have. */
#define KISSM_POSE_GRAPH_MAX_NODES 100000000
/** The default bound on a robust edge's squared error xi^T I xi at which truncated least squares rejects it: the
 * 99.9% quantile of a chi-square with 6 degrees of freedom (a right edge with a calibrated information exceeds it
 * once in a thousand). */
#define KISSM_POSE_GRAPH_DEFAULT_BOUND 22.4577

/**
 * @brief Creates a graph of @p num_nodes nodes, numbered 0 to num_nodes - 1, with no edges.
 * @param[in] num_nodes 1 to #KISSM_POSE_GRAPH_MAX_NODES.
 * @param[out] out_graph The graph, for kissm_pose_graph_destroy().
 * @retval KISSM_OK Done.
 * @retval KISSM_ERR_NULL_ARGUMENT @p out_graph is NULL.
 * @retval KISSM_ERR_INVALID_ARGUMENT @p num_nodes is 0 or above #KISSM_POSE_GRAPH_MAX_NODES.
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_pose_graph_create(uint64_t num_nodes, kissm_pose_graph **out_graph);
/**
 * @brief Destroys a graph.
 * @param[in] graph A graph from kissm_pose_graph_create(); NULL is fine.
 */
KISSM_API void kissm_pose_graph_destroy(kissm_pose_graph *graph);
/**
 * @brief Number of nodes of a graph.
 * @param[in] graph The graph.
 * @return The number of nodes; 0 for NULL.
 */
KISSM_API uint64_t kissm_pose_graph_num_nodes(const kissm_pose_graph *graph);
/**
 * @brief Number of edges of a graph.
 * @param[in] graph The graph.
 * @return The number of edges; 0 for NULL.
 */
KISSM_API uint64_t kissm_pose_graph_num_edges(const kissm_pose_graph *graph);
/**
 * @brief Adds an edge; edges are numbered in the order they are added, from 0. Forgets the last solution.
 * @param[in,out] graph The graph.
 * @param[in] source The source node (the node whose points the transform moves).
 * @param[in] target The target node, not @p source.
 * @param[in] transform T_target_source, 4x4 row-major, rigid (as kissm_register() checks an initial transform).
 * @param[in] information 6x6 row-major, symmetric (to 1e-9 of its largest entry) and positive definite: the
 *            inverse covariance of xi, rotation first, in the source's frame (kissm_result.information as it is).
 * @param[in] robust 1: a candidate that may be wrong (a loop closure), which the optimisation may reject; 0: a
 *            trusted edge (odometry, a user's constraint), always kept.
 * @param[out] out_edge The edge's number; may be NULL.
 * @retval KISSM_OK Done.
 * @retval KISSM_ERR_NULL_ARGUMENT @p graph, @p transform or @p information is NULL.
 * @retval KISSM_ERR_INVALID_ARGUMENT A node is not in the graph, @p source equals @p target, @p transform is not
 *         finite and rigid, @p information is not finite, symmetric and positive definite, or @p robust is not 0
 *         or 1.
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 * On an error the graph is unchanged.
 */
KISSM_API int32_t kissm_pose_graph_add_edge(kissm_pose_graph *graph, uint64_t source, uint64_t target,
                                            const double transform[16], const double information[36], int32_t robust,
                                            uint64_t *out_edge);
/**
 * @brief Optimises the graph: the nodes joined to @p anchor get poses in its frame (its own is the identity).
 *
 * The start is a spanning tree from the anchor (trusted edges first, then the most informative), then robust
 * edges are weighed by graduated non-convexity: an edge whose squared error xi^T I xi ends above @p bound is
 * rejected. A node is placed when accepted edges join it to the anchor; the others get NaN poses, never a
 * guess. The same graph gives the same bits on every run.
 * @param[in,out] graph The graph.
 * @param[in] anchor The node whose frame the poses are in.
 * @param[in] bound The squared error at which a robust edge is rejected, finite and above 0
 *            (#KISSM_POSE_GRAPH_DEFAULT_BOUND for calibrated informations).
 * @retval KISSM_OK Done; read the solution with kissm_pose_graph_poses() and kissm_pose_graph_edges().
 * @retval KISSM_ERR_NULL_ARGUMENT @p graph is NULL.
 * @retval KISSM_ERR_INVALID_ARGUMENT @p anchor is not in the graph, or @p bound is not a finite number above 0
 *         (the graph keeps its last solution).
 * @retval KISSM_ERR_CANCELLED kissm_pose_graph_cancel() stopped it (the graph keeps no solution).
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_pose_graph_optimize(kissm_pose_graph *graph, uint64_t anchor, double bound);
/**
 * @brief Stops a running kissm_pose_graph_optimize() of @p graph; callable from any thread. A request made
 *        before the call starts is dropped.
 * @param[in] graph The graph; NULL is fine.
 */
KISSM_API void kissm_pose_graph_cancel(kissm_pose_graph *graph);
/**
 * @brief The nodes of the last solution. Any output may be NULL.
 * @param[in] graph The graph.
 * @param[out] out_poses num_nodes 4x4 row-major world-from-node poses (world = the anchor's frame), packed; NaN
 *             for a node that is not placed.
 * @param[out] out_placed num_nodes flags: 1 when accepted edges join the node to the anchor.
 * @param[out] out_components num_nodes labels: the smallest node joined to it by accepted and trusted edges (the
 *             anchor's component is the placed nodes).
 * @retval KISSM_OK Done.
 * @retval KISSM_ERR_NULL_ARGUMENT @p graph is NULL.
 * @retval KISSM_ERR_INVALID_ARGUMENT The graph has no solution (never optimised, changed since, or cancelled).
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_pose_graph_poses(const kissm_pose_graph *graph, double *out_poses, uint8_t *out_placed,
                                         uint64_t *out_components);
/**
 * @brief The edges of the last solution, in the order they were added. Any output may be NULL.
 * @param[in] graph The graph.
 * @param[out] out_accepted num_edges flags: 1 for a trusted edge and an accepted robust one, 0 for a rejected one
 *             and for an edge outside the anchor's component.
 * @param[out] out_residuals num_edges squared errors xi^T I xi at the solution; NaN where a node is not placed.
 * @retval KISSM_OK Done.
 * @retval KISSM_ERR_NULL_ARGUMENT @p graph is NULL.
 * @retval KISSM_ERR_INVALID_ARGUMENT The graph has no solution (never optimised, changed since, or cancelled).
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_pose_graph_edges(const kissm_pose_graph *graph, uint8_t *out_accepted, double *out_residuals);

/** @} */

/* ------------------------------------------------------------------------------------------------ */
/* Multiway alignment: many scans into one frame                                                    */
/* ------------------------------------------------------------------------------------------------ */

/**
 * @defgroup align Multiway alignment
 * @brief Many scans registered into the first one's frame with no initial guess: pairs chosen by a policy,
 *        registered from their features, their valid poses made edges of a pose graph and optimised
 *        (docs/multiway.md). kissm_align_features() is the whole job in one call, as Python's
 *        kissm.multiway.align and `kissm align` run it: the same features, settings and pairs give the same bits
 *        in all three. kissm_sequence_loops() is its loop-candidate rule alone, for a job of one's own.
 * @{
 */

/** @name Pair policies (kissm_align_options.pairs) */
/** @{ */
/** Every pair once, the later scan the source: (j, i) for i < j, i outer. Sensible up to some tens of scans. */
#define KISSM_PAIRS_ALL 0
/** Scans in acquisition order: each with the next (k+1, k), then the loop candidates kissm_sequence_loops() gives
 * for those registrations (or for kissm_align_options.priors), so the work grows with the scans, not their square;
 * without priors, where the chain breaks, also kissm_sequence_similar()'s (kissm_align_options.similar_per_scan),
 * the registrations between pieces filtered by kissm_sequence_corroborated(). */
#define KISSM_PAIRS_SEQUENCE 1
/** The pairs of kissm_align_options.pair_list, in its order. */
#define KISSM_PAIRS_LIST 2
/** Several sessions (drives, robots, survey days) merged, the scans ordered session by session
 * (kissm_align_options.sessions): each session's consecutive pairs as trusted odometry (a valid one is taken as
 * right), its loop candidates as #KISSM_PAIRS_SEQUENCE finds them, a grid of every stride-th scan of a later
 * session with every stride-th scan of each earlier one; then, once the graph places a later session, its scans
 * with the loops_per_scan nearest placed scans of earlier sessions within loop_radius, and one more optimisation.
 * Python's kissm.multiway.align_sessions. */
#define KISSM_PAIRS_SESSIONS 3
/** @} */

/**
 * @brief Settings of kissm_align_features(). Fill it with kissm_align_options_init(), then change what you need.
 *        The arrays it points to are read during the call only.
 */
typedef struct kissm_align_options {
    /** sizeof(kissm_align_options) as the caller knows it; set by kissm_align_options_init(). */
    uint32_t struct_size;
    /** A KISSM_PAIRS_* policy. Default #KISSM_PAIRS_ALL. */
    int32_t pairs;
    /** #KISSM_PAIRS_LIST: num_pairs (source, target) scan positions, packed; otherwise NULL. Default NULL. */
    const uint64_t *pair_list;
    /** #KISSM_PAIRS_LIST: the number of pairs, 0 to 100,000,000; otherwise 0. Default 0. */
    uint64_t num_pairs;
    /** #KISSM_PAIRS_SEQUENCE: NULL, or num_scans 4x4 row-major world <- scan poses (GNSS, a SLAM run) whose
     * positions choose the loop candidates instead of the chained registrations; a pose with a non-finite
     * translation marks a scan without one. Otherwise NULL. Default NULL. */
    const double *priors;
    /** #KISSM_PAIRS_SEQUENCE: a loop candidate's scans lie within this distance (the clouds' unit) of each other;
     * > 0, finite, or 0 for 30 voxels (the matcher's voxel_size). Default 0. */
    double loop_radius;
    /** #KISSM_PAIRS_SEQUENCE: a loop candidate's scans are at least this many apart in the sequence; 1 to
     * 1,000,000. Default 10. */
    int32_t loop_gap;
    /** #KISSM_PAIRS_SEQUENCE: at most this many candidates per scan (the nearest); 0 (none) to 1,000,000.
     * Default 5. */
    int32_t loops_per_scan;
    /** The pose graph's bound (kissm_pose_graph_optimize()); finite, > 0. Default
     * #KISSM_POSE_GRAPH_DEFAULT_BOUND. */
    double bound;
    /** #KISSM_PAIRS_SESSIONS: num_scans session numbers, the scans in session order: sessions[0] = 0, each next one
     * equal to or 1 above the one before. Otherwise NULL. Default NULL. */
    const uint32_t *sessions;
    /** #KISSM_PAIRS_SESSIONS: the grid across sessions takes every stride-th scan of each; 1 to 1,000,000.
     * Default 10. */
    int32_t stride;
    /** 0. */
    int32_t reserved;
    /** #KISSM_PAIRS_SEQUENCE without priors: where the chained registrations break into pieces, each scan's loop
     * candidates also include the similar_per_scan scans of other pieces, at least loop_gap back, whose signatures
     * (kissm_features_signature()) are the nearest, and of the valid registrations between two pieces only the
     * largest set that agrees joins the graph (kissm_sequence_similar(), kissm_sequence_corroborated()); 0 (none)
     * to 1,000,000. Read by #KISSM_PAIRS_SEQUENCE only. Default 3. */
    int32_t similar_per_scan;
    /** 0. */
    int32_t reserved2;
    /* New fields are only ever appended here. */
} kissm_align_options;

/**
 * @brief Writes the documented defaults into the first struct_size bytes of *options and sets
 *        options->struct_size = struct_size.
 * @param[out] options The struct to fill.
 * @param[in] struct_size Pass sizeof(kissm_align_options).
 * @retval KISSM_OK Done.
 * @retval KISSM_ERR_NULL_ARGUMENT @p options is NULL.
 * @retval KISSM_ERR_STRUCT_SIZE @p struct_size is smaller than this struct, or above 65536.
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_align_options_init(kissm_align_options *options, uint32_t struct_size);

/** @brief The outcome of kissm_align_features(): the scans' poses and every registration with its edge. */
typedef struct kissm_alignment kissm_alignment;

/**
 * @brief Registers the pairs the policy chooses, makes each valid pose a robust edge of a pose graph and optimises
 *        it from scan 0: every scan joined to scan 0 by accepted edges gets its pose in scan 0's frame, the others
 *        none (NaN), never a guess.
 *
 * Each registration is kissm_register_features() with @p matcher's settings; set refine_mode to
 * #KISSM_REFINE_GICP for edges weighed by their information (a coarse pose's edge gets an isotropic one from its
 * rotation_uncertainty, at least 1e-4 rad, and a translation sigma of its noise_bound). The pairs run on the
 * matcher's threads, one pair per thread; the result does not depend on their number. kissm_cancel() on @p matcher
 * stops the call; the matcher's progress callback is not called (its log callback is not either).
 * @param[in,out] matcher The registrations' settings; the features must have been computed under its descriptor
 *                settings (else #KISSM_ERR_FEATURES_MISMATCH, before any registration).
 * With #KISSM_PAIRS_SESSIONS the consecutive pairs within a session are trusted edges (always accepted when
 * valid); every other edge is robust.
 * @param[in] features num_scans features, in order (scan 0 is the anchor); a NULL entry is a scan that could not
 *            be described: no pair with it is registered, and it is not placed.
 * @param[in] num_scans 1 to #KISSM_POSE_GRAPH_MAX_NODES.
 * @param[in] options The pair policy and its settings; NULL for the defaults.
 * @param[out] out_alignment The outcome, for kissm_alignment_destroy(); NULL on an error.
 * @retval KISSM_OK Done.
 * @retval KISSM_ERR_NULL_ARGUMENT @p matcher, @p features or @p out_alignment is NULL, or a policy's array is.
 * @retval KISSM_ERR_INVALID_ARGUMENT An option is out of its range, a listed pair names a scan out of range or
 *         pairs a scan with itself, or an option is given that the policy does not read.
 * @retval KISSM_ERR_STRUCT_SIZE options->struct_size is not this struct's, or above 65536.
 * @retval KISSM_ERR_FEATURES_MISMATCH Some features were not computed under @p matcher's descriptor settings.
 * @retval KISSM_ERR_CANCELLED kissm_cancel() stopped it.
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_align_features(kissm_matcher *matcher, const kissm_features *const *features,
                                       uint64_t num_scans, const kissm_align_options *options,
                                       kissm_alignment **out_alignment);
/**
 * @brief Destroys an alignment.
 * @param[in] alignment From kissm_align_features(); NULL is fine.
 */
KISSM_API void kissm_alignment_destroy(kissm_alignment *alignment);
/**
 * @brief Number of scans of an alignment.
 * @param[in] alignment The alignment.
 * @return The number of scans; 0 for NULL.
 */
KISSM_API uint64_t kissm_alignment_num_scans(const kissm_alignment *alignment);
/**
 * @brief Number of registrations an alignment ran (the pairs with features on both sides, in the order they ran).
 * @param[in] alignment The alignment.
 * @return The number of registrations; 0 for NULL.
 */
KISSM_API uint64_t kissm_alignment_num_registrations(const kissm_alignment *alignment);
/**
 * @brief The scans' poses, as kissm_pose_graph_poses() gives them. Any output may be NULL.
 * @param[in] alignment The alignment.
 * @param[out] out_poses num_scans 4x4 row-major world <- scan poses (world = scan 0's frame), packed; NaN for a
 *             scan that is not placed.
 * @param[out] out_placed num_scans flags: 1 when accepted edges join the scan to scan 0.
 * @param[out] out_components num_scans labels: the smallest scan joined to it by accepted edges.
 * @retval KISSM_OK Done.
 * @retval KISSM_ERR_NULL_ARGUMENT @p alignment is NULL.
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_alignment_poses(const kissm_alignment *alignment, double *out_poses, uint8_t *out_placed,
                                        uint64_t *out_components);
/**
 * @brief One registration of an alignment and its edge. Any output may be NULL.
 * @param[in] alignment The alignment.
 * @param[in] index 0 to kissm_alignment_num_registrations() - 1.
 * @param[out] out_source The source scan (the one the transform moves).
 * @param[out] out_target The target scan.
 * @param[out] out_result The registration, as kissm_register_features() wrote it (struct_size set by
 *             kissm_result_init()).
 * @param[out] out_edge -1 when the registration is not an edge (not valid), 0 for a rejected edge (or one held out
 *             of the graph: a registration between the pieces of a broken #KISSM_PAIRS_SEQUENCE chain that
 *             kissm_sequence_corroborated() does not keep), 1 for an accepted one.
 * @param[out] out_information The edge's 6x6 information as the graph weighed it; NaN when not an edge.
 * @param[out] out_residual The edge's squared error xi^T I xi at the solution; NaN when not an edge, held out, or a
 *             scan of it is not placed.
 * @retval KISSM_OK Done.
 * @retval KISSM_ERR_NULL_ARGUMENT @p alignment is NULL.
 * @retval KISSM_ERR_INVALID_ARGUMENT @p index is out of range (nothing written).
 * @retval KISSM_ERR_STRUCT_SIZE out_result->struct_size is too small or above 65536 (nothing written).
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_alignment_registration(const kissm_alignment *alignment, uint64_t index, uint64_t *out_source,
                                               uint64_t *out_target, kissm_result *out_result, int32_t *out_edge,
                                               double out_information[36], double *out_residual);

/**
 * @brief The loop candidates of a sequence of scans: pairs far apart in the sequence but near in space, the rule of
 *        #KISSM_PAIRS_SEQUENCE (and of Python's and the CLI's sequences).
 *
 * The scans' positions are @p priors' translations when given; otherwise the consecutive registrations chained
 * from scan 0, and then the radius grows by 2% of the path between the two scans (the odometry's drift), and an
 * invalid step starts a new piece of the sequence in a frame of its own, with no candidates across pieces. For
 * each scan j from @p gap on, the scans i <= j - gap within the radius, the @p per_scan nearest (by distance, then
 * i), are written as pairs (j, i) by increasing i; then j + 1.
 * @param[in] num_scans 1 to #KISSM_POSE_GRAPH_MAX_NODES.
 * @param[in] steps NULL when @p priors is given; else num_scans - 1 4x4 row-major transforms, packed: step k is
 *            T_k_(k+1), scan k+1 into scan k (kissm_result.transform of the pair (k+1, k)).
 * @param[in] step_valid NULL (every step valid) or num_scans - 1 flags, 1 valid, 0 not (its transform is not read).
 * @param[in] priors NULL, or num_scans 4x4 row-major world <- scan poses; a non-finite translation marks a scan
 *            without a position.
 * @param[in] radius Finite, > 0 (the clouds' unit).
 * @param[in] gap 1 to 1,000,000.
 * @param[in] per_scan 0 to 1,000,000.
 * @param[out] out_pairs capacity (source, target) pairs, packed; may be NULL to count only. At most
 *             num_scans x per_scan pairs are written.
 * @param[in] capacity The pairs @p out_pairs has room for.
 * @param[out] out_count The number of candidates.
 * @retval KISSM_OK Done.
 * @retval KISSM_ERR_NULL_ARGUMENT @p out_count is NULL, or both @p steps and @p priors are (with num_scans > 1).
 * @retval KISSM_ERR_INVALID_ARGUMENT An argument is out of its range, both @p steps and @p priors are given,
 *         @p step_valid holds a flag other than 0 and 1, or @p capacity is below the count (*out_count is set,
 *         nothing else written).
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_sequence_loops(uint64_t num_scans, const double *steps, const uint8_t *step_valid,
                                       const double *priors, double radius, uint64_t gap, uint64_t per_scan,
                                       uint64_t *out_pairs, uint64_t capacity, uint64_t *out_count);

/**
 * @brief Loop candidates by similarity, the rule of #KISSM_PAIRS_SEQUENCE where its chain breaks: the scans of a
 *        sequence whose signatures are alike, between pieces of the chained registrations (where their positions
 *        say nothing).
 *
 * An invalid step (step_valid[k] = 0) starts a new piece of the sequence at scan k+1. For each scan j from @p gap
 * on, the scans i <= j - gap of other pieces whose signatures are the nearest (the squared differences summed
 * column by column, in order, from 0), the @p per_scan nearest (by distance, then i), are written as pairs (j, i)
 * by increasing i; then j + 1. Python's kissm.multiway.align and `kissm align` call it; so does
 * kissm_align_features().
 * @param[in] num_scans 1 to #KISSM_POSE_GRAPH_MAX_NODES.
 * @param[in] step_valid NULL (every step valid: one piece, no candidates) or num_scans - 1 flags, 1 valid, 0 not.
 * @param[in] signatures num_scans x #KISSM_SIGNATURE_SIZE numbers, packed (kissm_features_signature()); a row
 *            holding a non-finite number is a scan without a signature, nobody's candidate.
 * @param[in] gap 1 to 1,000,000.
 * @param[in] per_scan 0 to 1,000,000.
 * @param[out] out_pairs capacity (source, target) pairs, packed; may be NULL to count only.
 * @param[in] capacity The pairs @p out_pairs has room for.
 * @param[out] out_count The number of candidates.
 * @retval KISSM_OK Done.
 * @retval KISSM_ERR_NULL_ARGUMENT @p out_count or @p signatures is NULL.
 * @retval KISSM_ERR_INVALID_ARGUMENT An argument is out of its range, @p step_valid holds a flag other than 0 and
 *         1, or @p capacity is below the count (*out_count is set, nothing else written).
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_sequence_similar(uint64_t num_scans, const uint8_t *step_valid, const double *signatures,
                                         uint64_t gap, uint64_t per_scan, uint64_t *out_pairs, uint64_t capacity,
                                         uint64_t *out_count);

/**
 * @brief Which registrations of a sequence join the pose graph when its chain breaks: every one within a piece of
 *        the chained registrations, and of those between two pieces only the largest set that agrees on where the
 *        later piece lies (a revisit gives several that agree; places that merely look alike give one, or fewer).
 *
 * The registrations between the same two pieces (the target's, the source's) form a group; in it, a agrees with b
 * when b's source is another scan than a's, and a, carried through the source piece's chained poses, puts b's
 * source within @p radius + 2% of the paths between their targets and between their sources of where b puts it.
 * The registration most others agree with (the first of equals) is kept with those it agrees with, if any.
 * #KISSM_PAIRS_SEQUENCE's rule (and Python's and the CLI's); the chain as kissm_sequence_loops() makes it.
 * @param[in] num_scans 1 to #KISSM_POSE_GRAPH_MAX_NODES.
 * @param[in] steps num_scans - 1 4x4 row-major transforms, packed, step k T_k_(k+1) (NULL with num_scans = 1).
 * @param[in] step_valid NULL (every step valid) or num_scans - 1 flags, 1 valid, 0 not (its transform is not read).
 * @param[in] radius Finite, > 0 (the clouds' unit).
 * @param[in] num_pairs The registrations, 0 to 100,000,000.
 * @param[in] pairs num_pairs (source, target) scan positions, packed (NULL when num_pairs is 0).
 * @param[in] transforms num_pairs 4x4 row-major T_target_source, packed (kissm_result.transform); one holding a
 *            non-finite number agrees with none.
 * @param[out] out_kept num_pairs flags: 1 when the graph takes the registration, 0 when it is kept out.
 * @retval KISSM_OK Done.
 * @retval KISSM_ERR_NULL_ARGUMENT @p out_kept (with num_pairs > 0), @p pairs or @p transforms (with num_pairs > 0),
 *         or @p steps (with num_scans > 1) is NULL.
 * @retval KISSM_ERR_INVALID_ARGUMENT An argument is out of its range, a pair names a scan out of range,
 *         @p step_valid holds a flag other than 0 and 1, or @p step_valid is given without @p steps (nothing
 *         written).
 * @retval KISSM_ERR_OUT_OF_MEMORY, KISSM_ERR_INTERNAL See the file's conventions.
 */
KISSM_API int32_t kissm_sequence_corroborated(uint64_t num_scans, const double *steps, const uint8_t *step_valid,
                                              double radius, uint64_t num_pairs, const uint64_t *pairs,
                                              const double *transforms, uint8_t *out_kept);

/** @} */

/* ------------------------------------------------------------------------------------------------ */
/* ABI self-check for bindings                                                                      */
/* ------------------------------------------------------------------------------------------------ */

/**
 * @defgroup abi ABI self-check for bindings
 * @brief The sizes of the public structs as compiled into the library.
 * @{
 */

#define KISSM_STRUCT_CONFIG 1        /**< kissm_config */
#define KISSM_STRUCT_POINTS 2        /**< kissm_points */
#define KISSM_STRUCT_RESULT 3        /**< kissm_result */
#define KISSM_STRUCT_ALIGN_OPTIONS 4 /**< kissm_align_options */

/**
 * @brief sizeof() of a public struct as compiled into the library.
 * @param[in] which A KISSM_STRUCT_* id.
 * @return The size in bytes; 0 for an unknown id.
 */
KISSM_API uint32_t kissm_abi_sizeof(int32_t which);

/** @} */

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* KISSM_H */
