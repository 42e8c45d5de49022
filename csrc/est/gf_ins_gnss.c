/* gf_ins_gnss.c — error-state INS/GNSS/baro/odometer filter; equations in gf_ins_gnss.h. */
#include "est/gf_ins_gnss.h"

#include <math.h>
#include <string.h>

#include "base/gf_linalg.h"
#include "base/gf_math.h"
#include "est/gf_ins_model.h"
#include "nav/gf_earth.h"

#define NMAX GF_INS_MAX_STATES
#define IV GF_INS_IDX_VEL
#define IP GF_INS_IDX_POS
#define IA GF_INS_IDX_ATT
#define IBG GF_INS_IDX_BG
#define IBA GF_INS_IDX_BA
/* where each block's estimates sit in the sensors[] array */
#define S_BG 0
#define S_BA 3
#define S_SG 6
#define S_SA 9
#define S_BARO 12
#define S_ODO 13
#define S_MOUNT 14   /* pitch, heading */
/* two times closer than this are the same instant (s) */
#define GF_INS_TIME_EPS_S 1e-9
/* propagation intervals up to this use Phi = I + F T (see gf_ins_gnss.h) */
#define GF_INS_FIRST_ORDER_MAX_T_S 0.02

/* ---- configuration ------------------------------------------------------------------ */

gf_status gf_ins_config_default(gf_ins_config *cfg)
{
    if (!cfg)
        return GF_ERR_NULL_POINTER;
    memset(cfg, 0, sizeof *cfg);
    cfg->input = GF_SINS_INPUT_INCREMENTS;
    cfg->coning = 1;
    cfg->filter = GF_INS_EKF;
    cfg->prop_interval_s = 0.1;
    cfg->max_imu_gap_s = 0.5;
    cfg->max_rate_rad_s = 50.0;
    cfg->max_specific_force_m_s2 = 1000.0;
    /* seed 004: beta = 2 (Gaussian), kappa = 0, alpha "small": 0.5 keeps the points
     * within ~2 sigma; alpha -> 0 turns the UKF into an EKF with central differences */
    cfg->ukf_alpha = 0.5;
    cfg->ukf_beta = 2.0;
    cfg->ukf_kappa = 0.0;
    cfg->nhc_std_m_s = 0.1;
    cfg->nhc_interval_s = 0.1;
    cfg->zupt_std_m_s = 0.01;
    cfg->zupt_interval_s = 0.1;
    cfg->still_window_s = 0.5;
    cfg->still_accel_std_m_s2 = 0.05;
    cfg->still_gyro_rad_s = 0.01;
    cfg->speed_min_m_s = 0.5;
    cfg->subsamples = 1;
    return GF_OK;
}

static int pos_finite(double x)
{
    return isfinite(x) && x > 0.0;
}

static int nonneg_finite(double x)
{
    return isfinite(x) && x >= 0.0;
}

/* 0 when valid, else the number of the first bad field (documented in the Python layer:
 * gfins_fmi.estimation._CONFIG_FIELDS) */
static int config_check(const gf_ins_config *c)
{
    const gf_ins_noise *q = &c->noise;
    if (c->input != GF_SINS_INPUT_INCREMENTS && c->input != GF_SINS_INPUT_RATES)
        return 1;
    if (c->coning != 0 && c->coning != 1)
        return 2;
    if (c->filter != GF_INS_EKF && c->filter != GF_INS_UKF)
        return 3;
    if ((c->scale_states | c->baro_state | c->odo_state | c->odo_mount_state) & ~1)
        return 4;
    if (!nonneg_finite(c->prop_interval_s))
        return 5;
    if (!pos_finite(c->max_imu_gap_s))
        return 6;
    if (!pos_finite(c->max_rate_rad_s) || !pos_finite(c->max_specific_force_m_s2))
        return 7;
    if (!pos_finite(c->ukf_alpha) || !isfinite(c->ukf_beta) || !isfinite(c->ukf_kappa))
        return 8;
    const double noise[] = {q->gyro_arw_rad_sqrt_s, q->accel_vrw_m_s_sqrt_s,
                            q->gyro_bias_std_rad_s, q->gyro_bias_tau_s,
                            q->accel_bias_std_m_s2, q->accel_bias_tau_s, q->gyro_scale_std,
                            q->gyro_scale_tau_s, q->accel_scale_std, q->accel_scale_tau_s,
                            q->baro_bias_std_m, q->baro_bias_tau_s, q->odo_scale_std,
                            q->odo_scale_tau_s, q->odo_mount_std_rad, q->odo_mount_tau_s};
    for (size_t i = 0; i < sizeof noise / sizeof noise[0]; ++i)
        if (!nonneg_finite(noise[i]))
            return 10 + (int)i;
    if (!gf_all_finite(c->gnss_lever_m, 3) || !gf_all_finite(c->odo_lever_m, 3))
        return 30;
    if (!(c->gate_prob == 0.0 || (c->gate_prob > 0.0 && c->gate_prob < 1.0)) || c->gate_reset_count < 0)
        return 31;
    if ((c->nhc & ~1) || (c->nhc && (!pos_finite(c->nhc_std_m_s) || !nonneg_finite(c->nhc_interval_s))))
        return 32;
    if ((c->zupt & ~1) || (c->zupt && (!pos_finite(c->zupt_std_m_s) ||
                                       !nonneg_finite(c->zaru_std_rad_s) ||
                                       !nonneg_finite(c->zupt_interval_s))))
        return 33;
    if (!pos_finite(c->still_window_s) || !pos_finite(c->still_accel_std_m_s2) ||
        !pos_finite(c->still_gyro_rad_s))
        return 34;
    if (!nonneg_finite(c->max_latency_s))
        return 35;
    if (!nonneg_finite(c->speed_min_m_s))
        return 36;
    if (!(fabs(c->odo_mount_rad[0]) < GF_HALF_PI) || !(fabs(c->odo_mount_rad[1]) < GF_HALF_PI))
        return 37;
    if (c->subsamples < 0 || c->subsamples > GF_SINS_MAX_SUBSAMPLES ||
        (c->subsamples > 1 && c->input != GF_SINS_INPUT_INCREMENTS))
        return 38;
    return 0;
}

gf_status gf_ins_state_count(const gf_ins_config *cfg, int32_t *n_states)
{
    if (!cfg || !n_states)
        return GF_ERR_NULL_POINTER;
    if (config_check(cfg))
        return GF_ERR_BAD_PARAMETER;
    *n_states = GF_INS_BASE_STATES + 6 * cfg->scale_states + cfg->baro_state + cfg->odo_state +
                2 * cfg->odo_mount_state;
    return GF_OK;
}

/* ---- navigation hypotheses: nominal (-) error ---------------------------------------- */

typedef struct nav_hyp {
    double q[4];
    gf_mat3 C;          /* C_b^n */
    double v[3];
    double lat, lon, h;
    double s[GF_INS_N_SENSORS];
} nav_hyp;

/* error-state block -> first index of its estimates in sensors[], for the blocks present */
typedef struct sensor_block {
    int idx, sens, len;
} sensor_block;

static int sensor_blocks(const gf_ins_filter *f, sensor_block b[7])
{
    int nb = 0;
    b[nb++] = (sensor_block){IBG, S_BG, 3};
    b[nb++] = (sensor_block){IBA, S_BA, 3};
    if (f->idx_sg >= 0)
        b[nb++] = (sensor_block){f->idx_sg, S_SG, 3};
    if (f->idx_sa >= 0)
        b[nb++] = (sensor_block){f->idx_sa, S_SA, 3};
    if (f->idx_baro >= 0)
        b[nb++] = (sensor_block){f->idx_baro, S_BARO, 1};
    if (f->idx_odo >= 0)
        b[nb++] = (sensor_block){f->idx_odo, S_ODO, 1};
    if (f->idx_mount >= 0)
        b[nb++] = (sensor_block){f->idx_mount, S_MOUNT, 2};
    return nb;
}

/* The truth hypothesis of an error dx about the nominal (q, v, lat, lon, h, sensors):
 * v = v_nom - dv, p = p_nom - dp, C = exp([phi x]) C_nom (q = q(phi) q_nom), sensor
 * errors = estimate + state (the states are true - estimated). */
static void hyp_from_error(const gf_ins_filter *f, const double q_nom[4], const double v_nom[3],
                           double lat, double lon, double h, const double *sens,
                           const double *dx, nav_hyp *out)
{
    double qphi[4];
    gf_q_from_rotvec(dx + IA, qphi);
    gf_q_mul(qphi, q_nom, out->q);
    gf_q_normalize(out->q, out->q);
    gf_q_to_dcm(out->q, &out->C);
    for (int i = 0; i < 3; ++i)
        out->v[i] = v_nom[i] - dx[IV + i];
    out->lat = lat - dx[IP];
    out->lon = lon - dx[IP + 1];
    out->h = h - dx[IP + 2];
    memcpy(out->s, sens, sizeof out->s);
    sensor_block b[7];
    const int nb = sensor_blocks(f, b);
    for (int k = 0; k < nb; ++k)
        for (int i = 0; i < b[k].len; ++i)
            out->s[b[k].sens + i] += dx[b[k].idx + i];
}

static void hyp_from_state(const gf_ins_filter *f, const gf_sins_state *nav, const double *sens,
                           const double *dx, nav_hyp *out)
{
    hyp_from_error(f, nav->q_bn, nav->v_n_m_s, nav->lat_rad, nav->lon_rad, nav->h_m, sens, dx,
                   out);
}

static double wrap_pi(double a)
{
    if (a > GF_PI)
        a -= 2.0 * GF_PI;
    else if (a <= -GF_PI)
        a += 2.0 * GF_PI;
    return a;
}

/* +1 forward in time, -1 after gf_ins_reverse (the nominal's Earth-rate sign) */
static inline double dir_of(const gf_ins_filter *f)
{
    return f->nav.earth_rate_sign < 0.0 ? -1.0 : 1.0;
}

/* dx of a hypothesis about a nominal: the inverse of hyp_from_error */
static void error_from_hyp(const gf_ins_filter *f, const gf_sins_state *nom, const double *sens,
                           const nav_hyp *hy, double *dx)
{
    memset(dx, 0, (size_t)f->n_states * sizeof *dx);
    for (int i = 0; i < 3; ++i)
        dx[IV + i] = nom->v_n_m_s[i] - hy->v[i];
    dx[IP] = nom->lat_rad - hy->lat;
    dx[IP + 1] = wrap_pi(nom->lon_rad - hy->lon);
    dx[IP + 2] = nom->h_m - hy->h;
    double qc[4], qd[4];
    gf_q_conj(nom->q_bn, qc);
    gf_q_mul(hy->q, qc, qd);                 /* q(phi) = q_true (x) q_nom^* */
    gf_q_to_rotvec(qd, dx + IA);
    sensor_block b[7];
    const int nb = sensor_blocks(f, b);
    for (int k = 0; k < nb; ++k)
        for (int i = 0; i < b[k].len; ++i)
            dx[b[k].idx + i] = hy->s[b[k].sens + i] - sens[b[k].sens + i];
}

/* ---- what the filter keeps from its state ------------------------------------------ */

static void refresh_scale(gf_ins_filter *f)
{
    for (int i = 0; i < 3; ++i) {
        f->inv_scale[i] = 1.0 / (1.0 + f->sensors[S_SG + i]);
        f->inv_scale[3 + i] = 1.0 / (1.0 + f->sensors[S_SA + i]);
    }
}

static void refresh_std(gf_ins_filter *f)
{
    const size_t n = (size_t)f->n_states;
    const double *P = f->kf.P;
    gf_earth e;
    gf_earth_from_sincos(&e, f->nav.sin_lat, f->nav.cos_lat, f->nav.h_m, NULL, 1.0);
    for (int i = 0; i < 3; ++i) {
        f->std9[i] = sqrt(P[(IV + i) * n + IV + i]);
        f->std9[6 + i] = sqrt(P[(IA + i) * n + IA + i]);
    }
    f->std9[3] = sqrt(P[(IP + 1) * n + IP + 1]) * (e.R_N_m + f->nav.h_m) * e.cos_lat;
    f->std9[4] = sqrt(P[IP * n + IP]) * (e.R_M_m + f->nav.h_m);
    f->std9[5] = sqrt(P[(IP + 2) * n + IP + 2]);
}

/* ---- initialisation ------------------------------------------------------------------ */

gf_status gf_ins_init(gf_ins_filter *f, const gf_ins_config *cfg, double t0_s,
                      const double *q_bn, const double *v_n_m_s, double lat_rad,
                      double lon_rad, double h_m, const double *sensors0, const double *P0,
                      int32_t *bad)
{
    if (bad)
        *bad = 0;
    if (!f || !cfg || !q_bn || !v_n_m_s || !P0)
        return GF_ERR_NULL_POINTER;
    const int check = config_check(cfg);
    if (check) {
        if (bad)
            *bad = check;
        return GF_ERR_BAD_PARAMETER;
    }
    if (!isfinite(t0_s) || (sensors0 && !gf_all_finite(sensors0, GF_INS_N_SENSORS)))
        return GF_ERR_NONFINITE_INPUT;
    for (int i = 0; sensors0 && i < 2; ++i)
        if (!(fabs(cfg->odo_mount_rad[i] + sensors0[S_MOUNT + i]) < GF_HALF_PI)) {
            if (bad)
                *bad = 37;   /* the boresight angles used: odo_mount_rad + the correction */
            return GF_ERR_BAD_PARAMETER;
        }
    gf_sins_config sc;
    gf_sins_config_default(&sc);
    sc.input = cfg->input;
    sc.coning = cfg->coning;
    sc.vertical = GF_SINS_VERTICAL_FREE; /* the filter estimates the height */
    sc.max_rate_rad_s = cfg->max_rate_rad_s;
    sc.max_specific_force_m_s2 = cfg->max_specific_force_m_s2;
    gf_sins_state nav;
    gf_status st = gf_sins_init(&nav, &sc, q_bn, v_n_m_s, lat_rad, lon_rad, h_m, t0_s);
    if (st != GF_OK)
        return st;
    int32_t n;
    st = gf_ins_state_count(cfg, &n);
    if (st != GF_OK)
        return st;
    /* P0 must be symmetric positive definite */
    double L[GF_KF_MAX_N * GF_KF_MAX_N];
    for (int i = 0; i < n * n; ++i)
        if (!isfinite(P0[i]))
            return GF_ERR_NONFINITE_INPUT;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < i; ++j)
            if (fabs(P0[i * n + j] - P0[j * n + i]) >
                1e-12 * (fabs(P0[i * n + j]) + fabs(P0[j * n + i])) + 1e-300)
                return GF_ERR_SINGULAR_GEOMETRY;
    memcpy(L, P0, (size_t)(n * n) * sizeof *L);
    st = gf_cholesky((size_t)n, L);
    if (st != GF_OK)
        return st;
    memset(f, 0, sizeof *f);
    f->cfg = *cfg;
    f->n_states = n;
    int next = GF_INS_BASE_STATES;
    f->idx_sg = f->idx_sa = f->idx_baro = f->idx_odo = f->idx_mount = -1;
    if (cfg->scale_states) {
        f->idx_sg = next;
        f->idx_sa = next + 3;
        next += 6;
    }
    if (cfg->baro_state)
        f->idx_baro = next++;
    if (cfg->odo_state)
        f->idx_odo = next++;
    if (cfg->odo_mount_state) {
        f->idx_mount = next;
        next += 2;
    }
    f->nav = nav;
    if (sensors0)
        memcpy(f->sensors, sensors0, sizeof f->sensors);
    const double x0[GF_KF_MAX_N] = {0};
    st = gf_kalman_init(&f->kf, (size_t)n, x0, P0);
    if (st != GF_OK)
        return st;
    st = gf_ukf_weights_init(&f->ukf_w, (size_t)n, cfg->ukf_alpha, cfg->ukf_beta, cfg->ukf_kappa);
    if (st != GF_OK) {
        if (bad)
            *bad = 8;
        return GF_ERR_BAD_PARAMETER;
    }
    f->t_s = t0_s;
    f->nav0 = f->nav;
    memcpy(f->sensors0, f->sensors, sizeof f->sensors);
    f->last_nhc_t_s = f->last_zupt_t_s = -INFINITY;
    f->last_regular_t_s = t0_s;
    refresh_scale(f);
    refresh_std(f);
    return GF_OK;
}

/* ---- error model (see gf_ins_gnss.h) ----------------------------------------------- */

static double gm_rate(double tau_s)
{
    return tau_s > 0.0 ? -1.0 / tau_s : 0.0;
}

static double gm_intensity(double std, double tau_s)
{
    return tau_s > 0.0 ? 2.0 * std * std / tau_s : 0.0;
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
        q_diag[f->idx_odo] = gm_intensity(nz->odo_scale_std, nz->odo_scale_tau_s);
    for (int i = 0; f->idx_mount >= 0 && i < 2; ++i)
        q_diag[f->idx_mount + i] = gm_intensity(nz->odo_mount_std_rad, nz->odo_mount_tau_s);
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
    if (f->idx_odo >= 0 && nz->odo_scale_tau_s > 0.0)
        FF(f->idx_odo, f->idx_odo) = gm_rate(nz->odo_scale_tau_s);
    for (int i = 0; f->idx_mount >= 0 && nz->odo_mount_tau_s > 0.0 && i < 2; ++i)
        FF(f->idx_mount + i, f->idx_mount + i) = gm_rate(nz->odo_mount_tau_s);
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

/* ---- feedback and epochs --------------------------------------------------------------- */

static gf_status feedback(gf_ins_filter *f)
{
    nav_hyp hy;
    hyp_from_state(f, &f->nav, f->sensors, f->kf.x, &hy);
    const gf_status st = gf_sins_set_navigation(&f->nav, hy.q, hy.v, hy.lat, hy.lon, hy.h);
    if (st != GF_OK)
        return GF_ERR_DIVERGED;
    memcpy(f->sensors, hy.s, sizeof f->sensors);
    memset(f->kf.x, 0, sizeof f->kf.x);
    refresh_scale(f);
    return GF_OK;
}

static void pack_upper(size_t n, const double *P, double *out)
{
    size_t k = 0;
    for (size_t i = 0; i < n; ++i)
        for (size_t j = i; j < n; ++j)
            out[k++] = P[i * n + j];
}

static void unpack_upper(size_t n, const double *in, double *P)
{
    size_t k = 0;
    for (size_t i = 0; i < n; ++i)
        for (size_t j = i; j < n; ++j)
            P[i * n + j] = P[j * n + i] = in[k++];
}

static void epoch_write_nav(const gf_ins_filter *f, gf_ins_epochs *ep, size_t e)
{
    double *nav = ep->nav + 10 * e;
    memcpy(nav, f->nav.q_bn, 4 * sizeof *nav);
    gf_v3_copy(f->nav.v_n_m_s, nav + 4);
    nav[7] = f->nav.lat_rad;
    nav[8] = f->nav.lon_rad;
    nav[9] = f->nav.h_m;
    memcpy(ep->sensors + GF_INS_N_SENSORS * e, f->sensors, sizeof f->sensors);
}

/* opens an epoch at the filter's time with transition Phi (NULL: identity) */
static gf_status epoch_open(const gf_ins_filter *f, gf_ins_epochs *ep, const double *Phi)
{
    if (!ep)
        return GF_OK;
    if (ep->count >= ep->capacity)
        return GF_ERR_BAD_SIZE;
    const size_t n = (size_t)f->n_states, e = ep->count++;
    const size_t tri = n * (n + 1) / 2;
    ep->t_s[e] = f->t_s;
    epoch_write_nav(f, ep, e);
    memset(ep->dx + n * e, 0, n * sizeof *ep->dx);
    pack_upper(n, f->kf.P, ep->P_prior + tri * e);
    memcpy(ep->P_post + tri * e, ep->P_prior + tri * e, tri * sizeof *ep->P_post);
    double *phi = ep->Phi + n * n * e;
    if (Phi) {
        memcpy(phi, Phi, n * n * sizeof *phi);
    } else {
        memset(phi, 0, n * n * sizeof *phi);
        for (size_t i = 0; i < n; ++i)
            phi[i * n + i] = 1.0;
    }
    return GF_OK;
}

/* after an accepted update: the correction dx (before the reset) joins the epoch */
static gf_status epoch_update(const gf_ins_filter *f, gf_ins_epochs *ep, const double *dx)
{
    if (!ep)
        return GF_OK;
    if (ep->count == 0 || fabs(ep->t_s[ep->count - 1] - f->t_s) > GF_INS_TIME_EPS_S) {
        const gf_status st = epoch_open(f, ep, NULL);
        if (st != GF_OK)
            return st;
    }
    const size_t n = (size_t)f->n_states, e = ep->count - 1;
    for (size_t i = 0; i < n; ++i)
        ep->dx[n * e + i] += dx[i];
    pack_upper(n, f->kf.P, ep->P_post + n * (n + 1) / 2 * e);
    epoch_write_nav(f, ep, e);
    return GF_OK;
}

/* ---- covariance propagation -------------------------------------------------------------- */

static gf_status check_covariance(const gf_kalman *kf)
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

/* the stride is GF_PADDED(n): 16, 20, 24 or 28 for 15 .. 25 states */
_Static_assert(GF_PADDED(GF_INS_BASE_STATES) == 16 && GF_PADDED(NMAX) == 28,
               "transition() handles the strides 16, 20, 24 and 28");
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
    else
        transition_rows(28, n, F, fmask, T, second_order, A, amask);
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
    st = check_covariance(&f->kf);
    if (st != GF_OK)
        return st;
    if (ep) {
        double Phi[NMAX * NMAX];      /* Phi = I + A, dense n x n for the smoother */
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j)
                Phi[i * n + j] = A[(size_t)i * s + (size_t)j] + (i == j ? 1.0 : 0.0);
        return epoch_open(f, ep, Phi);
    }
    return GF_OK;
}

/* one coarse mechanization step of a hypothesis over the interval, with the interval's
 * compensated increments corrected for the hypothesis' sensor errors */
static gf_status coarse_step(const gf_ins_filter *f, const nav_hyp *hy, const double dth[3],
                             const double dv[3], double T, nav_hyp *out)
{
    gf_sins_state s = f->nav0;
    s.cfg.input = GF_SINS_INPUT_INCREMENTS;
    s.cfg.coning = 0;
    s.have_prev = 0;          /* the Earth-rate sign is the nominal's (reverse filtering) */
    gf_status st = gf_sins_set_navigation(&s, hy->q, hy->v, hy->lat, hy->lon, hy->h);
    if (st != GF_OK)
        return GF_ERR_DIVERGED;
    /* true increment = (1 + s)^-1 ... to first order: compensated - db T - ds (.) compensated */
    double g[3], a[3];
    for (int i = 0; i < 3; ++i) {
        const double dbg = hy->s[S_BG + i] - f->sensors0[S_BG + i];
        const double dba = hy->s[S_BA + i] - f->sensors0[S_BA + i];
        const double dsg = hy->s[S_SG + i] - f->sensors0[S_SG + i];
        const double dsa = hy->s[S_SA + i] - f->sensors0[S_SA + i];
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

static gf_status propagate_ukf(gf_ins_filter *f, gf_ins_epochs *ep)
{
    const int n = f->n_states, np = 2 * n + 1;
    const double T = f->acc_T_s;
    const gf_ins_noise *nz = &f->cfg.noise;
    double X[(2 * NMAX + 1) * NMAX], Y[(2 * NMAX + 1) * NMAX];
    gf_status st = gf_ukf_sigma_points(&f->kf, &f->ukf_w, X);
    if (st != GF_OK)
        return GF_ERR_DIVERGED;
    /* the nominal moved by the same coarse step */
    nav_hyp nom0, nom1;
    const double zero[NMAX] = {0};
    hyp_from_state(f, &f->nav0, f->sensors0, zero, &nom0);
    st = coarse_step(f, &nom0, f->acc_dtheta_rad, f->acc_dv_m_s, T, &nom1);
    if (st != GF_OK)
        return st;
    gf_sins_state nom1_state = f->nav0;
    st = gf_sins_set_navigation(&nom1_state, nom1.q, nom1.v, nom1.lat, nom1.lon, nom1.h);
    if (st != GF_OK)
        return GF_ERR_DIVERGED;
    double decay[NMAX];
    for (int i = 0; i < n; ++i)
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
        decay[f->idx_odo] = gm_decay(nz->odo_scale_tau_s, T);
    for (int i = 0; f->idx_mount >= 0 && i < 2; ++i)
        decay[f->idx_mount + i] = gm_decay(nz->odo_mount_tau_s, T);
    for (int p = 0; p < np; ++p) {
        nav_hyp h0, h1;
        hyp_from_state(f, &f->nav0, f->sensors0, X + p * n, &h0);
        st = coarse_step(f, &h0, f->acc_dtheta_rad, f->acc_dv_m_s, T, &h1);
        if (st != GF_OK)
            return st;
        error_from_hyp(f, &nom1_state, f->sensors0, &h1, Y + p * n);
        for (int i = IBG; i < n; ++i)
            Y[p * n + i] = decay[i] * X[p * n + i];
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
    st = check_covariance(&f->kf);
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
    st = feedback(f);
    if (st != GF_OK)
        return st;
    return ep ? epoch_open(f, ep, Phi) : GF_OK;
}

static gf_status propagate(gf_ins_filter *f, gf_ins_epochs *ep)
{
    if (!(f->acc_T_s > 0.0))
        return GF_OK;
    const gf_status st = f->cfg.filter == GF_INS_UKF ? propagate_ukf(f, ep) : propagate_ekf(f, ep);
    f->acc_T_s = 0.0;
    gf_v3_set(0.0, 0.0, 0.0, f->acc_dtheta_rad);
    gf_v3_set(0.0, 0.0, 0.0, f->acc_dv_m_s);
    f->nav0 = f->nav;
    memcpy(f->sensors0, f->sensors, sizeof f->sensors);
    if (st == GF_OK)
        refresh_std(f);
    return st;
}

/* ---- measurement models ------------------------------------------------------------------ */

static int meas_rows(int32_t type)
{
    switch (type) {
    case GF_INS_MEAS_GNSS_POS:
    case GF_INS_MEAS_GNSS_VEL:
    case GF_INS_MEAS_ZUPT:
    case GF_INS_MEAS_ZARU:
        return 3;
    case GF_INS_MEAS_NHC:
        return 2;
    case GF_INS_MEAS_BARO:
    case GF_INS_MEAS_ODO:
    case GF_INS_MEAS_SPEED:
        return 1;
    default:
        return 0;
    }
}

/* Local metric frame of the nominal for positions: ENU metres about (lat0, lon0, h0). */
typedef struct local_frame {
    double lat0, lon0, h0, kE, kN;
} local_frame;

static void local_frame_of(const gf_sins_state *nav, local_frame *lf)
{
    gf_earth e;
    gf_earth_from_sincos(&e, nav->sin_lat, nav->cos_lat, nav->h_m, NULL, 1.0);
    lf->lat0 = nav->lat_rad;
    lf->lon0 = nav->lon_rad;
    lf->h0 = nav->h_m;
    lf->kE = (e.R_N_m + nav->h_m) * e.cos_lat;
    lf->kN = e.R_M_m + nav->h_m;
}

static void to_local(const local_frame *lf, double lat, double lon, double h, double out[3])
{
    out[0] = wrap_pi(lon - lf->lon0) * lf->kE;
    out[1] = (lat - lf->lat0) * lf->kN;
    out[2] = h - lf->h0;
}

/* w_eb^b of a hypothesis: its rate w_ib (the compensated rate corrected for its sensor
 * errors) minus the Earth rate in body axes */
static void hyp_rate(const gf_ins_filter *f, const nav_hyp *hy, const double w_comp[3],
                     double w_ib[3], double w_eb[3])
{
    for (int i = 0; i < 3; ++i) {
        const double dbg = hy->s[S_BG + i] - f->sensors[S_BG + i];
        const double dsg = hy->s[S_SG + i] - f->sensors[S_SG + i];
        w_ib[i] = w_comp[i] - dbg - dsg * w_comp[i];
    }
    const double W = dir_of(f) * GF_WGS84_OMEGA_IE_RAD_S;
    const double w_ie[3] = {0.0, W * cos(hy->lat), W * sin(hy->lat)};
    double w_ie_b[3];
    gf_m3t_mul_v3(&hy->C, w_ie, w_ie_b);
    gf_v3_sub(w_ib, w_ie_b, w_eb);
}

/* C_b^m of the odometer's mounting: the transpose of C_m^b = Rz(-heading_m) Rx(pitch_m)
 * (the Euler convention of gf_sins.h without roll) at pitch_m = cfg.odo_mount_rad[0] +
 * s[S_MOUNT], heading_m = cfg.odo_mount_rad[1] + s[S_MOUNT + 1] (s: the hypothesis'
 * sensor estimates); identity for zero angles (exactly: cos 0 = 1, sin 0 = 0, so the
 * products below keep their bits). dMp, dMh (may be NULL) receive dM/dpitch_m and
 * dM/dheading_m, entry by entry (rad^-1). */
static void odo_mount(const gf_ins_filter *f, const double *s, double M[3][3], double dMp[3][3],
                      double dMh[3][3])
{
    const double p = f->cfg.odo_mount_rad[0] + s[S_MOUNT];
    const double hd = f->cfg.odo_mount_rad[1] + s[S_MOUNT + 1];
    const double sp = sin(p), cp = cos(p), sh = sin(hd), ch = cos(hd);
    /* rows of C_b^m = columns of C_m^b: the odometer's x, y (forward), z axes in body */
    M[0][0] = ch;       M[0][1] = -sh;      M[0][2] = 0.0;
    M[1][0] = sh * cp;  M[1][1] = ch * cp;  M[1][2] = sp;
    M[2][0] = -sh * sp; M[2][1] = -ch * sp; M[2][2] = cp;
    if (dMp) {
        dMp[0][0] = 0.0;      dMp[0][1] = 0.0;      dMp[0][2] = 0.0;
        dMp[1][0] = -sh * sp; dMp[1][1] = -ch * sp; dMp[1][2] = cp;
        dMp[2][0] = -sh * cp; dMp[2][1] = -ch * cp; dMp[2][2] = -sp;
    }
    if (dMh) {
        dMh[0][0] = -sh;      dMh[0][1] = -ch;      dMh[0][2] = 0.0;
        dMh[1][0] = ch * cp;  dMh[1][1] = -sh * cp; dMh[1][2] = 0.0;
        dMh[2][0] = -ch * sp; dMh[2][1] = sh * sp;  dMh[2][2] = 0.0;
    }
}

/* velocity of the odometer point in body axes: C^T v + w_eb x l */
static void odo_body_velocity(const gf_ins_filter *f, const nav_hyp *hy, const double w_comp[3],
                              double ub[3])
{
    double w_ib[3], w_eb[3], vb[3], wl[3];
    hyp_rate(f, hy, w_comp, w_ib, w_eb);
    gf_m3t_mul_v3(&hy->C, hy->v, vb);
    gf_v3_cross(w_eb, f->cfg.odo_lever_m, wl);
    gf_v3_add(vb, wl, ub);
}

/* velocity of the odometer point in the odometer's axes: C_b^m (C^T v + w_eb x l) */
static void odo_point_velocity(const gf_ins_filter *f, const nav_hyp *hy, const double w_comp[3],
                               double out[3])
{
    double ub[3], M[3][3];
    odo_body_velocity(f, hy, w_comp, ub);
    odo_mount(f, hy->s, M, NULL, NULL);
    for (int i = 0; i < 3; ++i)
        out[i] = M[i][0] * ub[0] + M[i][1] * ub[1] + M[i][2] * ub[2];
}

/* The full (nonlinear) prediction of a measurement from a hypothesis; positions in the
 * nominal's local frame. */
static void meas_predict(const gf_ins_filter *f, const local_frame *lf, const nav_hyp *hy,
                         const double w_comp[3], int32_t type, double *y)
{
    switch (type) {
    case GF_INS_MEAS_GNSS_POS: {
        double cl[3];
        gf_m3_mul_v3(&hy->C, f->cfg.gnss_lever_m, cl);
        double p[3];
        to_local(lf, hy->lat, hy->lon, hy->h, p);
        /* p_ant = p + C l (the lever arm is metres in ENU directly) */
        gf_v3_add(p, cl, y);
        break;
    }
    case GF_INS_MEAS_GNSS_VEL: {
        double w_ib[3], w_eb[3], wl[3], cwl[3];
        hyp_rate(f, hy, w_comp, w_ib, w_eb);
        gf_v3_cross(w_eb, f->cfg.gnss_lever_m, wl);
        gf_m3_mul_v3(&hy->C, wl, cwl);
        gf_v3_add(hy->v, cwl, y);
        break;
    }
    case GF_INS_MEAS_BARO:
        y[0] = hy->h + hy->s[S_BARO];
        break;
    case GF_INS_MEAS_ODO: {
        double u[3];
        odo_point_velocity(f, hy, w_comp, u);
        y[0] = (1.0 + hy->s[S_ODO]) * u[1];
        break;
    }
    case GF_INS_MEAS_NHC: {
        double u[3];
        odo_point_velocity(f, hy, w_comp, u);
        y[0] = u[0];
        y[1] = u[2];
        break;
    }
    case GF_INS_MEAS_ZUPT:
        gf_v3_copy(hy->v, y);
        break;
    case GF_INS_MEAS_ZARU: {
        double w_ib[3], w_eb[3];
        hyp_rate(f, hy, f->still_w, w_ib, w_eb);
        gf_v3_copy(w_eb, y);
        break;
    }
    case GF_INS_MEAS_SPEED:
        /* seed 003 eq. 7: the SINS horizontal speed, scaled by the speed-scale estimate */
        y[0] = (1.0 + hy->s[S_ODO]) * hypot(hy->v[0], hy->v[1]);
        break;
    default:
        break;
    }
}

/* rows of [a x] */
static void skew_rows(const double a[3], double S[3][3])
{
    S[0][0] = 0.0;   S[0][1] = -a[2]; S[0][2] = a[1];
    S[1][0] = a[2];  S[1][1] = 0.0;   S[1][2] = -a[0];
    S[2][0] = -a[1]; S[2][1] = a[0];  S[2][2] = 0.0;
}

/* The linearised model H (m x n) of a measurement at the nominal (EKF). */
static void meas_jacobian(const gf_ins_filter *f, const local_frame *lf, const nav_hyp *nom,
                          const double w_comp[3], int32_t type, double *H)
{
    const int n = f->n_states;
    const int m = meas_rows(type);
    memset(H, 0, (size_t)(m * n) * sizeof *H);
#define HH(i, j) H[(i) * n + (j)]
    const double *w = type == GF_INS_MEAS_ZARU ? f->still_w : w_comp;
    switch (type) {
    case GF_INS_MEAS_GNSS_POS: {
        double cl[3], S[3][3];
        gf_m3_mul_v3(&nom->C, f->cfg.gnss_lever_m, cl);
        skew_rows(cl, S);                                  /* [(C l) x] phi */
        HH(0, IP + 1) = lf->kE;
        HH(1, IP + 0) = lf->kN;
        HH(2, IP + 2) = 1.0;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                HH(i, IA + j) = S[i][j];
        break;
    }
    case GF_INS_MEAS_GNSS_VEL: {
        double w_ib[3], w_eb[3], wl[3], cwl[3], S[3][3], Lx[3][3];
        hyp_rate(f, nom, w, w_ib, w_eb);
        gf_v3_cross(w_eb, f->cfg.gnss_lever_m, wl);
        gf_m3_mul_v3(&nom->C, wl, cwl);
        skew_rows(cwl, S);
        skew_rows(f->cfg.gnss_lever_m, Lx);
        for (int i = 0; i < 3; ++i) {
            HH(i, IV + i) = 1.0;
            for (int j = 0; j < 3; ++j) {
                HH(i, IA + j) = S[i][j];
                double cl = 0.0;                           /* (C [l x])_ij */
                for (int k = 0; k < 3; ++k)
                    cl += nom->C.m[i][k] * Lx[k][j];
                HH(i, IBG + j) = -cl;
                if (f->idx_sg >= 0)
                    HH(i, f->idx_sg + j) = -cl * w[j];
            }
        }
        break;
    }
    case GF_INS_MEAS_BARO:
        HH(0, IP + 2) = 1.0;
        if (f->idx_baro >= 0)
            HH(0, f->idx_baro) = -1.0;
        break;
    case GF_INS_MEAS_ODO:
    case GF_INS_MEAS_NHC: {
        /* u = C_b^m (C^T v + w_eb x l): du = C_b^m (C^T dv - C^T [v x] phi - [l x] dw)
         * + (dM/dpitch_m ub) dpitch_m + (dM/dheading_m ub) dheading_m, ub = C^T v + w_eb x l
         * the odometer point's body velocity and dM/d. the entry-wise derivatives of
         * M = C_b^m (odo_mount). The states are true - estimated and z_err = predicted -
         * measured, so the boresight columns are -k1 (dM/d. ub)_a; the other terms as
         * before (dv, phi, dw are computed - true). */
        double Vx[3][3], Lx[3][3], CtV[3][3], M[3][3], MCt[3][3], MCtV[3][3], MLx[3][3];
        skew_rows(nom->v, Vx);
        skew_rows(f->cfg.odo_lever_m, Lx);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                double acc = 0.0;
                for (int k = 0; k < 3; ++k)
                    acc += nom->C.m[k][i] * Vx[k][j];
                CtV[i][j] = acc;
            }
        odo_mount(f, nom->s, M, NULL, NULL);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                MCt[i][j] = M[i][0] * nom->C.m[j][0] + M[i][1] * nom->C.m[j][1] + M[i][2] * nom->C.m[j][2];
                MCtV[i][j] = M[i][0] * CtV[0][j] + M[i][1] * CtV[1][j] + M[i][2] * CtV[2][j];
                MLx[i][j] = M[i][0] * Lx[0][j] + M[i][1] * Lx[1][j] + M[i][2] * Lx[2][j];
            }
        const int rows_odo[1] = {1}, rows_nhc[2] = {0, 2};
        const int *rows = type == GF_INS_MEAS_ODO ? rows_odo : rows_nhc;
        const double k1 = type == GF_INS_MEAS_ODO ? 1.0 + nom->s[S_ODO] : 1.0;
        for (int r = 0; r < m; ++r) {
            const int a = rows[r];
            for (int j = 0; j < 3; ++j) {
                HH(r, IV + j) = k1 * MCt[a][j];
                HH(r, IA + j) = -k1 * MCtV[a][j];
                HH(r, IBG + j) = -k1 * MLx[a][j];
                if (f->idx_sg >= 0)
                    HH(r, f->idx_sg + j) = -k1 * MLx[a][j] * w[j];
            }
        }
        if (f->idx_mount >= 0) {
            double ub[3], Md[3][3], dMp[3][3], dMh[3][3];
            odo_body_velocity(f, nom, w_comp, ub);
            odo_mount(f, nom->s, Md, dMp, dMh);
            for (int r = 0; r < m; ++r) {
                const int a = rows[r];
                HH(r, f->idx_mount) = -k1 * gf_v3_dot(dMp[a], ub);
                HH(r, f->idx_mount + 1) = -k1 * gf_v3_dot(dMh[a], ub);
            }
        }
        if (type == GF_INS_MEAS_ODO && f->idx_odo >= 0) {
            double u[3];
            odo_point_velocity(f, nom, w_comp, u);
            HH(0, f->idx_odo) = -u[1];
        }
        break;
    }
    case GF_INS_MEAS_ZUPT:
        for (int i = 0; i < 3; ++i)
            HH(i, IV + i) = 1.0;
        break;
    case GF_INS_MEAS_SPEED: {
        /* seed 003 eq. 8 (Taylor expansion at the nominal), derived in the header:
         * dy = (1 + k) (v_E dv_E + v_N dv_N) / |v_h| - |v_h| dk; update_at has refused
         * |v_h| < speed_min_m_s */
        const double sp = hypot(nom->v[0], nom->v[1]), k1 = 1.0 + nom->s[S_ODO];
        HH(0, IV + 0) = k1 * nom->v[0] / sp;
        HH(0, IV + 1) = k1 * nom->v[1] / sp;
        if (f->idx_odo >= 0)
            HH(0, f->idx_odo) = -sp;
        break;
    }
    case GF_INS_MEAS_ZARU: {
        /* y = w_ib - C^T w_ie: dy = dw + C^T [w_ie x] phi */
        const double W = dir_of(f) * GF_WGS84_OMEGA_IE_RAD_S;
        const double w_ie[3] = {0.0, W * cos(nom->lat), W * sin(nom->lat)};
        double Wx[3][3];
        skew_rows(w_ie, Wx);
        for (int i = 0; i < 3; ++i) {
            HH(i, IBG + i) = 1.0;
            if (f->idx_sg >= 0)
                HH(i, f->idx_sg + i) = w[i];
            for (int j = 0; j < 3; ++j) {
                double acc = 0.0;
                for (int k = 0; k < 3; ++k)
                    acc += nom->C.m[k][i] * Wx[k][j];
                HH(i, IA + j) = acc;
            }
        }
        break;
    }
    default:
        break;
    }
#undef HH
}

/* The measured value in the prediction's units (positions in the local frame). */
static void meas_value(const local_frame *lf, const gf_ins_meas *ms, int32_t type, double *z)
{
    if (type == GF_INS_MEAS_GNSS_POS)
        to_local(lf, ms->z[0], ms->z[1], ms->z[2], z);
    else if (ms)
        memcpy(z, ms->z, 3 * sizeof *z);
}

static void log_entry(gf_ins_log *log, double t, int32_t type, int32_t status, int m, double nis,
                      const double *r, const double *s_std)
{
    if (!log || !log->entries)
        return;
    if (log->count >= log->capacity) {
        log->n_dropped++;
        return;
    }
    gf_ins_innovation *e = log->entries + log->count++;
    memset(e, 0, sizeof *e);
    e->t_s = t;
    e->type = type;
    e->status = status;
    e->m = m;
    e->nis = nis;
    for (int i = 0; i < m && i < 3; ++i) {
        e->r[i] = r ? r[i] : NAN;
        e->s_std[i] = s_std ? s_std[i] : NAN;
    }
}

/* One update of type `type` (external measurement *ms, or internal with ms NULL and
 * std std_int). The measurement is predicted from the nominal `ref` with compensated
 * rate `w_ref` (the current ones, or their past values for a delayed measurement: the
 * error state is then taken as unchanged over the delay) and the correction goes to the
 * current nominal. */
static gf_status update_at(gf_ins_filter *f, int32_t type, const gf_ins_meas *ms, double std_int,
                           const gf_sins_state *ref, const double *w_ref, gf_ins_epochs *ep,
                           gf_ins_log *log)
{
    const int n = f->n_states, m = meas_rows(type);
    if (type == GF_INS_MEAS_SPEED && !(hypot(ref->v_n_m_s[0], ref->v_n_m_s[1]) > f->cfg.speed_min_m_s)) {
        f->n_rejected++;
        log_entry(log, ms ? ms->t_s : f->t_s, type, GF_INS_REJECTED_LOW_SPEED, m, NAN, NULL, NULL);
        return GF_OK;
    }
    local_frame lf;
    local_frame_of(ref, &lf);
    const double zero[NMAX] = {0};
    nav_hyp nom;
    hyp_from_state(f, ref, f->sensors, zero, &nom);
    double y_nom[3], z[3] = {0, 0, 0}, r[3], R[9] = {0}, s_std[3];
    meas_predict(f, &lf, &nom, w_ref, type, y_nom);
    if (ms)
        meas_value(&lf, ms, type, z);
    for (int i = 0; i < m; ++i) {
        const double sd = ms ? ms->std[i] : std_int;
        R[i * m + i] = sd * sd;
        r[i] = y_nom[i] - z[i];
    }
    double gate = 0.0;
    int forced = 0;
    if (f->cfg.gate_prob > 0.0) {
        gf_chi2_quantile(m, f->cfg.gate_prob, &gate);
        if (f->cfg.gate_reset_count > 0 && f->gate_run[type] >= f->cfg.gate_reset_count) {
            gate = 0.0;          /* the gate has rejected too many in a row: apply this one */
            forced = 1;
        }
    }
    double nis = NAN;
    int accepted = 0;
    gf_status st;
    if (f->cfg.filter == GF_INS_UKF) {
        const int np = 2 * n + 1;
        double X[(2 * NMAX + 1) * NMAX], Zp[(2 * NMAX + 1) * 3];
        st = gf_ukf_sigma_points(&f->kf, &f->ukf_w, X);
        if (st != GF_OK)
            return GF_ERR_DIVERGED;
        for (int p = 0; p < np; ++p) {
            nav_hyp hy;
            double y[3];
            hyp_from_state(f, ref, f->sensors, X + p * n, &hy);
            meas_predict(f, &lf, &hy, w_ref, type, y);
            for (int i = 0; i < m; ++i)
                Zp[p * m + i] = y_nom[i] - y[i];
        }
        for (int i = 0; i < m; ++i) {                      /* sqrt diag Pyy */
            double mean = 0.0, acc = 0.0;
            for (int p = 1; p < np; ++p)
                mean += Zp[p * m + i];
            mean = f->ukf_w.wm0 * Zp[i] + f->ukf_w.wi * mean;
            for (int p = 0; p < np; ++p) {
                const double d = Zp[p * m + i] - mean;
                acc += (p == 0 ? f->ukf_w.wc0 : f->ukf_w.wi) * d * d;
            }
            s_std[i] = sqrt(fmax(0.0, acc + R[i * m + i]));
        }
        st = gf_ukf_update(&f->kf, &f->ukf_w, X, (size_t)m, Zp, r, R, gate, &nis, &accepted);
    } else {
        double H[3 * NMAX];
        meas_jacobian(f, &lf, &nom, w_ref, type, H);
        for (int i = 0; i < m; ++i) {                      /* sqrt diag (H P H^T + R) */
            double acc = R[i * m + i];
            for (int a = 0; a < n; ++a) {
                const double ha = H[i * n + a];
                if (ha == 0.0)
                    continue;
                for (int b = 0; b < n; ++b)
                    acc += ha * f->kf.P[a * n + b] * H[i * n + b];
            }
            s_std[i] = sqrt(fmax(0.0, acc));
        }
        st = gf_kalman_update_gated(&f->kf, (size_t)m, r, H, R, gate, &nis, &accepted);
    }
    /* logged at the measurement's time of validity (a delayed one is applied later) */
    const double t = ms ? ms->t_s : f->t_s;
    if (st == GF_ERR_SINGULAR_GEOMETRY || st == GF_ERR_DIVERGED) {
        f->n_rejected++;
        log_entry(log, t, type, GF_INS_REJECTED_SINGULAR, m, nis, r, s_std);
        return GF_OK;
    }
    if (st != GF_OK)
        return st;
    if (!accepted) {
        f->n_rejected++;
        f->gate_run[type]++;
        log_entry(log, t, type, GF_INS_REJECTED_GATE, m, nis, r, s_std);
        return GF_OK;
    }
    f->n_updates++;
    f->gate_run[type] = 0;
    log_entry(log, t, type, forced ? GF_INS_FORCED : GF_INS_ACCEPTED, m, nis, r, s_std);
    double dx[NMAX];
    memcpy(dx, f->kf.x, (size_t)n * sizeof *dx);
    st = feedback(f);
    if (st != GF_OK)
        return st;
    st = check_covariance(&f->kf);
    if (st != GF_OK)
        return st;
    f->nav0 = f->nav;
    memcpy(f->sensors0, f->sensors, sizeof f->sensors);
    refresh_std(f);
    return epoch_update(f, ep, dx);
}

static gf_status update(gf_ins_filter *f, int32_t type, const gf_ins_meas *ms, double std_int,
                        gf_ins_epochs *ep, gf_ins_log *log)
{
    return update_at(f, type, ms, std_int, &f->nav, f->w_ib_b_rad_s, ep, log);
}

/* ---- the sample ---------------------------------------------------------------------------- */

static void compensate(const gf_ins_filter *f, const double g_raw[3], const double a_raw[3],
                       double T, double g[3], double a[3])
{
    const double *s = f->sensors;
    const double k = f->cfg.input == GF_SINS_INPUT_INCREMENTS ? T : 1.0;
    for (int i = 0; i < 3; ++i) {
        g[i] = (g_raw[i] - s[S_BG + i] * k) * f->inv_scale[i];
        a[i] = (a_raw[i] - s[S_BA + i] * k) * f->inv_scale[3 + i];
    }
}

/* mechanizes a part of a sample (raw increments over dt, or the raw rate sample at the
 * part's end) and accumulates it for the covariance */
static gf_status mech_part(gf_ins_filter *f, const double g_raw[3], const double a_raw[3],
                           double dt, double t_end)
{
    double g[3], a[3];
    compensate(f, g_raw, a_raw, dt, g, a);
    const gf_status st = gf_sins_step_trusted(&f->nav, g, a, dt);
    if (st != GF_OK)
        return st;
    if (f->cfg.input == GF_SINS_INPUT_INCREMENTS) {
        gf_v3_add(f->acc_dtheta_rad, g, f->acc_dtheta_rad);
        gf_v3_add(f->acc_dv_m_s, a, f->acc_dv_m_s);
        gf_v3_scale(g, 1.0 / dt, f->w_ib_b_rad_s);
        gf_v3_scale(a, 1.0 / dt, f->f_b_m_s2);
    } else {
        for (int i = 0; i < 3; ++i) {
            f->acc_dtheta_rad[i] += 0.5 * dt * (f->w_ib_b_rad_s[i] + g[i]);
            f->acc_dv_m_s[i] += 0.5 * dt * (f->f_b_m_s2[i] + a[i]);
        }
        gf_v3_copy(g, f->w_ib_b_rad_s);
        gf_v3_copy(a, f->f_b_m_s2);
    }
    f->acc_T_s += dt;
    f->t_s = t_end;
    f->nav.time_s = t_end;
    return GF_OK;
}

static void standstill_update(gf_ins_filter *f, double T)
{
    const double *w = f->w_ib_b_rad_s, *fb = f->f_b_m_s2;
    const double wn = gf_v3_norm(w), fn = gf_v3_norm(fb);
    if (f->n_imu == 0) {
        gf_v3_copy(fb, f->still_f);
        gf_v3_copy(w, f->still_w);
        f->still_fn = fn;
        f->still_fn2 = fn * fn;
        f->still_wn = wn;
    }
    const double a = fmin(1.0, T / f->cfg.still_window_s);   /* exponential average */
    for (int i = 0; i < 3; ++i) {
        f->still_f[i] += a * (fb[i] - f->still_f[i]);
        f->still_w[i] += a * (w[i] - f->still_w[i]);
    }
    f->still_fn += a * (fn - f->still_fn);
    f->still_fn2 += a * (fn * fn - f->still_fn2);
    f->still_wn += a * (wn - f->still_wn);
    const double sd = sqrt(fmax(0.0, f->still_fn2 - f->still_fn * f->still_fn));
    const double ta = f->cfg.still_accel_std_m_s2, tg = f->cfg.still_gyro_rad_s;
    const int quiet = sd < ta && f->still_wn < tg && wn < 3.0 * tg && fabs(fn - f->still_fn) < 3.0 * ta;
    f->still_time_s = quiet ? f->still_time_s + T : 0.0;
    f->standstill = f->still_time_s >= f->cfg.still_window_s;
}

static int meas_type_external(int32_t type)
{
    return (type >= GF_INS_MEAS_GNSS_POS && type <= GF_INS_MEAS_ODO) || type == GF_INS_MEAS_SPEED;
}

static gf_status meas_check(const gf_ins_meas *ms)
{
    if (!meas_type_external(ms->type))
        return GF_ERR_BAD_PARAMETER;
    const int m = meas_rows(ms->type);
    if (!isfinite(ms->t_s) || !gf_all_finite(ms->z, (size_t)m) || !gf_all_finite(ms->std, (size_t)m))
        return GF_ERR_NONFINITE_INPUT;
    for (int i = 0; i < m; ++i)
        if (!(ms->std[i] > 0.0))
            return GF_ERR_BAD_PARAMETER;
    if (ms->type == GF_INS_MEAS_GNSS_POS && !(fabs(ms->z[0]) < GF_HALF_PI))
        return GF_ERR_BAD_PARAMETER;
    return GF_OK;
}

/* ---- delayed measurements ---------------------------------------------------------------- */

static void history_push(gf_ins_filter *f)
{
    gf_ins_history *h = f->hist + f->hist_head;
    h->t_s = f->t_s;
    memcpy(h->q_bn, f->nav.q_bn, sizeof h->q_bn);
    gf_v3_copy(f->nav.v_n_m_s, h->v_n_m_s);
    h->lat_rad = f->nav.lat_rad;
    h->lon_rad = f->nav.lon_rad;
    h->h_m = f->nav.h_m;
    gf_v3_copy(f->w_ib_b_rad_s, h->w_ib_b_rad_s);
    f->hist_head = (f->hist_head + 1) % GF_INS_HISTORY;
    if (f->hist_count < GF_INS_HISTORY)
        f->hist_count++;
}

/* The nominal at time t from the history (linear between samples, the quaternion by
 * normalised linear interpolation); 0 if t is not covered. */
static int history_at(const gf_ins_filter *f, double t, gf_sins_state *ref, double w[3])
{
    for (int k = 0; k + 1 < f->hist_count; ++k) {
        /* newest first: b is the later entry, a the one before it */
        const int ib = (f->hist_head - 1 - k + 2 * GF_INS_HISTORY) % GF_INS_HISTORY;
        const int ia = (ib - 1 + GF_INS_HISTORY) % GF_INS_HISTORY;
        const gf_ins_history *a = f->hist + ia, *b = f->hist + ib;
        if (t > b->t_s + GF_INS_TIME_EPS_S)
            return 0;
        if (t < a->t_s - GF_INS_TIME_EPS_S)
            continue;
        const double u = b->t_s > a->t_s ? fmin(1.0, fmax(0.0, (t - a->t_s) / (b->t_s - a->t_s))) : 1.0;
        double q[4], v[3];
        const double sgn = gf_v3_dot(a->q_bn + 1, b->q_bn + 1) + a->q_bn[0] * b->q_bn[0] < 0 ? -1.0 : 1.0;
        for (int i = 0; i < 4; ++i)
            q[i] = (1.0 - u) * a->q_bn[i] + u * sgn * b->q_bn[i];
        for (int i = 0; i < 3; ++i) {
            v[i] = (1.0 - u) * a->v_n_m_s[i] + u * b->v_n_m_s[i];
            w[i] = (1.0 - u) * a->w_ib_b_rad_s[i] + u * b->w_ib_b_rad_s[i];
        }
        *ref = f->nav;
        return gf_sins_set_navigation(ref, q, v, (1.0 - u) * a->lat_rad + u * b->lat_rad,
                                      a->lon_rad + u * wrap_pi(b->lon_rad - a->lon_rad),
                                      (1.0 - u) * a->h_m + u * b->h_m) == GF_OK;
    }
    return 0;
}

/* A measurement valid at or before the filter's time: a delayed update, or stale. */
static gf_status past_measurement(gf_ins_filter *f, const gf_ins_meas *ms, gf_ins_epochs *ep,
                                  gf_ins_log *log)
{
    gf_sins_state ref;
    double w[3];
    if (f->cfg.max_latency_s > 0.0 && dir_of(f) > 0.0 && f->t_s - ms->t_s <= f->cfg.max_latency_s &&
        history_at(f, ms->t_s, &ref, w)) {
        const gf_status st = propagate(f, ep);
        if (st != GF_OK)
            return st;
        return update_at(f, ms->type, ms, 0.0, &ref, w, ep, log);
    }
    f->n_rejected++;
    log_entry(log, ms->t_s, ms->type, GF_INS_REJECTED_STALE, meas_rows(ms->type), NAN, NULL, NULL);
    return GF_OK;
}

/* what sizes or indexes arrays in a filter handed in by a caller (cheap: every step) */
static int layout_is_valid(const gf_ins_filter *f)
{
    const int n = f->n_states;
    if (n < GF_INS_BASE_STATES || n > NMAX || (size_t)n != f->kf.n)
        return 0;
    const int32_t idx[5] = {f->idx_sg, f->idx_sa, f->idx_baro, f->idx_odo, f->idx_mount};
    const int len[5] = {3, 3, 1, 1, 2};
    for (int i = 0; i < 5; ++i)
        if (idx[i] != -1 && (idx[i] < GF_INS_BASE_STATES || idx[i] + len[i] > n))
            return 0;
    return f->ukf_w.n == (size_t)n && f->hist_head >= 0 && f->hist_head < GF_INS_HISTORY &&
           f->hist_count >= 0 && f->hist_count <= GF_INS_HISTORY;
}

gf_status gf_ins_filter_check(const gf_ins_filter *f)
{
    if (!f)
        return GF_ERR_NULL_POINTER;
    int32_t n = 0;
    if (config_check(&f->cfg) || gf_ins_state_count(&f->cfg, &n) != GF_OK || f->n_states != n ||
        !layout_is_valid(f))
        return GF_ERR_BAD_SIZE;
    int32_t next = GF_INS_BASE_STATES;
    const int32_t sg = f->cfg.scale_states ? next : -1;
    next += f->cfg.scale_states ? 6 : 0;
    const int32_t baro = f->cfg.baro_state ? next++ : -1;
    const int32_t odo = f->cfg.odo_state ? next++ : -1;
    const int32_t mount = f->cfg.odo_mount_state ? next : -1;
    if (f->idx_sg != sg || f->idx_sa != (sg < 0 ? -1 : sg + 3) || f->idx_baro != baro ||
        f->idx_odo != odo || f->idx_mount != mount)
        return GF_ERR_BAD_SIZE;
    if ((f->have_sample & ~1) || (f->standstill & ~1))
        return GF_ERR_BAD_PARAMETER;
    for (int i = 0; i < GF_INS_N_MEAS_KINDS; ++i)
        if (f->gate_run[i] < 0)
            return GF_ERR_BAD_PARAMETER;
    if (gf_sins_state_check(&f->nav) != GF_OK || gf_sins_state_check(&f->nav0) != GF_OK ||
        f->nav.cfg.vertical != GF_SINS_VERTICAL_FREE || f->nav.cfg.earth != GF_SINS_EARTH_WGS84 ||
        f->nav.cfg.input != f->cfg.input)
        return GF_ERR_BAD_PARAMETER;
    if (!isfinite(f->t_s) || !gf_all_finite(f->sensors, GF_INS_N_SENSORS) ||
        !gf_all_finite(f->kf.x, (size_t)n))
        return GF_ERR_NONFINITE_INPUT;
    for (int i = 0; i < n; ++i)
        if (!(f->kf.P[i * n + i] > 0.0) || !isfinite(f->kf.P[i * n + i]))
            return GF_ERR_BAD_PARAMETER;
    return GF_OK;
}

/* the measurement as the filter uses it: in reverse (gf_ins_reverse) velocities change
 * sign (GNSS velocity, odometer forward speed); positions, heights and the tachometer's
 * speed magnitude do not */
static void meas_directed(const gf_ins_filter *f, const gf_ins_meas *in, gf_ins_meas *out)
{
    *out = *in;
    if (dir_of(f) < 0.0 && (in->type == GF_INS_MEAS_GNSS_VEL || in->type == GF_INS_MEAS_ODO))
        for (int i = 0; i < 3; ++i)
            out->z[i] = -in->z[i];
}

/* gf_ins_step after its checks of the pointers and of the filter's layout (gf_ins_run
 * makes them once for its whole record: nothing in a step changes the layout). The
 * measurements are meas[0], meas[stride], ... (stride -1: a backward walk over a record
 * stored in increasing time). Times are compared in the filter's direction: with
 * dir = -1 (reversed) time decreases, and every difference below is dir * (a - b). */
/* A sample within the absurd-sample limits: |gyro| <= max_rate k, |accel| <= max_f k
 * (k = 1 for rates, the interval for increments; NaN fails) */
static inline int within_limits(const gf_ins_config *c, const double g[3], const double a[3],
                                double k)
{
    const double wm = c->max_rate_rad_s * k, fm = c->max_specific_force_m_s2 * k;
    return gf_v3_dot(g, g) <= wm * wm && gf_v3_dot(a, a) <= fm * fm;
}

/* After a sample (or a group of them) that ends at the filter's time: on the regular
 * grid, the covariance propagation and the internal updates (NHC, ZUPT, ZARU) that are due.
 * Measurement instants propagate too, but do not move the grid. */
static gf_status regular_updates(gf_ins_filter *f, gf_ins_epochs *epochs, gf_ins_log *log)
{
    const double dir = dir_of(f), t_s = f->t_s;
    if (!(dir * (t_s - f->last_regular_t_s) >= f->cfg.prop_interval_s - GF_INS_TIME_EPS_S))
        return GF_OK;
    f->last_regular_t_s = t_s;
    gf_status st = propagate(f, epochs);
    if (st == GF_OK && f->cfg.nhc &&
        dir * (t_s - f->last_nhc_t_s) >= f->cfg.nhc_interval_s - GF_INS_TIME_EPS_S) {
        f->last_nhc_t_s = t_s;
        st = update(f, GF_INS_MEAS_NHC, NULL, f->cfg.nhc_std_m_s, epochs, log);
    }
    if (st == GF_OK && f->cfg.zupt && f->standstill &&
        dir * (t_s - f->last_zupt_t_s) >= f->cfg.zupt_interval_s - GF_INS_TIME_EPS_S) {
        f->last_zupt_t_s = t_s;
        st = update(f, GF_INS_MEAS_ZUPT, NULL, f->cfg.zupt_std_m_s, epochs, log);
        if (st == GF_OK && f->cfg.zaru_std_rad_s > 0.0)
            st = update(f, GF_INS_MEAS_ZARU, NULL, f->cfg.zaru_std_rad_s, epochs, log);
    }
    return st;
}

static gf_status ins_step(gf_ins_filter *f, double t_s, const double *gyro_in, const double *accel,
                          size_t n_meas, const gf_ins_meas *meas, ptrdiff_t stride,
                          gf_ins_epochs *epochs, gf_ins_log *log)
{
    if (!isfinite(t_s) || !gf_all_finite(gyro_in, 3) || !gf_all_finite(accel, 3))
        return GF_ERR_NONFINITE_INPUT;
    const double dir = dir_of(f);
    /* reverse navigation: the gyro increments (or rates) change sign, dv does not */
    const double gyro[3] = {dir * gyro_in[0], dir * gyro_in[1], dir * gyro_in[2]};
    const int rates = f->cfg.input == GF_SINS_INPUT_RATES;
    const int first_rate = rates && !f->have_sample;
    const double t_prev = f->t_s;
    const double T = dir * (t_s - t_prev);
    if (!first_rate && !(T > 0.0 && T <= f->cfg.max_imu_gap_s))
        return GF_ERR_BAD_TIME;
    if (first_rate && T < 0.0)
        return GF_ERR_BAD_TIME;
#define MS(j) (meas + (ptrdiff_t)(j) * stride)
    for (size_t j = 0; j < n_meas; ++j) {
        const gf_status st = meas_check(MS(j));
        if (st != GF_OK)
            return st;
        if (dir * (MS(j)->t_s - t_s) > GF_INS_TIME_EPS_S ||
            (j && dir * (MS(j)->t_s - MS(j - 1)->t_s) < 0.0))
            return GF_ERR_BAD_TIME;
    }
    if (epochs && (epochs->count > epochs->capacity ||
                   epochs->capacity - epochs->count < n_meas + 2))
        return GF_ERR_BAD_SIZE;
    /* the absurd-sample limits, checked here so that an error leaves the filter unchanged */
    if (!within_limits(&f->cfg, gyro, accel, rates ? 1.0 : T))
        return GF_ERR_OUT_OF_RANGE;

    gf_status st = GF_OK;
    if (first_rate) {
        /* a rate record's first sample starts it: no interval, no motion */
        double g[3], a[3];
        compensate(f, gyro, accel, 0.0, g, a);
        st = gf_sins_step_trusted(&f->nav, g, a, 0.0);
        if (st != GF_OK)
            return st;
        gf_v3_copy(g, f->w_ib_b_rad_s);
        gf_v3_copy(a, f->f_b_m_s2);
        f->t_s = t_s;
        f->nav.time_s = t_s;
        for (size_t j = 0; j < n_meas && st == GF_OK; ++j) {
            gf_ins_meas ms;
            meas_directed(f, MS(j), &ms);
            st = fabs(ms.t_s - f->t_s) <= GF_INS_TIME_EPS_S ? update(f, ms.type, &ms, 0.0, epochs, log)
                                                            : past_measurement(f, &ms, epochs, log);
        }
        if (st != GF_OK)
            return st;
    } else {
        double rem_g[3], rem_a[3];
        gf_v3_copy(gyro, rem_g);
        gf_v3_copy(accel, rem_a);
        double t_cur = t_prev;
        int done = 0;
        for (size_t j = 0; j < n_meas && st == GF_OK; ++j) {
            gf_ins_meas msd;
            meas_directed(f, MS(j), &msd);
            const gf_ins_meas *ms = &msd;
            if (dir * (ms->t_s - t_prev) <= GF_INS_TIME_EPS_S) {
                /* valid at the filter's time (the first sample of a record whose first
                 * measurement is at its start): applied there; earlier: delayed or stale */
                if (fabs(ms->t_s - t_prev) <= GF_INS_TIME_EPS_S) {
                    st = propagate(f, epochs);
                    if (st == GF_OK)
                        st = update(f, ms->type, ms, 0.0, epochs, log);
                } else {
                    st = past_measurement(f, ms, epochs, log);
                }
                continue;
            }
            if (!done && dir * (ms->t_s - t_s) < -GF_INS_TIME_EPS_S) {
                if (dir * (ms->t_s - t_cur) > GF_INS_TIME_EPS_S) {
                    /* split the interval at the time of validity */
                    const double dt = dir * (ms->t_s - t_cur);
                    double pg[3], pa[3];
                    if (rates) {
                        const double u = dir * (ms->t_s - t_prev) / T;
                        for (int i = 0; i < 3; ++i) {
                            pg[i] = f->prev_gyro_raw[i] + u * (gyro[i] - f->prev_gyro_raw[i]);
                            pa[i] = f->prev_accel_raw[i] + u * (accel[i] - f->prev_accel_raw[i]);
                        }
                    } else {
                        const double u = dt / (dir * (t_s - t_cur));
                        for (int i = 0; i < 3; ++i) {
                            pg[i] = u * rem_g[i];
                            pa[i] = u * rem_a[i];
                            rem_g[i] -= pg[i];
                            rem_a[i] -= pa[i];
                        }
                    }
                    st = mech_part(f, pg, pa, dt, ms->t_s);
                    t_cur = ms->t_s;
                }
            } else if (!done) {
                st = mech_part(f, rem_g, rem_a, dir * (t_s - t_cur), t_s);
                t_cur = t_s;
                done = 1;
            }
            if (st == GF_OK)
                st = propagate(f, epochs);
            if (st == GF_OK)
                st = update(f, ms->type, ms, 0.0, epochs, log);
        }
        if (st == GF_OK && !done)
            st = mech_part(f, rem_g, rem_a, dir * (t_s - t_cur), t_s);
        if (st != GF_OK)
            return st;
        if (f->cfg.zupt)
            standstill_update(f, T);
        st = regular_updates(f, epochs, log);
        if (st != GF_OK)
            return st;
    }
#undef MS
    gf_v3_copy(gyro, f->prev_gyro_raw);
    gf_v3_copy(accel, f->prev_accel_raw);
    f->have_sample = 1;
    f->n_imu++;
    if (f->cfg.max_latency_s > 0.0 && dir > 0.0)
        history_push(f);
    return GF_OK;
}

/* Samples k .. k+m-1 of a forward run (t_s, gyro, accel point at sample k) as one
 * navigation update of gf_sins_step_group (cfg.subsamples = m), when nothing needs the
 * state inside the group: no measurement valid before the end of its last sample (t_meas
 * is the next one's time, +inf if none), no propagation instant at its first m-1
 * samples, no standstill detector or delayed-measurement history (per-sample), the
 * intervals within 1% of their mean (the m-sample coning and sculling coefficients
 * assume equal sub-intervals), every sample passing ins_step's checks, room for the
 * epochs. 0: not applicable — the caller steps the samples one by one, which reports a
 * faulty sample at its index; otherwise the status of the update. */
static gf_status group_step(gf_ins_filter *f, int m, const double *t_s, const double *gyro,
                            const double *accel, double t_meas, gf_ins_epochs *epochs,
                            gf_ins_log *log, int *applied)
{
    *applied = 0;
    const gf_ins_config *c = &f->cfg;
    if (!(t_meas - t_s[m - 1] > GF_INS_TIME_EPS_S) ||
        !(t_s[m - 2] - f->last_regular_t_s < c->prop_interval_s - GF_INS_TIME_EPS_S))
        return GF_OK;
    if (epochs && (epochs->count > epochs->capacity || epochs->capacity - epochs->count < 2))
        return GF_OK;
    const double mean = (t_s[m - 1] - f->t_s) / (double)m;
    double dt[GF_SINS_MAX_SUBSAMPLES], g[3 * GF_SINS_MAX_SUBSAMPLES], a[3 * GF_SINS_MAX_SUBSAMPLES];
    for (int i = 0; i < m; ++i) {
        const double *gi = gyro + 3 * i, *ai = accel + 3 * i;
        dt[i] = t_s[i] - (i ? t_s[i - 1] : f->t_s);
        if (!(fabs(dt[i] - mean) <= 0.01 * mean && dt[i] <= c->max_imu_gap_s) ||
            !gf_all_finite(gi, 3) || !gf_all_finite(ai, 3))
            return GF_OK;
        if (!within_limits(c, gi, ai, dt[i]))
            return GF_OK;
        compensate(f, gi, ai, dt[i], g + 3 * i, a + 3 * i);
    }
    *applied = 1;
    gf_status st = gf_sins_step_group_trusted(&f->nav, m, g, a, dt);
    if (st != GF_OK)
        return st;
    for (int i = 0; i < m; ++i) {
        gf_v3_add(f->acc_dtheta_rad, g + 3 * i, f->acc_dtheta_rad);
        gf_v3_add(f->acc_dv_m_s, a + 3 * i, f->acc_dv_m_s);
    }
    const int l = m - 1;
    gf_v3_scale(g + 3 * l, 1.0 / dt[l], f->w_ib_b_rad_s);
    gf_v3_scale(a + 3 * l, 1.0 / dt[l], f->f_b_m_s2);
    f->acc_T_s += t_s[l] - f->t_s;
    f->t_s = t_s[l];
    f->nav.time_s = t_s[l];
    gf_v3_copy(gyro + 3 * l, f->prev_gyro_raw);
    gf_v3_copy(accel + 3 * l, f->prev_accel_raw);
    f->have_sample = 1;
    f->n_imu += (uint64_t)m;
    return regular_updates(f, epochs, log);
}

gf_status gf_ins_step(gf_ins_filter *f, double t_s, const double *gyro, const double *accel,
                      size_t n_meas, const gf_ins_meas *meas, gf_ins_epochs *epochs,
                      gf_ins_log *log)
{
    if (!f || !gyro || !accel || (n_meas && !meas))
        return GF_ERR_NULL_POINTER;
    if (!layout_is_valid(f))
        return GF_ERR_BAD_PARAMETER;
    return ins_step(f, t_s, gyro, accel, n_meas, meas, 1, epochs, log);
}

/* row k of the outputs: true-time velocity and gyro bias (reverse filtering negates them) */
static void write_output(const gf_ins_filter *f, const gf_ins_output *out, size_t k)
{
    const double dir = dir_of(f);
    out->t_s[k] = f->t_s;
    memcpy(out->q_bn + 4 * k, f->nav.q_bn, 4 * sizeof(double));
    gf_v3_scale(f->nav.v_n_m_s, dir, out->v_n_m_s + 3 * k);
    out->pos[3 * k] = f->nav.lat_rad;
    out->pos[3 * k + 1] = f->nav.lon_rad;
    out->pos[3 * k + 2] = f->nav.h_m;
    if (out->std)
        memcpy(out->std + 9 * k, f->std9, sizeof f->std9);
    if (out->sensors) {
        double *s = out->sensors + GF_INS_N_SENSORS * k;
        memcpy(s, f->sensors, sizeof f->sensors);
        gf_v3_scale(f->sensors + S_BG, dir, s + S_BG);
    }
    if (out->standstill)
        out->standstill[k] = (int8_t)f->standstill;
}

static int output_ok(const gf_ins_output *out)
{
    return !out || (out->t_s && out->q_bn && out->v_n_m_s && out->pos);
}

/* Forward over samples 0..n-1 in the order given (gf_ins_run), or backward over a record
 * stored in increasing time (gf_ins_run_backward: sample k = n-1 .. 0 takes the state to
 * t_s[k-1], t_start_s for k = 0, with increments; to t_s[k] with rates). out may be NULL. */
static gf_status walk(gf_ins_filter *f, int backward, size_t n, const double *t_s,
                      const double *gyro, const double *accel, double t_start_s, size_t n_meas,
                      const gf_ins_meas *meas, gf_ins_output *out, gf_ins_epochs *epochs,
                      gf_ins_log *log, size_t *n_done, size_t *meas_done)
{
    size_t k = 0, used = 0, row = 0;
    gf_status st = GF_OK;
    if (!backward) {
        const double dir = dir_of(f);
        /* groups of m samples (cfg.subsamples) on the grid of the filter's sample count,
         * so that a record cut into calls at multiples of m is processed as one */
        const int m = f->cfg.subsamples;
        const int grouping = m > 1 && dir > 0.0 && !f->cfg.zupt && f->cfg.max_latency_s == 0.0 &&
                             f->cfg.input == GF_SINS_INPUT_INCREMENTS;
        while (k < n) {
            if (grouping && n - k >= (size_t)m && f->n_imu % (uint64_t)m == 0) {
                int applied;
                const double t_meas = used < n_meas ? meas[used].t_s : INFINITY;
                st = group_step(f, m, t_s + k, gyro + 3 * k, accel + 3 * k, t_meas, epochs, log,
                                &applied);
                if (st != GF_OK)
                    break;
                if (applied) {
                    k += (size_t)m;
                    if (out)
                        write_output(f, out, row++);
                    continue;
                }
            }
            size_t cnt = 0;
            while (used + cnt < n_meas && dir * (meas[used + cnt].t_s - t_s[k]) <= GF_INS_TIME_EPS_S)
                ++cnt;
            st = ins_step(f, t_s[k], gyro + 3 * k, accel + 3 * k, cnt, meas + used, 1, epochs, log);
            if (st != GF_OK)
                break;
            used += cnt;
            ++k;
            if (out)
                write_output(f, out, row++);
        }
    } else {
        const int rates = f->cfg.input == GF_SINS_INPUT_RATES;
        /* measurements after the filter's time stay (they belong to a later period) */
        size_t top = n_meas;
        while (top > 0 && meas[top - 1].t_s > f->t_s + GF_INS_TIME_EPS_S)
            --top;
        for (; k < n; ++k) {
            const size_t r = n - 1 - k;
            const double t_new = rates ? t_s[r] : (r ? t_s[r - 1] : t_start_s);
            size_t cnt = 0;
            while (used + cnt < top && meas[top - 1 - used - cnt].t_s >= t_new - GF_INS_TIME_EPS_S)
                ++cnt;
            st = ins_step(f, t_new, gyro + 3 * r, accel + 3 * r, cnt,
                          cnt ? meas + (top - 1 - used) : meas, -1, epochs, log);
            if (st != GF_OK)
                break;
            used += cnt;
            if (out)
                write_output(f, out, r);
        }
        row = k;
    }
    if (out)
        out->n_rows = row;
    if (n_done)
        *n_done = k;
    if (meas_done)
        *meas_done = used;
    return st;
}

gf_status gf_ins_run(gf_ins_filter *f, size_t n, const double *t_s, const double *gyro,
                     const double *accel, size_t n_meas, const gf_ins_meas *meas,
                     gf_ins_output *out, gf_ins_epochs *epochs, gf_ins_log *log,
                     size_t *n_done, size_t *meas_done)
{
    if (n_done)
        *n_done = 0;
    if (meas_done)
        *meas_done = 0;
    if (!f || !t_s || !gyro || !accel || !out || !output_ok(out) || (n_meas && !meas))
        return GF_ERR_NULL_POINTER;
    if (!layout_is_valid(f))
        return GF_ERR_BAD_PARAMETER;
    const double dir = dir_of(f);
    for (size_t j = 1; j < n_meas; ++j)
        if (!(dir * (meas[j].t_s - meas[j - 1].t_s) >= 0.0))
            return GF_ERR_BAD_TIME;
    return walk(f, 0, n, t_s, gyro, accel, 0.0, n_meas, meas, out, epochs, log, n_done, meas_done);
}

/* checks of a record stored in increasing time, and of its measurements */
static gf_status record_check(size_t n, const double *t_s, size_t n_meas, const gf_ins_meas *meas)
{
    for (size_t k = 0; k < n; ++k)
        if (!isfinite(t_s[k]))
            return GF_ERR_NONFINITE_INPUT;
    for (size_t k = 1; k < n; ++k)
        if (!(t_s[k] > t_s[k - 1]))
            return GF_ERR_BAD_TIME;
    for (size_t j = 1; j < n_meas; ++j)
        if (!(meas[j].t_s >= meas[j - 1].t_s))
            return GF_ERR_BAD_TIME;
    return GF_OK;
}

gf_status gf_ins_run_backward(gf_ins_filter *f, size_t n, const double *t_s, const double *gyro,
                              const double *accel, double t_start_s, size_t n_meas,
                              const gf_ins_meas *meas, gf_ins_output *out, gf_ins_log *log,
                              size_t *n_done, size_t *meas_done)
{
    if (n_done)
        *n_done = 0;
    if (meas_done)
        *meas_done = 0;
    if (!f || !t_s || !gyro || !accel || !output_ok(out) || (n_meas && !meas))
        return GF_ERR_NULL_POINTER;
    if (!layout_is_valid(f) || dir_of(f) > 0.0)
        return GF_ERR_BAD_PARAMETER;
    if (n == 0)
        return GF_OK;
    gf_status st = record_check(n, t_s, n_meas, meas);
    if (st != GF_OK)
        return st;
    const int rates = f->cfg.input == GF_SINS_INPUT_RATES;
    if (!isfinite(t_start_s) || (!rates && !(t_start_s < t_s[0])))
        return GF_ERR_BAD_TIME;
    if (fabs(f->t_s - t_s[n - 1]) > GF_INS_TIME_EPS_S)
        return GF_ERR_BAD_TIME;
    return walk(f, 1, n, t_s, gyro, accel, t_start_s, n_meas, meas, out, NULL, log, n_done,
                meas_done);
}

/* ---- reverse-time filtering and forward-backward processing (seed 003) ------------------- */

gf_status gf_ins_reverse(gf_ins_filter *f)
{
    if (!f)
        return GF_ERR_NULL_POINTER;
    if (!layout_is_valid(f))
        return GF_ERR_BAD_PARAMETER;
    /* the covariance at the turning point (no epochs: the smoother does not cross it) */
    gf_status st = propagate(f, NULL);
    if (st != GF_OK)
        return st;
    st = gf_sins_reverse(&f->nav);
    if (st != GF_OK)
        return st;
    /* x_r = D x, P_r = D P D, D = -1 on dv and dbg (derivation in the header) */
    const int n = f->n_states;
    double d[NMAX];
    for (int i = 0; i < n; ++i)
        d[i] = 1.0;
    for (int i = 0; i < 3; ++i)
        d[IV + i] = d[IBG + i] = -1.0;
    for (int i = 0; i < n; ++i) {
        f->kf.x[i] *= d[i];
        for (int j = 0; j < n; ++j)
            f->kf.P[i * n + j] *= d[i] * d[j];
    }
    for (int i = 0; i < 3; ++i) {
        f->sensors[S_BG + i] = -f->sensors[S_BG + i];
        f->w_ib_b_rad_s[i] = -f->w_ib_b_rad_s[i];
        f->prev_gyro_raw[i] = -f->prev_gyro_raw[i];
        f->still_w[i] = -f->still_w[i];
    }
    f->nav0 = f->nav;
    memcpy(f->sensors0, f->sensors, sizeof f->sensors);
    if (f->cfg.input == GF_SINS_INPUT_RATES)
        f->have_sample = 0;          /* the next sample (the same instant) restarts the record */
    const double dir = dir_of(f);
    f->last_regular_t_s = f->t_s;
    f->last_nhc_t_s = f->last_zupt_t_s = -dir * INFINITY;
    f->hist_head = f->hist_count = 0;
    refresh_scale(f);
    refresh_std(f);
    return GF_OK;
}

static void pass_write(const gf_ins_filter *f, gf_ins_pass *p, uint64_t upd0, uint64_t rej0)
{
    const double dir = dir_of(f);
    p->direction = (int32_t)dir;
    p->t_s = f->t_s;
    memcpy(p->q_bn, f->nav.q_bn, sizeof p->q_bn);
    gf_v3_scale(f->nav.v_n_m_s, dir, p->v_n_m_s);
    memcpy(p->std9, f->std9, sizeof p->std9);
    memcpy(p->sensors, f->sensors, sizeof p->sensors);
    gf_v3_scale(f->sensors + S_BG, dir, p->sensors + S_BG);
    p->n_updates = f->n_updates - upd0;
    p->n_rejected = f->n_rejected - rej0;
}

gf_status gf_ins_forward_backward(gf_ins_filter *f, size_t n, const double *t_s,
                                  const double *gyro, const double *accel, size_t n_meas,
                                  const gf_ins_meas *meas, int32_t n_fb, gf_ins_pass *passes,
                                  gf_ins_log *log, int32_t *n_passes_done)
{
    if (n_passes_done)
        *n_passes_done = 0;
    if (!f || !t_s || !gyro || !accel || (n_meas && !meas))
        return GF_ERR_NULL_POINTER;
    if (!layout_is_valid(f) || dir_of(f) < 0.0 || n_fb < 0 || n_fb > 10000)
        return GF_ERR_BAD_PARAMETER;
    if (n < 2)
        return GF_ERR_BAD_SIZE;
    gf_status st = record_check(n, t_s, n_meas, meas);
    if (st != GF_OK)
        return st;
    const double t_start = f->t_s;
    /* a measurement at a turning point (the start or the end of the record) was applied
     * at the end of the pass before: the next pass leaves it out (no double use at one
     * instant) */
    size_t j_first = 0, n_before_end = n_meas;
    while (j_first < n_meas && meas[j_first].t_s <= t_start + GF_INS_TIME_EPS_S)
        ++j_first;
    while (n_before_end > 0 && meas[n_before_end - 1].t_s >= t_s[n - 1] - GF_INS_TIME_EPS_S)
        --n_before_end;
    for (int32_t p = 0; p <= 2 * n_fb; ++p) {
        const uint64_t upd0 = f->n_updates, rej0 = f->n_rejected;
        const int backward = p % 2 == 1;
        if (p > 0) {
            st = gf_ins_reverse(f);
            if (st != GF_OK)
                return st;
        }
        if (backward)
            st = walk(f, 1, n, t_s, gyro, accel, t_start, n_before_end, meas, NULL, NULL, log,
                      NULL, NULL);
        else if (p == 0)
            st = walk(f, 0, n, t_s, gyro, accel, t_start, n_meas, meas, NULL, NULL, log, NULL,
                      NULL);
        else
            st = walk(f, 0, n, t_s, gyro, accel, t_start, n_meas - j_first, meas + j_first, NULL,
                      NULL, log, NULL, NULL);
        if (st != GF_OK) {
            if (backward)           /* hand the filter back forward in time */
                gf_ins_reverse(f);
            return st;
        }
        if (passes)
            pass_write(f, passes + p, upd0, rej0);
        if (n_passes_done)
            *n_passes_done = p + 1;
    }
    return GF_OK;
}

/* ---- coarse alignment at rest (for the FMU's alignment phase) ----------------------------- */

/* q_bn of C_b^n whose rows are the east, north and up unit vectors in body axes */
static void q_from_enu_axes(const double *e, const double *n, const double *u, double *q_bn)
{
    gf_mat3 C;
    for (int j = 0; j < 3; ++j) {
        C.m[0][j] = e[j];
        C.m[1][j] = n[j];
        C.m[2][j] = u[j];
    }
    gf_q_from_dcm(&C, q_bn);
    gf_q_normalize(q_bn, q_bn);
}

gf_status gf_ins_coarse_align(const double *f_b_m_s2, const double *w_b_rad_s, double *q_bn)
{
    if (!f_b_m_s2 || !w_b_rad_s || !q_bn)
        return GF_ERR_NULL_POINTER;
    if (!gf_all_finite(f_b_m_s2, 3) || !gf_all_finite(w_b_rad_s, 3))
        return GF_ERR_NONFINITE_INPUT;
    const double fn = gf_v3_norm(f_b_m_s2), wn = gf_v3_norm(w_b_rad_s);
    if (!(fn > 5.0 && fn < 15.0))
        return GF_ERR_SINGULAR_GEOMETRY;
    double e[3], u[3], nn[3];
    gf_v3_cross(w_b_rad_s, f_b_m_s2, e);
    const double en = gf_v3_norm(e);
    if (!(en > 1e-3 * wn * fn) || !(wn > 0.0))
        return GF_ERR_SINGULAR_GEOMETRY;
    gf_v3_scale(e, 1.0 / en, e);
    gf_v3_scale(f_b_m_s2, 1.0 / fn, u);
    gf_v3_cross(u, e, nn);
    q_from_enu_axes(e, nn, u, q_bn);
    return GF_OK;
}

gf_status gf_ins_level_align(const double *f_b_m_s2, double *q_bn)
{
    if (!f_b_m_s2 || !q_bn)
        return GF_ERR_NULL_POINTER;
    if (!gf_all_finite(f_b_m_s2, 3))
        return GF_ERR_NONFINITE_INPUT;
    const double fn = gf_v3_norm(f_b_m_s2);
    if (!(fn > 5.0 && fn < 15.0))
        return GF_ERR_SINGULAR_GEOMETRY;
    double u[3], nn[3], e[3];
    gf_v3_scale(f_b_m_s2, 1.0 / fn, u);
    /* north: the forward axis y = (0, 1, 0) minus its vertical part */
    nn[0] = -u[1] * u[0];
    nn[1] = 1.0 - u[1] * u[1];
    nn[2] = -u[1] * u[2];
    const double nnn = gf_v3_norm(nn);
    if (!(nnn > 1e-3))   /* |horizontal part of y| = sqrt(1 - u_y^2): pitch within 0.06 deg of 90 */
        return GF_ERR_SINGULAR_GEOMETRY;
    gf_v3_scale(nn, 1.0 / nnn, nn);
    gf_v3_cross(nn, u, e);
    q_from_enu_axes(e, nn, u, q_bn);
    return GF_OK;
}

gf_status gf_ins_rotate_heading(double *q_bn, double *v_n_m_s, double dpsi_rad)
{
    if (!q_bn)
        return GF_ERR_NULL_POINTER;
    if (!gf_all_finite(q_bn, 4) || !isfinite(dpsi_rad) || (v_n_m_s && !gf_all_finite(v_n_m_s, 3)))
        return GF_ERR_NONFINITE_INPUT;
    /* the heading is clockwise from north: a rotation by -dpsi about up */
    const double r[4] = {cos(0.5 * dpsi_rad), 0.0, 0.0, -sin(0.5 * dpsi_rad)};
    gf_q_mul(r, q_bn, q_bn);
    gf_q_normalize(q_bn, q_bn);
    if (v_n_m_s) {
        const double c = cos(dpsi_rad), s = sin(dpsi_rad), ve = v_n_m_s[0], vn = v_n_m_s[1];
        v_n_m_s[0] = c * ve + s * vn;
        v_n_m_s[1] = -s * ve + c * vn;
    }
    return GF_OK;
}

/* ---- smoother and helpers ------------------------------------------------------------------ */

gf_status gf_ins_smooth(size_t n, const gf_ins_epochs *ep, double *xs, double *Ps)
{
    if (!ep || !xs || !Ps || !ep->P_post || !ep->P_prior || !ep->Phi || !ep->dx)
        return GF_ERR_NULL_POINTER;
    if (n == 0 || n > NMAX)
        return GF_ERR_BAD_SIZE;
    const size_t E = ep->count, tri = n * (n + 1) / 2;
    if (E == 0)
        return GF_OK;
    memset(xs + n * (E - 1), 0, n * sizeof *xs);
    if (Ps != ep->P_post)
        memcpy(Ps + tri * (E - 1), ep->P_post + tri * (E - 1), tri * sizeof *Ps);
    double Ppost[NMAX * NMAX], Pprior[NMAX * NMAX], Psn[NMAX * NMAX], Pk[NMAX * NMAX];
    double xnext[NMAX];
    for (size_t e = E - 1; e-- > 0;) {
        unpack_upper(n, ep->P_post + tri * e, Ppost);
        unpack_upper(n, ep->P_prior + tri * (e + 1), Pprior);
        unpack_upper(n, Ps + tri * (e + 1), Psn);
        /* the smoothed error of the prior nominal at e+1 = that of its posterior + dx */
        for (size_t i = 0; i < n; ++i)
            xnext[i] = xs[n * (e + 1) + i] + ep->dx[n * (e + 1) + i];
        const gf_status st = gf_kalman_rts_step(n, Ppost, NULL, ep->Phi + n * n * (e + 1), Pprior,
                                                NULL, Psn, xnext, xs + n * e, Pk);
        if (st != GF_OK)
            return st;
        pack_upper(n, Pk, Ps + tri * e);
    }
    return GF_OK;
}

gf_status gf_ins_apply_error(const gf_ins_filter *f, const double *dx, double *nav,
                             double *sensors)
{
    if (!f || !dx || !nav)
        return GF_ERR_NULL_POINTER;
    if (!gf_all_finite(dx, (size_t)f->n_states) || !gf_all_finite(nav, 10))
        return GF_ERR_NONFINITE_INPUT;
    const double zero[GF_INS_N_SENSORS] = {0};
    nav_hyp hy;
    hyp_from_error(f, nav, nav + 4, nav[7], nav[8], nav[9], sensors ? sensors : zero, dx, &hy);
    memcpy(nav, hy.q, 4 * sizeof *nav);
    gf_v3_copy(hy.v, nav + 4);
    nav[7] = hy.lat;
    nav[8] = wrap_pi(hy.lon);
    nav[9] = hy.h;
    if (sensors)
        memcpy(sensors, hy.s, GF_INS_N_SENSORS * sizeof *sensors);
    return GF_OK;
}

/* inverse of the standard normal distribution (Acklam's rational approximation with one
 * Newton step on erfc: relative error ~1e-15) */
static double normal_quantile(double p)
{
    static const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02,
                               -2.759285104469687e+02, 1.383577518672690e+02,
                               -3.066479806614716e+01, 2.506628277459239e+00};
    static const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02,
                               -1.556989798598866e+02, 6.680131188771972e+01,
                               -1.328068155288572e+01};
    static const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01,
                               -2.400758277161838e+00, -2.549732539343734e+00,
                               4.374664141464968e+00, 2.938163982698783e+00};
    static const double d[] = {7.784695709041462e-03, 3.224671290700398e-01,
                               2.445134137142996e+00, 3.754408661907416e+00};
    double x;
    if (p < 0.02425) {
        const double q = sqrt(-2.0 * log(p));
        x = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
            ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
    } else if (p <= 1.0 - 0.02425) {
        const double q = p - 0.5, r = q * q;
        x = (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
            (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0);
    } else {
        const double q = sqrt(-2.0 * log(1.0 - p));
        x = -(((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
            ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
    }
    const double e = 0.5 * erfc(-x / sqrt(2.0)) - p;
    const double u = e * sqrt(2.0 * GF_PI) * exp(0.5 * x * x);
    return x - u / (1.0 + 0.5 * x * u);
}

/* chi-square distribution function for integer m by its closed forms:
 *   m = 2k:     1 - e^(-x/2) sum_{i<k} (x/2)^i / i!
 *   m = 2k + 1: erf(sqrt(x/2)) - e^(-x/2) sum_{i<k} (x/2)^(i+1/2) / Gamma(i + 3/2) */
static double chi2_cdf(int m, double x)
{
    const double y = 0.5 * x;
    double sum = 0.0, term;
    if (m % 2 == 0) {
        term = 1.0;
        for (int i = 0; i < m / 2; ++i) {
            sum += term;
            term *= y / (i + 1);
        }
        return 1.0 - exp(-y) * sum;
    }
    term = sqrt(y) / (0.5 * sqrt(GF_PI));            /* y^(1/2) / Gamma(3/2) */
    for (int i = 0; i < m / 2; ++i) {
        sum += term;
        term *= y / (i + 1.5);
    }
    return erf(sqrt(y)) - exp(-y) * sum;
}

gf_status gf_chi2_quantile(int32_t m, double p, double *q)
{
    if (!q)
        return GF_ERR_NULL_POINTER;
    if (m < 1 || m > GF_KF_MAX_M || !(p > 0.0 && p < 1.0))
        return GF_ERR_BAD_PARAMETER;
    /* Wilson-Hilferty start, then Newton steps on the closed-form distribution */
    const double z = normal_quantile(p), k = 2.0 / (9.0 * m);
    const double t = 1.0 - k + z * sqrt(k);
    double x = fmax(m * t * t * t, 1e-3);
    const double log_norm = -0.5 * m * log(2.0) - log(tgamma(0.5 * m));
    for (int it = 0; it < 50; ++it) {
        const double pdf = exp(log_norm + (0.5 * m - 1.0) * log(x) - 0.5 * x);
        double step = (chi2_cdf(m, x) - p) / pdf;
        if (step > 0.5 * x)           /* keep x > 0 */
            step = 0.5 * x;
        x -= step;
        if (fabs(step) < 1e-13 * x)
            break;
    }
    *q = x;
    return GF_OK;
}

gf_status gf_ins_epochs_begin(gf_ins_filter *f, gf_ins_epochs *epochs)
{
    if (!f || !epochs || !epochs->t_s || !epochs->nav || !epochs->sensors || !epochs->dx ||
        !epochs->P_prior || !epochs->P_post || !epochs->Phi)
        return GF_ERR_NULL_POINTER;
    return epoch_open(f, epochs, NULL);
}

gf_status gf_ins_smooth_apply(const gf_ins_filter *f, size_t n_epochs, const double *epoch_t,
                              const double *xs, const double *dx, size_t n, const double *t_s,
                              double *q_bn, double *v_n_m_s, double *pos, double *sensors)
{
    if (!f || !epoch_t || !xs || !dx || !t_s || !q_bn || !v_n_m_s || !pos)
        return GF_ERR_NULL_POINTER;
    const size_t ns = (size_t)f->n_states;
    if (n_epochs == 0 || ns < GF_INS_BASE_STATES || ns > NMAX)
        return GF_ERR_BAD_SIZE;
    size_t j = 0;
    for (size_t k = 0; k < n; ++k) {
        const double t = t_s[k];
        if (!isfinite(t))
            return GF_ERR_NONFINITE_INPUT;
        while (j + 1 < n_epochs && epoch_t[j + 1] <= t + GF_INS_TIME_EPS_S)
            ++j;
        double e[NMAX];
        if (j + 1 >= n_epochs || t <= epoch_t[j] + GF_INS_TIME_EPS_S) {
            memcpy(e, xs + ns * j, ns * sizeof *e);
        } else {
            /* between the posterior nominal of epoch j and the prior nominal of j + 1 */
            const double u = (t - epoch_t[j]) / (epoch_t[j + 1] - epoch_t[j]);
            for (size_t i = 0; i < ns; ++i)
                e[i] = (1.0 - u) * xs[ns * j + i] + u * (xs[ns * (j + 1) + i] + dx[ns * (j + 1) + i]);
        }
        double nav[10];
        memcpy(nav, q_bn + 4 * k, 4 * sizeof *nav);
        gf_v3_copy(v_n_m_s + 3 * k, nav + 4);
        memcpy(nav + 7, pos + 3 * k, 3 * sizeof *nav);
        const gf_status st = gf_ins_apply_error(f, e, nav, sensors ? sensors + GF_INS_N_SENSORS * k : NULL);
        if (st != GF_OK)
            return st;
        memcpy(q_bn + 4 * k, nav, 4 * sizeof *nav);
        gf_v3_copy(nav + 4, v_n_m_s + 3 * k);
        memcpy(pos + 3 * k, nav + 7, 3 * sizeof *nav);
    }
    return GF_OK;
}
