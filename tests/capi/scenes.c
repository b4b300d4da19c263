/* SPDX-License-Identifier: MIT */
/* Deterministic synthetic scenes for the C API tests (see scenes.h). */
#define _POSIX_C_SOURCE 200809L

#include "scenes.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "splitmix64.h"

#define SCN_PI 3.14159265358979323846

/* ---------------------------------------------------------------------------------------------- */
/* Random numbers                                                                                   */
/* ---------------------------------------------------------------------------------------------- */

/* The scenes draw from splitmix64 (src/common/splitmix64.h) started at seed ^ this constant. */
static uint64_t scn_rng_state(uint64_t seed) { return seed ^ UINT64_C(0x6a09e667f3bcc909); }

/* [0, n), n > 0, unbiased: draws above the largest multiple of n are redrawn. */
static uint64_t scn_rng_below(uint64_t *rng, uint64_t n) {
    const uint64_t limit = UINT64_MAX - UINT64_MAX % n;
    uint64_t x;
    do {
        x = splitmix64_next(rng);
    } while (x >= limit);
    return x % n;
}

/* ---------------------------------------------------------------------------------------------- */
/* Clouds                                                                                           */
/* ---------------------------------------------------------------------------------------------- */

static void *scn_xmalloc(size_t bytes) {
    void *p = malloc(bytes == 0 ? 1 : bytes);
    if (p == NULL) {
        fprintf(stderr, "scenes: out of memory (%lu bytes)\n", (unsigned long)bytes);
        exit(2);
    }
    return p;
}

void scn_cloud_init(scn_cloud *c) {
    c->xyz = NULL;
    c->count = 0;
    c->capacity = 0;
}

void scn_cloud_free(scn_cloud *c) {
    free(c->xyz);
    scn_cloud_init(c);
}

static void scn_cloud_reserve(scn_cloud *c, size_t n) {
    double *grown;
    if (n <= c->capacity) return;
    grown = (double *)realloc(c->xyz, n * 3 * sizeof(double));
    if (grown == NULL) {
        fprintf(stderr, "scenes: out of memory (%lu points)\n", (unsigned long)n);
        exit(2);
    }
    c->xyz = grown;
    c->capacity = n;
}

void scn_cloud_push(scn_cloud *c, double x, double y, double z) {
    if (c->count == c->capacity) scn_cloud_reserve(c, c->capacity < 1024 ? 1024 : 2 * c->capacity);
    c->xyz[3 * c->count + 0] = x;
    c->xyz[3 * c->count + 1] = y;
    c->xyz[3 * c->count + 2] = z;
    c->count++;
}

void scn_cloud_copy(scn_cloud *dst, const scn_cloud *src) {
    scn_cloud_free(dst);
    scn_cloud_reserve(dst, src->count);
    if (src->count) memcpy(dst->xyz, src->xyz, src->count * 3 * sizeof(double));
    dst->count = src->count;
}

void scn_cloud_crop(scn_cloud *c, const double n[3], double d) {
    size_t i, kept = 0;
    for (i = 0; i < c->count; ++i) {
        const double *p = c->xyz + 3 * i;
        if (n[0] * p[0] + n[1] * p[1] + n[2] * p[2] <= d) {
            memmove(c->xyz + 3 * kept, p, 3 * sizeof(double));
            kept++;
        }
    }
    c->count = kept;
}

void scn_cloud_quantize(scn_cloud *c, double step) {
    size_t i;
    for (i = 0; i < 3 * c->count; ++i) c->xyz[i] = floor(c->xyz[i] / step + 0.5) * step;
}

void scn_cloud_translate(scn_cloud *c, double dx, double dy, double dz) {
    size_t i;
    for (i = 0; i < c->count; ++i) {
        c->xyz[3 * i + 0] += dx;
        c->xyz[3 * i + 1] += dy;
        c->xyz[3 * i + 2] += dz;
    }
}

void scn_shifted_copies(const scn_cloud *source, const scn_cloud *target, const double shift[3], scn_cloud *s0,
                        scn_cloud *t0, scn_cloud *s1, scn_cloud *t1) {
    scn_cloud_init(s0), scn_cloud_init(t0), scn_cloud_init(s1), scn_cloud_init(t1);
    scn_cloud_copy(s0, source);
    scn_cloud_copy(t0, target);
    scn_cloud_quantize(s0, 1.0 / 1048576.0);
    scn_cloud_quantize(t0, 1.0 / 1048576.0);
    scn_cloud_copy(s1, s0);
    scn_cloud_copy(t1, t0);
    scn_cloud_translate(s1, shift[0], shift[1], shift[2]);
    scn_cloud_translate(t1, shift[0], shift[1], shift[2]);
}

void scn_cloud_shuffle(scn_cloud *c, uint64_t seed) {
    uint64_t rng;
    size_t i;
    rng = scn_rng_state(seed);
    for (i = c->count; i > 1; --i) {
        const size_t j = (size_t)scn_rng_below(&rng, (uint64_t)i);
        double tmp[3];
        memcpy(tmp, c->xyz + 3 * (i - 1), sizeof(tmp));
        memcpy(c->xyz + 3 * (i - 1), c->xyz + 3 * j, sizeof(tmp));
        memcpy(c->xyz + 3 * j, tmp, sizeof(tmp));
    }
}

float *scn_cloud_to_float(const scn_cloud *c) {
    float *f = (float *)scn_xmalloc(c->count * 3 * sizeof(float));
    size_t i;
    for (i = 0; i < 3 * c->count; ++i) f[i] = (float)c->xyz[i];
    return f;
}

void scn_cloud_extent(const scn_cloud *c, double extent[3]) {
    double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    size_t i;
    int a;
    for (i = 0; i < c->count; ++i)
        for (a = 0; a < 3; ++a) {
            const double v = c->xyz[3 * i + (size_t)a];
            if (i == 0 || v < lo[a]) lo[a] = v;
            if (i == 0 || v > hi[a]) hi[a] = v;
        }
    for (a = 0; a < 3; ++a) extent[a] = hi[a] - lo[a];
}

kissm_points scn_points(const scn_cloud *c) {
    kissm_points p;
    memset(&p, 0, sizeof(p));
    p.data = c->xyz;
    p.count = (uint64_t)c->count;
    p.stride_bytes = 0;
    p.scalar_type = KISSM_SCALAR_FLOAT64;
    p.reserved = 0;
    return p;
}

kissm_points scn_points_f32(const float *xyz, size_t count) {
    kissm_points p;
    memset(&p, 0, sizeof(p));
    p.data = xyz;
    p.count = (uint64_t)count;
    p.stride_bytes = 0;
    p.scalar_type = KISSM_SCALAR_FLOAT32;
    p.reserved = 0;
    return p;
}

/* ---------------------------------------------------------------------------------------------- */
/* Poses                                                                                            */
/* ---------------------------------------------------------------------------------------------- */

void scn_pose_identity(scn_pose *p) {
    memset(p, 0, sizeof(*p));
    p->R[0] = p->R[4] = p->R[8] = 1.0;
}

void scn_pose_axis_angle(scn_pose *p, const double axis[3], double angle_rad, const double t[3]) {
    const double norm = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    const double x = axis[0] / norm, y = axis[1] / norm, z = axis[2] / norm;
    const double c = cos(angle_rad), s = sin(angle_rad), C = 1.0 - c;
    p->R[0] = c + x * x * C;
    p->R[1] = x * y * C - z * s;
    p->R[2] = x * z * C + y * s;
    p->R[3] = y * x * C + z * s;
    p->R[4] = c + y * y * C;
    p->R[5] = y * z * C - x * s;
    p->R[6] = z * x * C - y * s;
    p->R[7] = z * y * C + x * s;
    p->R[8] = c + z * z * C;
    p->t[0] = t[0];
    p->t[1] = t[1];
    p->t[2] = t[2];
}

void scn_pose_inverse(const scn_pose *p, scn_pose *out) {
    int i, j;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) out->R[3 * i + j] = p->R[3 * j + i];
    for (i = 0; i < 3; ++i)
        out->t[i] = -(out->R[3 * i + 0] * p->t[0] + out->R[3 * i + 1] * p->t[1] + out->R[3 * i + 2] * p->t[2]);
}

void scn_pose_compose(const scn_pose *a, const scn_pose *b, scn_pose *out) {
    int i, j, k;
    for (i = 0; i < 3; ++i) {
        for (j = 0; j < 3; ++j) {
            double s = 0.0;
            for (k = 0; k < 3; ++k) s += a->R[3 * i + k] * b->R[3 * k + j];
            out->R[3 * i + j] = s;
        }
        out->t[i] = a->R[3 * i + 0] * b->t[0] + a->R[3 * i + 1] * b->t[1] + a->R[3 * i + 2] * b->t[2] + a->t[i];
    }
}

void scn_pose_apply_point(const scn_pose *p, const double in[3], double out[3]) {
    int i;
    double tmp[3];
    for (i = 0; i < 3; ++i)
        tmp[i] = p->R[3 * i + 0] * in[0] + p->R[3 * i + 1] * in[1] + p->R[3 * i + 2] * in[2] + p->t[i];
    memcpy(out, tmp, sizeof(tmp));
}

void scn_cloud_apply(scn_cloud *c, const scn_pose *p) {
    size_t i;
    for (i = 0; i < c->count; ++i) scn_pose_apply_point(p, c->xyz + 3 * i, c->xyz + 3 * i);
}

double scn_rotation_error_deg(const double Ra[9], const double Rb[9]) {
    /* trace(Ra^T Rb) = sum over all entries of Ra .* Rb */
    double tr = 0.0, c;
    int i;
    for (i = 0; i < 9; ++i) tr += Ra[i] * Rb[i];
    c = 0.5 * (tr - 1.0);
    if (c > 1.0) c = 1.0;
    if (c < -1.0) c = -1.0;
    if (tr != tr) return NAN;
    return acos(c) * 180.0 / SCN_PI;
}

double scn_translation_error(const double ta[3], const double tb[3]) {
    const double dx = ta[0] - tb[0], dy = ta[1] - tb[1], dz = ta[2] - tb[2];
    return sqrt(dx * dx + dy * dy + dz * dz);
}

void scn_pose_to_matrix(const scn_pose *p, double m[16]) {
    int i, j;
    for (i = 0; i < 3; ++i) {
        for (j = 0; j < 3; ++j) m[4 * i + j] = p->R[3 * i + j];
        m[4 * i + 3] = p->t[i];
    }
    m[12] = m[13] = m[14] = 0.0;
    m[15] = 1.0;
}

void scn_pose_from_matrix(const double m[16], scn_pose *p) {
    int i, j;
    for (i = 0; i < 3; ++i) {
        for (j = 0; j < 3; ++j) p->R[3 * i + j] = m[4 * i + j];
        p->t[i] = m[4 * i + 3];
    }
}

/* ---------------------------------------------------------------------------------------------- */
/* Surface samplers                                                                                 */
/* ---------------------------------------------------------------------------------------------- */

static size_t scn_count_for(double area, double density) { return (size_t)(area * density + 0.5); }

static void scn_push_noisy(scn_cloud *c, uint64_t *rng, double x, double y, double z, double sigma) {
    const double nx = sigma * splitmix64_gauss(rng);
    const double ny = sigma * splitmix64_gauss(rng);
    const double nz = sigma * splitmix64_gauss(rng);
    scn_cloud_push(c, x + nx, y + ny, z + nz);
}

/* The parallelogram o + a u + b v, (a, b) in [0, 1]^2. */
static void scn_sample_rect(scn_cloud *c, uint64_t *rng, const double o[3], const double u[3], const double v[3],
                            double density, double sigma) {
    const double cx = u[1] * v[2] - u[2] * v[1], cy = u[2] * v[0] - u[0] * v[2], cz = u[0] * v[1] - u[1] * v[0];
    const size_t n = scn_count_for(sqrt(cx * cx + cy * cy + cz * cz), density);
    size_t i;
    for (i = 0; i < n; ++i) {
        const double a = splitmix64_uniform(rng), b = splitmix64_uniform(rng);
        scn_push_noisy(c, rng, o[0] + a * u[0] + b * v[0], o[1] + a * u[1] + b * v[1], o[2] + a * u[2] + b * v[2],
                       sigma);
    }
}

/* A box standing on z = z0: four sides and the top (no bottom), rotated by yaw about its vertical axis. */
static void scn_sample_box(scn_cloud *c, uint64_t *rng, double cx, double cy, double z0, double sx, double sy,
                           double sz, double yaw, double density, double sigma) {
    const double ex[3] = {cos(yaw) * sx, sin(yaw) * sx, 0.0};
    const double ey[3] = {-sin(yaw) * sy, cos(yaw) * sy, 0.0};
    const double ez[3] = {0.0, 0.0, sz};
    const double base[3] = {cx - 0.5 * (ex[0] + ey[0]), cy - 0.5 * (ex[1] + ey[1]), z0};
    double o[3];
    int k;
    scn_sample_rect(c, rng, base, ex, ez, density, sigma); /* front */
    for (k = 0; k < 3; ++k) o[k] = base[k] + ey[k];
    scn_sample_rect(c, rng, o, ex, ez, density, sigma);    /* back */
    scn_sample_rect(c, rng, base, ey, ez, density, sigma); /* left */
    for (k = 0; k < 3; ++k) o[k] = base[k] + ex[k];
    scn_sample_rect(c, rng, o, ey, ez, density, sigma); /* right */
    for (k = 0; k < 3; ++k) o[k] = base[k] + ez[k];
    scn_sample_rect(c, rng, o, ex, ey, density, sigma); /* top */
}

/* A vertical cylinder standing on z = z0: mantle and top disc. */
static void scn_sample_cylinder(scn_cloud *c, uint64_t *rng, double cx, double cy, double z0, double r, double h,
                                double density, double sigma) {
    const size_t n_side = scn_count_for(2.0 * SCN_PI * r * h, density);
    const size_t n_top = scn_count_for(SCN_PI * r * r, density);
    size_t i;
    for (i = 0; i < n_side; ++i) {
        const double a = 2.0 * SCN_PI * splitmix64_uniform(rng), z = z0 + h * splitmix64_uniform(rng);
        scn_push_noisy(c, rng, cx + r * cos(a), cy + r * sin(a), z, sigma);
    }
    for (i = 0; i < n_top; ++i) {
        const double a = 2.0 * SCN_PI * splitmix64_uniform(rng), rr = r * sqrt(splitmix64_uniform(rng));
        scn_push_noisy(c, rng, cx + rr * cos(a), cy + rr * sin(a), z0 + h, sigma);
    }
}

/* The part of a sphere above z = ground. */
static void scn_sample_sphere(scn_cloud *c, uint64_t *rng, double cx, double cy, double cz, double r, double ground,
                              double density, double sigma) {
    const size_t n = scn_count_for(4.0 * SCN_PI * r * r, density);
    size_t i;
    for (i = 0; i < n; ++i) {
        double d[3], len;
        d[0] = splitmix64_gauss(rng);
        d[1] = splitmix64_gauss(rng);
        d[2] = splitmix64_gauss(rng);
        len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (len < 1e-12) continue;
        if (cz + r * d[2] / len < ground) continue;
        scn_push_noisy(c, rng, cx + r * d[0] / len, cy + r * d[1] / len, cz + r * d[2] / len, sigma);
    }
}

/* ---------------------------------------------------------------------------------------------- */
/* Scenes                                                                                           */
/* ---------------------------------------------------------------------------------------------- */

#define SCN_GROUND (-1.7)
#define SCN_NUM_BOXES 7
#define SCN_NUM_POLES 6
#define SCN_NUM_SPHERES 3

typedef struct scn_layout {
    double box[SCN_NUM_BOXES][6];      /* cx, cy, sx, sy, sz, yaw */
    double pole[SCN_NUM_POLES][4];     /* cx, cy, r, h */
    double sphere[SCN_NUM_SPHERES][3]; /* cx, cy, r */
} scn_layout;

static void scn_make_layout(scn_layout *l, uint64_t layout_seed) {
    uint64_t rng;
    int i;
    rng = scn_rng_state(layout_seed * UINT64_C(0x100000001b3) + 17);
    for (i = 0; i < SCN_NUM_BOXES; ++i) {
        l->box[i][0] = splitmix64_range(&rng, -10.0, 10.0);
        l->box[i][1] = splitmix64_range(&rng, -6.5, 6.5);
        l->box[i][2] = splitmix64_range(&rng, 0.6, 2.8);
        l->box[i][3] = splitmix64_range(&rng, 0.6, 2.2);
        l->box[i][4] = splitmix64_range(&rng, 0.5, 2.5);
        l->box[i][5] = splitmix64_range(&rng, 0.0, SCN_PI);
    }
    for (i = 0; i < SCN_NUM_POLES; ++i) {
        l->pole[i][0] = splitmix64_range(&rng, -10.5, 10.5);
        l->pole[i][1] = splitmix64_range(&rng, -7.0, 7.0);
        l->pole[i][2] = splitmix64_range(&rng, 0.12, 0.5);
        l->pole[i][3] = splitmix64_range(&rng, 1.5, 4.5);
    }
    for (i = 0; i < SCN_NUM_SPHERES; ++i) {
        l->sphere[i][0] = splitmix64_range(&rng, -9.0, 9.0);
        l->sphere[i][1] = splitmix64_range(&rng, -6.0, 6.0);
        l->sphere[i][2] = splitmix64_range(&rng, 0.5, 1.3);
    }
}

void scn_make_scene(scn_cloud *out, uint64_t layout_seed, uint64_t sample_seed, double points_per_m2,
                    double noise_sigma) {
    scn_layout l;
    uint64_t rng;
    const double g = SCN_GROUND;
    int i;
    scn_make_layout(&l, layout_seed);
    rng = scn_rng_state(sample_seed);
    scn_cloud_free(out);
    {
        /* ground: 24 m x 16 m */
        const double o[3] = {-12.0, -8.0, g}, u[3] = {24.0, 0.0, 0.0}, v[3] = {0.0, 16.0, 0.0};
        scn_sample_rect(out, &rng, o, u, v, points_per_m2, noise_sigma);
    }
    {
        /* west wall, 4 m high */
        const double o[3] = {-12.0, -8.0, g}, u[3] = {0.0, 16.0, 0.0}, v[3] = {0.0, 0.0, 4.0};
        scn_sample_rect(out, &rng, o, u, v, points_per_m2, noise_sigma);
    }
    {
        /* north wall, 3.2 m high, ending at x = 5 */
        const double o[3] = {-12.0, 8.0, g}, u[3] = {17.0, 0.0, 0.0}, v[3] = {0.0, 0.0, 3.2};
        scn_sample_rect(out, &rng, o, u, v, points_per_m2, noise_sigma);
    }
    {
        /* south-east wall at an angle, 2.6 m high */
        const double o[3] = {5.0, -8.0, g}, u[3] = {7.0, 5.5, 0.0}, v[3] = {0.0, 0.0, 2.6};
        scn_sample_rect(out, &rng, o, u, v, points_per_m2, noise_sigma);
    }
    {
        /* a ramp rising 1.2 m over 5 m along -y */
        const double o[3] = {-3.0, -3.0, g}, u[3] = {4.0, 0.0, 0.0}, v[3] = {0.0, -5.0, 1.2};
        scn_sample_rect(out, &rng, o, u, v, points_per_m2, noise_sigma);
    }
    for (i = 0; i < SCN_NUM_BOXES; ++i)
        scn_sample_box(out, &rng, l.box[i][0], l.box[i][1], g, l.box[i][2], l.box[i][3], l.box[i][4], l.box[i][5],
                       points_per_m2, noise_sigma);
    for (i = 0; i < SCN_NUM_POLES; ++i)
        scn_sample_cylinder(out, &rng, l.pole[i][0], l.pole[i][1], g, l.pole[i][2], l.pole[i][3], points_per_m2,
                            noise_sigma);
    for (i = 0; i < SCN_NUM_SPHERES; ++i)
        scn_sample_sphere(out, &rng, l.sphere[i][0], l.sphere[i][1], g + 0.6 * l.sphere[i][2], l.sphere[i][2], g,
                          points_per_m2, noise_sigma);
}

void scn_make_pair(scn_pair *pair, uint64_t seed, double points_per_m2, double noise_sigma) {
    const double axis[3] = {1.0, -2.0, 3.0};
    const double sensor[3] = {4.0, 3.0, 0.0};
    const double keep_west[3] = {1.0, 0.0, 0.0};  /* x <= 6 */
    const double keep_east[3] = {-1.0, 0.0, 0.0}; /* -x <= 6 */
    scn_pose sensor_pose;
    scn_cloud_init(&pair->source);
    scn_cloud_init(&pair->target);
    scn_make_scene(&pair->source, seed, 2 * seed + 1, points_per_m2, noise_sigma);
    scn_make_scene(&pair->target, seed, 2 * seed + 2, points_per_m2, noise_sigma);
    scn_cloud_crop(&pair->source, keep_west, 6.0);
    scn_cloud_crop(&pair->target, keep_east, 6.0);
    /* The target sensor's pose in the world: rotated 150 degrees, at `sensor`. Target coordinates are
     * world coordinates seen from that sensor, so truth = inverse(sensor pose). */
    scn_pose_axis_angle(&sensor_pose, axis, 150.0 * SCN_PI / 180.0, sensor);
    scn_pose_inverse(&sensor_pose, &pair->truth);
    scn_cloud_apply(&pair->target, &pair->truth);
}

void scn_pair_free(scn_pair *pair) {
    scn_cloud_free(&pair->source);
    scn_cloud_free(&pair->target);
}

void scn_make_line(scn_cloud *out, uint64_t seed, size_t n, double noise_sigma) {
    const double o[3] = {1.0, -2.0, 0.5}, d[3] = {0.6, 0.64, 0.48}; /* |d| = 1 */
    uint64_t rng;
    size_t i;
    rng = scn_rng_state(seed);
    scn_cloud_free(out);
    for (i = 0; i < n; ++i) {
        const double s = splitmix64_range(&rng, 0.0, 20.0);
        scn_push_noisy(out, &rng, o[0] + s * d[0], o[1] + s * d[1], o[2] + s * d[2], noise_sigma);
    }
}

void scn_make_plane(scn_cloud *out, uint64_t seed, size_t n, double noise_sigma) {
    const double o[3] = {-8.0, -8.0, -1.5};
    const double u[3] = {16.0, 0.0, 2.0}, v[3] = {0.0, 16.0, -1.0};
    uint64_t rng;
    size_t i;
    rng = scn_rng_state(seed);
    scn_cloud_free(out);
    for (i = 0; i < n; ++i) {
        const double a = splitmix64_uniform(&rng), b = splitmix64_uniform(&rng);
        scn_push_noisy(out, &rng, o[0] + a * u[0] + b * v[0], o[1] + a * u[1] + b * v[1], o[2] + a * u[2] + b * v[2],
                       noise_sigma);
    }
}

void scn_make_corridor(scn_cloud *out, uint64_t seed, double points_per_m2, double noise_sigma) {
    const double o[3] = {-15.0, -1.5, SCN_GROUND}, X[3] = {30.0, 0.0, 0.0}, Y[3] = {0.0, 3.0, 0.0};
    const double Z[3] = {0.0, 0.0, 2.5}, far_wall[3] = {-15.0, 1.5, SCN_GROUND};
    uint64_t rng;
    rng = scn_rng_state(seed);
    scn_cloud_free(out);
    scn_sample_rect(out, &rng, o, X, Y, points_per_m2, noise_sigma);
    scn_sample_rect(out, &rng, o, X, Z, points_per_m2, noise_sigma);
    scn_sample_rect(out, &rng, far_wall, X, Z, points_per_m2, noise_sigma);
}

void scn_make_pipe(scn_cloud *out, uint64_t seed, size_t n, const double centre[3], const double axis[3], double radius,
                   double length, double noise_sigma) {
    const double len = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    const double d[3] = {axis[0] / len, axis[1] / len, axis[2] / len};
    double e1[3], e2[3], norm;
    uint64_t rng;
    size_t i;
    int k;
    /* e1, e2: an orthonormal pair perpendicular to d */
    if (fabs(d[0]) < 0.9) {
        e1[0] = 0.0, e1[1] = d[2], e1[2] = -d[1];
    } else {
        e1[0] = -d[2], e1[1] = 0.0, e1[2] = d[0];
    }
    norm = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
    for (k = 0; k < 3; ++k) e1[k] /= norm;
    e2[0] = d[1] * e1[2] - d[2] * e1[1];
    e2[1] = d[2] * e1[0] - d[0] * e1[2];
    e2[2] = d[0] * e1[1] - d[1] * e1[0];
    rng = scn_rng_state(seed);
    scn_cloud_free(out);
    for (i = 0; i < n; ++i) {
        const double s = splitmix64_range(&rng, -0.5 * length, 0.5 * length);
        const double a = splitmix64_range(&rng, 0.0, 2.0 * SCN_PI);
        double p[3];
        for (k = 0; k < 3; ++k) p[k] = centre[k] + s * d[k] + radius * (cos(a) * e1[k] + sin(a) * e2[k]);
        scn_push_noisy(out, &rng, p[0], p[1], p[2], noise_sigma);
    }
}

void scn_make_duplicates(scn_cloud *out, size_t n, double x, double y, double z) {
    size_t i;
    scn_cloud_free(out);
    for (i = 0; i < n; ++i) scn_cloud_push(out, x, y, z);
}

void scn_make_blob(scn_cloud *out, uint64_t seed, size_t n, const double c[3], double h) {
    uint64_t rng;
    size_t i;
    rng = scn_rng_state(seed);
    scn_cloud_free(out);
    for (i = 0; i < n; ++i) {
        const double x = splitmix64_range(&rng, c[0] - h, c[0] + h);
        const double y = splitmix64_range(&rng, c[1] - h, c[1] + h);
        const double z = splitmix64_range(&rng, c[2] - h, c[2] + h);
        scn_cloud_push(out, x, y, z);
    }
}

/* ---------------------------------------------------------------------------------------------- */
/* Results and configs                                                                              */
/* ---------------------------------------------------------------------------------------------- */

kissm_config scn_config(double voxel_size) {
    kissm_config c;
    if (kissm_config_init(&c, (uint32_t)sizeof(c)) != KISSM_OK) {
        fprintf(stderr, "scenes: kissm_config_init failed: %s\n", kissm_last_error_message());
        exit(2);
    }
    c.voxel_size = voxel_size;
    return c;
}

void scn_result_poison(kissm_result *r) {
    int i;
    memset(r, 0x5A, sizeof(*r));
    r->struct_size = (uint32_t)sizeof(*r);
    r->valid = 1;
    r->reason = KISSM_REASON_NONE;
    for (i = 0; i < 16; ++i) r->transform[i] = (i % 5 == 0) ? 1.0 : 0.0;
    for (i = 0; i < 9; ++i) r->rotation[i] = (i % 4 == 0) ? 1.0 : 0.0;
    for (i = 0; i < 3; ++i) r->translation[i] = 1.5;
    r->num_final_inliers = 1234;
}

#define SCN_FAIL(...)                                                                                                  \
  do {                                                                                                                 \
    fprintf(stderr, "  result not reset: ");                                                                           \
    fprintf(stderr, __VA_ARGS__);                                                                                      \
    fprintf(stderr, "\n");                                                                                             \
    ok = 0;                                                                                                            \
  } while (0)

int scn_result_is_reset(const kissm_result *r) {
    const uint64_t *counts = &r->num_source_points;
    int ok = 1, i;
    size_t k;
    if (r->struct_size != sizeof(*r)) SCN_FAIL("struct_size %u", (unsigned)r->struct_size);
    if (r->valid != 0) SCN_FAIL("valid %d", (int)r->valid);
    if (r->reason < KISSM_REASON_NONE || r->reason > KISSM_REASON_NOT_CONVERGED) SCN_FAIL("reason %d", (int)r->reason);
    for (i = 0; i < 16; ++i)
        if (!isnan(r->transform[i])) SCN_FAIL("transform[%d] = %g", i, r->transform[i]);
    for (i = 0; i < 9; ++i)
        if (!isnan(r->rotation[i])) SCN_FAIL("rotation[%d] = %g", i, r->rotation[i]);
    for (i = 0; i < 3; ++i)
        if (!isnan(r->translation[i])) SCN_FAIL("translation[%d] = %g", i, r->translation[i]);
    for (i = 0; i < 13; ++i) /* num_source_points .. max_core_number */
        if (counts[i] != 0) SCN_FAIL("count #%d = %llu", i, (unsigned long long)counts[i]);
    if (r->time_total_ms < 0 || r->time_voxelize_ms < 0 || r->time_features_ms < 0 || r->time_matching_ms < 0 ||
        r->time_pruning_ms < 0 || r->time_solver_ms < 0)
        SCN_FAIL("negative time");
    for (i = 0; i < 16; ++i)
        if (!isnan(r->coarse_transform[i])) SCN_FAIL("coarse_transform[%d] = %g", i, r->coarse_transform[i]);
    for (i = 0; i < 36; ++i)
        if (!isnan(r->information[i])) SCN_FAIL("information[%d] = %g", i, r->information[i]);
    if (!isnan(r->overlap)) SCN_FAIL("overlap %g", r->overlap);
    if (!isnan(r->refine_rmse)) SCN_FAIL("refine_rmse %g", r->refine_rmse);
    if (!isnan(r->refine_condition)) SCN_FAIL("refine_condition %g", r->refine_condition);
    if (!isnan(r->rotation_uncertainty)) SCN_FAIL("rotation_uncertainty %g", r->rotation_uncertainty);
    if (!isnan(r->inlier_coverage)) SCN_FAIL("inlier_coverage %g", r->inlier_coverage);
    if (!isnan(r->ambiguity)) SCN_FAIL("ambiguity %g", r->ambiguity);
    if (!isnan(r->confidence)) SCN_FAIL("confidence %g", r->confidence);
    if (r->voxel_size_used != 0.0) SCN_FAIL("voxel_size_used %g", r->voxel_size_used);
    if (r->time_refine_ms != 0.0) SCN_FAIL("time_refine_ms %g", r->time_refine_ms);
    if (r->num_refine_correspondences != 0)
        SCN_FAIL("num_refine_correspondences %llu", (unsigned long long)r->num_refine_correspondences);
    if (r->refine_iterations != 0) SCN_FAIL("refine_iterations %d", (int)r->refine_iterations);
    if (r->refine_converged != 0) SCN_FAIL("refine_converged %d", (int)r->refine_converged);
    if (r->degenerate != 0) SCN_FAIL("degenerate %d", (int)r->degenerate);
    if (r->num_weak_directions != 0) SCN_FAIL("num_weak_directions %d", (int)r->num_weak_directions);
    for (i = 0; i < 36; ++i)
        if (!isnan(r->weak_directions[i])) SCN_FAIL("weak_directions[%d] = %g", i, r->weak_directions[i]);
    k = scn_result_poison_left(r);
    if (k != 0) SCN_FAIL("poison left at byte offset %lu", (unsigned long)(k - 1));
    return ok;
}

size_t scn_result_poison_left(const kissm_result *r) {
    /* No 4-byte run of the poison may survive anywhere in the struct (reserved0 included). */
    const unsigned char *bytes = (const unsigned char *)r;
    size_t k;
    for (k = 0; k + 4 <= sizeof(*r); k += 4)
        if (bytes[k] == 0x5A && bytes[k + 1] == 0x5A && bytes[k + 2] == 0x5A && bytes[k + 3] == 0x5A) return k + 1;
    return 0;
}

int scn_result_equal(const kissm_result *a, const kissm_result *b) {
    kissm_result x = *a, y = *b;
    x.time_voxelize_ms = x.time_features_ms = x.time_matching_ms = x.time_pruning_ms = x.time_solver_ms =
        x.time_refine_ms = x.time_total_ms = 0.0;
    y.time_voxelize_ms = y.time_features_ms = y.time_matching_ms = y.time_pruning_ms = y.time_solver_ms =
        y.time_refine_ms = y.time_total_ms = 0.0;
    return memcmp(&x, &y, sizeof(x)) == 0;
}

void scn_result_print(const char *label, const kissm_result *r) {
    fprintf(stderr,
            "  %s: valid=%d reason=%d (%s) pts=%llu/%llu nonfinite=%llu/%llu voxels=%llu/%llu kp=%llu/%llu "
            "initial=%llu pruned=%llu (k=%llu) rot_inl=%llu final=%llu rms=%g t=(%.6f %.6f %.6f) total=%.2fms "
            "refine: corr=%llu it=%d conv=%d overlap=%g rmse=%g cond=%g %.2fms\n",
            label, (int)r->valid, (int)r->reason, kissm_reason_string(r->reason),
            (unsigned long long)r->num_source_points, (unsigned long long)r->num_target_points,
            (unsigned long long)r->num_source_nonfinite, (unsigned long long)r->num_target_nonfinite,
            (unsigned long long)r->num_source_voxels, (unsigned long long)r->num_target_voxels,
            (unsigned long long)r->num_source_keypoints, (unsigned long long)r->num_target_keypoints,
            (unsigned long long)r->num_initial_correspondences, (unsigned long long)r->num_pruned_correspondences,
            (unsigned long long)r->max_core_number, (unsigned long long)r->num_rotation_inliers,
            (unsigned long long)r->num_final_inliers, r->residual_rms, r->translation[0], r->translation[1],
            r->translation[2], r->time_total_ms, (unsigned long long)r->num_refine_correspondences,
            (int)r->refine_iterations, (int)r->refine_converged, r->overlap, r->refine_rmse, r->refine_condition,
            r->time_refine_ms);
}

double scn_now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
