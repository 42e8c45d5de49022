/* gf_math.h — the one vector / matrix / quaternion library of gfins_fmi.
 *
 * Plain fixed-size arrays, no heap, no state: every function is a pure static inline
 * function so that hot loops inline it.
 *
 * Conventions (used by every module of the core):
 *   - vectors are double[3]; matrices are gf_mat3 (a struct around double m[3][3],
 *     row-major m[row][col]; the struct lets const matrices be passed in ISO C11);
 *   - quaternions are double[4] = {q0, q1, q2, q3}, scalar first, Hamilton product
 *     (i*j = k), as in Savage (Strapdown Analytics) and seed 002;
 *   - a quaternion q_b^n rotates body-frame vectors into the navigation frame:
 *     v^n = q (x) [0, v^b] (x) q*, and gf_quat_to_dcm(q) returns C_b^n.
 *   - functions write their result through the last argument; outputs may alias
 *     inputs except where stated.
 */
#ifndef GF_MATH_H
#define GF_MATH_H

#include <math.h>
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

#define GF_PI 3.14159265358979323846
#define GF_HALF_PI (0.5 * GF_PI)
#define GF_SQRT2 1.41421356237309504880
#define GF_SQRT1_2 0.70710678118654752440

/* 1 if all n values are finite. x - x is 0 for finite x and NaN for NaN or +-Inf, so
 * one sum tests every element without a branch per element. */
static inline int gf_all_finite(const double *x, size_t n)
{
    double acc = 0.0;
    for (size_t i = 0; i < n; ++i)
        acc += x[i] - x[i];
    return acc == 0.0;
}

/* ---- 3-vectors ------------------------------------------------------------ */

static inline void gf_v3_set(double x, double y, double z, double out[3])
{
    out[0] = x; out[1] = y; out[2] = z;
}

static inline void gf_v3_copy(const double a[3], double out[3])
{
    out[0] = a[0]; out[1] = a[1]; out[2] = a[2];
}

static inline void gf_v3_add(const double a[3], const double b[3], double out[3])
{
    out[0] = a[0] + b[0]; out[1] = a[1] + b[1]; out[2] = a[2] + b[2];
}

static inline void gf_v3_sub(const double a[3], const double b[3], double out[3])
{
    out[0] = a[0] - b[0]; out[1] = a[1] - b[1]; out[2] = a[2] - b[2];
}

static inline void gf_v3_scale(const double a[3], double s, double out[3])
{
    out[0] = s * a[0]; out[1] = s * a[1]; out[2] = s * a[2];
}

/* out = a + s * b */
static inline void gf_v3_axpy(const double a[3], double s, const double b[3], double out[3])
{
    out[0] = a[0] + s * b[0]; out[1] = a[1] + s * b[1]; out[2] = a[2] + s * b[2];
}

static inline double gf_v3_dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static inline double gf_v3_norm(const double a[3])
{
    return sqrt(gf_v3_dot(a, a));
}

/* out = a x b; out must not alias a or b. */
static inline void gf_v3_cross(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static inline int gf_v3_isfinite(const double a[3])
{
    return gf_all_finite(a, 3);
}

/* ---- 3x3 matrices --------------------------------------------------------- */

typedef struct gf_mat3 {
    double m[3][3];
} gf_mat3;

static inline void gf_m3_identity(gf_mat3 *out)
{
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            out->m[i][j] = (i == j) ? 1.0 : 0.0;
}

/* out = m * v; out must not alias v. */
static inline void gf_m3_mul_v3(const gf_mat3 *a, const double v[3], double out[3])
{
    for (int i = 0; i < 3; ++i)
        out[i] = a->m[i][0] * v[0] + a->m[i][1] * v[1] + a->m[i][2] * v[2];
}

/* out = m^T * v; out must not alias v. */
static inline void gf_m3t_mul_v3(const gf_mat3 *a, const double v[3], double out[3])
{
    for (int i = 0; i < 3; ++i)
        out[i] = a->m[0][i] * v[0] + a->m[1][i] * v[1] + a->m[2][i] * v[2];
}

/* out = a * b; out must not alias a or b. */
static inline void gf_m3_mul(const gf_mat3 *a, const gf_mat3 *b, gf_mat3 *out)
{
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            out->m[i][j] = a->m[i][0] * b->m[0][j] + a->m[i][1] * b->m[1][j] +
                           a->m[i][2] * b->m[2][j];
}

/* out = a^T; out may alias a. */
static inline void gf_m3_transpose(const gf_mat3 *a, gf_mat3 *out)
{
    gf_mat3 t;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            t.m[i][j] = a->m[j][i];
    *out = t;
}

/* Skew-symmetric (cross-product) matrix: skew(a) * b = a x b. */
static inline void gf_m3_skew(const double a[3], gf_mat3 *out)
{
    out->m[0][0] = 0.0;   out->m[0][1] = -a[2]; out->m[0][2] = a[1];
    out->m[1][0] = a[2];  out->m[1][1] = 0.0;   out->m[1][2] = -a[0];
    out->m[2][0] = -a[1]; out->m[2][1] = a[0];  out->m[2][2] = 0.0;
}

/* ---- quaternions ---------------------------------------------------------- */

static inline void gf_q_identity(double out[4])
{
    out[0] = 1.0; out[1] = 0.0; out[2] = 0.0; out[3] = 0.0;
}

/* Hamilton product out = p (x) q; out may alias p or q. */
static inline void gf_q_mul(const double p[4], const double q[4], double out[4])
{
    const double w = p[0] * q[0] - p[1] * q[1] - p[2] * q[2] - p[3] * q[3];
    const double x = p[0] * q[1] + p[1] * q[0] + p[2] * q[3] - p[3] * q[2];
    const double y = p[0] * q[2] - p[1] * q[3] + p[2] * q[0] + p[3] * q[1];
    const double z = p[0] * q[3] + p[1] * q[2] - p[2] * q[1] + p[3] * q[0];
    out[0] = w; out[1] = x; out[2] = y; out[3] = z;
}

static inline void gf_q_conj(const double q[4], double out[4])
{
    out[0] = q[0]; out[1] = -q[1]; out[2] = -q[2]; out[3] = -q[3];
}

static inline double gf_q_norm(const double q[4])
{
    return sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
}

/* Normalises q in place into out. Returns 0 (and leaves out untouched) when q cannot
 * be normalised (zero or non-finite norm), 1 otherwise. */
static inline int gf_q_normalize(const double q[4], double out[4])
{
    const double n = gf_q_norm(q);
    if (!(n > 0.0) || !isfinite(n))
        return 0;
    const double s = 1.0 / n;
    out[0] = q[0] * s; out[1] = q[1] * s; out[2] = q[2] * s; out[3] = q[3] * s;
    return 1;
}

/* Quaternion of the rotation vector phi (axis * angle, rad): q = [cos|phi|/2,
 * sin(|phi|/2) phi/|phi|]. Uses the Taylor series below 1e-4 rad so that the
 * result is exact to round-off for tiny increments. */
static inline void gf_q_from_rotvec(const double phi_rad[3], double out[4])
{
    const double a2 = gf_v3_dot(phi_rad, phi_rad);
    double c, s; /* c = cos(a/2), s = sin(a/2)/a */
    if (a2 < 1e-8) {
        c = 1.0 - a2 / 8.0 + a2 * a2 / 384.0;
        s = 0.5 - a2 / 48.0 + a2 * a2 / 3840.0;
    } else {
        const double a = sqrt(a2);
        c = cos(0.5 * a);
        s = sin(0.5 * a) / a;
    }
    out[0] = c; out[1] = s * phi_rad[0]; out[2] = s * phi_rad[1]; out[3] = s * phi_rad[2];
}

/* gf_q_from_rotvec without trigonometry for |phi| < 0.1 rad (the usual size of one
 * navigation update): Taylor series of cos(a/2) and sin(a/2)/a to a^10, whose remainder
 * is below 1e-19 there; larger angles go to gf_q_from_rotvec. */
static inline void gf_q_from_rotvec_fast(const double phi[3], double q[4])
{
    const double a2 = gf_v3_dot(phi, phi);
    if (a2 < 1e-2) {
        const double x = 0.25 * a2; /* (a/2)^2 */
        const double c = 1.0 - x * (1.0 / 2 - x * (1.0 / 24 - x * (1.0 / 720 - x * (1.0 / 40320 - x / 3628800.0))));
        const double s = 0.5 * (1.0 - x * (1.0 / 6 - x * (1.0 / 120 - x * (1.0 / 5040 - x * (1.0 / 362880 - x / 39916800.0)))));
        q[0] = c;
        q[1] = s * phi[0];
        q[2] = s * phi[1];
        q[3] = s * phi[2];
    } else {
        gf_q_from_rotvec(phi, q);
    }
}

/* Rotation vector (rad) of a unit quaternion, the inverse of gf_q_from_rotvec on the
 * shortest rotation (angle in [0, pi]; q and -q give the same vector). */
static inline void gf_q_to_rotvec(const double q[4], double out_rad[3])
{
    const double sgn = q[0] < 0.0 ? -1.0 : 1.0;
    const double c = sgn * q[0];
    const double v[3] = {sgn * q[1], sgn * q[2], sgn * q[3]};
    const double sn = gf_v3_norm(v);
    /* angle = 2 atan2(|v|, c); the factor angle / |v| -> 2 / c (1 - |v|^2 / (3 c^2))
     * for tiny |v|, where the remainder (|v|^4 terms) is below round-off */
    const double k = sn < 1e-8 ? 2.0 / c * (1.0 - sn * sn / (3.0 * c * c))
                               : 2.0 * atan2(sn, c) / sn;
    gf_v3_scale(v, k, out_rad);
}

/* Rotates v by q: out = q (x) [0, v] (x) q*; out may alias v. */
static inline void gf_q_rotate(const double q[4], const double v[3], double out[3])
{
    /* t = 2 q_v x v;  out = v + q0 t + q_v x t  (Rodrigues form, 15 mul) */
    const double qv[3] = {q[1], q[2], q[3]};
    double t[3], u[3];
    gf_v3_cross(qv, v, t);
    gf_v3_scale(t, 2.0, t);
    gf_v3_cross(qv, t, u);
    out[0] = v[0] + q[0] * t[0] + u[0];
    out[1] = v[1] + q[0] * t[1] + u[1];
    out[2] = v[2] + q[0] * t[2] + u[2];
}

/* Direction cosine matrix of a unit quaternion q_b^n: returns C_b^n. */
static inline void gf_q_to_dcm(const double q[4], gf_mat3 *dcm)
{
    const double q0 = q[0], q1 = q[1], q2 = q[2], q3 = q[3];
    double (*out)[3] = dcm->m;
    out[0][0] = q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3;
    out[0][1] = 2.0 * (q1 * q2 - q0 * q3);
    out[0][2] = 2.0 * (q1 * q3 + q0 * q2);
    out[1][0] = 2.0 * (q1 * q2 + q0 * q3);
    out[1][1] = q0 * q0 - q1 * q1 + q2 * q2 - q3 * q3;
    out[1][2] = 2.0 * (q2 * q3 - q0 * q1);
    out[2][0] = 2.0 * (q1 * q3 - q0 * q2);
    out[2][1] = 2.0 * (q2 * q3 + q0 * q1);
    out[2][2] = q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3;
}

/* The unit quaternion of a rotation matrix (the inverse of gf_q_to_dcm), scalar part
 * >= 0: Shepperd's method, from the largest of 1 + trace and 1 + 2 m_ii - trace, so that
 * no small divisor appears (Shepperd, J. Guidance Control 1(3), 1978). */
static inline void gf_q_from_dcm(const gf_mat3 *dcm, double q[4])
{
    const double (*m)[3] = dcm->m;
    const double tr = m[0][0] + m[1][1] + m[2][2];
    const double c[4] = {1.0 + tr, 1.0 + 2.0 * m[0][0] - tr, 1.0 + 2.0 * m[1][1] - tr,
                         1.0 + 2.0 * m[2][2] - tr};
    int k = 0;
    for (int i = 1; i < 4; ++i)
        if (c[i] > c[k])
            k = i;
    const double r = sqrt(c[k]), h = 0.5 / r;
    double v[4];
    if (k == 0) {
        v[0] = 0.5 * r; v[1] = (m[2][1] - m[1][2]) * h; v[2] = (m[0][2] - m[2][0]) * h;
        v[3] = (m[1][0] - m[0][1]) * h;
    } else if (k == 1) {
        v[0] = (m[2][1] - m[1][2]) * h; v[1] = 0.5 * r; v[2] = (m[0][1] + m[1][0]) * h;
        v[3] = (m[0][2] + m[2][0]) * h;
    } else if (k == 2) {
        v[0] = (m[0][2] - m[2][0]) * h; v[1] = (m[0][1] + m[1][0]) * h; v[2] = 0.5 * r;
        v[3] = (m[1][2] + m[2][1]) * h;
    } else {
        v[0] = (m[1][0] - m[0][1]) * h; v[1] = (m[0][2] + m[2][0]) * h;
        v[2] = (m[1][2] + m[2][1]) * h; v[3] = 0.5 * r;
    }
    const double s = v[0] < 0.0 ? -1.0 : 1.0;
    for (int i = 0; i < 4; ++i)
        q[i] = s * v[i];
}

/* ---- profiles ------------------------------------------------------------- */

/* C2 smooth step S(s) = s - sin(2 pi s)/(2 pi) on [0, 1] (s clamped), its derivatives
 * S' = 1 - cos(2 pi s), S'' = 2 pi sin(2 pi s) (both vanish at s = 0 and 1) and its
 * integral I(s) = int_0^s S = s^2/2 + (cos(2 pi s) - 1)/(4 pi^2): the one step shape of
 * the vehicle profiles (gf_vehicle) and the turns of the rotation schedules
 * (gf_rot). */
static inline void gf_smooth_step(double s, double *S, double *dS, double *ddS, double *I)
{
    s = s < 0.0 ? 0.0 : (s > 1.0 ? 1.0 : s);
    const double w = 2.0 * GF_PI * s;
    *S = s - sin(w) / (2.0 * GF_PI);
    *dS = 1.0 - cos(w);
    *ddS = 2.0 * GF_PI * sin(w);
    *I = 0.5 * s * s + (cos(w) - 1.0) / (4.0 * GF_PI * GF_PI);
}

#ifdef __cplusplus
}
#endif

#endif /* GF_MATH_H */
