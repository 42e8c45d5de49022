/* gf_imu_error.c — see gf_imu_error.h. */
#include "nav/gf_imu_error.h"

#include <math.h>
#include <string.h>

#include "base/gf_math.h"

gf_status gf_imu_errors_check(const gf_imu_errors *e, int *bad)
{
    if (bad)
        *bad = 0;
    if (!e)
        return GF_ERR_NULL_POINTER;
    const double *fields[] = {e->g_scale, e->g_misalign_rad, e->g_bias_rad_s, e->a_scale,
                              e->a_misalign_rad, e->a_bias_m_s2, e->a_k2_s2_m, e->a_lever_pos_m,
                              &e->a_delay_s};
    const size_t sizes[] = {3, 9, 3, 3, 9, 3, 3, 9, 1};
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; ++i)
        if (!gf_all_finite(fields[i], sizes[i]))
            return GF_ERR_NONFINITE_INPUT;
    if (!isfinite(e->t0) || !gf_all_finite(e->g_bias_tc, 3 * GF_IMU_TEMP_ORDER_MAX) ||
        !gf_all_finite(e->g_scale_tc, 3 * GF_IMU_TEMP_ORDER_MAX) ||
        !gf_all_finite(e->a_bias_tc, 3 * GF_IMU_TEMP_ORDER_MAX) ||
        !gf_all_finite(e->a_scale_tc, 3 * GF_IMU_TEMP_ORDER_MAX))
        return GF_ERR_NONFINITE_INPUT;
    int field = 0;
    for (int k = 0; k < 3 && !field; ++k) {
        if (!(fabs(e->g_scale[k]) < 0.5)) field = 1;
        else if (!(fabs(e->a_scale[k]) < 0.5)) field = 3;
        else if (!(fabs(e->a_k2_s2_m[k]) * GF_IMU_K2_RANGE_M_S2 < 0.1)) field = 5;
        else if (!(fabs(e->a_lever_pos_m[4 * k]) < GF_IMU_MAX_LEVER_M)) field = 6;
        else if (!(fabs(e->g_bias_rad_s[k]) < GF_IMU_MAX_GYRO_BIAS_RAD_S)) field = 8;
        else if (!(fabs(e->a_bias_m_s2[k]) < GF_IMU_MAX_ACCEL_BIAS_M_S2)) field = 9;
    }
    for (int k = 0; k < 9 && !field; ++k) {
        const int diag = (k % 4) == 0;
        if (!(fabs(e->g_misalign_rad[k]) < 0.1) || (diag && e->g_misalign_rad[k] != 0.0)) field = 2;
        else if (!(fabs(e->a_misalign_rad[k]) < 0.1) || (diag && e->a_misalign_rad[k] != 0.0)) field = 4;
        else if (!(fabs(e->a_lever_pos_m[k]) < GF_IMU_MAX_LEVER_M)) field = 6;
    }
    if (!field && !(fabs(e->a_delay_s) < 1e-3 * GF_IMU_MAX_DELAY_MS))
        field = 10;
    if (!field && (e->temp_order < 0 || e->temp_order > GF_IMU_TEMP_ORDER_MAX))
        field = 7;
    if (field) {
        if (bad)
            *bad = field;
        return GF_ERR_BAD_PARAMETER;
    }
    return GF_OK;
}

/* Bias and scale of the three axes at temperature dt = T - T0. Returns 0 when the
 * model is outside its range of validity there (a scale factor not in (-0.5, 0.5), the
 * limit of gf_imu_errors_check, so that 1 + s >= 0.5; or a bias beyond its limit). */
static int at_temperature(const gf_imu_errors *e, double dt, double gb[3], double gs[3],
                          double ab[3], double as[3])
{
    for (int k = 0; k < 3; ++k) {
        gb[k] = e->g_bias_rad_s[k];
        gs[k] = e->g_scale[k];
        ab[k] = e->a_bias_m_s2[k];
        as[k] = e->a_scale[k];
    }
    double p = dt;
    for (int j = 0; j < e->temp_order; ++j, p *= dt)
        for (int k = 0; k < 3; ++k) {
            gb[k] += e->g_bias_tc[3 * j + k] * p;
            gs[k] += e->g_scale_tc[3 * j + k] * p;
            ab[k] += e->a_bias_tc[3 * j + k] * p;
            as[k] += e->a_scale_tc[3 * j + k] * p;
        }
    for (int k = 0; k < 3; ++k)
        if (!(fabs(gs[k]) < 0.5) || !(fabs(as[k]) < 0.5) ||
            !(fabs(gb[k]) < GF_IMU_MAX_GYRO_BIAS_RAD_S) || !(fabs(ab[k]) < GF_IMU_MAX_ACCEL_BIAS_M_S2))
            return 0;
    return 1;
}

/* (I + N) v */
static void one_plus_n(const double n[9], const double v[3], double out[3])
{
    for (int i = 0; i < 3; ++i)
        out[i] = v[i] + n[3 * i] * v[0] + n[3 * i + 1] * v[1] + n[3 * i + 2] * v[2];
}

/* (I + N)^-1 v by Cramer's rule on M = I + N (|N| < 0.1: well conditioned) */
static void one_plus_n_solve(const double n[9], const double v[3], double out[3])
{
    gf_mat3 m;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            m.m[i][j] = (i == j ? 1.0 : 0.0) + n[3 * i + j];
    const double c0[3] = {m.m[0][0], m.m[1][0], m.m[2][0]}, c1[3] = {m.m[0][1], m.m[1][1], m.m[2][1]},
                 c2[3] = {m.m[0][2], m.m[1][2], m.m[2][2]};
    double t[3];
    gf_v3_cross(c1, c2, t);
    const double det = gf_v3_dot(c0, t);
    out[0] = gf_v3_dot(v, t) / det;
    gf_v3_cross(v, c2, t);
    out[1] = gf_v3_dot(c0, t) / det;
    gf_v3_cross(c1, v, t);
    out[2] = gf_v3_dot(c0, t) / det;
}

/* lever arms across the sensing axes: any non-zero off-diagonal position */
static int has_transverse(const gf_imu_errors *e)
{
    for (int k = 0; k < 9; ++k)
        if (k % 4 && e->a_lever_pos_m[k] != 0.0)
            return 1;
    return 0;
}

/* the off-diagonal part of e_i^T W r_i, W = [w_dot x] + w w^T - |w|^2 I: for accelerometer
 * i, sum over j != i of r_ij (w_i w_j + [w_dot x]_ij) (gf_imu_error.h) */
static void transverse_lever(const double r[9], const double w[3], const double wd[3], double t[3])
{
    const double z[3] = {0.0, 0.0, 0.0};
    const double *a = wd ? wd : z;
    /* [a x] = [[0, -a_z, a_y], [a_z, 0, -a_x], [-a_y, a_x, 0]] */
    t[0] = r[1] * (w[0] * w[1] - a[2]) + r[2] * (w[0] * w[2] + a[1]);
    t[1] = r[3] * (w[1] * w[0] + a[2]) + r[5] * (w[1] * w[2] - a[0]);
    t[2] = r[6] * (w[2] * w[0] - a[1]) + r[7] * (w[2] * w[1] + a[0]);
}

static void centripetal(const double w[3], double c[3])
{
    const double x2 = w[0] * w[0], y2 = w[1] * w[1], z2 = w[2] * w[2];
    c[0] = y2 + z2;
    c[1] = x2 + z2;
    c[2] = x2 + y2;
}

gf_status gf_imu_apply(const gf_imu_errors *e, size_t n, const double *w, const double *f,
                       const double *temp, double *w_out, double *f_out, size_t *n_done)
{
    return gf_imu_apply_dw(e, n, w, NULL, f, temp, w_out, f_out, n_done);
}

gf_status gf_imu_apply_dw(const gf_imu_errors *e, size_t n, const double *w, const double *w_dot,
                          const double *f, const double *temp, double *w_out, double *f_out,
                          size_t *n_done)
{
    if (n_done)
        *n_done = 0;
    if (!e || !w || !f || !w_out || !f_out)
        return GF_ERR_NULL_POINTER;
    const gf_status st = gf_imu_errors_check(e, NULL);
    if (st != GF_OK)
        return st;
    const int transverse = has_transverse(e);
    for (size_t k = 0; k < n; ++k) {
        const double *wk = w + 3 * k, *fk = f + 3 * k, *ak = w_dot ? w_dot + 3 * k : NULL;
        const double dt = temp ? temp[k] - e->t0 : 0.0;
        if (!gf_all_finite(wk, 3) || !gf_all_finite(fk, 3) || !isfinite(dt) ||
            (ak && !gf_all_finite(ak, 3))) {
            if (n_done)
                *n_done = k;
            return GF_ERR_NONFINITE_INPUT;
        }
        double gb[3], gs[3], ab[3], as[3], t[3], u[3], c[3], wo[3], fo[3];
        if (!at_temperature(e, dt, gb, gs, ab, as)) {
            if (n_done)
                *n_done = k;
            return GF_ERR_OUT_OF_RANGE;
        }
        one_plus_n(e->g_misalign_rad, wk, t);
        for (int i = 0; i < 3; ++i)
            wo[i] = (1.0 + gs[i]) * t[i] + gb[i];
        double fd[3], tr[3];
        if (e->a_delay_s != 0.0) {       /* f(t - d) = (I + d [w x]) f */
            const double dw[9] = {0.0, -e->a_delay_s * wk[2], e->a_delay_s * wk[1],
                                  e->a_delay_s * wk[2], 0.0, -e->a_delay_s * wk[0],
                                  -e->a_delay_s * wk[1], e->a_delay_s * wk[0], 0.0};
            one_plus_n(dw, fk, fd);
        } else {
            gf_v3_copy(fk, fd);
        }
        one_plus_n(e->a_misalign_rad, fd, u);
        centripetal(wk, c);
        if (transverse)
            transverse_lever(e->a_lever_pos_m, wk, ak, tr);
        int in_range = 1;
        for (int i = 0; i < 3; ++i) {
            double ui = u[i] - e->a_lever_pos_m[4 * i] * c[i];
            if (transverse)
                ui += tr[i];
            in_range &= fabs(ui) <= GF_IMU_K2_RANGE_M_S2;
            fo[i] = (1.0 + as[i]) * ui + e->a_k2_s2_m[i] * ui * ui + ab[i];
        }
        if (!in_range) {
            if (n_done)
                *n_done = k;
            return GF_ERR_OUT_OF_RANGE;
        }
        if (!gf_all_finite(wo, 3) || !gf_all_finite(fo, 3)) { /* finite inputs, overflow */
            if (n_done)
                *n_done = k;
            return GF_ERR_OUT_OF_RANGE;
        }
        gf_v3_copy(wo, w_out + 3 * k);
        gf_v3_copy(fo, f_out + 3 * k);
    }
    if (n_done)
        *n_done = n;
    return GF_OK;
}

gf_status gf_imu_compensate(const gf_imu_errors *e, size_t n, const double *w_out,
                            const double *f_out, const double *temp, double *w, double *f,
                            size_t *n_done)
{
    return gf_imu_compensate_dw(e, n, w_out, NULL, f_out, temp, w, f, n_done);
}

gf_status gf_imu_compensate_dw(const gf_imu_errors *e, size_t n, const double *w_out,
                               const double *w_dot, const double *f_out, const double *temp,
                               double *w, double *f, size_t *n_done)
{
    if (n_done)
        *n_done = 0;
    if (!e || !w_out || !f_out || !w || !f)
        return GF_ERR_NULL_POINTER;
    const gf_status st = gf_imu_errors_check(e, NULL);
    if (st != GF_OK)
        return st;
    const int transverse = has_transverse(e);
    for (size_t k = 0; k < n; ++k) {
        const double *wo = w_out + 3 * k, *fo = f_out + 3 * k, *ak = w_dot ? w_dot + 3 * k : NULL;
        const double dt = temp ? temp[k] - e->t0 : 0.0;
        if (!gf_all_finite(wo, 3) || !gf_all_finite(fo, 3) || !isfinite(dt) ||
            (ak && !gf_all_finite(ak, 3))) {
            if (n_done)
                *n_done = k;
            return GF_ERR_NONFINITE_INPUT;
        }
        double gb[3], gs[3], ab[3], as[3], t[3], u[3], c[3], wk[3], fk[3];
        if (!at_temperature(e, dt, gb, gs, ab, as)) {
            if (n_done)
                *n_done = k;
            return GF_ERR_OUT_OF_RANGE;
        }
        for (int i = 0; i < 3; ++i)
            t[i] = (wo[i] - gb[i]) / (1.0 + gs[i]);
        one_plus_n_solve(e->g_misalign_rad, t, wk);
        centripetal(wk, c);
        double tr[3];
        if (transverse)
            transverse_lever(e->a_lever_pos_m, wk, ak, tr);
        for (int i = 0; i < 3; ++i) {
            /* K2 u^2 + (1 + s) u + (b - a) = 0, the root near the linear solution in the
             * form without cancellation: u = -2 C / (B + sqrt(B^2 - 4 A C)) */
            const double A = e->a_k2_s2_m[i], B = 1.0 + as[i], C = ab[i] - fo[i];
            const double disc = B * B - 4.0 * A * C;
            const double ui = -2.0 * C / (B + sqrt(disc));
            if (!(disc >= 0.0) || !(fabs(ui) <= GF_IMU_K2_RANGE_M_S2)) {
                if (n_done)
                    *n_done = k;
                return GF_ERR_OUT_OF_RANGE; /* no real solution, or beyond the K2 range */
            }
            u[i] = ui + e->a_lever_pos_m[4 * i] * c[i];
            if (transverse)
                u[i] -= tr[i];
        }
        one_plus_n_solve(e->a_misalign_rad, u, fk);
        if (e->a_delay_s != 0.0) {       /* f = (I + d [w x])^-1 f(t - d) */
            const double dw[9] = {0.0, -e->a_delay_s * wk[2], e->a_delay_s * wk[1],
                                  e->a_delay_s * wk[2], 0.0, -e->a_delay_s * wk[0],
                                  -e->a_delay_s * wk[1], e->a_delay_s * wk[0], 0.0};
            double fd[3];
            gf_v3_copy(fk, fd);
            one_plus_n_solve(dw, fd, fk);
        }
        if (!gf_all_finite(wk, 3) || !gf_all_finite(fk, 3)) { /* finite inputs, overflow */
            if (n_done)
                *n_done = k;
            return GF_ERR_OUT_OF_RANGE;
        }
        gf_v3_copy(fk, f + 3 * k);
        gf_v3_copy(wk, w + 3 * k);
    }
    if (n_done)
        *n_done = n;
    return GF_OK;
}

gf_status gf_imu_compensate_step(const gf_imu_errors *e, const double w_out[3],
                                 const double f_out[3], const double *temp, const double *w_prev,
                                 double dt_s, double w[3], double f[3])
{
    if (!e || !w_out || !f_out || !w || !f)
        return GF_ERR_NULL_POINTER;
    if (w_prev && !(dt_s > 0.0 && isfinite(dt_s)))
        return GF_ERR_BAD_TIME;
    if (w_prev && !gf_all_finite(w_prev, 3))
        return GF_ERR_NONFINITE_INPUT;
    double wk[3], fk[3], wd[3];
    size_t done = 0;
    /* the rates do not depend on w_dot: a first call gives them */
    gf_status st = gf_imu_compensate_dw(e, 1, w_out, NULL, f_out, temp, wk, fk, &done);
    if (st != GF_OK || !w_prev || !has_transverse(e)) {
        if (st == GF_OK) {
            gf_v3_copy(wk, w);
            gf_v3_copy(fk, f);
        }
        return st;
    }
    for (int i = 0; i < 3; ++i)
        wd[i] = (wk[i] - w_prev[i]) / dt_s;
    st = gf_imu_compensate_dw(e, 1, w_out, wd, f_out, temp, wk, fk, &done);
    if (st == GF_OK) {
        gf_v3_copy(wk, w);
        gf_v3_copy(fk, f);
    }
    return st;
}
