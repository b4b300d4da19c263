// SPDX-License-Identifier: MIT
// Ray intersections with the primitives and the ground (see ray_geometry.hpp).
#include "ray_geometry.hpp"

#include <algorithm>
#include <cmath>

namespace kissm_sim {
namespace {

// Each returns the distance along the ray to the first hit in front of the origin, or +inf.

double hit_box(const Box &b, const Ray &r) {
    const double ox = r.o[0] - b.c[0], oy = r.o[1] - b.c[1];
    const double o[3] = {b.cs * ox + b.sn * oy, -b.sn * ox + b.cs * oy, r.o[2] - b.c[2]};
    const double d[3] = {b.cs * r.d[0] + b.sn * r.d[1], -b.sn * r.d[0] + b.cs * r.d[1], r.d[2]};
    double tmin = -kInf, tmax = kInf;
    for (int k = 0; k < 3; ++k) {
        if (std::fabs(d[k]) < 1e-12) {
            if (std::fabs(o[k]) > b.h[k]) return kInf;
            continue;
        }
        double t1 = (-b.h[k] - o[k]) / d[k];
        double t2 = (b.h[k] - o[k]) / d[k];
        if (t1 > t2) std::swap(t1, t2);
        tmin = std::max(tmin, t1);
        tmax = std::min(tmax, t2);
        if (tmin > tmax) return kInf;
    }
    return tmin > 0.0 ? tmin : kInf; // an origin inside a box sees nothing of it
}

double hit_cylinder(const Cylinder &c, const Ray &r) {
    const double ox = r.o[0] - c.cx, oy = r.o[1] - c.cy;
    double best = kInf;
    const double a = r.d[0] * r.d[0] + r.d[1] * r.d[1];
    if (a > 1e-12) {
        const double b = 2.0 * (ox * r.d[0] + oy * r.d[1]);
        const double cc = ox * ox + oy * oy - c.r * c.r;
        const double disc = b * b - 4.0 * a * cc;
        if (disc >= 0.0) {
            const double t = (-b - std::sqrt(disc)) / (2.0 * a);
            if (t > 0.0) {
                const double z = r.o[2] + t * r.d[2];
                if (z >= c.z0 && z <= c.z1) best = t;
            }
        }
    }
    if (r.d[2] < 0.0) { // the top cap, seen from above
        const double t = (c.z1 - r.o[2]) / r.d[2];
        if (t > 0.0 && t < best) {
            const double x = ox + t * r.d[0], y = oy + t * r.d[1];
            if (x * x + y * y <= c.r * c.r) best = t;
        }
    }
    return best;
}

double hit_ellipsoid(const Ellipsoid &e, const Ray &r, Rng &rng) {
    // Scale z so that the ellipsoid becomes a sphere of radius rxy; t keeps its meaning along the ray.
    const double s = e.rxy / e.rz;
    const double o[3] = {r.o[0] - e.c[0], r.o[1] - e.c[1], (r.o[2] - e.c[2]) * s};
    const double d[3] = {r.d[0], r.d[1], r.d[2] * s};
    const double a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    const double b = 2.0 * (o[0] * d[0] + o[1] * d[1] + o[2] * d[2]);
    const double c = o[0] * o[0] + o[1] * o[1] + o[2] * o[2] - e.rxy * e.rxy;
    const double disc = b * b - 4.0 * a * c;
    if (disc < 0.0) return kInf;
    const double sq = std::sqrt(disc);
    const double t0 = (-b - sq) / (2.0 * a);
    const double t1 = (-b + sq) / (2.0 * a);
    if (t1 <= 0.0) return kInf;
    const double enter = std::max(t0, 0.0);
    if (e.free_path <= 0.0) return enter > 0.0 ? enter : kInf;
    const double t = enter + rng.exponential(e.free_path);
    return t <= t1 ? t : kInf; // a ray may pass through sparse foliage
}

} // namespace

// First crossing of the ray with the height field, up to max_t: safe steps until the sign changes, then the
// Illinois variant of regula falsi. Away from the kerbs |f'| <= |dz| + max_gradient; a kerb can raise the
// ground by at most curb_height (plus the roughness it scales) within a step, so a step of
// (f - jump) / lipschitz cannot pass through the surface.
double hit_ground(const Ground &g, const Ray &r, double max_t) {
    const double dz = r.d[2];
    if (dz >= -1e-9) return kInf; // the sensor is well above the ground's whole height range
    const double t_lo = std::max(0.0, (r.o[2] - g.hmax) / -dz);
    const double t_hi = std::min(max_t, (r.o[2] - g.hmin) / -dz);
    if (t_lo > t_hi) return kInf;
    const auto f = [&](double t) { return r.o[2] + t * dz - g.height(r.o[0] + t * r.d[0], r.o[1] + t * r.d[1]); };
    const double lipschitz = -dz + g.max_gradient;
    const double jump = g.curb_height + Ground::kRoughWaves * std::fabs(g.rough_off_road - g.rough_road);
    double ta = t_lo, fa = f(ta);
    if (fa <= 0.0) return ta > 0.0 ? ta : kInf;
    while (ta < t_hi) {
        const double tb = std::min(t_hi, ta + std::max((fa - jump) / lipschitz, 0.1));
        const double fb = f(tb);
        if (fb <= 0.0) {
            double lo = ta, flo = fa, hi = tb, fhi = fb;
            int side = 0;
            for (int iter = 0; iter < 30; ++iter) {
                const double t = (lo * fhi - hi * flo) / (fhi - flo);
                const double ft = f(t);
                if (std::fabs(ft) < 1e-7) return t;
                if (ft > 0.0) {
                    lo = t;
                    flo = ft;
                    if (side == 1) fhi *= 0.5;
                    side = 1;
                } else {
                    hi = t;
                    fhi = ft;
                    if (side == -1) flo *= 0.5;
                    side = -1;
                }
            }
            return 0.5 * (lo + hi);
        }
        ta = tb;
        fa = fb;
    }
    return kInf;
}

double hit_prim(const Scene &s, const PrimRef &p, const Ray &r, Rng &rng) {
    switch (p.kind) {
    case Kind::Box: return hit_box(s.boxes[p.index], r);
    case Kind::Cylinder: return hit_cylinder(s.cylinders[p.index], r);
    case Kind::Ellipsoid: return hit_ellipsoid(s.ellipsoids[p.index], r, rng);
    }
    return kInf;
}

} // namespace kissm_sim
