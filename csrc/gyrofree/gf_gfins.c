/* gf_gfins.c — gyro-free array solver, rate strategies and navigator; see gf_gfins.h. */
#include "gyrofree/gf_gfins.h"

#include <float.h>
#include <math.h>
#include <string.h>

#include "base/gf_linalg.h"
#include "base/gf_math.h"

#define NS GF_ARRAY_MAX_SENSORS
#define GF_SQRT1_2 0.70710678118654752440
#define GF_SQRT2 1.41421356237309504880

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

/* orthonormal product coordinates (gf_gfins.h): p = [W11, W22, W33, sqrt2 W12, ...] */
static void products_on(const double w[3], double p[6])
{
    p[0] = w[0] * w[0]; p[1] = w[1] * w[1]; p[2] = w[2] * w[2];
    p[3] = GF_SQRT2 * w[0] * w[1]; p[4] = GF_SQRT2 * w[0] * w[2]; p[5] = GF_SQRT2 * w[1] * w[2];
}

/* d p / d w (6 x 3, row-major) in the orthonormal coordinates */
static void products_on_jacobian(const double w[3], double J[18])
{
    const double r = GF_SQRT2;
    const double x = w[0], y = w[1], z = w[2];
    const double Jv[18] = {2 * x, 0, 0, 0, 2 * y, 0, 0, 0, 2 * z,
                           r * y, r * x, 0, r * z, 0, r * x, 0, r * z, r * y};
    memcpy(J, Jv, sizeof Jv);
}

/* K_pred rows [r0, r0 + nr) times the orthonormal products p: out (nr) */
static void kpred_times(const gf_array_solver *s, size_t r0, size_t nr, const double p[6], double *out)
{
    for (size_t r = 0; r < nr; ++r) {
        const double *kr = s->K_pred + (r0 + r) * 6;
        out[r] = kr[0] * p[0] + kr[1] * p[1] + kr[2] * p[2] + kr[3] * p[3] + kr[4] * p[4] + kr[5] * p[5];
    }
}

/* relative rank tolerance: geometry typed to ~1e-12 m must not count as singular, a
 * genuinely dependent column (coincident sensors) gives s ~ 1e-16 s_max */
#define GF_RANK_TOL 1e-9

/* Thin SVD of the m x k matrix a (row-major, m <= NS), zero rows padding m < k. */
static gf_status svd_padded(size_t m, size_t k, const double *a, double *u, double *sv,
                            double *v)
{
    const size_t mm = m < k ? k : m;
    for (size_t i = 0; i < mm; ++i)
        for (size_t j = 0; j < k; ++j)
            u[i * k + j] = i < m ? a[i * k + j] : 0.0;
    return gf_svd(mm, k, u, sv, v);
}

/* out[i * stride + off + c] = H_p row i . column c0 + c of the 6x6 basis B, c < nc: the
 * outputs of product-basis directions */
static void hp_times_columns(size_t m, const double *Hp, const double *B, size_t c0, size_t nc,
                             double *out, size_t stride, size_t off)
{
    for (size_t i = 0; i < m; ++i)
        for (size_t c = 0; c < nc; ++c) {
            double acc = 0.0;
            for (int k = 0; k < 6; ++k)
                acc += Hp[i * 6 + (size_t)k] * B[(size_t)k * 6 + c0 + c];
            out[i * stride + off + c] = acc;
        }
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
    const size_t m = g->n_sensors;
    s->n_sensors = m;
    double hmax = 0.0;
    for (size_t i = 0; i < m; ++i) {
        if (!gf_v3_isfinite(g->u_m[i]) || !gf_v3_isfinite(g->theta[i]))
            return GF_ERR_NONFINITE_INPUT;
        model_row(g->u_m[i], g->theta[i], s->H + i * GF_X_N);
        for (int j = 0; j < GF_X_N; ++j)
            hmax = fmax(hmax, fabs(s->H[i * GF_X_N + j]));
    }
    /* a column is present when it affects the outputs beyond round-off of the geometry */
    for (int j = 0; j < GF_X_N; ++j) {
        double cmax = 0.0;
        for (size_t i = 0; i < m; ++i)
            cmax = fmax(cmax, fabs(s->H[i * GF_X_N + j]));
        if (cmax > 1e-12 * hmax)
            s->present |= kGroupOf[j];
    }
    /* H_l (m x 6) and H_p (m x 6, orthonormal product coordinates) */
    static const double kScale[6] = {1.0, 1.0, 1.0, GF_SQRT1_2, GF_SQRT1_2, GF_SQRT1_2};
    double Hl[NS * 6], Hp[NS * 6];
    for (size_t i = 0; i < m; ++i)
        for (int j = 0; j < 6; ++j) {
            Hl[i * 6 + j] = s->H[i * GF_X_N + j];
            Hp[i * 6 + j] = s->H[i * GF_X_N + 6 + j] * kScale[j];
        }
    double U[NS * GF_X_N], sv[GF_X_N], V[GF_X_N * GF_X_N];
    gf_status st = svd_padded(m, 6, Hl, U, sv, V);
    if (st != GF_OK)
        return st;
    double sp_max = 0.0;
    {
        double Up[NS * 6], svp[6], Vp[36];
        if (svd_padded(m, 6, Hp, Up, svp, Vp) != GF_OK)
            return GF_ERR_SINGULAR_GEOMETRY;
        sp_max = svp[0];
    }
    const double tol = GF_RANK_TOL * fmax(sv[0], sp_max);
    size_t rank_l = 0;
    for (int j = 0; j < 6; ++j)
        if (sv[j] > tol)
            ++rank_l;
    if (rank_l < 6 || m < 6) {
        if (unobservable)
            for (int j = 0; j < 6; ++j) {
                double w2 = 0.0;
                for (size_t c = rank_l; c < 6; ++c)
                    w2 += V[j * 6 + c] * V[j * 6 + c];
                if (w2 > 1e-6)
                    *unobservable |= 1u << j;
            }
        return GF_ERR_SINGULAR_GEOMETRY;
    }
    /* Q H_p = H_p - U_l U_l^T H_p (U_l: the m x 6 left singular vectors of H_l) */
    double QHp[NS * 6];
    for (int c = 0; c < 6; ++c) {
        double proj[6];
        for (int k = 0; k < 6; ++k) {
            double acc = 0.0;
            for (size_t i = 0; i < m; ++i)
                acc += U[i * 6 + k] * Hp[i * 6 + c];
            proj[k] = acc;
        }
        for (size_t i = 0; i < m; ++i) {
            double acc = Hp[i * 6 + c];
            for (int k = 0; k < 6; ++k)
                acc -= U[i * 6 + k] * proj[k];
            QHp[i * 6 + c] = acc;
        }
    }
    double Vo[36];
    if (svd_padded(m, 6, QHp, U, sv, Vo) != GF_OK)
        return GF_ERR_SINGULAR_GEOMETRY;
    size_t n_obs = 0;
    for (int j = 0; j < 6; ++j)
        if (sv[j] > tol)
            ++n_obs;
    /* the rest: confounded (H_p v != 0) or absent, by the SVD of H_p V_n */
    const size_t n_null = 6 - n_obs;
    size_t n_conf = 0;
    double Vc[36] = {0};
    if (n_null > 0) {
        double HpVn[NS * 6];
        hp_times_columns(m, Hp, Vo, n_obs, n_null, HpVn, n_null, 0);
        double Wc[36];
        if (svd_padded(m, n_null, HpVn, U, sv, Wc) != GF_OK)
            return GF_ERR_SINGULAR_GEOMETRY;
        for (size_t c = 0; c < n_null; ++c)
            if (sv[c] > tol)
                ++n_conf;
        /* null basis rotated so that the confounded directions come first */
        for (int k = 0; k < 6; ++k)
            for (size_t c = 0; c < n_null; ++c) {
                double acc = 0.0;
                for (size_t d = 0; d < n_null; ++d)
                    acc += Vo[k * 6 + n_obs + d] * Wc[d * n_null + c];
                Vc[k * 6 + c] = acc;
            }
    }
    for (int k = 0; k < 6; ++k) {
        for (size_t c = 0; c < n_obs; ++c)
            s->basis[k * 6 + c] = Vo[k * 6 + c];
        for (size_t c = 0; c < n_null; ++c)
            s->basis[k * 6 + n_obs + c] = Vc[k * 6 + c];
    }
    s->n_obs = n_obs;
    s->n_conf = n_conf;
    /* least squares for [f, w_dot, z]: X = [H_l, H_p B_o] */
    const size_t k = 6 + n_obs;
    double X[NS * GF_X_N];
    for (size_t i = 0; i < m; ++i)
        for (int j = 0; j < 6; ++j)
            X[i * k + (size_t)j] = Hl[i * 6 + (size_t)j];
    hp_times_columns(m, Hp, s->basis, 0, n_obs, X, k, 6);
    if (svd_padded(m, k, X, U, sv, V) != GF_OK)
        return GF_ERR_SINGULAR_GEOMETRY;
    size_t rank = 0;
    for (size_t j = 0; j < k; ++j)
        if (sv[j] > GF_RANK_TOL * sv[0])
            ++rank;
    if (rank < k)
        return GF_ERR_SINGULAR_GEOMETRY;   /* not expected: the observed part is outside range(H_l) */
    s->rank = rank;
    s->n_est = k;
    s->cond = sv[0] / sv[k - 1];
    for (size_t r = 0; r < k; ++r)
        for (size_t i = 0; i < m; ++i) {
            double acc = 0.0;
            for (size_t c = 0; c < k; ++c)
                acc += V[r * k + c] / sv[c] * U[i * k + c];
            s->pinv[r * NS + i] = acc;
            s->pinv_t[i * GF_X_N + r] = acc;
        }
    /* K_pred = pinv H_p B_c B_c^T (n_est x 6) */
    if (n_conf > 0) {
        double HpBc[NS * 6];
        hp_times_columns(m, Hp, s->basis, n_obs, n_conf, HpBc, 6, 0);
        for (size_t r = 0; r < k; ++r) {
            double t[6] = {0, 0, 0, 0, 0, 0};
            for (size_t c = 0; c < n_conf; ++c) {
                double acc = 0.0;
                for (size_t i = 0; i < m; ++i)
                    acc += s->pinv[r * NS + i] * HpBc[i * 6 + c];
                t[c] = acc;
            }
            for (int j = 0; j < 6; ++j) {
                double acc = 0.0;
                for (size_t c = 0; c < n_conf; ++c)
                    acc += t[c] * s->basis[j * 6 + n_obs + c];
                s->K_pred[r * 6 + j] = acc;
            }
        }
    }
    /* noise gains in body axes: f, w_dot; a product W_jk when its unit vector lies in the
     * observed subspace (then W_jk = kScale_j e_j^T B_o z). A group is estimated when all
     * its components are observed, from the rate when one of them touches the
     * confounded subspace. */
    uint32_t all_observed = GF_GROUP_W_DIAG | GF_GROUP_W_OFFDIAG, touches_conf = 0;
    for (int j = 0; j < 6; ++j) {
        double in_obs = 0.0, in_conf = 0.0;
        for (size_t c = 0; c < n_obs; ++c)
            in_obs += s->basis[j * 6 + c] * s->basis[j * 6 + c];
        for (size_t c = 0; c < n_conf; ++c)
            in_conf += s->basis[j * 6 + n_obs + c] * s->basis[j * 6 + n_obs + c];
        const uint32_t grp = kGroupOf[6 + j];
        if (in_conf > 1e-12)
            touches_conf |= grp;
        if (!(in_obs > 1.0 - 1e-9)) {
            all_observed &= ~grp;
            continue;
        }
        double g2 = 0.0;
        for (size_t i = 0; i < m; ++i) {
            double acc = 0.0;
            for (size_t c = 0; c < n_obs; ++c)
                acc += s->basis[j * 6 + c] * s->pinv[(6 + c) * NS + i];
            g2 += acc * acc;
        }
        s->noise_gain[6 + j] = kScale[j] * sqrt(g2);
    }
    for (int j = 0; j < 6; ++j) {
        double g2 = 0.0;
        for (size_t i = 0; i < m; ++i)
            g2 += s->pinv[(size_t)j * NS + i] * s->pinv[(size_t)j * NS + i];
        s->noise_gain[j] = sqrt(g2);
    }
    /* W (as in x) = S B_o z + S B_n B_n^T p(w), S = diag(1, 1, 1, 1/sqrt2, ...) */
    for (int j = 0; j < 6; ++j) {
        for (size_t c = 0; c < n_obs; ++c)
            s->W_obs[j * 6 + (int)c] = kScale[j] * s->basis[j * 6 + c];
        for (int i = 0; i < 6; ++i) {
            double acc = 0.0;
            for (size_t c = n_obs; c < 6; ++c)
                acc += s->basis[j * 6 + c] * s->basis[i * 6 + c];
            s->W_rate[j * 6 + i] = kScale[j] * acc;
        }
    }
    s->estimated = GF_GROUP_F | GF_GROUP_OMEGA_DOT | (all_observed & s->present);
    s->from_rate = s->present & touches_conf & ~s->estimated & (GF_GROUP_W_DIAG | GF_GROUP_W_OFFDIAG);
    return GF_OK;
}

/* The solver fields that size a loop or index an array: n_sensors rows of H and of
 * the outputs, n_est rows of pinv, n_obs + n_conf basis columns. Integer compares
 * only: runs before every use of a solver handed in by a caller. */
static int solver_valid(const gf_array_solver *s)
{
    return s->n_sensors >= 6 && s->n_sensors <= NS && s->n_obs <= 6 &&
           s->n_conf <= 6 - s->n_obs && s->n_est == 6 + s->n_obs;
}

/* y = pinv A (12 entries, zero beyond n_est) on a solver already checked (solver_valid):
 * one axpy of 12 per output, which the compiler vectorises */
static void array_linear(const gf_array_solver *s, const double *A, double *y)
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
static void array_finish(const gf_array_solver *s, const double *y, const double *w, double *x)
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

gf_status gf_array_solve(const gf_array_solver *s, const double *A, const double *w_pred,
                         double *x)
{
    if (!s || !A || !x)
        return GF_ERR_NULL_POINTER;
    if (!solver_valid(s))
        return GF_ERR_BAD_SIZE;
    if (s->n_conf && !w_pred)
        return GF_ERR_NULL_POINTER;
    double y[GF_X_N];
    array_linear(s, A, y);
    array_finish(s, y, w_pred, x);
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

/* The rate model a strategy needs on this solver (GF_RATE_MODEL_*), NONE if it cannot run */
static int model_allowed(int32_t strategy, size_t n_obs, int32_t model)
{
    switch (strategy) {
    case GF_RATE_SQRT:
        return (model == GF_RATE_MODEL_FRAME && n_obs == 3) ||
               (model == GF_RATE_MODEL_FIT && n_obs >= 3 && n_obs <= 6);
    case GF_RATE_EIGEN:
        return model == GF_RATE_MODEL_FULL && n_obs == 6;
    default:
        return model == GF_RATE_MODEL_NONE;
    }
}

/* What a rate step uses to size loops, index arrays or select a branch: the solver's
 * sizes, the strategy and its rate model, and for FUSED the measurement count and the
 * filter dimension. Integer compares only: runs before every step. */
static int rate_state_valid(const gf_gfins_state *st)
{
    if (!solver_valid(&st->solver) || st->cfg.strategy < GF_RATE_INTEGRATE ||
        st->cfg.strategy > GF_RATE_FUSED ||
        !model_allowed(st->cfg.strategy, st->solver.n_obs, st->rate_model))
        return 0;
    if (st->cfg.strategy == GF_RATE_FUSED)
        return st->n_w_meas >= 1 && (size_t)st->n_w_meas == st->solver.n_obs && st->kf.n == 6;
    return 1;
}

static int config_valid(const gf_rate_config *c)
{
    return c->strategy >= GF_RATE_INTEGRATE && c->strategy <= GF_RATE_FUSED &&
           c->accel_noise_m_s2 > 0.0 && isfinite(c->accel_noise_m_s2) &&
           c->bias_walk_rad_s2_sqrt_s >= 0.0 && isfinite(c->bias_walk_rad_s2_sqrt_s) &&
           c->init_std_rad_s > 0.0 && isfinite(c->init_std_rad_s) &&
           c->init_bias_std_rad_s2 >= 0.0 && isfinite(c->init_bias_std_rad_s2);
}

gf_status gf_gfins_state_check(const gf_gfins_state *st)
{
    if (!st)
        return GF_ERR_NULL_POINTER;
    if (!rate_state_valid(st))
        return GF_ERR_BAD_SIZE;
    const gf_array_solver *s = &st->solver;
    if (!config_valid(&st->cfg))
        return GF_ERR_BAD_PARAMETER;
    if ((s->present | s->estimated | s->from_rate) > 15u || s->rank != s->n_est ||
        !estimates(s, GF_GROUP_F | GF_GROUP_OMEGA_DOT))
        return GF_ERR_BAD_PARAMETER;
    if (!gf_all_finite(s->H, s->n_sensors * GF_X_N) || !gf_all_finite(s->noise_gain, GF_X_N) ||
        !isfinite(s->cond) || !gf_all_finite(s->basis, 36) || !gf_all_finite(s->K_pred, GF_X_N * 6))
        return GF_ERR_NONFINITE_INPUT;
    for (size_t r = 0; r < s->n_est; ++r)
        if (!gf_all_finite(s->pinv + r * NS, s->n_sensors))
            return GF_ERR_NONFINITE_INPUT;
    if (!gf_all_finite(s->pinv_t, s->n_sensors * GF_X_N))
        return GF_ERR_NONFINITE_INPUT;
    if (!gf_all_finite(st->omega_rad_s, 3) || !gf_all_finite(st->omega_ref_rad_s, 3) ||
        !gf_all_finite(st->omega_dot_rad_s2, 3) || !gf_all_finite(st->R_W, 36) ||
        !gf_all_finite(st->omega_dot_prev_rad_s2, 3) || !isfinite(st->dt_prev_s) ||
        !gf_all_finite(st->var_omega_dot, 9) || !gf_all_finite(st->frame, 9) ||
        !gf_all_finite(st->diag_map, 18) || !gf_all_finite(st->amb_rad_s, 3) ||
        !gf_all_finite(st->whiten, 36))
        return GF_ERR_NONFINITE_INPUT;
    if (st->cfg.strategy == GF_RATE_FUSED)
        return gf_kalman_check(&st->kf);
    return GF_OK;
}

/* symmetric 3x3 matrix of a vector in the orthonormal product coordinates */
static void sym_of(const double p[6], double M[9])
{
    M[0] = p[0]; M[4] = p[1]; M[8] = p[2];
    M[1] = M[3] = p[3] * GF_SQRT1_2;
    M[2] = M[6] = p[4] * GF_SQRT1_2;
    M[5] = M[7] = p[5] * GF_SQRT1_2;
}

/* column c of the solver's product basis as a symmetric matrix */
static void basis_matrix(const gf_array_solver *s, size_t c, double M[9])
{
    double p[6];
    for (int j = 0; j < 6; ++j)
        p[j] = s->basis[j * 6 + c];
    sym_of(p, M);
}

/* FRAME detection: the three observed combinations are the diagonal of W in one
 * orthonormal frame iff their matrices commute, i.e. are all diagonal in the
 * eigenbasis of a generic combination of them. The frame is made canonical (each axis
 * along the body axis it is closest to, in body-axis order where that is a permutation,
 * pointing to its positive side), so that Qin's array as tabled gives the body axes. */
static int find_frame(const gf_array_solver *s, double frame[9])
{
    if (s->n_obs != 3)
        return 0;
    double B[3][9];
    for (size_t c = 0; c < 3; ++c)
        basis_matrix(s, c, B[c]);
    static const double kMix[2][3] = {{1.0, 0.41421356237309505, 0.71828182845904524},
                                      {0.3, 1.0, -0.57721566490153286}};
    for (int attempt = 0; attempt < 2; ++attempt) {
        double M[9], ev[3], V[9];
        for (int i = 0; i < 9; ++i)
            M[i] = kMix[attempt][0] * B[0][i] + kMix[attempt][1] * B[1][i] + kMix[attempt][2] * B[2][i];
        gf_sym3_eig(M, ev, V);
        int ok = 1;
        for (size_t c = 0; c < 3 && ok; ++c) {
            double off = 0.0, nrm = 0.0;
            for (int i = 0; i < 9; ++i)
                nrm += B[c][i] * B[c][i];
            for (int p = 0; p < 3; ++p)
                for (int q = 0; q < 3; ++q) {
                    if (p == q)
                        continue;
                    double acc = 0.0; /* v_p^T B v_q */
                    for (int i = 0; i < 3; ++i)
                        for (int j = 0; j < 3; ++j)
                            acc += V[3 * i + p] * B[c][3 * i + j] * V[3 * j + q];
                    off += acc * acc;
                }
            ok = off <= 1e-18 * nrm;
        }
        if (!ok)
            continue;
        /* canonical order and signs */
        int axis_of[3], used[3] = {0, 0, 0}, perm = 1;
        for (int p = 0; p < 3; ++p) {
            int best = 0;
            for (int i = 1; i < 3; ++i)
                if (fabs(V[3 * i + p]) > fabs(V[3 * best + p]))
                    best = i;
            axis_of[p] = best;
            perm &= !used[best];
            used[best] = 1;
        }
        for (int p = 0; p < 3; ++p) {
            const int dst = perm ? axis_of[p] : p;
            const double sg = V[3 * axis_of[p] + p] < 0.0 ? -1.0 : 1.0;
            for (int i = 0; i < 3; ++i)
                frame[3 * i + dst] = sg * V[3 * i + p];
        }
        /* the body axes within round-off (Qin's array as tabled): exactly them, so that
         * the per-sample step can skip the frame rotations */
        double dI = 0.0;
        for (int i = 0; i < 9; ++i)
            dI = fmax(dI, fabs(frame[i] - (i % 4 == 0 ? 1.0 : 0.0)));
        if (dI <= 1e-13)
            for (int i = 0; i < 9; ++i)
                frame[i] = i % 4 == 0 ? 1.0 : 0.0;
        return 1;
    }
    return 0;
}

gf_status gf_gfins_init(gf_gfins_state *st, const gf_array_geometry *g, const gf_rate_config *cfg,
                        const double *omega_init, uint32_t *unobservable)
{
    if (!st || !g || !cfg)
        return GF_ERR_NULL_POINTER;
    if (!config_valid(cfg))
        return GF_ERR_BAD_PARAMETER;
    if (omega_init && !gf_v3_isfinite(omega_init))
        return GF_ERR_BAD_PARAMETER;
    memset(st, 0, sizeof *st);
    gf_status status = gf_array_solver_init(&st->solver, g, unobservable);
    if (status != GF_OK)
        return status;
    const gf_array_solver *s = &st->solver;
    const size_t no = s->n_obs;
    st->cfg = *cfg;
    /* the rate model of SQRT and EIGEN */
    if (cfg->strategy == GF_RATE_EIGEN) {
        st->rate_model = GF_RATE_MODEL_FULL;
        if (!model_allowed(cfg->strategy, no, st->rate_model))
            return GF_ERR_BAD_PARAMETER;
    } else if (cfg->strategy == GF_RATE_SQRT) {
        if (find_frame(s, st->frame))
            st->rate_model = GF_RATE_MODEL_FRAME;
        else if (no >= 3)
            st->rate_model = GF_RATE_MODEL_FIT;
        if (!model_allowed(cfg->strategy, no, st->rate_model))
            return GF_ERR_BAD_PARAMETER;
    }
    if (cfg->strategy == GF_RATE_FUSED && no == 0)
        return GF_ERR_BAD_PARAMETER;
    if (omega_init) {
        gf_v3_copy(omega_init, st->omega_rad_s);
        gf_v3_copy(omega_init, st->omega_ref_rad_s);
    }
    /* noise covariances of the linear estimates: sigma^2 P P^T over the pinv rows */
    const double s2 = cfg->accel_noise_m_s2 * cfg->accel_noise_m_s2;
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
            const double *pa = s->pinv + (size_t)(3 + a) * NS, *pb = s->pinv + (size_t)(3 + b) * NS;
            double acc = 0.0;
            for (size_t i = 0; i < s->n_sensors; ++i)
                acc += pa[i] * pb[i];
            st->var_omega_dot[3 * a + b] = s2 * acc;
        }
    for (size_t a = 0; a < no; ++a)
        for (size_t b = 0; b < no; ++b) {
            const double *pa = s->pinv + (6 + a) * NS, *pb = s->pinv + (6 + b) * NS;
            double acc = 0.0;
            for (size_t i = 0; i < s->n_sensors; ++i)
                acc += pa[i] * pb[i];
            st->R_W[no * a + b] = s2 * acc;
        }
    /* ambiguity resolution: 2.5 sqrt(std) of the products the rate is read from */
    if (st->rate_model == GF_RATE_MODEL_FRAME) {
        for (int k = 0; k < 3; ++k) {
            double M[9];
            for (size_t c = 0; c < 3; ++c) {
                basis_matrix(s, c, M);
                double acc = 0.0; /* a_k^T B_c a_k */
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j)
                        acc += st->frame[3 * i + k] * M[3 * i + j] * st->frame[3 * j + k];
                st->diag_map[3 * k + c] = acc;
            }
            double var = 0.0; /* of d_k = diag_map_k z */
            for (size_t a = 0; a < 3; ++a)
                for (size_t b = 0; b < 3; ++b)
                    var += st->diag_map[3 * k + a] * st->R_W[3 * a + b] * st->diag_map[3 * k + b];
            st->amb_rad_s[k] = 2.5 * sqrt(sqrt(var));
        }
    } else if (st->rate_model != GF_RATE_MODEL_NONE) {
        double vmax = 0.0;
        for (size_t a = 0; a < no; ++a)
            vmax = fmax(vmax, st->R_W[no * a + a]);
        st->amb_rad_s[0] = 2.5 * sqrt(sqrt(vmax));
        if (st->rate_model == GF_RATE_MODEL_FIT) {
            /* whitening L^-1 of R_W / vmax (the weights of the fit; scaled so that the
             * whitened Jacobian is in rad/s like the resolution) */
            double Lc[36];
            for (size_t i = 0; i < no * no; ++i)
                Lc[i] = st->R_W[i] / vmax;
            if (gf_cholesky(no, Lc) != GF_OK)
                return GF_ERR_SINGULAR_GEOMETRY;
            for (size_t c = 0; c < no; ++c) { /* column c of L^-1: forward substitution */
                for (size_t i = 0; i < no; ++i) {
                    double acc = i == c ? 1.0 : 0.0;
                    for (size_t j = 0; j < i; ++j)
                        acc -= Lc[i * no + j] * st->whiten[j * no + c];
                    st->whiten[i * no + c] = acc / Lc[i * no + i];
                }
            }
        }
    }
    if (cfg->strategy == GF_RATE_FUSED) {
        st->n_w_meas = (int32_t)no;
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
    /* a finite but absurd noise std (1e308 m/s^2) overflows the covariances: the state
     * would be refused when restored (found by fuzzing) */
    if (!gf_all_finite(st->var_omega_dot, 9) || !gf_all_finite(st->R_W, 36))
        return GF_ERR_BAD_PARAMETER;
    return GF_OK;
}


/* Pending results of one rate step (committed only if the whole sample succeeds). */
typedef struct rate_step_result {
    double f[3], w[3], wd[3], ref[3], y[GF_X_N], dt;
    double kf_x[6], kf_P[36];
    uint8_t flags;
} rate_step_result;

/* (n x 6) times (6 x 3) -> n x 3 */
static void times_jacobian(const double *M, size_t n, size_t stride, const double J[18], double *out)
{
    for (size_t r = 0; r < n; ++r)
        for (int c = 0; c < 3; ++c) {
            double acc = 0.0;
            for (int j = 0; j < 6; ++j)
                acc += M[r * stride + (size_t)j] * J[3 * j + c];
            out[3 * r + (size_t)c] = acc;
        }
}

/* A sign reference carries no information below this fraction of the rates' scale
 * (|reference|, |previous rate|): it is round-off of an integral started at zero. */
#define SIGN_INFO 1e-6

/* SQRT, FRAME: w.a_k = +-sqrt(a_k^T W a_k) with the sign of the reference (seed 000
 * eq. 4 and 6 in the array's frame); the reference is re-anchored on the axes that are
 * unambiguous */
static void rate_frame(const gf_gfins_state *st, const double *z, rate_step_result *r)
{
    double wp[3], refp[3], prevp[3];
    const double *fr = st->frame;
    const int body = fr[0] == 1.0 && fr[4] == 1.0 && fr[8] == 1.0; /* then exactly I */
    const double *w0 = st->omega_rad_s;
    const double tiny = SIGN_INFO * fmax(gf_v3_norm(r->ref), gf_v3_norm(w0));
    for (int k = 0; k < 3; ++k) {
        const double *fk = st->frame;
        refp[k] = body ? r->ref[k] : fk[k] * r->ref[0] + fk[3 + k] * r->ref[1] + fk[6 + k] * r->ref[2];
        prevp[k] = body ? w0[k] : fk[k] * w0[0] + fk[3 + k] * w0[1] + fk[6 + k] * w0[2];
        const double d = st->diag_map[3 * k] * z[0] + st->diag_map[3 * k + 1] * z[1] +
                         st->diag_map[3 * k + 2] * z[2];
        if (d >= 0.0) {
            const double mag = sqrt(d);
            /* the sign of the w_dot integral, or where it holds no information (a start at
             * rest from zero: round-off), the previous rate's: continuity */
            const double sref = fabs(refp[k]) > tiny ? refp[k] : prevp[k];
            wp[k] = sref < 0.0 ? -mag : mag;
            if (sref == 0.0 && mag > 0.0)
                r->flags |= GF_RATE_FLAG_SIGN_UNKNOWN;
            if (mag < st->amb_rad_s[k])
                r->flags |= GF_RATE_FLAG_AMBIGUOUS;
            else
                refp[k] = wp[k];
        } else {
            wp[k] = refp[k];
            r->flags |= (uint8_t)(GF_RATE_FLAG_NEG_X << k);
        }
    }
    if (body) {
        gf_v3_copy(wp, r->w);
        gf_v3_copy(refp, r->ref);
        return;
    }
    for (int i = 0; i < 3; ++i) {
        const double *fi = st->frame + 3 * i;
        r->w[i] = fi[0] * wp[0] + fi[1] * wp[1] + fi[2] * wp[2];
        r->ref[i] = fi[0] * refp[0] + fi[1] * refp[1] + fi[2] * refp[2];
    }
}

/* SQRT/EIGEN, FULL: dominant eigenpair of the measured W, global sign from the reference */
static void rate_full(const gf_gfins_state *st, const double *Wx, rate_step_result *r)
{
    const double W[9] = {Wx[0], Wx[3], Wx[4], Wx[3], Wx[1], Wx[5], Wx[4], Wx[5], Wx[2]};
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
        /* the sign of the w_dot integral, or the previous rate's where the integral holds
         * no information along w (a start at rest from zero: round-off) */
        double d = gf_v3_dot(r->w, r->ref);
        if (!(fabs(d) > SIGN_INFO * mag * fmax(gf_v3_norm(r->ref), gf_v3_norm(st->omega_rad_s))))
            d = gf_v3_dot(r->w, st->omega_rad_s);
        if (d < 0.0)
            gf_v3_scale(r->w, -1.0, r->w);
        else if (d == 0.0)
            r->flags |= GF_RATE_FLAG_SIGN_UNKNOWN;
        if (mag < st->amb_rad_s[0])
            r->flags |= GF_RATE_FLAG_AMBIGUOUS;
        else
            gf_v3_copy(r->w, r->ref);
    } else {
        gf_v3_copy(r->ref, r->w);
        r->flags |= GF_RATE_FLAG_NEG_X;
    }
}

/* SQRT, FIT: Gauss-Newton fit of w to the observed combinations z, weighted by R_W^-1,
 * from the reference (the branch of the w_dot integral); ambiguous where the whitened
 * Jacobian L^-1 B_o^T J(w) has sigma_min / 2 below the resolution (two branches meet
 * there; for Qin's array sigma_min = 2 |w_k|) */
static void rate_fit(const gf_gfins_state *st, const double *z, rate_step_result *r)
{
    const gf_array_solver *s = &st->solver;
    const size_t no = s->n_obs;
    double w[3];
    gf_v3_copy(r->ref, w);
    if (!(gf_v3_norm(r->ref) > SIGN_INFO * gf_v3_norm(st->omega_rad_s)))
        gf_v3_copy(st->omega_rad_s, w); /* the integral holds no information: continuity */
    double GtG[9] = {0};
    int converged = 0;
    for (int it = 0; it < 12; ++it) {
        double p[6], J[18], G[18], res[6], g[3] = {0, 0, 0};
        products_on(w, p);
        products_on_jacobian(w, J);
        double Gr[18], rr[6];
        for (size_t c = 0; c < no; ++c) {
            double acc = 0.0, gc[3] = {0, 0, 0};
            for (int j = 0; j < 6; ++j) {
                const double b = s->basis[j * 6 + c];
                acc += b * p[j];
                gc[0] += b * J[3 * j];
                gc[1] += b * J[3 * j + 1];
                gc[2] += b * J[3 * j + 2];
            }
            rr[c] = z[c] - acc;
            memcpy(Gr + 3 * c, gc, sizeof gc);
        }
        /* whitened: L^-1 r, L^-1 G */
        for (size_t i = 0; i < no; ++i) {
            double a0 = 0.0, g0 = 0.0, g1 = 0.0, g2 = 0.0;
            for (size_t j = 0; j <= i; ++j) {
                const double l = st->whiten[i * no + j];
                a0 += l * rr[j];
                g0 += l * Gr[3 * j];
                g1 += l * Gr[3 * j + 1];
                g2 += l * Gr[3 * j + 2];
            }
            res[i] = a0;
            G[3 * i] = g0, G[3 * i + 1] = g1, G[3 * i + 2] = g2;
        }
        for (int a = 0; a < 3; ++a) {
            for (int b = 0; b < 3; ++b) {
                double acc = 0.0;
                for (size_t c = 0; c < no; ++c)
                    acc += G[3 * c + a] * G[3 * c + b];
                GtG[3 * a + b] = acc;
            }
            for (size_t c = 0; c < no; ++c)
                g[a] += G[3 * c + a] * res[c];
        }
        double L[9];
        memcpy(L, GtG, sizeof L);
        if (gf_cholesky(3, L) != GF_OK)
            break;
        gf_cholesky_solve(3, L, 1, g);
        gf_v3_add(w, g, w);
        if (gf_v3_norm(g) <= 4.0 * DBL_EPSILON * gf_v3_norm(w)) {
            converged = 1;
            break;
        }
    }
    if (!converged || !gf_v3_isfinite(w)) {
        gf_v3_copy(r->ref, r->w);
        r->flags |= GF_RATE_FLAG_NEG_X;
        return;
    }
    gf_v3_copy(w, r->w);
    double ev[3], V[9];
    gf_sym3_eig(GtG, ev, V);
    if (!(ev[2] > 0.0) || 0.5 * sqrt(ev[2]) < st->amb_rad_s[0])
        r->flags |= GF_RATE_FLAG_AMBIGUOUS;
    else
        gf_v3_copy(w, r->ref);
}

/* the w_dot integral over the new interval (gf_gfins.h): third-order Adams-Moulton when
 * the two previous intervals are equal, else the trapezoid */
static int am3_ok(const gf_gfins_state *st, double dt)
{
    return st->n_samples >= 2 && fabs(dt - st->dt_prev_s) <= 1e-9 * dt;
}

static void wdot_integral(const gf_gfins_state *st, const double wd_new[3], double dt, double out[3])
{
    const double *w1 = st->omega_dot_rad_s2, *w2 = st->omega_dot_prev_rad_s2;
    if (am3_ok(st, dt))
        for (int k = 0; k < 3; ++k)
            out[k] = dt / 12.0 * (5.0 * wd_new[k] + 8.0 * w1[k] - w2[k]);
    else
        for (int k = 0; k < 3; ++k)
            out[k] = 0.5 * dt * (w1[k] + wd_new[k]);
}

static gf_status rate_step(const gf_gfins_state *st, const double *A, double dt,
                           rate_step_result *r)
{
    const gf_array_solver *s = &st->solver;
    if (!gf_all_finite(A, s->n_sensors))
        return GF_ERR_NONFINITE_INPUT;
    const int first = st->n_samples == 0;
    if (!first && !(dt > 0.0 && isfinite(dt)))
        return GF_ERR_BAD_TIME;
    r->dt = dt;
    double pred[3], y[GF_X_N], z[6], p_pred[6];
    if (first)
        gf_v3_copy(st->omega_rad_s, pred);
    else if (am3_ok(st, dt))
        for (int k = 0; k < 3; ++k)
            pred[k] = st->omega_rad_s[k] +
                      0.5 * dt * (3.0 * st->omega_dot_rad_s2[k] - st->omega_dot_prev_rad_s2[k]);
    else
        gf_v3_axpy(st->omega_rad_s, dt, st->omega_dot_rad_s2, pred);
    /* y = pinv A; w_dot and the observed combinations less the confounded products of
     * the predicted rate */
    array_linear(s, A, y);
    gf_v3_copy(y + 3, r->wd);
    memcpy(z, y + 6, s->n_obs * sizeof(double));
    if (s->n_conf) {
        double kp[GF_X_N] = {0};
        products_on(pred, p_pred);
        kpred_times(s, 3, 3 + s->n_obs, p_pred, kp);
        for (int k = 0; k < 3; ++k)
            r->wd[k] -= kp[k];
        for (size_t c = 0; c < s->n_obs; ++c)
            z[c] -= kp[3 + c];
    }
    double dw[3] = {0, 0, 0};
    if (!first)
        wdot_integral(st, r->wd, dt, dw);
    gf_v3_add(st->omega_ref_rad_s, dw, r->ref);
    r->flags = 0;
    switch (st->cfg.strategy) {
    case GF_RATE_INTEGRATE:
        gf_v3_add(st->omega_rad_s, dw, r->w);
        gf_v3_copy(r->w, r->ref);
        break;
    case GF_RATE_SQRT:
    case GF_RATE_EIGEN:
        if (st->rate_model == GF_RATE_MODEL_FRAME) {
            rate_frame(st, z, r);
        } else if (st->rate_model == GF_RATE_MODEL_FULL) {
            double W[6];
            for (int j = 0; j < 6; ++j) {
                const double *wo = s->W_obs + j * 6;
                W[j] = wo[0] * z[0] + wo[1] * z[1] + wo[2] * z[2] + wo[3] * z[3] + wo[4] * z[4] +
                       wo[5] * z[5];
            }
            rate_full(st, W, r);
        } else {
            rate_fit(st, z, r);
        }
        break;
    case GF_RATE_FUSED: {
        /* EKF on [w, b]: w' = w_dot(w) - b, w_dot(w) = y_wd - K_wd p(w) (the confounded
         * products, if any, at the filter's rate); the observed combinations measure
         * h(w) = (B_o^T + K_z) p(w), exactly, whatever the prediction */
        gf_kalman kf;
        kf.n = 6;
        memcpy(kf.x, st->kf.x, 6 * sizeof(double));
        memcpy(kf.P, st->kf.P, 36 * sizeof(double));
        const size_t no = s->n_obs;
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
            if (s->n_conf) { /* the loop through the confounded products: dw' = -K_wd J dw */
                double J[18], Aw[9];
                products_on_jacobian(kf.x, J);
                times_jacobian(s->K_pred + 3 * 6, 3, 6, J, Aw);
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j)
                        F[6 * i + j] -= dt * Aw[3 * i + j];
            }
            for (int k = 0; k < 3; ++k)
                kf.x[k] += dw[k] - dt * kf.x[3 + k];
            gf_kalman_predict(&kf, F, Q, 0);
        }
        const double *w = kf.x;
        double p[6], J[18], M[GF_X_N * 6], H[36], res[6];
        products_on(w, p);
        products_on_jacobian(w, J);
        for (size_t c = 0; c < no; ++c)
            for (int j = 0; j < 6; ++j)
                M[c * 6 + (size_t)j] = s->basis[j * 6 + c] + s->K_pred[(6 + c) * 6 + (size_t)j];
        double Hw[18];
        times_jacobian(M, no, 6, J, Hw);
        memset(H, 0, sizeof H);
        for (size_t c = 0; c < no; ++c) {
            double hc = 0.0;
            for (int j = 0; j < 6; ++j)
                hc += M[c * 6 + (size_t)j] * p[j];
            res[c] = y[6 + c] - hc;
            H[c * 6 + 0] = Hw[3 * c];
            H[c * 6 + 1] = Hw[3 * c + 1];
            H[c * 6 + 2] = Hw[3 * c + 2];
        }
        if (gf_kalman_update(&kf, no, res, H, st->R_W, NULL) != GF_OK)
            r->flags |= GF_RATE_FLAG_UPDATE_SKIPPED;
        gf_v3_copy(kf.x, r->w);
        gf_v3_copy(kf.x, r->ref);
        memcpy(r->kf_x, kf.x, sizeof r->kf_x);
        memcpy(r->kf_P, kf.P, sizeof r->kf_P);
        break;
    }
    default:
        return GF_ERR_BAD_PARAMETER;
    }
    /* f and w_dot with the confounded products of the final rate: the w_dot kept for the
     * next intervals' integral is then that of the rate the strategy settled on, the
     * w' = w_dot(w) the filter models (the products W are formed only when a caller
     * asks for them: rate_products) */
    gf_v3_copy(y, r->f);
    if (s->n_conf) {
        double p[6], kf[6];
        products_on(r->w, p);
        kpred_times(s, 0, 6, p, kf);
        for (int k = 0; k < 3; ++k) {
            r->f[k] -= kf[k];
            r->wd[k] = y[3 + k] - kf[3 + k];
        }
    }
    memcpy(r->y, y, s->n_est * sizeof(double));
    /* every output and the state to commit (found by fuzzing: samples near 1e307 m/s^2
     * overflowed w_dot and the products with GF_OK) */
    if (!gf_all_finite(r->w, 3) || !gf_all_finite(r->f, 3) || !gf_all_finite(r->wd, 3) ||
        !gf_all_finite(r->y, s->n_est) || !gf_all_finite(r->ref, 3) ||
        (st->cfg.strategy == GF_RATE_FUSED &&
         (!gf_all_finite(r->kf_x, 6) || !gf_all_finite(r->kf_P, 36))))
        return GF_ERR_DIVERGED;
    return GF_OK;
}

/* the products W (as in x) of a step's result: observed from the outputs, the rest from
 * the final rate */
static void rate_products(const gf_array_solver *s, const rate_step_result *r, double W[6])
{
    double x[GF_X_N];
    array_finish(s, r->y, r->w, x);
    memcpy(W, x + 6, 6 * sizeof(double));
}

static void rate_commit(gf_gfins_state *st, const rate_step_result *r)
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
    /* the products of a finite but absurd rate overflow (found by fuzzing: w = 1.8e308
     * rad/s gave GF_OK with NaN products): checked before anything is committed */
    double Wk[6];
    if (W) {
        rate_products(&st->solver, &r, Wk);
        if (!gf_all_finite(Wk, 6))
            return GF_ERR_DIVERGED;
    }
    rate_commit(st, &r);
    if (f) gf_v3_copy(r.f, f);
    if (w) gf_v3_copy(r.w, w);
    if (wd) gf_v3_copy(r.wd, wd);
    if (W) memcpy(W, Wk, sizeof Wk);
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
        if (W) {   /* as in gf_gfins_step: overflowing products refuse the sample */
            rate_products(&st->solver, &r, W + 6 * k);
            if (!gf_all_finite(W + 6 * k, 6)) {
                status = GF_ERR_DIVERGED;
                break;
            }
        }
        rate_commit(st, &r);
        gf_v3_copy(r.f, f + 3 * k);
        gf_v3_copy(r.w, w + 3 * k);
        gf_v3_copy(r.wd, wd + 3 * k);
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
    /* both parts into a copy, committed only when both start (found by fuzzing: a refused
     * strapdown start left a new rate solver beside the old navigation state) */
    gf_gfnav_state fresh;
    memset(&fresh, 0, sizeof fresh);   /* padding included: states are compared and hashed as bytes */
    gf_status status = gf_gfins_init(&fresh.rate, g, rc, omega_init, unobservable);
    if (status != GF_OK)
        return status;
    fresh.integration = GF_GFNAV_HERMITE;
    status = gf_sins_init(&fresh.nav, sc, q_bn, v_n, lat, lon, h, t0);
    if (status == GF_OK)
        *st = fresh;
    return status;
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

/* the body-rate commutator [a, b] = b x a (gf_gfins.h) */
static void commutator(const double a[3], const double b[3], double out[3])
{
    gf_v3_cross(b, a, out);
}

/* The increments of gf_gfins.h, and the quaternion q(phi) of the rotation. With
 * m = (w0 + w1)/2, D = w1 - w0 and u = tau - 1/2, the Hermite rate is
 *   w = m + (3u/2 - 2u^3) D + T [(1/8 - u^2/2)(w_dot0 - w_dot1) + (u^3 - u/4)(w_dot0 + w_dot1)],
 * so at the nodes u = 0, +-sqrt(15)/10 the Magnus terms reduce to
 *   B1 = T (m + T (w_dot0 - w_dot1) / 8),
 *   B2 = T (6 D / 5 - T (w_dot0 + w_dot1) / 10),
 *   B3 = -T^2 (w_dot0 - w_dot1) / 2. */
static void hermite_increments(const double w0[3], const double wd0[3], const double f0[3],
                               const double w1[3], const double wd1[3], const double f1[3],
                               double T, double phi[3], double dv_b[3], double q[4])
{
    double B1[3], B2[3], B3[3], C1[3], C2[3], t1[3], t2[3];
    for (int i = 0; i < 3; ++i) {
        const double dd = wd0[i] - wd1[i], sd = wd0[i] + wd1[i];
        B1[i] = T * (0.5 * (w0[i] + w1[i]) + 0.125 * T * dd);
        B2[i] = T * (1.2 * (w1[i] - w0[i]) - 0.1 * T * sd);
        B3[i] = -0.5 * T * T * dd;
    }
    commutator(B1, B2, C1);
    for (int i = 0; i < 3; ++i)
        t1[i] = 2.0 * B3[i] + C1[i];
    commutator(B1, t1, C2);
    /* (multiplications by the reciprocals: divisions would lengthen the dependent chain) */
    for (int i = 0; i < 3; ++i) {
        t1[i] = -20.0 * B1[i] - B3[i] + C1[i];
        t2[i] = B2[i] - C2[i] * (1.0 / 60.0);
    }
    commutator(t1, t2, C1);
    for (int i = 0; i < 3; ++i)
        phi[i] = B1[i] + B3[i] * (1.0 / 12.0) + C1[i] * (1.0 / 240.0);
    /* specific force in the body frame at the start: trapezoid of h(t) = R(t) f(t) */
    double h1[3];
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
    double q[4];
    hermite_increments(w0, wd0, f0, w1, wd1, f1, T, phi, dv_b, q);
    return GF_OK;
}

/* What rate_commit changes in a rate state, to undo commits */
typedef struct rate_snapshot {
    double w[3], ref[3], wd[3], wd_prev[3], dt_prev, kf_x[6], kf_P[36];
    uint64_t n_samples;
} rate_snapshot;

static rate_snapshot rate_save(const gf_gfins_state *st)
{
    rate_snapshot s;
    gf_v3_copy(st->omega_rad_s, s.w);
    gf_v3_copy(st->omega_ref_rad_s, s.ref);
    gf_v3_copy(st->omega_dot_rad_s2, s.wd);
    gf_v3_copy(st->omega_dot_prev_rad_s2, s.wd_prev);
    s.dt_prev = st->dt_prev_s;
    memcpy(s.kf_x, st->kf.x, sizeof s.kf_x);
    memcpy(s.kf_P, st->kf.P, sizeof s.kf_P);
    s.n_samples = st->n_samples;
    return s;
}

static void rate_restore(gf_gfins_state *st, const rate_snapshot *s)
{
    gf_v3_copy(s->w, st->omega_rad_s);
    gf_v3_copy(s->ref, st->omega_ref_rad_s);
    gf_v3_copy(s->wd, st->omega_dot_rad_s2);
    gf_v3_copy(s->wd_prev, st->omega_dot_prev_rad_s2);
    st->dt_prev_s = s->dt_prev;
    memcpy(st->kf.x, s->kf_x, sizeof s->kf_x);
    memcpy(st->kf.P, s->kf_P, sizeof s->kf_P);
    st->n_samples = s->n_samples;
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
    if (!gf_sins_state_valid(&st->nav))
        return GF_ERR_BAD_PARAMETER;
    if (!(dt > 0.0 && isfinite(dt)))
        return GF_ERR_BAD_TIME;
    /* In blocks of samples, three passes each: the rate solutions (their own recursion),
     * then the Hermite increments (no recursion: the processor overlaps the samples'
     * dependent chains), then the mechanization (its recursion). The results are those of
     * one sample at a time, bit for bit: the rate commits are replayed from the block's
     * start up to a failed mechanization step, so that an error leaves both states after
     * the last good sample. */
    enum { BLOCK = 32 };
    const size_t ns = st->rate.solver.n_sensors;
    const int hermite = st->integration == GF_GFNAV_HERMITE;
    const int fused = st->rate.cfg.strategy == GF_RATE_FUSED;
    gf_status status = GF_OK;
    size_t k = 0;
    gf_sins_state nav = st->nav;
    while (k < n && status == GF_OK) {
        const size_t m = n - k < BLOCK ? n - k : BLOCK;
        rate_step_result R[BLOCK];
        double wd0[BLOCK][3], phi[BLOCK][3], dv_b[BLOCK][3], q_phi[BLOCK][4];
        const rate_snapshot start = rate_save(&st->rate);
        size_t got = 0;
        for (; got < m; ++got) {
            /* the rate's derivative at the interval's start, less the fused filter's bias */
            gf_v3_copy(st->rate.omega_dot_rad_s2, wd0[got]);
            if (fused)
                gf_v3_sub(wd0[got], st->rate.kf.x + 3, wd0[got]);
            status = rate_step(&st->rate, A + ns * (k + got), dt, R + got);
            if (status != GF_OK)
                break;
            rate_commit(&st->rate, R + got);
        }
        const int had_prev = nav.have_prev;
        if (hermite)
            for (size_t j = had_prev ? 0 : 1; j < got; ++j) {
                const double *w0 = j ? R[j - 1].w : nav.prev_gyro;
                const double *f0 = j ? R[j - 1].f : nav.prev_accel;
                double wd1[3];
                gf_v3_copy(R[j].wd, wd1);
                if (fused)
                    gf_v3_sub(wd1, R[j].kf_x + 3, wd1);
                hermite_increments(w0, wd0[j], f0, R[j].w, wd1, R[j].f, dt, phi[j], dv_b[j],
                                   q_phi[j]);
            }
        size_t j = 0;
        for (; j < got; ++j) {
            const double he = h_ext ? h_ext[k + j] : NAN;
            /* the state was checked at the start of the call (gf_sins_state_valid) and is
             * written only by the mechanization since */
            const gf_status e =
                hermite && (j || had_prev)
                    ? gf_sins_step_compensated_trusted(&nav, phi[j], q_phi[j], dv_b[j], R[j].w,
                                                       R[j].f, dt, he)
                    : gf_sins_step(&nav, R[j].w, R[j].f, dt, he);
            if (e != GF_OK) {
                status = e;
                break;
            }
            memcpy(q_bn + 4 * (k + j), nav.q_bn, sizeof nav.q_bn);
            gf_v3_copy(nav.v_n_m_s, v_n + 3 * (k + j));
            gf_sins_position(&nav, pos + 3 * (k + j));
            if (w_out)
                gf_v3_copy(R[j].w, w_out + 3 * (k + j));
            if (f_out)
                gf_v3_copy(R[j].f, f_out + 3 * (k + j));
            if (flags)
                flags[k + j] = R[j].flags;
        }
        if (j < got) { /* the mechanization refused sample k + j: rates up to k + j - 1 */
            rate_restore(&st->rate, &start);
            for (size_t i = 0; i < j; ++i)
                rate_commit(&st->rate, R + i);
        }
        k += j;
    }
    st->nav = nav;
    if (n_done)
        *n_done = k;
    return status;
}
