/* gf_syscal.c — the system-level calibration filter (seed 001's 36/37 states, the full
 * lever-arm model's 39/40); equations in gf_syscal.h. */
#include "est/gf_syscal.h"

#include <math.h>
#include <string.h>

#include "base/gf_linalg.h"
#include "base/gf_math.h"
#include "est/gf_ins_model.h"
#include "nav/gf_earth.h"

#define NMAX GF_SYSCAL_MAX_STATES
#define SP GF_PADDED(NMAX)                    /* padded row stride of F and A */
#define TIME_EPS_S 1e-9                       /* intervals closer than this are reached */
#define LAT_MAX_RAD (89.0 * GF_PI / 180.0)
#define MAX_DELAY_S 1.0                       /* |accelerometer delay| estimates beyond: absurd */
#define MAX_GRAVITY_ANOMALY_M_S2 0.1          /* 10 000 ugal... 10 000 ug: beyond any site */

static int is_full(int32_t n) { return n == GF_SYSCAL_N_FULL || n == GF_SYSCAL_MAX_STATES; }
static int has_delay(int32_t n) { return n == GF_SYSCAL_N_BASE + 1 || n == GF_SYSCAL_MAX_STATES; }
static int n_valid(int32_t n)
{
    return n == GF_SYSCAL_N_BASE || n == GF_SYSCAL_N_BASE + 1 || n == GF_SYSCAL_N_FULL ||
           n == GF_SYSCAL_MAX_STATES;
}

int32_t gf_syscal_param_index(int32_t n, int32_t k)
{
    if (!n_valid(n) || k < GF_SYSCAL_IDX_KG || k >= n)
        return -1;
    if (has_delay(n) && k == n - 1)
        return GF_SYSCAL_P_DELAY;
    if (k < GF_SYSCAL_IDX_R)
        return k - GF_SYSCAL_IDX_KG;
    const int32_t j = k - GF_SYSCAL_IDX_R;          /* 0..2 seed, 0..5 full */
    return is_full(n) ? GF_SYSCAL_P_LEVER + j : GF_SYSCAL_P_LEVER + 4 * j;
}

gf_status gf_syscal_config_default(gf_syscal_config *cfg)
{
    if (!cfg)
        return GF_ERR_NULL_POINTER;
    memset(cfg, 0, sizeof *cfg);
    cfg->n_states = GF_SYSCAL_N_BASE;
    cfg->prop_interval_s = 0.1;
    cfg->update_interval_s = 1.0;
    cfg->vel_std_m_s = 1e-3;
    cfg->max_rate_rad_s = 50.0;
    cfg->max_specific_force_m_s2 = 1000.0;
    cfg->max_gap_s = 0.5;
    cfg->feedback_params = 1;
    return GF_OK;
}

gf_status gf_syscal_errors(const double *p, gf_imu_errors *e)
{
    if (!p || !e)
        return GF_ERR_NULL_POINTER;
    if (!gf_all_finite(p, GF_SYSCAL_N_PARAMS))
        return GF_ERR_NONFINITE_INPUT;
    gf_imu_errors out;
    memset(&out, 0, sizeof out);
    const double *g = p, *a = p + (GF_SYSCAL_IDX_KA - GF_SYSCAL_IDX_KG);
    for (int i = 0; i < 3; ++i) {
        out.g_scale[i] = g[i];
        out.g_bias_rad_s[i] = g[6 + i];
        out.a_scale[i] = a[i];
        out.a_bias_m_s2[i] = a[9 + i];
        out.a_k2_s2_m[i] = p[GF_SYSCAL_IDX_KA2 - GF_SYSCAL_IDX_KG + i];
    }
    memcpy(out.a_lever_pos_m, p + GF_SYSCAL_P_LEVER, sizeof out.a_lever_pos_m);
    out.a_delay_s = p[GF_SYSCAL_P_DELAY];
    /* seed 001 S107: gamma_yz, gamma_zy, gamma_zx (gfins_fmi.imu_errors.seed001_gyro_misalignment) */
    out.g_misalign_rad[3] = -g[3];
    out.g_misalign_rad[6] = g[4];
    out.g_misalign_rad[7] = -g[5];
    /* S108: alpha_xz, xy, yz, yx, zy, zx (seed001_accel_misalignment) */
    out.a_misalign_rad[1] = a[3];
    out.a_misalign_rad[2] = -a[4];
    out.a_misalign_rad[3] = -a[5];
    out.a_misalign_rad[5] = a[6];
    out.a_misalign_rad[6] = a[7];
    out.a_misalign_rad[7] = -a[8];
    if (gf_imu_errors_check(&out, NULL) != GF_OK)
        return GF_ERR_BAD_PARAMETER;
    *e = out;
    return GF_OK;
}

/* the compensation the filter applies sample by sample: the model without the delay
 * (compensated by the filter itself with the rate relative to the navigation frame) */
static gf_status build_comp(const double *p, gf_imu_errors *e)
{
    const gf_status st = gf_syscal_errors(p, e);
    if (st == GF_OK)
        e->a_delay_s = 0.0;
    return st;
}

static int config_check(const gf_syscal_config *c)
{
    if (!n_valid(c->n_states))
        return GF_SYSCAL_BAD_N_STATES;
    if (!(fabs(c->lat_rad) < LAT_MAX_RAD) || !isfinite(c->lon_rad) || !(c->h_m >= -1000.0) ||
        !(c->h_m <= 1e5) || !(fabs(c->gravity_anomaly_m_s2) < MAX_GRAVITY_ANOMALY_M_S2))
        return GF_SYSCAL_BAD_SITE;
    if (!(c->prop_interval_s > 0.0) || !isfinite(c->prop_interval_s) ||
        !(c->update_interval_s > 0.0) || !isfinite(c->update_interval_s))
        return GF_SYSCAL_BAD_INTERVALS;
    if (!(c->vel_std_m_s > 0.0) || !isfinite(c->vel_std_m_s))
        return GF_SYSCAL_BAD_VEL_STD;
    if (!(c->gyro_arw_rad_sqrt_s >= 0.0) || !isfinite(c->gyro_arw_rad_sqrt_s) ||
        !(c->accel_vrw_m_s_sqrt_s >= 0.0) || !isfinite(c->accel_vrw_m_s_sqrt_s))
        return GF_SYSCAL_BAD_NOISE;
    /* a variance that is a normal double; attitude errors within the small-angle model
     * (found by fuzzing: a 1e6 rad attitude prior beside a 5e-324 one lost positivity) */
    for (int i = 0; i < c->n_states; ++i)
        if (!(c->p0_std[i] >= 1e-150 && c->p0_std[i] <= 1e150) ||
            (i < GF_SYSCAL_IDX_DV && !(c->p0_std[i] <= 1.0)))
            return GF_SYSCAL_BAD_P0;
    if (!(c->max_rate_rad_s > 0.0) || !isfinite(c->max_rate_rad_s) ||
        !(c->max_specific_force_m_s2 > 0.0) || !isfinite(c->max_specific_force_m_s2) ||
        !(c->max_gap_s > 0.0) || !isfinite(c->max_gap_s))
        return GF_SYSCAL_BAD_LIMITS;
    if (c->feedback_params != 0 && c->feedback_params != 1)
        return GF_SYSCAL_BAD_FEEDBACK;
    return 0;
}

static void reset_accumulators(gf_syscal *s)
{
    s->acc_T_s = 0.0;
    memset(s->acc_w, 0, sizeof s->acc_w);
    memset(s->acc_f, 0, sizeof s->acc_f);
    memset(s->acc_f2, 0, sizeof s->acc_f2);
    memset(s->acc_c, 0, sizeof s->acc_c);
    memset(s->acc_fdot, 0, sizeof s->acc_fdot);
    memset(s->acc_wxy, 0, sizeof s->acc_wxy);
    memset(s->acc_wdot, 0, sizeof s->acc_wdot);
    memcpy(s->acc_q0, s->nav.q_bn, sizeof s->acc_q0);
}

gf_status gf_syscal_init(gf_syscal *s, const gf_syscal_config *cfg, const double *q_mn0,
                         const double *param0, double t0_s, int *bad)
{
    if (bad)
        *bad = 0;
    if (!s || !cfg || !q_mn0)
        return GF_ERR_NULL_POINTER;
    if (!gf_all_finite(q_mn0, 4) || !isfinite(t0_s) || (param0 && !gf_all_finite(param0, GF_SYSCAL_N_PARAMS)))
        return GF_ERR_NONFINITE_INPUT;
    int which = config_check(cfg);
    gf_syscal f;
    memset(&f, 0, sizeof f);
    f.cfg = *cfg;
    if (!which && param0) {
        memcpy(f.param, param0, sizeof f.param);
        if (!(fabs(param0[GF_SYSCAL_P_DELAY]) < MAX_DELAY_S))
            which = GF_SYSCAL_BAD_PARAM0;
    }
    if (!which && build_comp(f.param, &f.comp) != GF_OK)
        which = GF_SYSCAL_BAD_PARAM0;
    if (which) {
        if (bad)
            *bad = which;
        return GF_ERR_BAD_PARAMETER;
    }
    gf_sins_config sc;
    gf_sins_config_default(&sc);
    sc.input = GF_SINS_INPUT_INCREMENTS;
    sc.coning = 1;
    sc.vertical = GF_SINS_VERTICAL_FREE; /* the zero-velocity updates hold it */
    sc.max_rate_rad_s = cfg->max_rate_rad_s;
    sc.max_specific_force_m_s2 = cfg->max_specific_force_m_s2;
    const double v0[3] = {0.0, 0.0, 0.0};
    gf_status st = gf_sins_init(&f.nav, &sc, q_mn0, v0, cfg->lat_rad, cfg->lon_rad, cfg->h_m, t0_s);
    if (st != GF_OK) {
        if (bad)
            *bad = GF_SYSCAL_BAD_SITE;
        return st;
    }
    const size_t n = (size_t)cfg->n_states;
    double x0[NMAX] = {0.0}, P0[NMAX * NMAX] = {0.0};
    for (size_t i = 0; i < n; ++i)
        P0[i * n + i] = cfg->p0_std[i] * cfg->p0_std[i];
    st = gf_kalman_init(&f.kf, n, x0, P0);
    if (st != GF_OK)
        return st;
    f.t_s = t0_s;
    reset_accumulators(&f);
    *s = f;
    return GF_OK;
}

/* column v (IMU axes) of a sensor error into F: rows r0..r0+2 get sign C v */
static void put_col(double *F, size_t ld, size_t r0, size_t k, const gf_mat3 *C,
                    const double v[3], double sign)
{
    double t[3];
    gf_m3_mul_v3(C, v, t);
    for (size_t i = 0; i < 3; ++i)
        F[(r0 + i) * ld + k] = sign * t[i];
}

/* W = [w_dot x] + w w^T - |w|^2 I from the means: entry (i, j) (gf_syscal.h) */
static double lever_W(const double c[3], const double wxy[3], const double wd[3], int i, int j)
{
    if (i == j)
        return -c[i];
    const int k = i + j - 1;                    /* (0,1) -> xy, (0,2) -> xz, (1,2) -> yz */
    /* [a x]_ij: (0,1) -a_z, (0,2) a_y, (1,0) a_z, (1,2) -a_x, (2,0) -a_y, (2,1) a_x */
    static const int comp[3][3] = {{0, 2, 1}, {2, 0, 0}, {1, 0, 0}};
    static const double sign[3][3] = {{0, -1, 1}, {1, 0, -1}, {-1, 1, 0}};
    return wxy[k] + sign[i][j] * wd[comp[i][j]];
}

/* F (continuous time) with the means w, w_dot, f, f o f, c(w), w_i w_j (xy, xz, yz) and
 * the rotation part of df/dt over an interval, C = C_m^n; F zeroed by the caller, rows
 * of stride ld. */
static void build_F(const gf_syscal *s, const gf_mat3 *C, const double w[3], const double wdot[3],
                    const double f[3], const double f2[3], const double c[3], const double wxy[3],
                    const double fdot[3], size_t ld, double *F)
{
    const size_t n = (size_t)s->cfg.n_states;
    gf_ins_nav_blocks(C, s->nav.v_n_m_s, s->nav.lat_rad, s->nav.h_m, f, ld, GF_SYSCAL_IDX_PHI,
                      GF_SYSCAL_IDX_DV, GF_SYSCAL_IDX_DP, F);
    /* gyro: phi' += -C dw, dw = dK_g w + eps */
    const size_t IA = GF_SYSCAL_IDX_PHI, IV = GF_SYSCAL_IDX_DV;
    for (int i = 0; i < 3; ++i) {
        double e[3] = {0.0, 0.0, 0.0};
        e[i] = w[i];
        put_col(F, ld, IA, GF_SYSCAL_IDX_KG + (size_t)i, C, e, -1.0);
        e[i] = 1.0;
        put_col(F, ld, IA, GF_SYSCAL_IDX_EPS + (size_t)i, C, e, -1.0);
    }
    {
        const double gyz[3] = {0.0, -w[0], 0.0}, gzy[3] = {0.0, 0.0, w[0]}, gzx[3] = {0.0, 0.0, -w[1]};
        put_col(F, ld, IA, GF_SYSCAL_IDX_GAMMA + 0, C, gyz, -1.0);
        put_col(F, ld, IA, GF_SYSCAL_IDX_GAMMA + 1, C, gzy, -1.0);
        put_col(F, ld, IA, GF_SYSCAL_IDX_GAMMA + 2, C, gzx, -1.0);
    }
    /* accelerometer: dv' += C df, df = dK_a f + dK_a2 f^2 + nabla + [W_i . dr_i] - dt_a df/dt */
    for (int i = 0; i < 3; ++i) {
        double e[3] = {0.0, 0.0, 0.0};
        e[i] = f[i];
        put_col(F, ld, IV, GF_SYSCAL_IDX_KA + (size_t)i, C, e, 1.0);
        e[i] = 1.0;
        put_col(F, ld, IV, GF_SYSCAL_IDX_NABLA + (size_t)i, C, e, 1.0);
        e[i] = f2[i];
        put_col(F, ld, IV, GF_SYSCAL_IDX_KA2 + (size_t)i, C, e, 1.0);
        if (!is_full(s->cfg.n_states)) {           /* seed: r_ii, W_ii = -c_i */
            e[i] = -c[i];
            put_col(F, ld, IV, GF_SYSCAL_IDX_R + (size_t)i, C, e, 1.0);
        }
    }
    if (is_full(s->cfg.n_states))                  /* full: rows x and y of the positions */
        for (int acc = 0; acc < 2; ++acc)
            for (int j = 0; j < 3; ++j) {
                double e[3] = {0.0, 0.0, 0.0};
                e[acc] = lever_W(c, wxy, wdot, acc, j);
                put_col(F, ld, IV, GF_SYSCAL_IDX_R + (size_t)(3 * acc + j), C, e, 1.0);
            }
    {
        const double axz[3] = {f[1], 0.0, 0.0}, axy[3] = {-f[2], 0.0, 0.0};
        const double ayz[3] = {0.0, -f[0], 0.0}, ayx[3] = {0.0, f[2], 0.0};
        const double azy[3] = {0.0, 0.0, f[0]}, azx[3] = {0.0, 0.0, -f[1]};
        const double *cols[6] = {axz, axy, ayz, ayx, azy, azx};
        for (size_t j = 0; j < 6; ++j)
            put_col(F, ld, IV, GF_SYSCAL_IDX_ALPHA + j, C, cols[j], 1.0);
    }
    if (has_delay(s->cfg.n_states))
        put_col(F, ld, IV, n - 1, C, fdot, -1.0);
}

static gf_status propagate(gf_syscal *s)
{
    const size_t n = (size_t)s->cfg.n_states;
    const double T = s->acc_T_s;
    double w[3], f[3], f2[3], c[3], fdot[3], wxy[3], wdot[3], g;
    if (gf_earth_gravity(s->nav.lat_rad, s->nav.h_m, &g) != GF_OK)
        return GF_ERR_DIVERGED;
    g += s->cfg.gravity_anomaly_m_s2;              /* the site's (gf_syscal.h) */
    for (int i = 0; i < 3; ++i) {
        w[i] = s->acc_w[i] / T;
        f[i] = g * s->acc_f[i] / T;                /* accumulated in units of g (sample()) */
        f2[i] = g * g * s->acc_f2[i] / T;
        c[i] = s->acc_c[i] / T;
        fdot[i] = g * s->acc_fdot[i] / T;
        wxy[i] = s->acc_wxy[i] / T;
        wdot[i] = s->acc_wdot[i] / T;
    }
    /* C_m^n at the interval's mid-point */
    double qm[4];
    const double *q0 = s->acc_q0, *q1 = s->nav.q_bn;
    const double sg = q0[0] * q1[0] + q0[1] * q1[1] + q0[2] * q1[2] + q0[3] * q1[3] < 0.0 ? -1.0 : 1.0;
    for (int i = 0; i < 4; ++i)
        qm[i] = q0[i] + sg * q1[i];
    if (!gf_q_normalize(qm, qm))
        return GF_ERR_DIVERGED;
    gf_mat3 C;
    gf_q_to_dcm(qm, &C);
    const size_t ld = SP;
    double F[NMAX * SP];
    memset(F, 0, sizeof F);
    build_F(s, &C, w, wdot, f, f2, c, wxy, fdot, ld, F);
    /* A = F T + (F T)^2 / 2 in padded rows */
    double A[NMAX * SP];
    for (size_t i = 0; i < n * ld; ++i)
        A[i] = F[i] * T;
    const double h2 = 0.5 * T * T;
    for (size_t i = 0; i < n; ++i)
        for (size_t k = 0; k < n; ++k) {
            const double fik = F[i * ld + k];
            if (fik != 0.0)
                gf_axpy4(ld, h2 * fik, F + k * ld, A + i * ld);
        }
    size_t start[NMAX + 1], nnz = 0;
    unsigned char col[NMAX * NMAX];
    double val[NMAX * NMAX];
    for (size_t i = 0; i < n; ++i) {
        start[i] = nnz;
        for (size_t j = 0; j < n; ++j) {
            const double a = A[i * ld + j];
            if (a != 0.0) {
                col[nnz] = (unsigned char)j;
                val[nnz++] = a;
            }
        }
    }
    start[n] = nnz;
    if (!s->cfg.feedback_params) {   /* x <- Phi x: the parameter states drive the navigation's */
        double xn[NMAX];
        for (size_t i = 0; i < n; ++i) {
            double acc = s->kf.x[i];
            for (size_t k = start[i]; k < start[i + 1]; ++k)
                acc += val[k] * s->kf.x[col[k]];
            xn[i] = acc;
        }
        memcpy(s->kf.x, xn, n * sizeof *xn);
    }
    double qh[NMAX] = {0.0};
    const double qa = 0.5 * T * s->cfg.gyro_arw_rad_sqrt_s * s->cfg.gyro_arw_rad_sqrt_s;
    const double qv = 0.5 * T * s->cfg.accel_vrw_m_s_sqrt_s * s->cfg.accel_vrw_m_s_sqrt_s;
    for (size_t i = 0; i < 3; ++i) {
        qh[GF_SYSCAL_IDX_PHI + i] = qa;
        qh[GF_SYSCAL_IDX_DV + i] = qv;
    }
    const gf_status st = gf_kalman_predict_csr(&s->kf, start, col, val, qh, qh);
    if (st != GF_OK)
        return GF_ERR_DIVERGED;
    for (size_t i = 0; i < n; ++i) {
        const double p = s->kf.P[i * n + i];
        if (!(p > 0.0) || !isfinite(p))
            return GF_ERR_DIVERGED;
    }
    return GF_OK;
}

static gf_status update(gf_syscal *s, gf_syscal_epoch *ep)
{
    const size_t n = (size_t)s->cfg.n_states;
    double H[3 * NMAX] = {0.0}, R[9] = {0.0}, r[3];
    const double var = s->cfg.vel_std_m_s * s->cfg.vel_std_m_s;
    for (size_t i = 0; i < 3; ++i) {
        H[i * n + GF_SYSCAL_IDX_DV + i] = 1.0;
        R[4 * i] = var;
        /* z - H x with z = v^n - v_true (0) and H x = dv: 0 when the filter feeds every
         * state back; the parameter states' effect otherwise */
        r[i] = s->nav.v_n_m_s[i] - s->kf.x[GF_SYSCAL_IDX_DV + i];
    }
    double nis = 0.0;
    int accepted = 0;
    const gf_kalman before = s->kf;
    gf_status st = gf_kalman_update_gated(&s->kf, 3, r, H, R, 0.0, &nis, &accepted);
    if (st != GF_OK)
        return GF_ERR_DIVERGED;
    for (size_t i = 0; i < n; ++i)   /* the covariance kept its positive diagonal */
        if (!(s->kf.P[i * n + i] > 0.0) || !isfinite(s->kf.P[i * n + i]))
            return GF_ERR_DIVERGED;
    const double *x = s->kf.x;
    double p[GF_SYSCAL_N_PARAMS];
    memcpy(p, s->param, sizeof p);
    for (size_t k = GF_SYSCAL_IDX_KG; k < n; ++k)
        p[gf_syscal_param_index(s->cfg.n_states, (int32_t)k)] += x[k];
    gf_imu_errors e;
    const int refused = build_comp(p, &e) != GF_OK || !(fabs(p[GF_SYSCAL_P_DELAY]) < MAX_DELAY_S);
    if (refused) {
        /* the update would take the estimates outside the error model (e.g. a lever arm
         * beyond 1 m): the linearised filter is outside its validity, typically because the
         * model lacks a term the data hold. The update is refused (the filter as before it)
         * and counted; the caller reports it. */
        s->kf = before;
        s->n_refused++;
    } else {
        /* feedback (S304) */
        double qphi[4], q[4], v[3];
        gf_q_from_rotvec(x + GF_SYSCAL_IDX_PHI, qphi);
        gf_q_mul(qphi, s->nav.q_bn, q);
        for (int i = 0; i < 3; ++i)
            v[i] = s->nav.v_n_m_s[i] - x[GF_SYSCAL_IDX_DV + i];
        st = gf_sins_set_navigation(&s->nav, q, v, s->nav.lat_rad - x[GF_SYSCAL_IDX_DP],
                                    s->nav.lon_rad - x[GF_SYSCAL_IDX_DP + 1],
                                    s->nav.h_m - x[GF_SYSCAL_IDX_DP + 2]);
        if (st != GF_OK)
            return GF_ERR_DIVERGED;
        if (s->cfg.feedback_params) {
            memcpy(s->param, p, sizeof p);
            s->comp = e;
            memset(s->kf.x, 0, sizeof s->kf.x);
        } else {
            memset(s->kf.x, 0, GF_SYSCAL_IDX_KG * sizeof *s->kf.x);   /* the navigation's only */
        }
    }
    s->n_updates++;
    if (ep) {
        ep->t_s = s->t_s;
        gf_syscal_estimate(s, ep->param);
        for (size_t i = 0; i < NMAX; ++i)
            ep->std[i] = i < n ? sqrt(s->kf.P[i * n + i]) : 0.0;
        memcpy(ep->residual_m_s, r, sizeof r);
        ep->nis = nis;
        ep->refused = refused ? 1.0 : 0.0;
    }
    return GF_OK;
}

/* One raw sample's compensation at the navigation state nav (gf_syscal_compensate): the
 * error model comp (w_dot from w_prev, NULL: 0), the delay d with the rate relative to
 * the navigation frame, the gravity anomaly dg. Also the angular acceleration wd and the
 * rotation part of df/dt fdot, for the propagation. */
static gf_status compensate_one(const gf_imu_errors *comp, double d, double dg,
                                const gf_sins_state *nav, const double dth[3], const double dv[3],
                                double T, const double *w_prev, double w[3], double wd[3],
                                double f[3], double fdot[3])
{
    double w_raw[3], f_raw[3];
    gf_v3_scale(dth, 1.0 / T, w_raw);
    gf_v3_scale(dv, 1.0 / T, f_raw);
    if (gf_imu_compensate_step(comp, w_raw, f_raw, NULL, w_prev, T, w, f) != GF_OK)
        return GF_ERR_DIVERGED;
    for (int i = 0; i < 3; ++i)
        wd[i] = w_prev ? (w[i] - w_prev[i]) / T : 0.0;
    /* accelerometer delay: f(t) = f(t - d) - d (w_nm x f) */
    const double W = GF_WGS84_OMEGA_IE_RAD_S;
    const double wie_n[3] = {0.0, W * nav->cos_lat, W * nav->sin_lat};
    double qc[4], wie_m[3], wnm[3];
    gf_q_conj(nav->q_bn, qc);
    gf_q_rotate(qc, wie_n, wie_m);
    gf_v3_sub(w, wie_m, wnm);
    gf_v3_cross(wnm, f, fdot);
    gf_v3_scale(fdot, -1.0, fdot); /* rotation part of df^m/dt */
    gf_v3_axpy(f, d, fdot, f);
    if (dg != 0.0) {               /* the site's gravity: f -= dg C_n^m e_U */
        const double up_n[3] = {0.0, 0.0, 1.0};
        double up_m[3];
        gf_q_rotate(qc, up_n, up_m);
        gf_v3_axpy(f, -dg, up_m, f);
    }
    return GF_OK;
}

/* one raw sample over the interval ending at t (s). A refused sample (non-finite, time,
 * range) changes nothing; a divergence (propagation or update) leaves the filter where it
 * failed (it is then not usable). */
static gf_status sample(gf_syscal *s, double t, const double dth[3], const double dv[3],
                        gf_syscal_epoch *epochs, size_t capacity, size_t *n_epochs)
{
    const double T = t - s->t_s;
    if (!isfinite(t) || !gf_all_finite(dth, 3) || !gf_all_finite(dv, 3))
        return GF_ERR_NONFINITE_INPUT;
    if (!(T > 0.0) || !(T <= s->cfg.max_gap_s))
        return GF_ERR_BAD_TIME;
    double w_raw[3], f_raw[3], w[3], f[3], wd[3], fdot[3];
    (void)fdot;
    gf_v3_scale(dth, 1.0 / T, w_raw);
    gf_v3_scale(dv, 1.0 / T, f_raw);
    if (!(gf_v3_norm(w_raw) <= s->cfg.max_rate_rad_s) ||
        !(gf_v3_norm(f_raw) <= s->cfg.max_specific_force_m_s2))
        return GF_ERR_OUT_OF_RANGE;
    gf_status st = compensate_one(&s->comp, s->param[GF_SYSCAL_P_DELAY], s->cfg.gravity_anomaly_m_s2,
                                  &s->nav, dth, dv, T, s->have_prev ? s->w_prev : NULL, w, wd, f, fdot);
    if (st != GF_OK)
        return st;
    double dth_c[3], dv_c[3], c1[3], c2[3];
    gf_v3_scale(w, T, dth_c);
    gf_v3_scale(f, T, dv_c);
    /* the second-order rotation term the two-sample velocity update of gf_sins leaves out:
     * for a constant rate over the sample it computes dv (I - [dth x]^2 / 6) of the exact
     * change (a turn at w over T overstates the specific force along it by (w T)^2 / 6;
     * docs/rotating_ins.md, "Sample rate"); added here so that a calibration at 100 Hz does
     * not carry it into the parameters */
    gf_v3_cross(dth_c, dv_c, c1);
    gf_v3_cross(dth_c, c1, c2);
    gf_v3_axpy(dv_c, 1.0 / 6.0, c2, dv_c);
    gf_sins_state nav = s->nav;
    st = gf_sins_step_trusted(&nav, dth_c, dv_c, T);
    if (st != GF_OK)
        return st == GF_ERR_OUT_OF_RANGE ? st : GF_ERR_DIVERGED;
    s->nav = nav;
    memcpy(s->w_prev, w, sizeof s->w_prev);
    s->have_prev = 1;
    /* the error model's specific force: that of a body at rest on the base, g C_n^m e_U (in
     * units of g here; propagate() scales it), not the measured one: the accelerometers'
     * white noise in F would make, e.g., a horizontal axis's scale factor look observed
     * from the correlation of its noise with the velocity it drives (an over-confident
     * filter once the priors are wide; docs/rotating_ins.md) */
    const double W = GF_WGS84_OMEGA_IE_RAD_S, e_up[3] = {0.0, 0.0, 1.0};
    const double wie_n[3] = {0.0, W * s->nav.cos_lat, W * s->nav.sin_lat};
    double qc[4], up[3], wie_m[3], wnm[3], updot[3];
    gf_q_conj(s->nav.q_bn, qc);
    gf_q_rotate(qc, e_up, up);
    gf_q_rotate(qc, wie_n, wie_m);
    gf_v3_sub(w, wie_m, wnm);
    gf_v3_cross(wnm, up, updot);
    const double cw[3] = {w[1] * w[1] + w[2] * w[2], w[0] * w[0] + w[2] * w[2], w[0] * w[0] + w[1] * w[1]};
    const double wxy[3] = {w[0] * w[1], w[0] * w[2], w[1] * w[2]};
    for (int i = 0; i < 3; ++i) {
        s->acc_w[i] += w[i] * T;
        s->acc_f[i] += up[i] * T;
        s->acc_f2[i] += up[i] * up[i] * T;
        s->acc_c[i] += cw[i] * T;
        s->acc_fdot[i] -= updot[i] * T;
        s->acc_wxy[i] += wxy[i] * T;
        s->acc_wdot[i] += wd[i] * T;
    }
    s->acc_T_s += T;
    s->since_update_s += T;
    s->t_s = t;
    s->n_samples++;
    if (s->acc_T_s >= s->cfg.prop_interval_s - TIME_EPS_S) {
        st = propagate(s);
        if (st != GF_OK)
            return st;
        if (s->since_update_s >= s->cfg.update_interval_s - TIME_EPS_S) {
            gf_syscal_epoch *ep = epochs && *n_epochs < capacity ? epochs + *n_epochs : NULL;
            st = update(s, ep);
            if (st != GF_OK)
                return st;
            if (ep)
                ++*n_epochs;
            s->since_update_s = 0.0;
        }
        reset_accumulators(s);
    }
    return GF_OK;
}

static int sizes_valid(const gf_syscal *s)
{
    return n_valid(s->cfg.n_states) && s->kf.n == (size_t)s->cfg.n_states;
}

gf_status gf_syscal_run(gf_syscal *s, size_t n, const double *t_s, const double *dtheta_rad,
                        const double *dv_m_s, gf_syscal_epoch *epochs, size_t capacity,
                        size_t *n_epochs, size_t *n_done)
{
    size_t ne = 0;
    if (n_done)
        *n_done = 0;
    if (n_epochs)
        *n_epochs = 0;
    if (!s || (n && (!t_s || !dtheta_rad || !dv_m_s)))
        return GF_ERR_NULL_POINTER;
    if (!sizes_valid(s))
        return GF_ERR_BAD_SIZE;
    for (size_t k = 0; k < n; ++k) {
        const gf_status st = sample(s, t_s[k], dtheta_rad + 3 * k, dv_m_s + 3 * k, epochs,
                                    capacity, &ne);
        if (st != GF_OK) {
            if (n_epochs)
                *n_epochs = ne;
            return st;
        }
        if (n_done)
            *n_done = k + 1;
    }
    if (n_epochs)
        *n_epochs = ne;
    return GF_OK;
}

gf_status gf_syscal_estimate(const gf_syscal *s, double *param)
{
    if (!s || !param)
        return GF_ERR_NULL_POINTER;
    if (!sizes_valid(s))
        return GF_ERR_BAD_SIZE;
    memcpy(param, s->param, GF_SYSCAL_N_PARAMS * sizeof *param);
    for (int32_t k = GF_SYSCAL_IDX_KG; k < s->cfg.n_states; ++k)
        param[gf_syscal_param_index(s->cfg.n_states, k)] += s->kf.x[k];
    return GF_OK;
}

gf_status gf_syscal_covariance(const gf_syscal *s, double *P, double *std)
{
    if (!s)
        return GF_ERR_NULL_POINTER;
    if (!sizes_valid(s))
        return GF_ERR_BAD_SIZE;
    const size_t n = (size_t)s->cfg.n_states;
    if (P)
        memcpy(P, s->kf.P, n * n * sizeof *P);
    if (std)
        for (size_t i = 0; i < n; ++i)
            std[i] = sqrt(s->kf.P[i * n + i]);
    return GF_OK;
}

gf_status gf_syscal_check(const gf_syscal *s)
{
    if (!s)
        return GF_ERR_NULL_POINTER;
    if (!sizes_valid(s))
        return GF_ERR_BAD_SIZE;
    if (config_check(&s->cfg))
        return GF_ERR_BAD_PARAMETER;
    gf_status st = gf_kalman_check(&s->kf);
    if (st != GF_OK)
        return st;
    st = gf_sins_state_check(&s->nav);
    if (st != GF_OK)
        return st;
    const double acc[] = {s->t_s, s->acc_T_s, s->since_update_s};
    if (!gf_all_finite(s->param, GF_SYSCAL_N_PARAMS) || !gf_all_finite(acc, 3) ||
        !gf_all_finite(s->acc_w, 3) || !gf_all_finite(s->acc_f, 3) ||
        !gf_all_finite(s->acc_f2, 3) || !gf_all_finite(s->acc_c, 3) ||
        !gf_all_finite(s->acc_fdot, 3) || !gf_all_finite(s->acc_q0, 4) ||
        !gf_all_finite(s->acc_wxy, 3) || !gf_all_finite(s->acc_wdot, 3) ||
        !gf_all_finite(s->w_prev, 3))
        return GF_ERR_NONFINITE_INPUT;
    if (s->have_prev != 0 && s->have_prev != 1)
        return GF_ERR_BAD_PARAMETER;
    gf_imu_errors e;
    if (build_comp(s->param, &e) != GF_OK || memcmp(&e, &s->comp, sizeof e) != 0)
        return GF_ERR_BAD_PARAMETER;
    return GF_OK;
}

gf_status gf_syscal_compensate(const gf_syscal *s, const double *param, const double *dtheta_rad,
                               const double *dv_m_s, double dt_s, const double *w_prev,
                               double *w_m, double *f_m)
{
    if (!s || !dtheta_rad || !dv_m_s || !w_m || !f_m)
        return GF_ERR_NULL_POINTER;
    if (!sizes_valid(s))
        return GF_ERR_BAD_SIZE;
    if (!gf_all_finite(dtheta_rad, 3) || !gf_all_finite(dv_m_s, 3) || !isfinite(dt_s) ||
        (w_prev && !gf_all_finite(w_prev, 3)) || (param && !gf_all_finite(param, GF_SYSCAL_N_PARAMS)))
        return GF_ERR_NONFINITE_INPUT;
    if (!(dt_s > 0.0))
        return GF_ERR_BAD_TIME;
    gf_imu_errors comp = s->comp;
    double d = s->param[GF_SYSCAL_P_DELAY];
    if (param) {
        if (build_comp(param, &comp) != GF_OK)
            return GF_ERR_BAD_PARAMETER;
        d = param[GF_SYSCAL_P_DELAY];
    }
    double w[3], wd[3], f[3], fdot[3];
    const gf_status st = compensate_one(&comp, d, s->cfg.gravity_anomaly_m_s2, &s->nav, dtheta_rad,
                                        dv_m_s, dt_s, w_prev, w, wd, f, fdot);
    if (st != GF_OK)
        return GF_ERR_OUT_OF_RANGE;
    gf_v3_copy(w, w_m);
    gf_v3_copy(f, f_m);
    return GF_OK;
}

gf_status gf_syscal_error_model(const gf_syscal *s, const double *w_m, const double *w_dot_m,
                                const double *f_m, double *F, double *H)
{
    if (!s || !w_m || !w_dot_m || !f_m)
        return GF_ERR_NULL_POINTER;
    if (!sizes_valid(s))
        return GF_ERR_BAD_SIZE;
    if (!gf_all_finite(w_m, 3) || !gf_all_finite(w_dot_m, 3) || !gf_all_finite(f_m, 3))
        return GF_ERR_NONFINITE_INPUT;
    const size_t n = (size_t)s->cfg.n_states;
    const double *w = w_m, *f = f_m;
    const double f2[3] = {f[0] * f[0], f[1] * f[1], f[2] * f[2]};
    const double c[3] = {w[1] * w[1] + w[2] * w[2], w[0] * w[0] + w[2] * w[2], w[0] * w[0] + w[1] * w[1]};
    const double wxy[3] = {w[0] * w[1], w[0] * w[2], w[1] * w[2]};
    const double W = GF_WGS84_OMEGA_IE_RAD_S;
    const double wie_n[3] = {0.0, W * s->nav.cos_lat, W * s->nav.sin_lat};
    double qc[4], wie_m[3], wnm[3], fdot[3];
    gf_q_conj(s->nav.q_bn, qc);
    gf_q_rotate(qc, wie_n, wie_m);
    gf_v3_sub(w, wie_m, wnm);
    gf_v3_cross(wnm, f, fdot);
    gf_v3_scale(fdot, -1.0, fdot);
    if (F) {
        gf_mat3 C;
        gf_q_to_dcm(s->nav.q_bn, &C);
        memset(F, 0, n * n * sizeof *F);
        build_F(s, &C, w, w_dot_m, f, f2, c, wxy, fdot, n, F);
    }
    if (H) {
        memset(H, 0, 3 * n * sizeof *H);
        for (size_t i = 0; i < 3; ++i)
            H[i * n + GF_SYSCAL_IDX_DV + i] = 1.0;
    }
    return GF_OK;
}
