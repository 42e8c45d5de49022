/* gf_array_solver.c — the any-array solver; see gf_array_solver.h. */
#include "gyrofree/gf_array_solver.h"

#include <math.h>
#include <string.h>

#include "base/gf_linalg.h"
#include "base/gf_math.h"
#include "gyrofree/gf_gfins_internal.h"

/* index ranges of the groups in x */
static const uint32_t kGroupOf[GF_X_N] = {
    GF_GROUP_F, GF_GROUP_F, GF_GROUP_F,
    GF_GROUP_OMEGA_DOT, GF_GROUP_OMEGA_DOT, GF_GROUP_OMEGA_DOT,
    GF_GROUP_W_DIAG, GF_GROUP_W_DIAG, GF_GROUP_W_DIAG,
    GF_GROUP_W_OFFDIAG, GF_GROUP_W_OFFDIAG, GF_GROUP_W_OFFDIAG};

/* Row of H for one sensor (see gf_array_solver.h). */
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

