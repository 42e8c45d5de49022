/* gf_ins_propagate.c — the INS/GNSS filter's error model (F, G, q) and its covariance
 * propagation over the accumulated interval: EKF (structured Phi) or UKF (sigma points
 * through the mechanization); see gf_ins_gnss.h. */
#include "est/gf_ins_gnss.h"

#include <math.h>
#include <string.h>

#include "base/gf_linalg.h"
#include "base/gf_math.h"
#include "est/gf_ins_internal.h"
#include "est/gf_ins_model.h"
#include "est/gf_kalman.h"
#include "nav/gf_sins.h"

/* propagation intervals up to this use Phi = I + F T (see gf_ins_gnss.h) */
#define GF_INS_FIRST_ORDER_MAX_T_S 0.02

/* ---- error model (see gf_ins_gnss.h) ----------------------------------------------- */

static double gm_rate(double tau_s)
{
    return tau_s > 0.0 ? -1.0 / tau_s : 0.0;
}

static double gm_intensity(double std, double tau_s)
{
    return tau_s > 0.0 ? 2.0 * std * std / tau_s : 0.0;
}

/* the flexure's b = 2.146 / tau (1/s) */
static double flexure_beta(const gf_ins_filter *f)
{
    return GF_INS_FLEX_BETA_TAU / f->cfg.noise.flexure_tau_s;
}

/* the diagonal of Qc = G diag(q) G^T (the white noises are the same on the three axes,
 * so C diag(q) C^T = q I) */
static void process_noise(const gf_ins_filter *f, double *q_diag)
{
    const int n = f->n_states;
    const gf_ins_noise *nz = &f->cfg.noise;
    memset(q_diag, 0, (size_t)n * sizeof *q_diag);
    for (int i = 0; i < 3; ++i) {
        q_diag[IV + i] = nz->accel_vrw_m_s_sqrt_s * nz->accel_vrw_m_s_sqrt_s;
        q_diag[IA + i] = nz->gyro_arw_rad_sqrt_s * nz->gyro_arw_rad_sqrt_s;
        q_diag[IBG + i] = gm_intensity(nz->gyro_bias_std_rad_s, nz->gyro_bias_tau_s);
        q_diag[IBA + i] = gm_intensity(nz->accel_bias_std_m_s2, nz->accel_bias_tau_s);
        if (f->idx_sg >= 0) {
            q_diag[f->idx_sg + i] = gm_intensity(nz->gyro_scale_std, nz->gyro_scale_tau_s);
            q_diag[f->idx_sa + i] = gm_intensity(nz->accel_scale_std, nz->accel_scale_tau_s);
        }
    }
    if (f->idx_baro >= 0)
        q_diag[f->idx_baro] = gm_intensity(nz->baro_bias_std_m, nz->baro_bias_tau_s);
    if (f->idx_odo >= 0)
        q_diag[f->idx_odo] = gm_intensity(nz->odometer_scale_std, nz->odometer_scale_tau_s);
    for (int i = 0; f->idx_mount >= 0 && i < 2; ++i)
        q_diag[f->idx_mount + i] = gm_intensity(nz->odometer_mount_std_rad, nz->odometer_mount_tau_s);
    /* the mounting, lever arm and time offset are random constants (no noise); the
     * flexure's driving noise enters its rate: E[w w] = 4 b^3 sigma^2 (gf_ins_gnss.h) */
    if (f->idx_flex >= 0) {
        const double b = flexure_beta(f), sg = nz->flexure_std_rad;
        for (int i = 0; i < 3; ++i)
            q_diag[f->idx_flex + 3 + i] = 4.0 * b * b * b * sg * sg;
    }
}

_Static_assert(GF_INS_MAX_STATES <= 64, "row masks of F are 64 bits");

/* F (n x n in rows of stride s >= n, zero-filled here; mask (n) receives the rows'
 * structure, see gf_ins_f_entry) at attitude C, velocity v, position (sin and cos of the
 * latitude, h), specific force f_b and rate w_b (body); q_diag (n, may be NULL):
 * process_noise(). Only entries that can be non-zero are written. */
static void error_model(const gf_ins_filter *f, const gf_mat3 *C, const double v[3],
                        double sin_lat, double cos_lat, double h, const double f_b[3],
                        const double w_b[3], double *F, size_t s, uint64_t *mask,
                        double *q_diag)
{
    const int n = f->n_states;
    const gf_ins_noise *nz = &f->cfg.noise;
    memset(F, 0, (size_t)n * s * sizeof *F);
    memset(mask, 0, (size_t)n * sizeof *mask);
#define FF(i, j) (*gf_ins_f_entry(F, s, mask, (size_t)(i), (size_t)(j)))
    /* the navigation blocks (phi, dv, dp): gf_ins_model, with the nominal's Earth-rate
     * sign (reverse-time filtering, see the header) */
    gf_ins_nav_blocks_sparse(C, v, sin_lat, cos_lat, h, dir_of(f), f_b, s, IA, IV, IP, F, mask);
    /* sensor errors into attitude and velocity */
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            FF(IA + i, IBG + j) = -C->m[i][j];
            FF(IV + i, IBA + j) = C->m[i][j];
            if (f->idx_sg >= 0)
                FF(IA + i, f->idx_sg + j) = -C->m[i][j] * w_b[j];
            if (f->idx_sa >= 0)
                FF(IV + i, f->idx_sa + j) = C->m[i][j] * f_b[j];
        }
    /* Gauss-Markov decay rates (none for random constants, tau = 0) */
    for (int i = 0; i < 3; ++i) {
        if (nz->gyro_bias_tau_s > 0.0)
            FF(IBG + i, IBG + i) = gm_rate(nz->gyro_bias_tau_s);
        if (nz->accel_bias_tau_s > 0.0)
            FF(IBA + i, IBA + i) = gm_rate(nz->accel_bias_tau_s);
        if (f->idx_sg >= 0 && nz->gyro_scale_tau_s > 0.0)
            FF(f->idx_sg + i, f->idx_sg + i) = gm_rate(nz->gyro_scale_tau_s);
        if (f->idx_sa >= 0 && nz->accel_scale_tau_s > 0.0)
            FF(f->idx_sa + i, f->idx_sa + i) = gm_rate(nz->accel_scale_tau_s);
    }
    if (f->idx_baro >= 0 && nz->baro_bias_tau_s > 0.0)
        FF(f->idx_baro, f->idx_baro) = gm_rate(nz->baro_bias_tau_s);
    if (f->idx_odo >= 0 && nz->odometer_scale_tau_s > 0.0)
        FF(f->idx_odo, f->idx_odo) = gm_rate(nz->odometer_scale_tau_s);
    for (int i = 0; f->idx_mount >= 0 && nz->odometer_mount_tau_s > 0.0 && i < 2; ++i)
        FF(f->idx_mount + i, f->idx_mount + i) = gm_rate(nz->odometer_mount_tau_s);
    /* flexure, per axis: f' = r, r' = -b^2 f - 2 b r + w (second-order Markov) */
    if (f->idx_flex >= 0) {
        const double b = flexure_beta(f);
        for (int i = 0; i < 3; ++i) {
            const int a = f->idx_flex + i, r = f->idx_flex + 3 + i;
            FF(a, r) = 1.0;
            FF(r, a) = -b * b;
            FF(r, r) = -2.0 * b;
        }
    }
#undef FF
    if (q_diag)
        process_noise(f, q_diag);
}

gf_status gf_ins_error_model(const gf_ins_filter *f, const double *f_b_m_s2,
                             const double *w_ib_b_rad_s, double *F, double *G, double *q)
{
    if (!f || !f_b_m_s2 || !w_ib_b_rad_s || !F)
        return GF_ERR_NULL_POINTER;
    if (f->n_states < GF_INS_BASE_STATES || f->n_states > NMAX)
        return GF_ERR_BAD_SIZE;
    if (!gf_all_finite(f_b_m_s2, 3) || !gf_all_finite(w_ib_b_rad_s, 3))
        return GF_ERR_NONFINITE_INPUT;
    const int n = f->n_states, nw = n - 3;
    gf_mat3 C;
    gf_q_to_dcm(f->nav.q_bn, &C);
    double qd[NMAX];
    uint64_t mask[NMAX];
    error_model(f, &C, f->nav.v_n_m_s, f->nav.sin_lat, f->nav.cos_lat, f->nav.h_m, f_b_m_s2,
                w_ib_b_rad_s, F, (size_t)n, mask, qd);
    /* noise inputs: accelerometer (3) -> dv through C, gyro (3) -> phi through -C, then
     * one per sensor-error state */
    if (G) {
        memset(G, 0, (size_t)(n * nw) * sizeof *G);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                G[(IV + i) * nw + j] = C.m[i][j];
                G[(IA + i) * nw + 3 + j] = -C.m[i][j];
            }
        for (int k = IBG; k < n; ++k)
            G[k * nw + (k - 3)] = 1.0;
    }
    if (q) {
        for (int j = 0; j < 3; ++j) {
            q[j] = qd[IV + j];
            q[3 + j] = qd[IA + j];
        }
        for (int k = IBG; k < n; ++k)
            q[k - 3] = qd[k];
    }
    return GF_OK;
}

/* ---- covariance propagation -------------------------------------------------------------- */

gf_status ins_check_covariance(const gf_kalman *kf)
{
    for (size_t i = 0; i < kf->n; ++i) {
        const double p = kf->P[i * kf->n + i];
        if (!(p > 0.0) || !isfinite(p))
            return GF_ERR_DIVERGED;
    }
    return GF_OK;
}

/* A = F T + (F T)^2 / 2 (second_order) or F T, n rows of stride S (F's and A's), row by
 * row in registers: F_i T, then + T^2/2 F_ik F_k over the non-zeros of row i of F; the
 * structure of A (amask) is that of F and F^2. */
static GF_ALWAYS_INLINE void transition_rows(const size_t S, int n, const double *F,
                                             const uint64_t *fmask, double T,
                                             int second_order, double *A, uint64_t *amask)
{
    const double h2 = 0.5 * T * T;
    for (int i = 0; i < n; ++i) {
        const double *fi = F + (size_t)i * S;
        gf_v4 acc[GF_PADDED(NMAX) / 4];
        for (size_t k = 0; k < S / 4; ++k)
            acc[k] = GF_V4_SCALE(T, fi + 4 * k);
        uint64_t mask = fmask[i];
        if (second_order)
            for (uint64_t m = fmask[i]; m; m &= m - 1) {
                const size_t l = gf_lowest_bit(m);
                const double a = h2 * fi[l], *fl = F + l * S;
                for (size_t k = 0; k < S / 4; ++k)
                    GF_V4_AXPY(acc[k], a, fl + 4 * k);
                mask |= fmask[l];
            }
        for (size_t k = 0; k < S / 4; ++k)
            GF_V4_STORE(A + (size_t)i * S + 4 * k, acc[k]);
        amask[i] = mask;
    }
}

/* the stride is GF_PADDED(n): 16 .. 40 in steps of 4 for 15 .. 38 states */
_Static_assert(GF_PADDED(GF_INS_BASE_STATES) == 16 && GF_PADDED(NMAX) == 40,
               "transition() handles the strides 16, 20, ..., 40");
GF_VECTOR_CLONES
static void transition(size_t s, int n, const double *F, const uint64_t *fmask, double T,
                       int second_order, double *A, uint64_t *amask)
{
    if (s == 16)
        transition_rows(16, n, F, fmask, T, second_order, A, amask);
    else if (s == 20)
        transition_rows(20, n, F, fmask, T, second_order, A, amask);
    else if (s == 24)
        transition_rows(24, n, F, fmask, T, second_order, A, amask);
    else if (s == 28)
        transition_rows(28, n, F, fmask, T, second_order, A, amask);
    else if (s == 32)
        transition_rows(32, n, F, fmask, T, second_order, A, amask);
    else if (s == 36)
        transition_rows(36, n, F, fmask, T, second_order, A, amask);
    else
        transition_rows(40, n, F, fmask, T, second_order, A, amask);
}

static gf_status propagate_ekf(gf_ins_filter *f, gf_ins_epochs *ep)
{
    const int n = f->n_states;
    const size_t s = GF_PADDED((size_t)n);   /* row stride of F and A */
    const double T = f->acc_T_s;
    double fb[3], wb[3];
    gf_v3_scale(f->acc_dv_m_s, 1.0 / T, fb);
    gf_v3_scale(f->acc_dtheta_rad, 1.0 / T, wb);
    gf_mat3 C;
    gf_q_to_dcm(f->nav.q_bn, &C);
    double F[NMAX * GF_PADDED(NMAX)], A[NMAX * GF_PADDED(NMAX)], qd[NMAX];
    uint64_t fmask[NMAX], amask[NMAX];
    error_model(f, &C, f->nav.v_n_m_s, f->nav.sin_lat, f->nav.cos_lat, f->nav.h_m, fb, wb, F, s,
                fmask, qd);
    /* A = Phi - I = F T + (F T)^2 / 2; for intervals up to GF_INS_FIRST_ORDER_MAX_T_S the
     * second-order term is dropped (see the header) */
    transition(s, n, F, fmask, T, T > GF_INS_FIRST_ORDER_MAX_T_S, A, amask);
    double qh[NMAX];
    for (int i = 0; i < n; ++i)
        qh[i] = 0.5 * T * qd[i];
    gf_status st = gf_kalman_predict_masked(&f->kf, A, s, amask, qh, qh);
    if (st != GF_OK)
        return st == GF_ERR_NONFINITE_INPUT ? GF_ERR_DIVERGED : st;
    st = ins_check_covariance(&f->kf);
    if (st != GF_OK)
        return st;
    if (ep) {
        double Phi[NMAX * NMAX];      /* Phi = I + A, dense n x n for the smoother */
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j)
                Phi[i * n + j] = A[(size_t)i * s + (size_t)j] + (i == j ? 1.0 : 0.0);
        return ins_epoch_open(f, ep, Phi);
    }
    return GF_OK;
}

/* one coarse mechanization step of a hypothesis over the interval, with the interval's
 * compensated increments corrected for the hypothesis' sensor errors about the estimates
 * sens (those the increments were compensated with); base: the nominal's mechanization
 * state (its configuration and Earth-rate sign) */
static gf_status coarse_step(const gf_sins_state *base, const double *sens, const nav_hyp *hy,
                             const double dth[3], const double dv[3], double T, nav_hyp *out)
{
    gf_sins_state s = *base;
    s.cfg.input = GF_SINS_INPUT_INCREMENTS;
    s.cfg.coning = 0;
    s.have_prev = 0;          /* the Earth-rate sign is the nominal's (reverse filtering) */
    gf_status st = gf_sins_set_navigation(&s, hy->q, hy->v, hy->lat, hy->lon, hy->h);
    if (st != GF_OK)
        return GF_ERR_DIVERGED;
    /* true increment = (1 + s)^-1 ... to first order: compensated - db T - ds (.) compensated */
    double g[3], a[3];
    for (int i = 0; i < 3; ++i) {
        const double dbg = hy->s[S_BG + i] - sens[S_BG + i];
        const double dba = hy->s[S_BA + i] - sens[S_BA + i];
        const double dsg = hy->s[S_SG + i] - sens[S_SG + i];
        const double dsa = hy->s[S_SA + i] - sens[S_SA + i];
        g[i] = dth[i] - dbg * T - dsg * dth[i];
        a[i] = dv[i] - dba * T - dsa * dv[i];
    }
    st = gf_sins_step_trusted(&s, g, a, T);   /* increments already in the filter's direction */
    if (st != GF_OK)
        return GF_ERR_DIVERGED;
    *out = *hy;
    memcpy(out->q, s.q_bn, sizeof out->q);
    gf_q_to_dcm(out->q, &out->C);
    gf_v3_copy(s.v_n_m_s, out->v);
    out->lat = s.lat_rad;
    out->lon = s.lon_rad;
    out->h = s.h_m;
    return GF_OK;
}

static double gm_decay(double tau_s, double T)
{
    return tau_s > 0.0 ? exp(-T / tau_s) : 1.0;
}

/* exp(-T / tau) of every state over an interval T (1 for the navigation states and the
 * random constants) */
static void state_decay(const gf_ins_filter *f, double T, double *decay)
{
    const gf_ins_noise *nz = &f->cfg.noise;
    for (int i = 0; i < f->n_states; ++i)
        decay[i] = 1.0;
    for (int i = 0; i < 3; ++i) {
        decay[IBG + i] = gm_decay(nz->gyro_bias_tau_s, T);
        decay[IBA + i] = gm_decay(nz->accel_bias_tau_s, T);
        if (f->idx_sg >= 0) {
            decay[f->idx_sg + i] = gm_decay(nz->gyro_scale_tau_s, T);
            decay[f->idx_sa + i] = gm_decay(nz->accel_scale_tau_s, T);
        }
    }
    if (f->idx_baro >= 0)
        decay[f->idx_baro] = gm_decay(nz->baro_bias_tau_s, T);
    if (f->idx_odo >= 0)
        decay[f->idx_odo] = gm_decay(nz->odometer_scale_tau_s, T);
    for (int i = 0; f->idx_mount >= 0 && i < 2; ++i)
        decay[f->idx_mount + i] = gm_decay(nz->odometer_mount_tau_s, T);
}

/* the nominal (nav, sens) moved by the coarse step: nom1 as a hypothesis and as a
 * mechanization state */
static gf_status move_nominal(const gf_ins_filter *f, const gf_sins_state *nav,
                              const double *sens, const double dth[3], const double dv[3],
                              double T, gf_sins_state *nom1_state)
{
    nav_hyp nom0, nom1;
    const double zero[NMAX] = {0};
    ins_hyp_from_state(f, nav, sens, zero, &nom0);
    gf_status st = coarse_step(nav, sens, &nom0, dth, dv, T, &nom1);
    if (st != GF_OK)
        return st;
    *nom1_state = *nav;
    st = gf_sins_set_navigation(nom1_state, nom1.q, nom1.v, nom1.lat, nom1.lon, nom1.h);
    return st == GF_OK ? GF_OK : GF_ERR_DIVERGED;
}

/* one point of the UKF's time update: dx0 about (nav, sens) -> dx1 about the moved
 * nominal nom1 */
static gf_status move_point(const gf_ins_filter *f, const gf_sins_state *nav, const double *sens,
                            const gf_sins_state *nom1, const double *decay,
                            const double phi_flex[4], const double *dx0,
                            const double dth[3], const double dv[3], double T, double *dx1)
{
    nav_hyp h0, h1;
    ins_hyp_from_state(f, nav, sens, dx0, &h0);
    const gf_status st = coarse_step(nav, sens, &h0, dth, dv, T, &h1);
    if (st != GF_OK)
        return st;
    ins_error_from_hyp(f, nom1, sens, &h1, dx1);
    for (int i = IBG; i < f->n_states; ++i)
        dx1[i] = decay[i] * dx0[i];
    for (int i = 0; f->idx_flex >= 0 && i < 3; ++i) {   /* the flexure's 2 x 2, as the EKF's */
        const double *x = dx0 + f->idx_flex;
        dx1[f->idx_flex + i] = phi_flex[0] * x[i] + phi_flex[1] * x[3 + i];
        dx1[f->idx_flex + 3 + i] = phi_flex[2] * x[i] + phi_flex[3] * x[3 + i];
    }
    return GF_OK;
}

gf_status gf_ins_propagate_error(const gf_ins_filter *f, const double *dx0,
                                 const double *dtheta_rad, const double *dv_m_s, double T_s,
                                 double *dx1)
{
    if (!f || !dx0 || !dtheta_rad || !dv_m_s || !dx1)
        return GF_ERR_NULL_POINTER;
    if (!ins_layout_is_valid(f) || !(T_s > 0.0) || !isfinite(T_s))
        return GF_ERR_BAD_PARAMETER;
    if (!gf_all_finite(dx0, (size_t)f->n_states) || !gf_all_finite(dtheta_rad, 3) ||
        !gf_all_finite(dv_m_s, 3))
        return GF_ERR_NONFINITE_INPUT;
    gf_sins_state nom1;
    gf_status st = move_nominal(f, &f->nav, f->sensors, dtheta_rad, dv_m_s, T_s, &nom1);
    if (st != GF_OK)
        return st;
    double decay[NMAX], phi_flex[4] = {1.0, 0.0, 0.0, 1.0};
    state_decay(f, T_s, decay);
    if (f->idx_flex >= 0)
        ins_flexure_transition(f, T_s, T_s > GF_INS_FIRST_ORDER_MAX_T_S, phi_flex);
    return move_point(f, &f->nav, f->sensors, &nom1, decay, phi_flex, dx0, dtheta_rad, dv_m_s, T_s,
                      dx1);
}

static gf_status propagate_ukf(gf_ins_filter *f, gf_ins_epochs *ep)
{
    const int n = f->n_states, np = 2 * n + 1;
    const double T = f->acc_T_s;
    double X[(2 * NMAX + 1) * NMAX], Y[(2 * NMAX + 1) * NMAX];
    gf_status st = gf_ukf_sigma_points(&f->kf, &f->ukf_w, X);
    if (st != GF_OK)
        return GF_ERR_DIVERGED;
    /* the nominal moved by the same coarse step */
    gf_sins_state nom1_state;
    st = move_nominal(f, &f->nav0, f->sensors0, f->acc_dtheta_rad, f->acc_dv_m_s, T, &nom1_state);
    if (st != GF_OK)
        return st;
    double decay[NMAX];
    state_decay(f, T, decay);
    double phi_flex[4] = {1.0, 0.0, 0.0, 1.0};   /* the flexure's 2 x 2, as the EKF's */
    if (f->idx_flex >= 0)
        ins_flexure_transition(f, T, T > GF_INS_FIRST_ORDER_MAX_T_S, phi_flex);
    for (int p = 0; p < np; ++p) {
        st = move_point(f, &f->nav0, f->sensors0, &nom1_state, decay, phi_flex, X + p * n,
                        f->acc_dtheta_rad, f->acc_dv_m_s, T, Y + p * n);
        if (st != GF_OK)
            return st;
    }
    double qd[NMAX], Q[NMAX * NMAX];
    process_noise(f, qd);
    memset(Q, 0, (size_t)(n * n) * sizeof *Q);
    for (int i = 0; i < n; ++i)
        Q[i * n + i] = qd[i] * T;
    double P_prev[NMAX * NMAX], Phi[NMAX * NMAX];
    if (ep)
        memcpy(P_prev, f->kf.P, (size_t)(n * n) * sizeof *P_prev);
    st = gf_ukf_predict(&f->kf, &f->ukf_w, Y, Q);
    if (st != GF_OK)
        return GF_ERR_DIVERGED;
    st = ins_check_covariance(&f->kf);
    if (st != GF_OK)
        return st;
    if (ep) {
        /* statistical linearisation for the smoother: Phi = Cxy^T P_prev^-1 with
         * Cxy = sum Wc (X_i - x)(Y_i - y)^T (the unscented RTS gain C P_prior^-1) */
        double xm[NMAX] = {0}, ym[NMAX] = {0}, Cxy[NMAX * NMAX], L[NMAX * NMAX];
        for (int i = 0; i < n; ++i) {
            double ax = 0.0, ay = 0.0;
            for (int p = 1; p < np; ++p) {
                ax += X[p * n + i];
                ay += Y[p * n + i];
            }
            xm[i] = f->ukf_w.wm0 * X[i] + f->ukf_w.wi * ax;
            ym[i] = f->ukf_w.wm0 * Y[i] + f->ukf_w.wi * ay;
        }
        memset(Cxy, 0, (size_t)(n * n) * sizeof *Cxy);
        for (int p = 0; p < np; ++p) {
            const double wc = p == 0 ? f->ukf_w.wc0 : f->ukf_w.wi;
            for (int i = 0; i < n; ++i) {
                const double dxi = wc * (X[p * n + i] - xm[i]);
                for (int j = 0; j < n; ++j)
                    Cxy[i * n + j] += dxi * (Y[p * n + j] - ym[j]);
            }
        }
        memcpy(L, P_prev, (size_t)(n * n) * sizeof *L);
        if (gf_cholesky((size_t)n, L) != GF_OK)
            return GF_ERR_DIVERGED;
        /* Phi^T = P_prev^-1 Cxy */
        gf_cholesky_solve((size_t)n, L, (size_t)n, Cxy);
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j)
                Phi[i * n + j] = Cxy[j * n + i];
    }
    /* the mean of the moved points is the nominal's error: feed it back */
    st = ins_feedback(f);
    if (st != GF_OK)
        return st;
    return ep ? ins_epoch_open(f, ep, Phi) : GF_OK;
}

/* ---- the flexure's mean between updates ------------------------------------------------ */

void ins_flexure_transition(const gf_ins_filter *f, double T, int second_order, double phi[4])
{
    /* per axis F = [[0, 1], [-b^2, -2 b]]; Phi = I + F T (+ (F T)^2 / 2), the series
     * transition() forms for the covariance */
    const double b = flexure_beta(f);
    const double F[4] = {0.0, 1.0, -b * b, -2.0 * b};
    phi[0] = 1.0 + F[0] * T;
    phi[1] = F[1] * T;
    phi[2] = F[2] * T;
    phi[3] = 1.0 + F[3] * T;
    if (second_order) {
        const double half_T2 = 0.5 * T * T;
        phi[0] += half_T2 * (F[0] * F[0] + F[1] * F[2]);
        phi[1] += half_T2 * (F[0] * F[1] + F[1] * F[3]);
        phi[2] += half_T2 * (F[2] * F[0] + F[3] * F[2]);
        phi[3] += half_T2 * (F[2] * F[1] + F[3] * F[3]);
    }
}

void ins_flexure_mean(gf_ins_filter *f, double T, int second_order)
{
    double phi[4];
    ins_flexure_transition(f, T, second_order, phi);
    double *a = f->transfer + T_FLEX, *r = f->transfer + T_FLEX_RATE;
    for (int i = 0; i < 3; ++i) {
        const double ai = a[i], ri = r[i];
        a[i] = phi[0] * ai + phi[1] * ri;
        r[i] = phi[2] * ai + phi[3] * ri;
    }
}

gf_status ins_propagate(gf_ins_filter *f, gf_ins_epochs *ep)
{
    if (!(f->acc_T_s > 0.0))
        return GF_OK;
    const gf_status st = f->cfg.filter == GF_INS_UKF ? propagate_ukf(f, ep) : propagate_ekf(f, ep);
    /* the flexure estimates move with the flexure's mean dynamics (the error state's F
     * is then theirs too: both the truth and the estimate follow it) */
    if (st == GF_OK && f->idx_flex >= 0)
        ins_flexure_mean(f, f->acc_T_s, f->acc_T_s > GF_INS_FIRST_ORDER_MAX_T_S);
    f->acc_T_s = 0.0;
    gf_v3_set(0.0, 0.0, 0.0, f->acc_dtheta_rad);
    gf_v3_set(0.0, 0.0, 0.0, f->acc_dv_m_s);
    f->nav0 = f->nav;
    memcpy(f->sensors0, f->sensors, sizeof f->sensors);
    if (st == GF_OK)
        ins_refresh_std(f);
    return st;
}
