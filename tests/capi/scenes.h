/* SPDX-License-Identifier: MIT */
/* Deterministic synthetic scenes and small helpers shared by the C API tests (C99).
 *
 * Everything here is a pure function of its seeds: splitmix64 (src/common/splitmix64.h, never rand()),
 * fixed sampling orders and no global state, so every test sees the same clouds on every run and every
 * machine of the same build.
 *
 * Coordinates are metres. The standard scene is a walled yard about 24 m x 16 m whose ground lies 1.7 m
 * below the source sensor (at the origin, like a car-mounted LiDAR): ground, three walls, a ramp, boxes,
 * poles and spheres, sampled with isotropic Gaussian noise. */
#ifndef KISSM_TEST_CAPI_SCENES_H
#define KISSM_TEST_CAPI_SCENES_H

#include <stddef.h>
#include <stdint.h>

#include "kissm.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---------------------------------------------------------------------------------------------- */
/* Clouds: growable packed float64 xyz                                                              */
/* ---------------------------------------------------------------------------------------------- */

typedef struct scn_cloud {
    double *xyz;
    size_t count;
    size_t capacity;
} scn_cloud;

void scn_cloud_init(scn_cloud *c);
void scn_cloud_free(scn_cloud *c);
void scn_cloud_push(scn_cloud *c, double x, double y, double z);
void scn_cloud_copy(scn_cloud *dst, const scn_cloud *src); /* dst must be initialised (it is replaced) */
/* Keeps the points with n . p <= d (order preserved). */
void scn_cloud_crop(scn_cloud *c, const double n[3], double d);
/* Rounds every coordinate to a multiple of step (a power of two keeps shifted copies exact). */
void scn_cloud_quantize(scn_cloud *c, double step);
void scn_cloud_translate(scn_cloud *c, double dx, double dy, double dz);
/* Georeferenced copies of a pair: s0, t0 = source, target snapped to a 2^-20 grid; s1, t1 = the same moved by
 * shift, exactly (the library then sees identical recentred clouds). All four are initialised here. */
void scn_shifted_copies(const scn_cloud *source, const scn_cloud *target, const double shift[3], scn_cloud *s0,
                        scn_cloud *t0, scn_cloud *s1, scn_cloud *t1);
/* Fisher-Yates shuffle with the given seed. */
void scn_cloud_shuffle(scn_cloud *c, uint64_t seed);
/* Float32 copy (count * 3 floats, malloc'ed; caller frees). */
float *scn_cloud_to_float(const scn_cloud *c);
/* Axis-aligned extent (max - min) of the cloud, per axis. */
void scn_cloud_extent(const scn_cloud *c, double extent[3]);

/* A packed float64 view of the cloud. */
kissm_points scn_points(const scn_cloud *c);
kissm_points scn_points_f32(const float *xyz, size_t count);

/* ---------------------------------------------------------------------------------------------- */
/* Rigid transforms: p' = R p + t, R row-major                                                      */
/* ---------------------------------------------------------------------------------------------- */

typedef struct scn_pose {
    double R[9];
    double t[3];
} scn_pose;

void scn_pose_identity(scn_pose *p);
/* Rotation of angle_rad about axis (need not be unit length), then translation t. */
void scn_pose_axis_angle(scn_pose *p, const double axis[3], double angle_rad, const double t[3]);
void scn_pose_inverse(const scn_pose *p, scn_pose *out);
/* out = a o b (apply b first). out may alias neither a nor b. */
void scn_pose_compose(const scn_pose *a, const scn_pose *b, scn_pose *out);
void scn_pose_apply_point(const scn_pose *p, const double in[3], double out[3]);
void scn_cloud_apply(scn_cloud *c, const scn_pose *p);
/* Angle of Ra^T Rb in degrees (the rotation error between two rotations). */
double scn_rotation_error_deg(const double Ra[9], const double Rb[9]);
/* |ta - tb| */
double scn_translation_error(const double ta[3], const double tb[3]);
/* The 4x4 row-major matrix of a pose (last row 0 0 0 1), as kissm_refine() takes it, and back. */
void scn_pose_to_matrix(const scn_pose *p, double m[16]);
void scn_pose_from_matrix(const double m[16], scn_pose *p);

/* ---------------------------------------------------------------------------------------------- */
/* Scenes                                                                                           */
/* ---------------------------------------------------------------------------------------------- */

/* The standard yard scene. layout_seed fixes where the objects are; sample_seed fixes which surface points
 * are drawn and their noise (two samples of one layout are two independent scans of the same place).
 * points_per_m2 is the sampling density (about 620 m^2 of surface: 25 per m^2 gives ~15K points). */
void scn_make_scene(scn_cloud *out, uint64_t layout_seed, uint64_t sample_seed, double points_per_m2,
                    double noise_sigma);

/* A source/target pair of the standard scene with a known transform:
 *  - source: a sample of the scene cropped to x <= 6 (source sensor frame = world);
 *  - target: an independent sample cropped to x >= -6, expressed in the frame of a second sensor that sits
 *    at world position (4, 3, 0) (5 m away) and is rotated by 150 degrees about the tilted axis (1, -2, 3).
 * truth maps source points into the target frame: p_t = R p_s + t. */
typedef struct scn_pair {
    scn_cloud source;
    scn_cloud target;
    scn_pose truth;
} scn_pair;

void scn_make_pair(scn_pair *pair, uint64_t seed, double points_per_m2, double noise_sigma);
void scn_pair_free(scn_pair *pair);

/* n noisy points on a straight 20 m segment (a collinear cloud). */
void scn_make_line(scn_cloud *out, uint64_t seed, size_t n, double noise_sigma);
/* n noisy points on one tilted 16 m x 16 m plane. */
void scn_make_plane(scn_cloud *out, uint64_t seed, size_t n, double noise_sigma);
/* A corridor along x, 30 m long and 3 m wide: floor and two 2.5 m walls, open at both ends (a pose can
 * slide along it), sampled at points_per_m2 with noise. */
void scn_make_corridor(scn_cloud *out, uint64_t seed, double points_per_m2, double noise_sigma);
/* The mantle of a pipe (a tunnel) of the given radius and length: its axis passes through `centre` with
 * direction `axis` (any length). A pose can slide along the axis and turn about it. */
void scn_make_pipe(scn_cloud *out, uint64_t seed, size_t n, const double centre[3], const double axis[3], double radius,
                   double length, double noise_sigma);
/* n copies of the point (x, y, z). */
void scn_make_duplicates(scn_cloud *out, size_t n, double x, double y, double z);
/* n points uniformly inside the axis-aligned cube centred on c with half side h. */
void scn_make_blob(scn_cloud *out, uint64_t seed, size_t n, const double c[3], double h);

/* ---------------------------------------------------------------------------------------------- */
/* Results and configs                                                                              */
/* ---------------------------------------------------------------------------------------------- */

/* A config with the defaults and the given voxel size (aborts the test binary if config_init fails). */
kissm_config scn_config(double voxel_size);

/* Fills *r with a recognisable garbage pattern (every byte 0x5A) that looks like a valid pose:
 * struct_size = sizeof(kissm_result), valid = 1, reason = 0, identity transform. */
void scn_result_poison(kissm_result *r);
/* 1 when a registration call overwrote every field of a poisoned result the way a failed call must:
 * struct_size kept, valid = 0, every pose entry NaN (coarse_transform and information too), every count 0,
 * overlap, refine_rmse, refine_condition, rotation_uncertainty and inlier_coverage NaN, the refinement's
 * counts and time 0, no byte pattern of the poison left. Prints what is wrong to stderr otherwise. */
int scn_result_is_reset(const kissm_result *r);
/* 0 when no 4-byte run of the poison is left in *r, else 1 + the byte offset of the first one. */
size_t scn_result_poison_left(const kissm_result *r);
/* 1 when a and b are bitwise identical in every field except the time_* fields (time_refine_ms included). */
int scn_result_equal(const kissm_result *a, const kissm_result *b);
/* Prints the main fields of a result to stderr (diagnostics for failing checks). */
void scn_result_print(const char *label, const kissm_result *r);

/* Monotonic wall clock in seconds. */
double scn_now(void);

#ifdef __cplusplus
}
#endif

#endif
