/* gf_gfins.c — gyro-free array solver, rate strategies and navigator; see gf_gfins.h. */
#include "gf_gfins.h"

#include <math.h>
#include <string.h>

#include "gf_linalg.h"
#include "gf_math.h"

#define NS GF_ARRAY_MAX_SENSORS
#define GF_SQRT1_2 0.70710678118654752440

/* index ranges of the groups in x */
static const uint32_t kGroupOf[GF_X_N] = {
    GF_GROUP_F, GF_GROUP_F, GF_GROUP_F,
    GF_GROUP_OMEGA_DOT, GF_GROUP_OMEGA_DOT, GF_GROUP_OMEGA_DOT,
    GF_GROUP_W_DIAG, GF_GROUP_W_DIAG, GF_GROUP_W_DIAG,
    GF_GROUP_W_OFFDIAG, GF_GROUP_W_OFFDIAG, GF_GROUP_W_OFFDIAG};

/* Row of H for one sensor (see gf_gfins.h). */
static void model_row(const double u[3], const double th[3], double row[GF_X_N])
{
    double uxt[3];
    gf_v3_cross(u, th, uxt);
    const double tu = gf_v3_dot(th, u);
    row[0] = th[0]; row[1] = th[1]; row[2] = th[2];
    row[3] = uxt[0]; row[4] = uxt[1]; row[5] = uxt[2];
    /* M = sym(theta u^T) - (theta . u) I; W_jk (j != k) appears twice in the sum */
    row[6] = th[0] * u[0] - tu;
    row[7] = th[1] * u[1] - tu;
    row[8] = th[2] * u[2] - tu;
    row[9] = th[0] * u[1] + th[1] * u[0];
    row[10] = th[0] * u[2] + th[2] * u[0];
    row[11] = th[1] * u[2] + th[2] * u[1];
}

static void products(const double w[3], double p[6])
{
    p[0] = w[0] * w[0]; p[1] = w[1] * w[1]; p[2] = w[2] * w[2];
    p[3] = w[0] * w[1]; p[4] = w[0] * w[2]; p[5] = w[1] * w[2];
}

/* SVD of the chosen columns: rank and, when full, the pseudo-inverse. Returns the rank;
 * on rank deficiency null (12 entries) gets the squared null-space weight per unknown. */
static size_t try_columns(gf_array_solver *s, const int32_t *cols, size_t k, double *null_w)
{
    const size_t m = s->n_sensors;
    double a[NS * GF_X_N], sv[GF_X_N], v[GF_X_N * GF_X_N];
    if (null_w)
        for (int j = 0; j < GF_X_N; ++j)
            null_w[j] = 0.0;
    /* fewer equations than unknowns: zero rows pad the system for the SVD, so that the
     * null space (and with it the unobservable unknowns) is still found */
    const size_t mm = m < k ? k : m;
    for (size_t i = 0; i < mm; ++i)
        for (size_t j = 0; j < k; ++j)
            a[i * k + j] = i < m ? s->H[i * GF_X_N + (size_t)cols[j]] : 0.0;
    if (gf_svd(mm, k, a, sv, v) != GF_OK)
        return 0;
    /* relative rank tolerance: geometry typed to ~1e-12 m must not count as singular,
     * a genuinely dependent column (coincident sensors) gives s ~ 1e-16 s_max */
    const double tol = 1e-9 * sv[0];
    size_t rank = 0;
    for (size_t j = 0; j < k; ++j)
        if (sv[j] > tol)
            ++rank;
    if (rank < k) {
        if (null_w)
            for (size_t c = rank; c < k; ++c)
                for (size_t j = 0; j < k; ++j)
                    null_w[cols[j]] += v[j * k + c] * v[j * k + c];
        return rank;
    }
    s->rank = rank;
    s->cond = sv[0] / sv[k - 1];
    s->n_est = k;
    for (size_t r = 0; r < k; ++r) {
        s->est[r] = cols[r];
        double g2 = 0.0;
        for (size_t i = 0; i < m; ++i) {
            double acc = 0.0;
            for (size_t c = 0; c < k; ++c)
                acc += v[r * k + c] / sv[c] * a[i * k + c];
            s->pinv[r * NS + i] = acc;
            g2 += acc * acc;
        }
        s->noise_gain[cols[r]] = sqrt(g2);
    }
    return rank;
}

gf_status gf_array_solver_init(gf_array_solver *s, const gf_array_geometry *g,
                               uint32_t *unobservable)
{
    if (unobservable)
        *unobservable = 0;
    if (!s || !g)
        return GF_ERR_NULL_POINTER;
    if (g->n_sensors == 0 || g->n_sensors > NS)
        return GF_ERR_BAD_SIZE;
    memset(s, 0, sizeof *s);
    s->n_sensors = g->n_sensors;
    double hmax = 0.0;
    for (size_t i = 0; i < g->n_sensors; ++i) {
        if (!gf_v3_isfinite(g->u_m[i]) || !gf_v3_isfinite(g->theta[i]))
            return GF_ERR_NONFINITE_INPUT;
        model_row(g->u_m[i], g->theta[i], s->H + i * GF_X_N);
        for (int j = 0; j < GF_X_N; ++j)
            hmax = fmax(hmax, fabs(s->H[i * GF_X_N + j]));
    }
    /* a column is present when it affects the outputs beyond round-off of the geometry */
    for (int j = 0; j < GF_X_N; ++j) {
        double cmax = 0.0;
        for (size_t i = 0; i < g->n_sensors; ++i)
            cmax = fmax(cmax, fabs(s->H[i * GF_X_N + j]));
        if (cmax > 1e-12 * hmax)
            s->present |= kGroupOf[j];
    }
    int32_t cols[GF_X_N];
    double null_w[GF_X_N];
    /* candidate sets, richest first: (estimated groups among the present W ones) */
    const uint32_t w_present = s->present & (GF_GROUP_W_DIAG | GF_GROUP_W_OFFDIAG);
    const uint32_t candidates[3] = {w_present, w_present & GF_GROUP_W_DIAG, 0u};
    for (int c = 0; c < 3; ++c) {
        if (c > 0 && candidates[c] == candidates[c - 1])
            continue;
        const uint32_t est = GF_GROUP_F | GF_GROUP_OMEGA_DOT | candidates[c];
        size_t k = 0;
        for (int j = 0; j < GF_X_N; ++j)
            if (kGroupOf[j] & est)
                cols[k++] = j;
        const size_t rank = try_columns(s, cols, k, null_w);
        if (rank == k) {
            s->estimated = est;
            s->from_rate = w_present & ~est;
            return GF_OK;
        }
    }
    if (unobservable)
        for (int j = 0; j < GF_X_N; ++j)
            if (null_w[j] > 1e-6)
                *unobservable |= 1u << j;
    return GF_ERR_SINGULAR_GEOMETRY;
}

/* The solver fields that size a loop or index an array: n_sensors rows of H and of
 * the outputs, n_est rows of pinv, est[] indices into x. Integer compares only: runs
 * before every use of a solver handed in by a caller. */
static int solver_valid(const gf_array_solver *s)
{
    if (s->n_sensors == 0 || s->n_sensors > NS || s->n_est > GF_X_N)
        return 0;
    for (size_t r = 0; r < s->n_est; ++r)
        if (s->est[r] < 0 || s->est[r] >= GF_X_N)
            return 0;
    return 1;
}

/* gf_array_solve on a solver already checked (solver_valid) with w_pred given. */
static void array_solve(const gf_array_solver *s, const double *A, const double *w_pred,
                        double *x)
{
    const size_t m = s->n_sensors;
    double p[6] = {0, 0, 0, 0, 0, 0};
    if (w_pred)
        products(w_pred, p);
    double y[NS];
    for (size_t i = 0; i < m; ++i) {
        double yi = A[i];
        if (s->from_rate) {
            const double *h = s->H + i * GF_X_N + 6;
            for (int j = 0; j < 6; ++j)
                if (kGroupOf[6 + j] & s->from_rate)
                    yi -= h[j] * p[j];
        }
        y[i] = yi;
    }
    for (int j = 0; j < 6; ++j) /* products not estimated: from the prediction */
        x[6 + j] = p[j];
    x[0] = x[1] = x[2] = x[3] = x[4] = x[5] = 0.0;
    for (size_t r = 0; r < s->n_est; ++r) {
        const double *row = s->pinv + r * NS;
        double acc = 0.0;
        for (size_t i = 0; i < m; ++i)
            acc += row[i] * y[i];
        x[s->est[r]] = acc;
    }
}

gf_status gf_array_solve(const gf_array_solver *s, const double *A, const double *w_pred,
                         double *x)
{
    if (!s || !A || !x)
        return GF_ERR_NULL_POINTER;
    if (!solver_valid(s))
        return GF_ERR_BAD_SIZE;
    if (s->from_rate && !w_pred)
        return GF_ERR_NULL_POINTER;
    array_solve(s, A, w_pred, x);
    return GF_OK;
}

/* ---- layouts ------------------------------------------------------------------------ */

gf_status gf_layout_cube6(double l, gf_array_geometry *g)
{
    if (!g)
        return GF_ERR_NULL_POINTER;
    if (!(l > 0.0) || !isfinite(l))
        return GF_ERR_BAD_PARAMETER;
    const double r = GF_SQRT1_2;
    /* mission digest, table "6-accelerometer cube (Tan & Park 2005)" */
    const double u[18] = {l, 0, 0, 0, l, 0, 0, 0, l, -l, 0, 0, 0, -l, 0, 0, 0, -l};
    const double t[18] = {0, r, r, r, 0, r, r, r, 0, 0, r, -r, -r, 0, r, r, -r, 0};
    return gf_array_geometry_set(g, 6, u, t, NULL);
}

gf_status gf_layout_12(double l, gf_array_geometry *g)
{
    if (!g)
        return GF_ERR_NULL_POINTER;
    gf_array_geometry g9;
    const gf_status st = gf9_geometry(l, &g9);
    if (st != GF_OK)
        return st;
    double u[36], t[36];
    for (int i = 0; i < 9; ++i) {
        gf_v3_copy(g9.u_m[i], u + 3 * i);
        gf_v3_copy(g9.theta[i], t + 3 * i);
    }
    const double extra_u[9] = {l, 0, 0, 0, l, 0, 0, 0, l};
    const double extra_t[9] = {0, 1, 0, 0, 0, 1, 1, 0, 0};
    memcpy(u + 27, extra_u, sizeof extra_u);
    memcpy(t + 27, extra_t, sizeof extra_t);
    return gf_array_geometry_set(g, 12, u, t, NULL);
}

/* ---- rate strategies ---------------------------------------------------------------- */

gf_status gf_rate_config_default(gf_rate_config *cfg)
{
    if (!cfg)
        return GF_ERR_NULL_POINTER;
    cfg->strategy = GF_RATE_INTEGRATE;
    cfg->accel_noise_m_s2 = 1e-4;
    cfg->bias_walk_rad_s2_sqrt_s = 1e-6;
    cfg->init_std_rad_s = 1e-2;
    cfg->init_bias_std_rad_s2 = 1e-3;
    return GF_OK;
}

static int estimates(const gf_array_solver *s, uint32_t groups)
{
    return (s->estimated & groups) == groups;
}

/* What a rate step uses to size loops, index arrays or select a branch: the solver's
 * sizes and indices, the strategy, and for FUSED the measurement count and the filter
 * dimension. Integer compares only: runs before every step. */
static int rate_state_valid(const gf_gfins_state *st)
{
    if (!solver_valid(&st->solver) || st->cfg.strategy < GF_RATE_INTEGRATE ||
        st->cfg.strategy > GF_RATE_FUSED)
        return 0;
    if (st->cfg.strategy == GF_RATE_FUSED)
        return (st->n_w_meas == 3 || st->n_w_meas == 6) && st->kf.n == 6;
    return 1;
}

gf_status gf_gfins_state_check(const gf_gfins_state *st)
{
    if (!st)
        return GF_ERR_NULL_POINTER;
    if (!rate_state_valid(st))
        return GF_ERR_BAD_SIZE;
    const gf_rate_config *c = &st->cfg;
    const gf_array_solver *s = &st->solver;
    if (!(c->accel_noise_m_s2 > 0.0) || !isfinite(c->accel_noise_m_s2) ||
        !(c->bias_walk_rad_s2_sqrt_s >= 0.0) || !isfinite(c->bias_walk_rad_s2_sqrt_s) ||
        !(c->init_std_rad_s > 0.0) || !isfinite(c->init_std_rad_s) ||
        !(c->init_bias_std_rad_s2 >= 0.0) || !isfinite(c->init_bias_std_rad_s2))
        return GF_ERR_BAD_PARAMETER;
    if ((s->present | s->estimated | s->from_rate) > 15u || s->rank > GF_X_N ||
        !estimates(s, GF_GROUP_F | GF_GROUP_OMEGA_DOT))
        return GF_ERR_BAD_PARAMETER;
    if (!gf_all_finite(s->H, s->n_sensors * GF_X_N) || !gf_all_finite(s->noise_gain, GF_X_N) ||
        !isfinite(s->cond))
        return GF_ERR_NONFINITE_INPUT;
    for (size_t r = 0; r < s->n_est; ++r)
        if (!gf_all_finite(s->pinv + r * NS, s->n_sensors))
            return GF_ERR_NONFINITE_INPUT;
    if (!gf_all_finite(st->omega_rad_s, 3) || !gf_all_finite(st->omega_ref_rad_s, 3) ||
        !gf_all_finite(st->omega_dot_rad_s2, 3) || !gf_all_finite(st->R_W, 36) ||
        !gf_all_finite(st->var_omega_dot, 9))
        return GF_ERR_NONFINITE_INPUT;
    if (c->strategy == GF_RATE_FUSED)
        return gf_kalman_check(&st->kf);
    return GF_OK;
}

gf_status gf_gfins_init(gf_gfins_state *st, const gf_array_geometry *g, const gf_rate_config *cfg,
                        const double *omega_init, uint32_t *unobservable)
{
    if (!st || !g || !cfg)
        return GF_ERR_NULL_POINTER;
    if (cfg->strategy < GF_RATE_INTEGRATE || cfg->strategy > GF_RATE_FUSED ||
        !(cfg->accel_noise_m_s2 > 0.0) || !isfinite(cfg->accel_noise_m_s2) ||
        !(cfg->bias_walk_rad_s2_sqrt_s >= 0.0) || !isfinite(cfg->bias_walk_rad_s2_sqrt_s) ||
        !(cfg->init_std_rad_s > 0.0) || !isfinite(cfg->init_std_rad_s) ||
        !(cfg->init_bias_std_rad_s2 >= 0.0) || !isfinite(cfg->init_bias_std_rad_s2))
        return GF_ERR_BAD_PARAMETER;
    if (omega_init && !gf_v3_isfinite(omega_init))
        return GF_ERR_BAD_PARAMETER;
    memset(st, 0, sizeof *st);
    gf_status status = gf_array_solver_init(&st->solver, g, unobservable);
    if (status != GF_OK)
        return status;
    const gf_array_solver *s = &st->solver;
    if ((cfg->strategy == GF_RATE_SQRT || cfg->strategy == GF_RATE_FUSED) &&
        !estimates(s, GF_GROUP_W_DIAG))
        return GF_ERR_BAD_PARAMETER;
    if (cfg->strategy == GF_RATE_EIGEN && !estimates(s, GF_GROUP_W_DIAG | GF_GROUP_W_OFFDIAG))
        return GF_ERR_BAD_PARAMETER;
    st->cfg = *cfg;
    if (omega_init) {
        gf_v3_copy(omega_init, st->omega_rad_s);
        gf_v3_copy(omega_init, st->omega_ref_rad_s);
    }
    /* noise covariances of the linear estimates: sigma^2 P P^T over the pinv rows */
    const double s2 = cfg->accel_noise_m_s2 * cfg->accel_noise_m_s2;
    int row_of[GF_X_N];
    for (int j = 0; j < GF_X_N; ++j)
        row_of[j] = -1;
    for (size_t r = 0; r < s->n_est; ++r)
        row_of[s->est[r]] = (int)r;
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
            const double *pa = s->pinv + (size_t)row_of[3 + a] * NS, *pb = s->pinv + (size_t)row_of[3 + b] * NS;
            double acc = 0.0;
            for (size_t i = 0; i < s->n_sensors; ++i)
                acc += pa[i] * pb[i];
            st->var_omega_dot[3 * a + b] = s2 * acc;
        }
    if (cfg->strategy == GF_RATE_FUSED) {
        const int m = estimates(s, GF_GROUP_W_OFFDIAG) ? 6 : 3;
        st->n_w_meas = m;
        for (int a = 0; a < m; ++a)
            for (int b = 0; b < m; ++b) {
                const double *pa = s->pinv + (size_t)row_of[6 + a] * NS, *pb = s->pinv + (size_t)row_of[6 + b] * NS;
                double acc = 0.0;
                for (size_t i = 0; i < s->n_sensors; ++i)
                    acc += pa[i] * pb[i];
                st->R_W[m * a + b] = s2 * acc;
            }
        double x0[6] = {0, 0, 0, 0, 0, 0}, P0[36];
        gf_v3_copy(st->omega_rad_s, x0);
        memset(P0, 0, sizeof P0);
        for (int i = 0; i < 3; ++i) {
            P0[7 * i] = cfg->init_std_rad_s * cfg->init_std_rad_s;
            P0[7 * (i + 3)] = cfg->init_bias_std_rad_s2 * cfg->init_bias_std_rad_s2;
        }
        status = gf_kalman_init(&st->kf, 6, x0, P0);
        if (status != GF_OK)
            return status;
    }
    return GF_OK;
}


/* Pending results of one rate step (committed only if the whole sample succeeds). */
typedef struct rate_step_result {
    double f[3], w[3], wd[3], W[6], ref[3];
    double kf_x[6], kf_P[36];
    uint8_t flags;
} rate_step_result;

static gf_status rate_step(const gf_gfins_state *st, const double *A, double dt,
                           rate_step_result *r)
{
    const gf_array_solver *s = &st->solver;
    if (!gf_all_finite(A, s->n_sensors))
        return GF_ERR_NONFINITE_INPUT;
    const int first = st->n_samples == 0;
    if (!first && !(dt > 0.0 && isfinite(dt)))
        return GF_ERR_BAD_TIME;
    double pred[3], x[GF_X_N];
    if (first)
        gf_v3_copy(st->omega_rad_s, pred);
    else
        gf_v3_axpy(st->omega_rad_s, dt, st->omega_dot_rad_s2, pred);
    array_solve(s, A, pred, x);
    gf_v3_copy(x + 3, r->wd);
    gf_v3_copy(st->omega_ref_rad_s, r->ref);
    if (!first)
        for (int k = 0; k < 3; ++k)
            r->ref[k] += 0.5 * dt * (st->omega_dot_rad_s2[k] + r->wd[k]);
    r->flags = 0;
    switch (st->cfg.strategy) {
    case GF_RATE_INTEGRATE:
        if (first)
            gf_v3_copy(st->omega_rad_s, r->w);
        else
            for (int k = 0; k < 3; ++k)
                r->w[k] = st->omega_rad_s[k] + 0.5 * dt * (st->omega_dot_rad_s2[k] + r->wd[k]);
        break;
    case GF_RATE_SQRT: /* seed 000: |w| from eq. 4, sign from eq. 6 integrated */
        for (int k = 0; k < 3; ++k) {
            const double wk2 = x[6 + k];
            if (wk2 >= 0.0) {
                const double mag = sqrt(wk2);
                r->w[k] = r->ref[k] < 0.0 ? -mag : mag;
                if (r->ref[k] == 0.0 && mag > 0.0)
                    r->flags |= GF_RATE_FLAG_SIGN_UNKNOWN;
            } else {
                r->w[k] = r->ref[k];
                r->flags |= (uint8_t)(GF_RATE_FLAG_NEG_X << k);
            }
        }
        break;
    case GF_RATE_EIGEN: {
        const double W[9] = {x[6], x[9], x[10], x[9], x[7], x[11], x[10], x[11], x[8]};
        double ev[3], V[9];
        /* W ~ w w^T is nearly rank one, so power iteration from the previous rate
         * converges in a few steps (error ratio lambda_2/lambda_1 ~ noise / |w|^2 per
         * step); the Jacobi solver takes over when there is no usable start */
        double v0[3], nv;
        gf_v3_copy(st->omega_rad_s, v0);
        nv = gf_v3_norm(v0);
        int done_power = 0;
        if (nv > 0.0) {
            gf_v3_scale(v0, 1.0 / nv, v0);
            double wv[3];
            for (int it = 0; it < 4; ++it) {
                for (int i = 0; i < 3; ++i)
                    wv[i] = W[3 * i] * v0[0] + W[3 * i + 1] * v0[1] + W[3 * i + 2] * v0[2];
                nv = gf_v3_norm(wv);
                if (!(nv > 0.0))
                    break;
                gf_v3_scale(wv, 1.0 / nv, v0);
            }
            if (nv > 0.0) {
                for (int i = 0; i < 3; ++i)
                    wv[i] = W[3 * i] * v0[0] + W[3 * i + 1] * v0[1] + W[3 * i + 2] * v0[2];
                ev[0] = gf_v3_dot(v0, wv);
                /* accept when v0 is an eigenvector far below any noise level */
                double res[3];
                gf_v3_axpy(wv, -ev[0], v0, res);
                if (gf_v3_norm(res) <= 1e-9 * fabs(ev[0])) {
                    V[0] = v0[0]; V[3] = v0[1]; V[6] = v0[2];
                    done_power = 1;
                }
            }
        }
        if (!done_power)
            gf_sym3_eig(W, ev, V);
        if (ev[0] > 0.0) {
            const double mag = sqrt(ev[0]);
            for (int k = 0; k < 3; ++k)
                r->w[k] = mag * V[3 * k];
            const double d = gf_v3_dot(r->w, r->ref);
            if (d < 0.0)
                gf_v3_scale(r->w, -1.0, r->w);
            else if (d == 0.0)
                r->flags |= GF_RATE_FLAG_SIGN_UNKNOWN;
        } else {
            gf_v3_copy(r->ref, r->w);
            r->flags |= GF_RATE_FLAG_NEG_X;
        }
        break;
    }
    case GF_RATE_FUSED: {
        /* EKF on [w, b]: w' = w_dot_meas - b; products measured with covariance R_W */
        gf_kalman kf;
        kf.n = 6;
        memcpy(kf.x, st->kf.x, 6 * sizeof(double));
        memcpy(kf.P, st->kf.P, 36 * sizeof(double));
        if (!first) {
            double F[36], Q[36];
            memset(F, 0, sizeof F);
            memset(Q, 0, sizeof Q);
            for (int i = 0; i < 6; ++i)
                F[7 * i] = 1.0;
            const double qb = st->cfg.bias_walk_rad_s2_sqrt_s * st->cfg.bias_walk_rad_s2_sqrt_s * dt;
            for (int i = 0; i < 3; ++i) {
                F[6 * i + 3 + i] = -dt;
                for (int j = 0; j < 3; ++j) /* trapezoid of two noisy samples: ~dt^2 var */
                    Q[6 * i + j] = dt * dt * st->var_omega_dot[3 * i + j];
                Q[7 * (i + 3)] = qb;
            }
            for (int k = 0; k < 3; ++k)
                kf.x[k] += 0.5 * dt * (st->omega_dot_rad_s2[k] + r->wd[k]) - dt * kf.x[3 + k];
            gf_kalman_predict(&kf, F, Q, 0);
        }
        const int m = st->n_w_meas;
        const double *w = kf.x;
        double h[6], H[36], z[6], res[6];
        products(w, h);
        memset(H, 0, sizeof H);
        /* d(w_i w_j)/dw for diag (rows 0..2) and off-diagonal (rows 3..5) products */
        H[0 * 6 + 0] = 2 * w[0];
        H[1 * 6 + 1] = 2 * w[1];
        H[2 * 6 + 2] = 2 * w[2];
        if (m == 6) {
            H[3 * 6 + 0] = w[1]; H[3 * 6 + 1] = w[0];
            H[4 * 6 + 0] = w[2]; H[4 * 6 + 2] = w[0];
            H[5 * 6 + 1] = w[2]; H[5 * 6 + 2] = w[1];
        }
        for (int i = 0; i < m; ++i) {
            z[i] = x[6 + i];
            res[i] = z[i] - h[i];
        }
        if (gf_kalman_update(&kf, (size_t)m, res, H, st->R_W, NULL) != GF_OK)
            r->flags |= GF_RATE_FLAG_UPDATE_SKIPPED;
        gf_v3_copy(kf.x, r->w);
        memcpy(r->kf_x, kf.x, sizeof r->kf_x);
        memcpy(r->kf_P, kf.P, sizeof r->kf_P);
        break;
    }
    default:
        return GF_ERR_BAD_PARAMETER;
    }
    if (s->from_rate) /* products from the rate: solve again with the final rate */
        array_solve(s, A, r->w, x);
    gf_v3_copy(x, r->f);
    memcpy(r->W, x + 6, sizeof r->W);
    if (!gf_all_finite(r->w, 3) || !gf_all_finite(r->f, 3))
        return GF_ERR_DIVERGED;
    return GF_OK;
}

static void rate_commit(gf_gfins_state *st, const rate_step_result *r)
{
    gf_v3_copy(r->w, st->omega_rad_s);
    gf_v3_copy(r->wd, st->omega_dot_rad_s2);
    gf_v3_copy(r->ref, st->omega_ref_rad_s);
    if (st->cfg.strategy == GF_RATE_FUSED) {
        memcpy(st->kf.x, r->kf_x, sizeof r->kf_x);
        memcpy(st->kf.P, r->kf_P, sizeof r->kf_P);
    }
    st->n_samples += 1;
}

gf_status gf_gfins_step(gf_gfins_state *st, const double *A, double dt, double *f, double *w,
                        double *wd, double *W, uint8_t *flags)
{
    if (!st || !A)
        return GF_ERR_NULL_POINTER;
    if (!rate_state_valid(st))
        return GF_ERR_BAD_SIZE;
    rate_step_result r;
    const gf_status status = rate_step(st, A, dt, &r);
    if (status != GF_OK)
        return status;
    rate_commit(st, &r);
    if (f) gf_v3_copy(r.f, f);
    if (w) gf_v3_copy(r.w, w);
    if (wd) gf_v3_copy(r.wd, wd);
    if (W) memcpy(W, r.W, sizeof r.W);
    if (flags) *flags = r.flags;
    return GF_OK;
}

gf_status gf_gfins_run(gf_gfins_state *st, size_t n, const double *A, double dt, double *f,
                       double *w, double *wd, double *W, uint8_t *flags, size_t *n_done)
{
    if (n_done)
        *n_done = 0;
    if (!st || !A || !f || !w || !wd || !flags)
        return GF_ERR_NULL_POINTER;
    if (!rate_state_valid(st))
        return GF_ERR_BAD_SIZE;
    if (!(dt > 0.0 && isfinite(dt)))
        return GF_ERR_BAD_TIME;
    const size_t ns = st->solver.n_sensors;
    gf_status status = GF_OK;
    size_t k = 0;
    for (; k < n; ++k) {
        rate_step_result r;
        status = rate_step(st, A + ns * k, dt, &r);
        if (status != GF_OK)
            break;
        rate_commit(st, &r);
        gf_v3_copy(r.f, f + 3 * k);
        gf_v3_copy(r.w, w + 3 * k);
        gf_v3_copy(r.wd, wd + 3 * k);
        if (W)
            memcpy(W + 6 * k, r.W, sizeof r.W);
        flags[k] = r.flags;
    }
    if (n_done)
        *n_done = k;
    return status;
}

/* ---- navigator ---------------------------------------------------------------------- */

gf_status gf_gfnav_init(gf_gfnav_state *st, const gf_array_geometry *g, const gf_rate_config *rc,
                        const double *omega_init, const gf_sins_config *sc, const double *q_bn,
                        const double *v_n, double lat, double lon, double h, double t0,
                        uint32_t *unobservable)
{
    if (!st || !sc)
        return GF_ERR_NULL_POINTER;
    if (sc->input != GF_SINS_INPUT_RATES)
        return GF_ERR_BAD_PARAMETER;
    gf_status status = gf_gfins_init(&st->rate, g, rc, omega_init, unobservable);
    if (status != GF_OK)
        return status;
    st->integration = GF_GFNAV_HERMITE;
    return gf_sins_init(&st->nav, sc, q_bn, v_n, lat, lon, h, t0);
}

gf_status gf_gfnav_set_integration(gf_gfnav_state *st, int32_t integration)
{
    if (!st)
        return GF_ERR_NULL_POINTER;
    if (integration != GF_GFNAV_LINEAR && integration != GF_GFNAV_HERMITE)
        return GF_ERR_BAD_PARAMETER;
    st->integration = integration;
    return GF_OK;
}

/* w(c T) of the cubic Hermite rate model (gf_gfins.h) */
static void hermite_rate(const double w0[3], const double wd0[3], const double w1[3],
                         const double wd1[3], double T, double c, double out[3])
{
    const double c2 = c * c, c3 = c2 * c;
    const double h00 = 2.0 * c3 - 3.0 * c2 + 1.0, h10 = (c3 - 2.0 * c2 + c) * T;
    const double h01 = 3.0 * c2 - 2.0 * c3, h11 = (c3 - c2) * T;
    for (int i = 0; i < 3; ++i)
        out[i] = h00 * w0[i] + h10 * wd0[i] + h01 * w1[i] + h11 * wd1[i];
}

/* the body-rate commutator [a, b] = b x a (gf_gfins.h) */
static void commutator(const double a[3], const double b[3], double out[3])
{
    gf_v3_cross(b, a, out);
}

static void hermite_increments(const double w0[3], const double wd0[3], const double f0[3],
                               const double w1[3], const double wd1[3], const double f1[3],
                               double T, double phi[3], double dv_b[3])
{
    /* sixth-order Magnus series at the Gauss-Legendre nodes 1/2 -+ sqrt(15)/10, 1/2 */
    const double d = 0.38729833462074168852; /* sqrt(15) / 10 */
    double a1[3], a2[3], a3[3], B1[3], B2[3], B3[3], C1[3], C2[3], t1[3], t2[3];
    hermite_rate(w0, wd0, w1, wd1, T, 0.5 - d, a1);
    hermite_rate(w0, wd0, w1, wd1, T, 0.5, a2);
    hermite_rate(w0, wd0, w1, wd1, T, 0.5 + d, a3);
    const double k2 = 3.87298334620741688518 * T / 3.0, k3 = 10.0 * T / 3.0; /* sqrt(15) T / 3 */
    for (int i = 0; i < 3; ++i) {
        B1[i] = T * a2[i];
        B2[i] = k2 * (a3[i] - a1[i]);
        B3[i] = k3 * (a3[i] - 2.0 * a2[i] + a1[i]);
    }
    commutator(B1, B2, C1);
    for (int i = 0; i < 3; ++i)
        t1[i] = 2.0 * B3[i] + C1[i];
    commutator(B1, t1, C2);
    for (int i = 0; i < 3; ++i) {
        C2[i] *= -1.0 / 60.0;
        t1[i] = -20.0 * B1[i] - B3[i] + C1[i];
        t2[i] = B2[i] + C2[i];
    }
    commutator(t1, t2, C1);
    for (int i = 0; i < 3; ++i)
        phi[i] = B1[i] + B3[i] / 12.0 + C1[i] / 240.0;
    /* specific force in the body frame at the start: trapezoid of h(t) = R(t) f(t) */
    double q[4], h1[3];
    gf_q_from_rotvec_fast(phi, q);
    gf_q_rotate(q, f1, h1);
    for (int i = 0; i < 3; ++i)
        dv_b[i] = 0.5 * T * (f0[i] + h1[i]);
}

gf_status gf_hermite_increments(const double *w0, const double *wd0, const double *f0,
                                const double *w1, const double *wd1, const double *f1, double T,
                                double *phi, double *dv_b)
{
    if (!w0 || !wd0 || !f0 || !w1 || !wd1 || !f1 || !phi || !dv_b)
        return GF_ERR_NULL_POINTER;
    if (!(T > 0.0 && isfinite(T)))
        return GF_ERR_BAD_TIME;
    if (!gf_v3_isfinite(w0) || !gf_v3_isfinite(wd0) || !gf_v3_isfinite(f0) ||
        !gf_v3_isfinite(w1) || !gf_v3_isfinite(wd1) || !gf_v3_isfinite(f1))
        return GF_ERR_NONFINITE_INPUT;
    hermite_increments(w0, wd0, f0, w1, wd1, f1, T, phi, dv_b);
    return GF_OK;
}

gf_status gf_gfnav_run(gf_gfnav_state *st, size_t n, const double *A, double dt,
                       const double *h_ext, double *q_bn, double *v_n, double *pos, double *w_out,
                       double *f_out, uint8_t *flags, size_t *n_done)
{
    if (n_done)
        *n_done = 0;
    if (!st || !A || !q_bn || !v_n || !pos)
        return GF_ERR_NULL_POINTER;
    if (!rate_state_valid(&st->rate))
        return GF_ERR_BAD_SIZE;
    if (st->integration != GF_GFNAV_LINEAR && st->integration != GF_GFNAV_HERMITE)
        return GF_ERR_BAD_PARAMETER;
    if (!(dt > 0.0 && isfinite(dt)))
        return GF_ERR_BAD_TIME;
    const size_t ns = st->rate.solver.n_sensors;
    gf_status status = GF_OK;
    size_t k = 0;
    for (; k < n; ++k) {
        rate_step_result r;
        status = rate_step(&st->rate, A + ns * k, dt, &r);
        if (status != GF_OK)
            break;
        gf_sins_state nav = st->nav;
        const double he = h_ext ? h_ext[k] : NAN;
        if (st->integration == GF_GFNAV_HERMITE && nav.have_prev) {
            /* the rate's derivative at both ends: w_dot, less the fused filter's bias */
            double wd0[3], wd1[3], phi[3], dv_b[3];
            gf_v3_copy(st->rate.omega_dot_rad_s2, wd0);
            gf_v3_copy(r.wd, wd1);
            if (st->rate.cfg.strategy == GF_RATE_FUSED) {
                gf_v3_sub(wd0, st->rate.kf.x + 3, wd0);
                gf_v3_sub(wd1, r.kf_x + 3, wd1);
            }
            hermite_increments(nav.prev_gyro, wd0, nav.prev_accel, r.w, wd1, r.f, dt, phi, dv_b);
            status = gf_sins_step_compensated(&nav, phi, dv_b, r.w, r.f, dt, he);
        } else {
            status = gf_sins_step(&nav, r.w, r.f, dt, he);
        }
        if (status != GF_OK)
            break;
        rate_commit(&st->rate, &r);
        st->nav = nav;
        memcpy(q_bn + 4 * k, nav.q_bn, sizeof nav.q_bn);
        gf_v3_copy(nav.v_n_m_s, v_n + 3 * k);
        gf_sins_position(&nav, pos + 3 * k);
        if (w_out)
            gf_v3_copy(r.w, w_out + 3 * k);
        if (f_out)
            gf_v3_copy(r.f, f_out + 3 * k);
        if (flags)
            flags[k] = r.flags;
    }
    if (n_done)
        *n_done = k;
    return status;
}
