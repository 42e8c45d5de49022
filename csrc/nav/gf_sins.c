/* gf_sins.c — ENU quaternion strapdown mechanization; equations in gf_sins.h. */
#include "nav/gf_sins.h"

#include <math.h>
#include <string.h>

#include "base/gf_math.h"


gf_status gf_sins_config_default(gf_sins_config *cfg)
{
    if (!cfg)
        return GF_ERR_NULL_POINTER;
    memset(cfg, 0, sizeof *cfg);
    cfg->input = GF_SINS_INPUT_INCREMENTS;
    cfg->coning = 1;
    cfg->vertical = GF_SINS_VERTICAL_FREE;
    cfg->earth = GF_SINS_EARTH_WGS84;
    cfg->hold_height_m = 0.0;
    cfg->baro_tau_s = 10.0;
    cfg->max_rate_rad_s = 50.0;
    cfg->max_specific_force_m_s2 = 1000.0;
    cfg->subsamples = 1;
    return GF_OK;
}

static int config_is_valid(const gf_sins_config *c)
{
    return (c->input == GF_SINS_INPUT_INCREMENTS || c->input == GF_SINS_INPUT_RATES) &&
           (c->coning == 0 || c->coning == 1) &&
           (c->vertical >= GF_SINS_VERTICAL_FREE && c->vertical <= GF_SINS_VERTICAL_BARO) &&
           (c->earth == GF_SINS_EARTH_WGS84 || c->earth == GF_SINS_EARTH_FLAT) &&
           c->flat_gravity_m_s2 >= 0.0 && isfinite(c->flat_gravity_m_s2) &&
           gf_earth_height_ok(c->hold_height_m) && /* gf_earth's range */
           c->baro_tau_s > 0.0 && isfinite(c->baro_tau_s) &&
           c->max_rate_rad_s > 0.0 && isfinite(c->max_rate_rad_s) &&
           c->max_specific_force_m_s2 > 0.0 && isfinite(c->max_specific_force_m_s2) &&
           c->subsamples >= 1 && c->subsamples <= GF_SINS_MAX_SUBSAMPLES &&
           (c->subsamples == 1 || c->input == GF_SINS_INPUT_INCREMENTS);
}

/* ---- attitude conventions (seed 002) ---------------------------------------------- */

static void quat_axis(int axis, double angle_rad, double q[4])
{
    q[0] = cos(0.5 * angle_rad);
    q[1] = q[2] = q[3] = 0.0;
    q[1 + axis] = sin(0.5 * angle_rad);
}

/* A caller's attitude quaternion made unit: the norm of a tiny one (components near
 * 1e-160, whose squares are denormal) is inexact, so the result is normalised again
 * and must then be unit to round-off (found by fuzzing: gf_sins_set_navigation stored
 * |q| - 1 = 7e-5 and the state was refused by gf_sins_state_check). 0: not
 * normalisable. */
static int q_normalize_given(const double q_in[4], double q[4])
{
    for (int pass = 0; pass < 2; ++pass) {
        if (!gf_q_normalize(pass ? q : q_in, q))
            return 0;
        const double n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
        if (fabs(n2 - 1.0) <= 1e-12)
            return 1;
    }
    return 0;
}

gf_status gf_euler_to_quat(const double *euler_rad, double *q_bn)
{
    if (!euler_rad || !q_bn)
        return GF_ERR_NULL_POINTER;
    if (!gf_all_finite(euler_rad, 3))
        return GF_ERR_NONFINITE_INPUT;
    /* C_b^n = Rz(-psi) Rx(theta) Ry(gamma) */
    double qz[4], qx[4], qy[4], t[4];
    quat_axis(2, -euler_rad[0], qz);
    quat_axis(0, euler_rad[1], qx);
    quat_axis(1, euler_rad[2], qy);
    gf_q_mul(qz, qx, t);
    gf_q_mul(t, qy, q_bn);
    return GF_OK;
}

/* Tolerance on |q| for Euler angles: unit quaternions carry a few ulp; a caller's
 * quaternion off by more is not an attitude (normalise it first). */
#define GF_QUAT_UNIT_TOL 1e-6

gf_status gf_quat_to_euler(const double *q_bn, double *euler_rad)
{
    if (!q_bn || !euler_rad)
        return GF_ERR_NULL_POINTER;
    if (!gf_all_finite(q_bn, 4))
        return GF_ERR_NONFINITE_INPUT;
    /* |q| within the tolerance of 1, tested on |q|^2 (no square root) */
    const double n2 = q_bn[0] * q_bn[0] + q_bn[1] * q_bn[1] + q_bn[2] * q_bn[2] + q_bn[3] * q_bn[3];
    if (!(n2 >= (1.0 - GF_QUAT_UNIT_TOL) * (1.0 - GF_QUAT_UNIT_TOL) &&
          n2 <= (1.0 + GF_QUAT_UNIT_TOL) * (1.0 + GF_QUAT_UNIT_TOL)))
        return GF_ERR_BAD_PARAMETER;
    /* The angles of the rotation q stands for: gf_q_to_dcm of a quaternion of norm |q|
     * gives |q|^2 times that rotation's matrix. The atan2 pairs are ratios of two entries
     * (the factor cancels); the asin argument is divided by |q|^2. */
    gf_mat3 C;
    gf_q_to_dcm(q_bn, &C);
    /* C[2][1] = sin(theta); C[2][0] = -cos(theta) sin(gamma), C[2][2] = cos(theta) cos(gamma);
     * C[0][1] = sin(psi) cos(theta), C[1][1] = cos(psi) cos(theta) */
    const double s = fmax(-1.0, fmin(1.0, C.m[2][1] / n2));
    double psi, gamma;
    const double theta = asin(s);
    if (fabs(s) < 1.0 - 1e-12) {
        gamma = atan2(-C.m[2][0], C.m[2][2]);
        psi = atan2(C.m[0][1], C.m[1][1]);
    } else { /* pitch +-90 deg: heading and roll are one angle; roll taken 0 */
        gamma = 0.0;
        psi = atan2(-C.m[0][2] * s, C.m[0][0]);
    }
    if (psi < 0.0)
        psi += 2.0 * GF_PI;
    if (psi >= 2.0 * GF_PI) /* -0 rounding up */
        psi -= 2.0 * GF_PI;
    euler_rad[0] = psi;
    euler_rad[1] = theta;
    euler_rad[2] = gamma;
    return GF_OK;
}

gf_status gf_quat_to_euler_batch(size_t n, const double *q_bn, double *euler_rad,
                                 size_t *n_done)
{
    if (n_done)
        *n_done = 0;
    if (!q_bn || !euler_rad)
        return GF_ERR_NULL_POINTER;
    for (size_t k = 0; k < n; ++k) {
        const gf_status st = gf_quat_to_euler(q_bn + 4 * k, euler_rad + 3 * k);
        if (st != GF_OK) {
            if (n_done)
                *n_done = k;
            return st;
        }
    }
    if (n_done)
        *n_done = n;
    return GF_OK;
}

/* ---- initialisation ---------------------------------------------------------------- */

gf_status gf_sins_init(gf_sins_state *state, const gf_sins_config *cfg, const double *q_bn,
                       const double *v_n_m_s, double lat_rad, double lon_rad, double h_m,
                       double t0_s)
{
    if (!state || !cfg || !q_bn || !v_n_m_s)
        return GF_ERR_NULL_POINTER;
    if (!config_is_valid(cfg))
        return GF_ERR_BAD_PARAMETER;
    if (!gf_v3_isfinite(v_n_m_s) || !isfinite(lat_rad) || !isfinite(lon_rad) ||
        !isfinite(h_m) || !isfinite(t0_s))
        return GF_ERR_NONFINITE_INPUT;
    if (cfg->earth == GF_SINS_EARTH_WGS84 && !(fabs(lat_rad) < GF_SINS_LAT_LIMIT_RAD))
        return GF_ERR_BAD_PARAMETER;
    gf_earth e;
    const gf_status st = gf_earth_update(&e, lat_rad, h_m, v_n_m_s, 1.0);
    if (st != GF_OK)
        return st;
    double q[4];
    if (!q_normalize_given(q_bn, q))
        return GF_ERR_BAD_PARAMETER;
    memset(state, 0, sizeof *state);
    state->cfg = *cfg;
    memcpy(state->q_bn, q, sizeof q);
    gf_v3_copy(v_n_m_s, state->v_n_m_s);
    state->lat_rad = lat_rad;
    state->lon_rad = lon_rad;
    state->h_m = cfg->vertical == GF_SINS_VERTICAL_HOLD ? cfg->hold_height_m : h_m;
    if (cfg->vertical == GF_SINS_VERTICAL_HOLD)
        state->v_n_m_s[2] = 0.0;
    state->time_s = t0_s;
    state->earth_rate_sign = 1.0;
    state->sin_lat = e.sin_lat;
    state->cos_lat = e.cos_lat;
    state->R_M_m = e.R_M_m;
    return GF_OK;
}

gf_status gf_sins_position(const gf_sins_state *s, double *pos)
{
    if (!s || !pos)
        return GF_ERR_NULL_POINTER;
    if (s->cfg.earth == GF_SINS_EARTH_FLAT) {
        gf_v3_copy(s->flat_pos_m, pos);
    } else {
        pos[0] = s->lat_rad;
        pos[1] = s->lon_rad;
        pos[2] = s->h_m;
    }
    return GF_OK;
}

gf_status gf_sins_set_flat_position(gf_sins_state *state, const double *pos_m)
{
    if (!state || !pos_m)
        return GF_ERR_NULL_POINTER;
    if (!gf_v3_isfinite(pos_m))
        return GF_ERR_NONFINITE_INPUT;
    gf_v3_copy(pos_m, state->flat_pos_m);
    return GF_OK;
}

gf_status gf_sins_set_navigation(gf_sins_state *state, const double *q_bn,
                                 const double *v_n_m_s, double lat_rad, double lon_rad,
                                 double h_m)
{
    if (!state || !q_bn || !v_n_m_s)
        return GF_ERR_NULL_POINTER;
    if (!gf_all_finite(q_bn, 4) || !gf_v3_isfinite(v_n_m_s) || !isfinite(lat_rad) ||
        !isfinite(lon_rad) || !isfinite(h_m))
        return GF_ERR_NONFINITE_INPUT;
    /* the latitude limit of gf_sins_init and gf_sins_state_check (found by fuzzing: a
     * latitude between it and 90 deg was stored, and the state refused on restore) */
    if (state->cfg.earth == GF_SINS_EARTH_WGS84 && !(fabs(lat_rad) < GF_SINS_LAT_LIMIT_RAD))
        return GF_ERR_BAD_PARAMETER;
    gf_earth e;
    const gf_status st = gf_earth_update(&e, lat_rad, h_m, NULL, 1.0);
    if (st != GF_OK)
        return st;
    double q[4];
    if (!q_normalize_given(q_bn, q))
        return GF_ERR_BAD_PARAMETER;
    memcpy(state->q_bn, q, sizeof q);
    gf_v3_copy(v_n_m_s, state->v_n_m_s);
    if (lon_rad > GF_PI)
        lon_rad -= 2.0 * GF_PI;
    else if (lon_rad <= -GF_PI)
        lon_rad += 2.0 * GF_PI;
    state->lat_rad = lat_rad;
    state->lon_rad = lon_rad;
    state->h_m = h_m;
    state->sin_lat = e.sin_lat;
    state->cos_lat = e.cos_lat;
    state->R_M_m = e.R_M_m;
    return GF_OK;
}

gf_status gf_sins_reverse(gf_sins_state *state)
{
    if (!state)
        return GF_ERR_NULL_POINTER;
    gf_v3_scale(state->v_n_m_s, -1.0, state->v_n_m_s);
    state->earth_rate_sign = -state->earth_rate_sign;
    /* the next sample in reverse order is not adjacent to the stored one in the sense
     * the coning terms need, and in rate mode it is the same sample again */
    state->have_prev = 0;
    return GF_OK;
}

/* ---- the update -------------------------------------------------------------------- */

static inline int v3_finite(const double a[3])
{
    return gf_all_finite(a, 3);
}

/* sin and cos of (x + d) from sin x, cos x for |d| < 1e-4 rad by the angle-sum formulas
 * with sin d = d - d^3/6, cos d = 1 - d^2/2 (remainders d^5/120, d^4/24 < 5e-18) */
static inline void sincos_shift(double s, double c, double d, double *s_out, double *c_out)
{
    const double cd = 1.0 - 0.5 * d * d, sd = d * (1.0 - d * d / 6.0);
    const double s_new = s * cd + c * sd;
    *c_out = c * cd - s * sd;
    *s_out = s_new;
}

/* Products of unit quaternions have |q|^2 = 1 + O(eps): one Newton step of 1/sqrt,
 * q (3 - |q|^2)/2, normalises to round-off without sqrt or division; anything further
 * from 1 is normalised in full. 0 if q cannot be normalised. */
static inline int renormalize(double q[4])
{
    const double n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
    if (fabs(n2 - 1.0) < 1e-6) {
        const double k = 1.5 - 0.5 * n2;
        q[0] *= k; q[1] *= k; q[2] *= k; q[3] *= k;
        return 1;
    }
    return gf_q_normalize(q, q);
}

/* What every successful update (of `samples` samples) ends with: the last sample becomes
 * the previous one, time moves by T in the direction of travel. */
static inline void finish_update(gf_sins_state *s, const double gyro[3], const double accel[3],
                                 double T, uint64_t samples)
{
    gf_v3_copy(gyro, s->prev_gyro);
    gf_v3_copy(accel, s->prev_accel);
    s->have_prev = 1;
    s->time_s += s->earth_rate_sign > 0 ? T : -T;
    s->n_samples += samples;
}

static gf_status nav_update(gf_sins_state *s, const double qb[4], const double dv_b[3], double T,
                            double h_ext_m);

/* One update of *s by one sample. All checks come before any write, so an error leaves
 * *s unchanged. dir = +1 forward, -1 backward (gyro already negated by the caller). */
static gf_status sins_update(gf_sins_state *s, const double gyro[3], const double accel[3],
                             double dt_s, double h_ext_m)
{
    const gf_sins_config *cfg = &s->cfg;
    if (!v3_finite(gyro) || !v3_finite(accel) || isinf(h_ext_m))
        return GF_ERR_NONFINITE_INPUT;
    const int rates = cfg->input == GF_SINS_INPUT_RATES;
    const int first_rate = rates && !s->have_prev;
    if (!first_rate && !(dt_s > 0.0 && isfinite(dt_s)))
        return GF_ERR_BAD_TIME;
    /* absurd samples */
    const double w2 = gf_v3_dot(gyro, gyro), f2 = gf_v3_dot(accel, accel);
    const double wmax = cfg->max_rate_rad_s * (rates ? 1.0 : dt_s);
    const double fmax_ = cfg->max_specific_force_m_s2 * (rates ? 1.0 : dt_s);
    if (!(w2 <= wmax * wmax) || !(f2 <= fmax_ * fmax_))
        return GF_ERR_OUT_OF_RANGE;

    if (first_rate) { /* a rate record's first sample only starts it */
        gf_v3_copy(gyro, s->prev_gyro);
        gf_v3_copy(accel, s->prev_accel);
        s->have_prev = 1;
        s->n_samples += 1;
        return GF_OK;
    }

    const double T = dt_s;
    /* increments, coning and sculling (see gf_sins.h) */
    double dth[3], dv[3], cone[3] = {0, 0, 0}, scul[3] = {0, 0, 0};
    if (rates) {
        for (int i = 0; i < 3; ++i) {
            dth[i] = 0.5 * T * (s->prev_gyro[i] + gyro[i]);
            dv[i] = 0.5 * T * (s->prev_accel[i] + accel[i]);
        }
        if (cfg->coning) {
            double a[3], b[3];
            const double c = T * T / 12.0;
            gf_v3_cross(s->prev_gyro, gyro, a);
            gf_v3_scale(a, c, cone);
            gf_v3_cross(s->prev_gyro, accel, a);
            gf_v3_cross(s->prev_accel, gyro, b);
            gf_v3_add(a, b, a);
            gf_v3_scale(a, c, scul);
        }
    } else {
        gf_v3_copy(gyro, dth);
        gf_v3_copy(accel, dv);
        if (cfg->coning && s->have_prev) {
            double a[3], b[3];
            gf_v3_cross(s->prev_gyro, gyro, a);
            gf_v3_scale(a, 1.0 / 12.0, cone);
            gf_v3_cross(s->prev_gyro, accel, a);
            gf_v3_cross(s->prev_accel, gyro, b);
            gf_v3_add(a, b, a);
            gf_v3_scale(a, 1.0 / 12.0, scul);
        }
    }
    double phi[3], dv_b[3], t1[3];
    gf_v3_add(dth, cone, phi);
    gf_v3_cross(dth, dv, t1);
    for (int i = 0; i < 3; ++i)
        dv_b[i] = dv[i] + 0.5 * t1[i] + scul[i];
    double qb[4];
    gf_q_from_rotvec_fast(phi, qb);
    const gf_status status = nav_update(s, qb, dv_b, T, h_ext_m);
    if (status == GF_OK)
        finish_update(s, gyro, accel, T, 1);
    return status;
}

/* Coning and sculling weights of the m-subsample update (gf_sins.h): the last subsample
 * is crossed with sum_(i<m) k_i dtheta_i; derived in docs/sins.md (sympy) and equal to
 * PSINS' conefactors. Row m. */
static const double k_subsample[GF_SINS_MAX_SUBSAMPLES + 1][GF_SINS_MAX_SUBSAMPLES - 1] = {
    {0.0, 0.0, 0.0},
    {0.0, 0.0, 0.0},
    {2.0 / 3.0, 0.0, 0.0},
    {9.0 / 20.0, 27.0 / 20.0, 0.0},
    {54.0 / 105.0, 92.0 / 105.0, 214.0 / 105.0},
};

/* One update of *s by m (2..4) increments g, a (m x 3, processing order, gyro already
 * negated for reverse navigation) over sub-intervals dt[i]. Checks before writes; on
 * an error *bad = the sample's index in the group (m: not a sample's fault). */
static inline gf_status group_update_m(gf_sins_state *s, int m, const double *g,
                                       const double *a, const double *dt, double h_ext_m,
                                       int *bad)
{
    const gf_sins_config *cfg = &s->cfg;
    *bad = m;
    if (isinf(h_ext_m))
        return GF_ERR_NONFINITE_INPUT;
    double T = 0.0, th[3] = {0, 0, 0}, V[3] = {0, 0, 0}, cg[3] = {0, 0, 0}, ca[3] = {0, 0, 0};
    const double *k = k_subsample[m];
    for (int i = 0; i < m; ++i) {
        const double *gi = g + 3 * i, *ai = a + 3 * i;
        *bad = i;
        if (!v3_finite(gi) || !v3_finite(ai))
            return GF_ERR_NONFINITE_INPUT;
        if (!(dt[i] > 0.0 && isfinite(dt[i])))
            return GF_ERR_BAD_TIME;
        const double wmax = cfg->max_rate_rad_s * dt[i], fmax_ = cfg->max_specific_force_m_s2 * dt[i];
        if (!(gf_v3_dot(gi, gi) <= wmax * wmax) || !(gf_v3_dot(ai, ai) <= fmax_ * fmax_))
            return GF_ERR_OUT_OF_RANGE;
        T += dt[i];
        for (int j = 0; j < 3; ++j) {
            th[j] += gi[j];
            V[j] += ai[j];
        }
        if (i < m - 1)
            for (int j = 0; j < 3; ++j) {
                cg[j] += k[i] * gi[j];
                ca[j] += k[i] * ai[j];
            }
    }
    *bad = m;
    if (!isfinite(T))
        return GF_ERR_BAD_TIME;
    const double *gl = g + 3 * (m - 1), *al = a + 3 * (m - 1);
    double phi[3], dv_b[3], t1[3];
    gf_v3_cross(th, V, t1);
    if (cfg->coning) {
        double cone[3], s1[3], s2[3];
        gf_v3_cross(cg, gl, cone);
        gf_v3_cross(cg, al, s1);
        gf_v3_cross(ca, gl, s2);
        for (int j = 0; j < 3; ++j) {
            phi[j] = th[j] + cone[j];
            dv_b[j] = V[j] + 0.5 * t1[j] + (s1[j] + s2[j]);
        }
    } else {
        for (int j = 0; j < 3; ++j) {
            phi[j] = th[j];
            dv_b[j] = V[j] + 0.5 * t1[j];
        }
    }
    double qb[4];
    gf_q_from_rotvec_fast(phi, qb);
    const gf_status status = nav_update(s, qb, dv_b, T, h_ext_m);
    if (status != GF_OK)
        return status;
    finish_update(s, gl, al, T, (uint64_t)m);   /* the group's last sample is the previous one */
    return GF_OK;
}

/* group_update_m with m a constant in each branch, so that its loops unroll */
static gf_status group_update(gf_sins_state *s, int m, const double *g, const double *a,
                              const double *dt, double h_ext_m, int *bad)
{
    switch (m) {
    case 2: return group_update_m(s, 2, g, a, dt, h_ext_m, bad);
    case 3: return group_update_m(s, 3, g, a, dt, h_ext_m, bad);
    default: return group_update_m(s, 4, g, a, dt, h_ext_m, bad);
    }
}

/* The navigation update of one interval from its compensated increments: the rotation
 * qb = q(phi) (phi: body at the start -> body at the end, coning included) and velocity
 * increment dv_b (specific force integrated over the interval in the body frame at its
 * start, rotation and sculling included). Checks before writes: an error leaves *s
 * unchanged; the caller records the sample (finish_update) on GF_OK. */
static gf_status nav_update(gf_sins_state *s, const double qb[4], const double dv_b[3], double T,
                            double h_ext_m)
{
    const gf_sins_config *cfg = &s->cfg;
    if (cfg->earth == GF_SINS_EARTH_FLAT) {
        /* fixed frame: v' = C f + g, r' = v, q' = q w/2, g = [0, 0, -flat_gravity] */
        double dvn[3], v_new[3], q[4];
        gf_q_rotate(s->q_bn, dv_b, dvn);
        gf_v3_add(s->v_n_m_s, dvn, v_new);
        v_new[2] -= cfg->flat_gravity_m_s2 * T;
        gf_q_mul(s->q_bn, qb, q);
        double pos_new[3], a_new[3];
        for (int i = 0; i < 3; ++i) {
            pos_new[i] = s->flat_pos_m[i] + 0.5 * T * (s->v_n_m_s[i] + v_new[i]);
            a_new[i] = (v_new[i] - s->v_n_m_s[i]) / T;
        }
        /* finite but absurd velocities can overflow the position (found by fuzzing) */
        if (!renormalize(q) || !v3_finite(v_new) || !v3_finite(pos_new) || !v3_finite(a_new))
            return GF_ERR_DIVERGED;
        gf_v3_copy(pos_new, s->flat_pos_m);
        gf_v3_copy(a_new, s->a_n_m_s2);
        memcpy(s->q_bn, q, sizeof q);
        gf_v3_copy(v_new, s->v_n_m_s);
        return GF_OK;
    }

    /* mid-interval navigation quantities, extrapolated with the last acceleration: the
     * latitude moves by d = T/2 vN / (R_M + h) (a few 1e-7 rad at most), so sin and cos
     * at the mid point follow from the kept ones by the angle-sum formulas with
     * sin d = d - d^3/6 and cos d = 1 - d^2/2 (remainders d^5/120 and d^4/24, below
     * 5e-18 for |d| < 1e-4 rad); larger steps use libm */
    gf_earth e;
    double v_mid[3];
    gf_v3_axpy(s->v_n_m_s, 0.5 * T, s->a_n_m_s2, v_mid);
    const double h_mid = s->h_m + 0.5 * T * v_mid[2];
    const double d_mid = 0.5 * T * v_mid[1] / (s->R_M_m + s->h_m);
    const double lat_mid = s->lat_rad + d_mid;
    {
        const double d = d_mid;
        double s_mid, c_mid;
        if (fabs(d) < 1e-4) {
            sincos_shift(s->sin_lat, s->cos_lat, d, &s_mid, &c_mid);
        } else {
            s_mid = sin(lat_mid);
            c_mid = cos(lat_mid);
        }
        /* the mid point's height within the Earth model's range (gf_earth_height_ok:
         * the gravity of NIMA TR8350.2 eq. 4-3 is not evaluated beyond it) */
        if (!(c_mid > 0.0) || !gf_earth_height_ok(h_mid) || !v3_finite(v_mid))
            return GF_ERR_DIVERGED;
        gf_earth_from_sincos(&e, s_mid, c_mid, h_mid, v_mid, s->earth_rate_sign);
    }

    double w_in[3], zeta[3];
    gf_v3_add(e.w_ie_n_rad_s, e.w_en_n_rad_s, w_in);
    gf_v3_scale(w_in, T, zeta);

    /* velocity */
    double dv_n0[3], dv_n[3], zx[3], cor[3], w2ie_en[3], v_new[3];
    gf_q_rotate(s->q_bn, dv_b, dv_n0);
    gf_v3_cross(zeta, dv_n0, zx);
    gf_v3_axpy(dv_n0, -0.5, zx, dv_n);
    gf_v3_axpy(e.w_en_n_rad_s, 2.0, e.w_ie_n_rad_s, w2ie_en);
    gf_v3_cross(w2ie_en, v_mid, cor);
    for (int i = 0; i < 3; ++i)
        v_new[i] = s->v_n_m_s[i] + dv_n[i] - cor[i] * T;
    v_new[2] -= e.gravity_m_s2 * T;

    /* vertical channel */
    double h_new, b_new = s->baro_accel_m_s2;
    if (cfg->vertical == GF_SINS_VERTICAL_HOLD) {
        v_new[2] = 0.0;
        h_new = cfg->hold_height_m;
    } else if (cfg->vertical == GF_SINS_VERTICAL_BARO && !isnan(h_ext_m)) {
        /* h_ext is the height at t_k: compare it with the inertial prediction for t_k,
         * then correct (predictor-corrector form of the loop in gf_sins.h) */
        const double tau = cfg->baro_tau_s;
        const double h_pred = s->h_m + 0.5 * T * (s->v_n_m_s[2] + v_new[2]);
        const double err = h_pred - h_ext_m;
        const double k1 = 3.0 / tau;
        const double k2 = 3.0 / (tau * tau) + 2.0 * e.gravity_m_s2 / (e.R_N_m + h_mid);
        const double k3 = 1.0 / (tau * tau * tau);
        v_new[2] -= (k2 * err + s->baro_accel_m_s2) * T;
        h_new = h_pred - k1 * err * T;
        b_new = s->baro_accel_m_s2 + k3 * err * T;
    } else {
        h_new = s->h_m + 0.5 * T * (s->v_n_m_s[2] + v_new[2]);
    }

    /* position: trapezoid with radii at the mid point */
    const double vN = 0.5 * (s->v_n_m_s[1] + v_new[1]), vE = 0.5 * (s->v_n_m_s[0] + v_new[0]);
    const double lat_new = s->lat_rad + T * vN / (e.R_M_m + h_mid);
    double lon_new = s->lon_rad + T * vE / ((e.R_N_m + h_mid) * e.cos_lat);
    /* the new state within the domain gf_sins_state_check asks: the height in the Earth
     * model's range (-a/2, a/3) (found by fuzzing: a GF_OK step of the BARO loop with an
     * external height of ~1.6e175 m took h to 4.7e172 m, h' ~ (3/tau) T h_ext, which only
     * the lower bound and finiteness were checked against, and the state was refused by
     * gf_sins_state_check), the baro loop's acceleration state finite
     * (k3 = 1/tau^3 overflows for tau below ~1e-103 s: b_new = Inf or Inf * 0 = NaN) */
    if (!(fabs(lat_new) < GF_SINS_LAT_LIMIT_RAD) || !gf_earth_height_ok(h_new) ||
        !v3_finite(v_new) || !isfinite(lon_new) || !isfinite(b_new))
        return GF_ERR_DIVERGED;
    if (lon_new > GF_PI)
        lon_new -= 2.0 * GF_PI;
    else if (lon_new <= -GF_PI)
        lon_new += 2.0 * GF_PI;
    if (!(lon_new > -GF_PI && lon_new <= GF_PI)) { /* more than a turn in one step */
        lon_new = remainder(lon_new, 2.0 * GF_PI);
        if (lon_new <= -GF_PI)
            lon_new += 2.0 * GF_PI;
    }

    /* attitude */
    double qn[4], q[4], zneg[3];
    gf_v3_scale(zeta, -1.0, zneg);
    gf_q_from_rotvec_fast(zneg, qn);
    gf_q_mul(qn, s->q_bn, q);
    gf_q_mul(q, qb, q);
    if (!renormalize(q))
        return GF_ERR_DIVERGED;

    /* commit (the acceleration checked first: finite but absurd velocities overflow it) */
    const double invT = 1.0 / T;
    double a_new[3];
    for (int i = 0; i < 3; ++i)
        a_new[i] = (v_new[i] - s->v_n_m_s[i]) * invT;
    if (!v3_finite(a_new))
        return GF_ERR_DIVERGED;
    gf_v3_copy(a_new, s->a_n_m_s2);
    memcpy(s->q_bn, q, sizeof q);
    gf_v3_copy(v_new, s->v_n_m_s);
    s->lat_rad = lat_new;
    s->lon_rad = lon_new;
    s->h_m = h_new;
    {
        /* sin and cos of the new latitude by the same angle-sum series from the mid
         * point; every 64th sample they are recomputed with libm so that rounding
         * cannot accumulate */
        const double d = lat_new - lat_mid;
        if ((s->n_samples & 63u) != 0 && fabs(d) < 1e-4) {
            sincos_shift(e.sin_lat, e.cos_lat, d, &s->sin_lat, &s->cos_lat);
        } else {
            s->sin_lat = sin(lat_new);
            s->cos_lat = cos(lat_new);
        }
    }
    /* R_M at the mid point is within 1e-9 relative of R_M(lat_new) for the usual half
     * step (|d| ~ 1e-7 rad; |dR_M / dL| <= 0.01 R_M); a half step beyond 1e-5 rad (64 m:
     * a long interval or a fast vehicle) takes R_M at lat_new, so that the state stays
     * within gf_sins_state_check's 1e-6 (found by fuzzing: a GF_OK step at 1e5 m/s left
     * R_M 4.4e-6 off and the state was refused on restore) */
    if (fabs(lat_new - lat_mid) < 1e-5) {
        s->R_M_m = e.R_M_m;
    } else {
        gf_earth e_new;
        gf_earth_from_sincos(&e_new, s->sin_lat, s->cos_lat, h_new, NULL, 1.0);
        s->R_M_m = e_new.R_M_m;
    }
    s->baro_accel_m_s2 = b_new;
    return GF_OK;
}

/* Runs before every step, so it checks what selects a branch or would be used before
 * the step's own checks (configuration, direction, attitude, the latitude range);
 * numbers that are not finite elsewhere in the state make the step's results
 * non-finite, which it reports as GF_ERR_DIVERGED. */
static int state_is_valid(const gf_sins_state *s)
{
    const int flat = s->cfg.earth == GF_SINS_EARTH_FLAT;
    return config_is_valid(&s->cfg) && (s->earth_rate_sign == 1.0 || s->earth_rate_sign == -1.0) &&
           fabs(gf_q_norm(s->q_bn) - 1.0) < 1e-6 && v3_finite(s->v_n_m_s) &&
           fabs(s->lat_rad) < (flat ? GF_HALF_PI : GF_SINS_LAT_LIMIT_RAD) &&
           (flat || (s->cos_lat > 0.0 && s->R_M_m > 0.0)) && isfinite(s->lon_rad) &&
           isfinite(s->h_m) && isfinite(s->time_s);
}

gf_status gf_sins_state_check(const gf_sins_state *s)
{
    if (!s)
        return GF_ERR_NULL_POINTER;
    /* flat_pos_m in either Earth model: the gyro-free navigator FMU publishes it as its
     * `pos` output whatever the model (fuzz_fmu_state_gfnav_cube6: a NaN there in a
     * WGS-84 state was accepted and reached the output after the next step) */
    if (!state_is_valid(s) || !v3_finite(s->a_n_m_s2) || !v3_finite(s->prev_gyro) ||
        !v3_finite(s->prev_accel) || !isfinite(s->baro_accel_m_s2) || !v3_finite(s->flat_pos_m))
        return GF_ERR_BAD_PARAMETER;
    if (s->cfg.earth == GF_SINS_EARTH_FLAT)
        return GF_OK;
    /* the kept sine and cosine are those of the latitude (they follow it by angle-sum
     * series, refreshed with libm every 64 samples: within a few ulp), the kept meridian
     * radius that of a point within one step of it (1e-9 relative, gf_sins.c); the height
     * within the Earth model's range (gf_earth_update refuses it otherwise, as every
     * step does: a restored state with h = 1e300 m must not get that far) */
    gf_earth e;
    if (gf_earth_update(&e, s->lat_rad, s->h_m, NULL, 1.0) != GF_OK ||
        !(fabs(s->sin_lat - e.sin_lat) <= 1e-12) || !(fabs(s->cos_lat - e.cos_lat) <= 1e-12) ||
        !(fabs(s->R_M_m - e.R_M_m) <= 1e-6 * e.R_M_m))
        return GF_ERR_BAD_PARAMETER;
    return GF_OK;
}

gf_status gf_sins_step(gf_sins_state *state, const double *gyro, const double *accel,
                       double dt_s, double h_ext_m)
{
    if (!state || !gyro || !accel)
        return GF_ERR_NULL_POINTER;
    if (!state_is_valid(state) || state->cfg.subsamples != 1)
        return GF_ERR_BAD_PARAMETER;
    if (state->earth_rate_sign < 0) {
        /* reverse navigation: the caller hands samples in reverse order; the gyro is
         * negated here so that gf_sins_step and gf_sins_run agree */
        const double g[3] = {-gyro[0], -gyro[1], -gyro[2]};
        return sins_update(state, g, accel, dt_s, h_ext_m);
    }
    return sins_update(state, gyro, accel, dt_s, h_ext_m);
}

gf_status gf_sins_step_group(gf_sins_state *state, size_t m, const double *gyro,
                             const double *accel, double dt_s, double h_ext_m)
{
    if (!state || !gyro || !accel)
        return GF_ERR_NULL_POINTER;
    if (!state_is_valid(state) || state->cfg.input != GF_SINS_INPUT_INCREMENTS || m < 1 ||
        m > GF_SINS_MAX_SUBSAMPLES)
        return GF_ERR_BAD_PARAMETER;
    const double sign = state->earth_rate_sign < 0 ? -1.0 : 1.0;
    if (m == 1) {
        const double g1[3] = {sign * gyro[0], sign * gyro[1], sign * gyro[2]};
        return sins_update(state, g1, accel, dt_s, h_ext_m);
    }
    double g[3 * GF_SINS_MAX_SUBSAMPLES], dt[GF_SINS_MAX_SUBSAMPLES];
    for (size_t i = 0; i < 3 * m; ++i)
        g[i] = sign * gyro[i];
    for (size_t i = 0; i < m; ++i)
        dt[i] = dt_s / (double)m;
    int bad;
    return group_update(state, (int)m, g, accel, dt, h_ext_m, &bad);
}

int gf_sins_state_valid(const gf_sins_state *state)
{
    return state && state_is_valid(state);
}

gf_status gf_sins_step_compensated(gf_sins_state *state, const double *phi, const double *dv_b,
                                   const double *rate, const double *f, double dt_s,
                                   double h_ext_m)
{
    if (!state || !phi || !dv_b || !rate || !f)
        return GF_ERR_NULL_POINTER;
    if (!state_is_valid(state))
        return GF_ERR_BAD_PARAMETER;
    if (!v3_finite(phi) || !v3_finite(dv_b) || !v3_finite(rate) || !v3_finite(f) ||
        isinf(h_ext_m))
        return GF_ERR_NONFINITE_INPUT;
    if (!(dt_s > 0.0 && isfinite(dt_s)))
        return GF_ERR_BAD_TIME;
    const double wmax_T = state->cfg.max_rate_rad_s * dt_s;
    const double fmax_T = state->cfg.max_specific_force_m_s2 * dt_s;
    if (!(gf_v3_dot(phi, phi) <= wmax_T * wmax_T) || !(gf_v3_dot(dv_b, dv_b) <= fmax_T * fmax_T))
        return GF_ERR_OUT_OF_RANGE;
    double q_phi[4];
    gf_q_from_rotvec_fast(phi, q_phi);
    return gf_sins_step_compensated_trusted(state, phi, q_phi, dv_b, rate, f, dt_s, h_ext_m);
}

gf_status gf_sins_step_compensated_trusted(gf_sins_state *state, const double *phi,
                                           const double *q_phi, const double *dv_b,
                                           const double *rate, const double *f, double dt_s,
                                           double h_ext_m)
{
    const gf_sins_config *cfg = &state->cfg;
    if (cfg->input != GF_SINS_INPUT_RATES || !state->have_prev || state->earth_rate_sign < 0)
        return GF_ERR_BAD_PARAMETER;
    /* finite inputs are the caller's (a NaN would fail the limits below: OUT_OF_RANGE) */
    if (!(dt_s > 0.0 && isfinite(dt_s)))
        return GF_ERR_BAD_TIME;
    /* absurd samples: the rate and force at the end of the interval, as gf_sins_step
     * checks its samples (the increments are made of them and of the previous sample,
     * which passed the same check) */
    const double wmax = cfg->max_rate_rad_s, fmax_ = cfg->max_specific_force_m_s2;
    if (!(gf_v3_dot(rate, rate) <= wmax * wmax) || !(gf_v3_dot(f, f) <= fmax_ * fmax_))
        return GF_ERR_OUT_OF_RANGE;
    (void)phi;
    const gf_status status = nav_update(state, q_phi, dv_b, dt_s, h_ext_m);
    if (status == GF_OK)
        finish_update(state, rate, f, dt_s, 1);
    return status;
}

/* gf_sins_run with cfg.subsamples = N > 1 (increments; gf_sins.h): one update per group
 * of N samples in recorded order, one output row per group. */
static gf_status run_groups(gf_sins_state *state, size_t n, const double *gyro,
                            const double *accel, double dt_s, const double *t_s,
                            const double *h_ext_m, int backward, double *q_bn,
                            double *v_n_m_s, double *pos, double *time_s, size_t *n_done)
{
    gf_sins_state s = *state;
    const size_t N = (size_t)s.cfg.subsamples, n_groups = (n + N - 1) / N;
    gf_status status = GF_OK;
    size_t done = 0;
    for (size_t gdone = 0; gdone < n_groups; ++gdone) {
        const size_t j = backward ? n_groups - 1 - gdone : gdone;
        const size_t a0 = j * N, m = n - a0 < N ? n - a0 : N;
        double g[3 * GF_SINS_MAX_SUBSAMPLES], dt[GF_SINS_MAX_SUBSAMPLES];
        const double *a = accel + 3 * a0, *gp = g;
        double ab[3 * GF_SINS_MAX_SUBSAMPLES];
        size_t k_last = a0 + m - 1;
        if (!backward && !t_s) { /* the usual case: the record's own rows, no copies */
            gp = gyro + 3 * a0;
            for (size_t i = 0; i < m; ++i)
                dt[i] = dt_s;
        }
        for (size_t i = 0; (backward || t_s) && i < m; ++i) {
            const size_t k = backward ? a0 + m - 1 - i : a0 + i; /* processing order */
            const double *gk = gyro + 3 * k;
            if (backward) {
                g[3 * i] = -gk[0]; g[3 * i + 1] = -gk[1]; g[3 * i + 2] = -gk[2];
                gf_v3_copy(accel + 3 * k, ab + 3 * i);
            } else {
                g[3 * i] = gk[0]; g[3 * i + 1] = gk[1]; g[3 * i + 2] = gk[2];
            }
            dt[i] = dt_s;
            if (t_s) {
                if (!isfinite(t_s[k])) {
                    status = GF_ERR_NONFINITE_INPUT;
                    break;
                }
                /* as gf_sins_run with N = 1: forward, sample 0 from the state's time;
                 * backward, interval 0 is dt_s */
                if (!backward)
                    dt[i] = k == 0 ? t_s[0] - s.time_s : t_s[k] - t_s[k - 1];
                else
                    dt[i] = k >= 1 ? t_s[k] - t_s[k - 1] : dt_s;
            }
            k_last = k;
        }
        if (status != GF_OK)
            break;
        const double h = h_ext_m ? h_ext_m[k_last] : NAN;
        if (m == 1) {
            status = sins_update(&s, gp, backward ? ab : a, dt[0], h);
        } else {
            int bad;
            status = group_update(&s, (int)m, gp, backward ? ab : a, dt, h, &bad);
        }
        if (status != GF_OK)
            break;
        done += m;
        memcpy(q_bn + 4 * j, s.q_bn, sizeof s.q_bn);
        gf_v3_copy(s.v_n_m_s, v_n_m_s + 3 * j);
        if (backward)
            gf_v3_scale(v_n_m_s + 3 * j, -1.0, v_n_m_s + 3 * j); /* true-time velocity */
        gf_sins_position(&s, pos + 3 * j);
        if (time_s)
            time_s[j] = s.time_s;
    }
    *state = s;
    if (n_done)
        *n_done = done;
    return status;
}

gf_status gf_sins_run(gf_sins_state *state, size_t n, const double *gyro, const double *accel,
                      double dt_s, const double *t_s, const double *h_ext_m, int backward,
                      double *q_bn, double *v_n_m_s, double *pos, double *time_s,
                      size_t *n_done)
{
    if (n_done)
        *n_done = 0;
    if (!state || !gyro || !accel || !q_bn || !v_n_m_s || !pos)
        return GF_ERR_NULL_POINTER;
    if (!state_is_valid(state))
        return GF_ERR_BAD_PARAMETER;
    if ((backward != 0) != (state->earth_rate_sign < 0))
        return GF_ERR_BAD_PARAMETER; /* backward runs need gf_sins_reverse() first */
    if (!t_s && !(dt_s > 0.0 && isfinite(dt_s)))
        return GF_ERR_BAD_TIME;
    if (state->cfg.subsamples > 1)
        return run_groups(state, n, gyro, accel, dt_s, t_s, h_ext_m, backward, q_bn, v_n_m_s,
                          pos, time_s, n_done);
    gf_sins_state s = *state;
    gf_status status = GF_OK;
    size_t done = 0;
    for (; done < n; ++done) {
        const size_t k = backward ? n - 1 - done : done;
        double dt = dt_s;
        if (t_s) {
            if (!isfinite(t_s[k])) {
                status = GF_ERR_NONFINITE_INPUT;
                break;
            }
            /* interval in processing order; the first sample of a run is measured from
             * the state's time, except that a backward increment run cannot know where
             * interval 0 starts and takes dt_s for it */
            if (s.cfg.input == GF_SINS_INPUT_RATES || !backward)
                dt = done == 0 ? (backward ? s.time_s - t_s[k] : t_s[k] - s.time_s)
                               : (backward ? t_s[k + 1] - t_s[k] : t_s[k] - t_s[k - 1]);
            else
                dt = k >= 1 ? t_s[k] - t_s[k - 1] : dt_s;
        }
        const double *g = gyro + 3 * k;
        double gneg[3];
        if (backward) {
            gf_v3_scale(g, -1.0, gneg);
            g = gneg;
        }
        const int starts_record = s.cfg.input == GF_SINS_INPUT_RATES && !s.have_prev;
        status = sins_update(&s, g, accel + 3 * k, dt, h_ext_m ? h_ext_m[k] : NAN);
        if (status != GF_OK)
            break;
        if (starts_record && t_s) /* a rate record that starts later than the state */
            s.time_s = t_s[k];
        memcpy(q_bn + 4 * k, s.q_bn, sizeof s.q_bn);
        gf_v3_copy(s.v_n_m_s, v_n_m_s + 3 * k);
        if (backward)
            gf_v3_scale(v_n_m_s + 3 * k, -1.0, v_n_m_s + 3 * k); /* report true-time velocity */
        gf_sins_position(&s, pos + 3 * k);
        if (time_s)
            time_s[k] = s.time_s;
    }
    *state = s;
    if (n_done)
        *n_done = done;
    return status;
}

gf_status gf_sins_step_trusted(gf_sins_state *state, const double *gyro, const double *accel,
                               double dt_s)
{
    /* the filters: the caller keeps *state valid and negates the gyro in reverse */
    return sins_update(state, gyro, accel, dt_s, NAN);
}

gf_status gf_sins_step_group_trusted(gf_sins_state *state, int m, const double *gyro,
                                     const double *accel, const double *dt_s)
{
    if (m == 1)
        return sins_update(state, gyro, accel, dt_s[0], NAN);
    if (m < 1 || m > GF_SINS_MAX_SUBSAMPLES)
        return GF_ERR_BAD_PARAMETER;
    int bad;
    return group_update(state, m, gyro, accel, dt_s, NAN, &bad);
}
