/* gf_gfins_internal.h — what the gyro-free files share and callers never see (not read
 * by cffi): the per-sample pieces of the array solver that the rate step uses
 * (gf_array_solver.c, gf_gfins.c), and the rate step itself with its pending result,
 * which the navigator drives (gf_gfins.c, gf_gfnav.c). Small per-sample helpers are
 * static inline here so that they inline in every loop, as they did in one file. */
#ifndef GF_GFINS_INTERNAL_H
#define GF_GFINS_INTERNAL_H

#include <stdint.h>
#include <string.h>

#include "base/gf_math.h"
#include "base/gf_status.h"
#include "gyrofree/gf_array_solver.h"
#include "gyrofree/gf_gfins.h"

#define NS GF_ARRAY_MAX_SENSORS   /* the short name the solver's bodies use */

/* ---- the array solver's per-sample pieces (gf_array_solver.h) ------------------------ */

/* orthonormal product coordinates (gf_array_solver.h): p = [W11, W22, W33, sqrt2 W12, ...] */
static inline void products_on(const double w[3], double p[6])
{
    p[0] = w[0] * w[0]; p[1] = w[1] * w[1]; p[2] = w[2] * w[2];
    p[3] = GF_SQRT2 * w[0] * w[1]; p[4] = GF_SQRT2 * w[0] * w[2]; p[5] = GF_SQRT2 * w[1] * w[2];
}

/* K_pred rows [r0, r0 + nr) times the orthonormal products p: out (nr) */
static inline void kpred_times(const gf_array_solver *s, size_t r0, size_t nr, const double p[6],
                               double *out)
{
    for (size_t r = 0; r < nr; ++r) {
        const double *kr = s->K_pred + (r0 + r) * 6;
        out[r] = kr[0] * p[0] + kr[1] * p[1] + kr[2] * p[2] + kr[3] * p[3] + kr[4] * p[4] + kr[5] * p[5];
    }
}

/* The solver fields that size a loop or index an array: n_sensors rows of H and of
 * the outputs, n_est rows of pinv, n_obs + n_conf basis columns. Integer compares
 * only: runs before every use of a solver handed in by a caller. */
static inline int solver_valid(const gf_array_solver *s)
{
    return s->n_sensors >= 6 && s->n_sensors <= NS && s->n_obs <= 6 &&
           s->n_conf <= 6 - s->n_obs && s->n_est == 6 + s->n_obs;
}

/* y = pinv A (12 entries, zero beyond n_est) on a solver already checked (solver_valid):
 * one axpy of 12 per output, which the compiler vectorises */
static inline void array_linear(const gf_array_solver *s, const double *A, double *y)
{
    const size_t m = s->n_sensors;
    double acc[GF_X_N] = {0};
    for (size_t i = 0; i < m; ++i) {
        const double a = A[i], *row = s->pinv_t + i * GF_X_N;
        for (int r = 0; r < GF_X_N; ++r)
            acc[r] += a * row[r];
    }
    memcpy(y, acc, sizeof acc);
}

/* x (12) from y = pinv A and the rate w: f, w_dot and the observed combinations less
 * the confounded products of w (K_pred), and the products W: the observed part from z,
 * the rest from w (0 without it) */
static inline void array_finish(const gf_array_solver *s, const double *y, const double *w,
                                double *x)
{
    const size_t ne = s->n_est, no = s->n_obs;
    double p[6] = {0, 0, 0, 0, 0, 0}, z[GF_X_N];
    if (w)
        products_on(w, p);
    memcpy(z, y, ne * sizeof(double));
    if (s->n_conf && w) {
        double kp[GF_X_N];
        kpred_times(s, 0, ne, p, kp);
        for (size_t r = 0; r < ne; ++r)
            z[r] -= kp[r];
    }
    memcpy(x, z, 6 * sizeof(double));
    for (int j = 0; j < 6; ++j) {
        const double *wo = s->W_obs + j * 6, *wr = s->W_rate + j * 6;
        double acc = 0.0;
        for (size_t c = 0; c < no; ++c)
            acc += wo[c] * z[6 + c];
        if (no < 6)
            acc += wr[0] * p[0] + wr[1] * p[1] + wr[2] * p[2] + wr[3] * p[3] + wr[4] * p[4] + wr[5] * p[5];
        x[6 + j] = acc;
    }
}

/* ---- the rate step (gf_gfins.h), driven by gf_gfins.c and gf_gfnav.c ---------------- */

/* Pending results of one rate step (committed only if the whole sample succeeds). */
typedef struct rate_step_result {
    double f[3], w[3], wd[3], ref[3], y[GF_X_N], dt;
    double kf_x[6], kf_P[36];
    uint8_t flags;
} rate_step_result;

/* What sizes a loop, indexes an array or selects a branch in a rate state (gf_gfins.c) */
int gfins_rate_state_valid(const gf_gfins_state *st);

/* One sample of the rate solver into *r, the state untouched (gf_gfins.c) */
gf_status gfins_rate_step(const gf_gfins_state *st, const double *A, double dt,
                          rate_step_result *r);

/* the products W (as in x) of a step's result: observed from the outputs, the rest from
 * the final rate */
static inline void rate_products(const gf_array_solver *s, const rate_step_result *r,
                                 double W[6])
{
    double x[GF_X_N];
    array_finish(s, r->y, r->w, x);
    memcpy(W, x + 6, 6 * sizeof(double));
}

static inline void rate_commit(gf_gfins_state *st, const rate_step_result *r)
{
    gf_v3_copy(r->w, st->omega_rad_s);
    if (st->n_samples > 0)
        st->dt_prev_s = r->dt;
    gf_v3_copy(st->omega_dot_rad_s2, st->omega_dot_prev_rad_s2);
    gf_v3_copy(r->wd, st->omega_dot_rad_s2);
    gf_v3_copy(r->ref, st->omega_ref_rad_s);
    if (st->cfg.strategy == GF_RATE_FUSED) {
        memcpy(st->kf.x, r->kf_x, sizeof r->kf_x);
        memcpy(st->kf.P, r->kf_P, sizeof r->kf_P);
    }
    st->n_samples += 1;
}

#endif /* GF_GFINS_INTERNAL_H */
