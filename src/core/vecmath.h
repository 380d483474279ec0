/* vec3, quaternion and HLU-frame math, header-only (static inline) so the hot loops of the
 * solvers and the turtle inline it. Quaternions are unit quaternions w + xi + yj + zk; a vector v
 * is rotated as q v q*. Frames are orthonormal and right-handed: H x L = U. */
#ifndef CBM_VECMATH_H
#define CBM_VECMATH_H

#include "cambium/base.h"

#include <math.h>

#ifndef CBM_PI
#define CBM_PI 3.14159265358979323846
#endif

static inline cbm_vec3 v3(double x, double y, double z)
{
    cbm_vec3 r = {x, y, z};
    return r;
}
static inline cbm_vec3 v3_add(cbm_vec3 a, cbm_vec3 b)
{
    return v3(a.x + b.x, a.y + b.y, a.z + b.z);
}
static inline cbm_vec3 v3_sub(cbm_vec3 a, cbm_vec3 b)
{
    return v3(a.x - b.x, a.y - b.y, a.z - b.z);
}
static inline cbm_vec3 v3_scale(cbm_vec3 a, double s)
{
    return v3(a.x * s, a.y * s, a.z * s);
}
/// a + s*b
static inline cbm_vec3 v3_madd(cbm_vec3 a, cbm_vec3 b, double s)
{
    return v3(a.x + s * b.x, a.y + s * b.y, a.z + s * b.z);
}
static inline cbm_vec3 v3_neg(cbm_vec3 a)
{
    return v3(-a.x, -a.y, -a.z);
}
static inline double v3_dot(cbm_vec3 a, cbm_vec3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
static inline cbm_vec3 v3_cross(cbm_vec3 a, cbm_vec3 b)
{
    return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline double v3_norm(cbm_vec3 a)
{
    return sqrt(v3_dot(a, a));
}
static inline double v3_norm2(cbm_vec3 a)
{
    return v3_dot(a, a);
}
/// Unit vector along a; a itself if its length is 0.
static inline cbm_vec3 v3_normalize(cbm_vec3 a)
{
    double n = v3_norm(a);
    return n > 0.0 ? v3_scale(a, 1.0 / n) : a;
}
static inline cbm_vec3 v3_mul(cbm_vec3 a, cbm_vec3 b)
{
    return v3(a.x * b.x, a.y * b.y, a.z * b.z);
}
static inline double v3_maxabs(cbm_vec3 a)
{
    double m = fabs(a.x);
    if (fabs(a.y) > m)
        m = fabs(a.y);
    if (fabs(a.z) > m)
        m = fabs(a.z);
    return m;
}
static inline int v3_isfinite(cbm_vec3 a)
{
    return isfinite(a.x) && isfinite(a.y) && isfinite(a.z);
}

/* ---- quaternions ---- */

static inline cbm_quat q_identity(void)
{
    cbm_quat q = {1.0, 0.0, 0.0, 0.0};
    return q;
}
/// Rotation by `angle` radians about the unit vector `axis` (right-hand rule).
static inline cbm_quat q_axis_angle(cbm_vec3 axis, double angle)
{
    double h = 0.5 * angle, s = sin(h);
    cbm_quat q = {cos(h), axis.x * s, axis.y * s, axis.z * s};
    return q;
}
/// Rotation by the rotation vector r (axis r/|r|, angle |r|); identity for r = 0. Accurate for
/// small |r| (uses sin(x)/x by its series near 0).
static inline cbm_quat q_from_rotvec(cbm_vec3 r)
{
    double a = v3_norm(r);
    double h = 0.5 * a;
    double k; /* sin(h)/a */
    if (a < 1e-4)
        k = 0.5 - a * a / 48.0;
    else
        k = sin(h) / a;
    cbm_quat q = {cos(h), r.x * k, r.y * k, r.z * k};
    return q;
}
/// Hamilton product a*b: rotation b followed by rotation a.
static inline cbm_quat q_mul(cbm_quat a, cbm_quat b)
{
    cbm_quat r = {a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z,
                  a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
                  a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
                  a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
    return r;
}
static inline cbm_quat q_conj(cbm_quat q)
{
    cbm_quat r = {q.w, -q.x, -q.y, -q.z};
    return r;
}
static inline cbm_quat q_normalize(cbm_quat q)
{
    double n = sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
    cbm_quat r = {q.w / n, q.x / n, q.y / n, q.z / n};
    return r;
}
/// The first axis (H) of the frame of a unit quaternion: q e_x q*, written out.
static inline cbm_vec3 q_h(cbm_quat q)
{
    return v3(1.0 - 2.0 * (q.y * q.y + q.z * q.z), 2.0 * (q.x * q.y + q.w * q.z),
              2.0 * (q.x * q.z - q.w * q.y));
}

/// q v q*
static inline cbm_vec3 q_rotate(cbm_quat q, cbm_vec3 v)
{
    cbm_vec3 u = v3(q.x, q.y, q.z);
    cbm_vec3 t = v3_scale(v3_cross(u, v), 2.0);
    return v3_add(v3_add(v, v3_scale(t, q.w)), v3_cross(u, t));
}

/* ---- frames ---- */

static inline cbm_frame frame_identity(void)
{
    /* heading up (+y), left -x... choose H=+y, L=-x, U=+z so H x L = U */
    cbm_frame f = {{0, 1, 0}, {-1, 0, 0}, {0, 0, 1}};
    return f;
}
static inline cbm_frame frame_rotate(cbm_quat q, cbm_frame f)
{
    cbm_frame r = {q_rotate(q, f.h), q_rotate(q, f.l), q_rotate(q, f.u)};
    return r;
}
/// Components of world vector v in the frame: (v.H, v.L, v.U).
static inline cbm_vec3 frame_to_local(cbm_frame f, cbm_vec3 v)
{
    return v3(v3_dot(v, f.h), v3_dot(v, f.l), v3_dot(v, f.u));
}
/// World vector from local components (h, l, u).
static inline cbm_vec3 frame_to_world(cbm_frame f, cbm_vec3 c)
{
    return v3_add(v3_add(v3_scale(f.h, c.x), v3_scale(f.l, c.y)), v3_scale(f.u, c.z));
}
/// Gram-Schmidt on H then L; U = H x L.
static inline cbm_frame frame_orthonormalize(cbm_frame f)
{
    cbm_frame r;
    r.h = v3_normalize(f.h);
    r.l = v3_normalize(v3_madd(f.l, r.h, -v3_dot(f.l, r.h)));
    r.u = v3_cross(r.h, r.l);
    return r;
}

#endif
