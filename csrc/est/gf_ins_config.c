/* gf_ins_config.c — the INS/GNSS filter's configuration, its checks and the state
 * layout: defaults, gf_ins_state_count, gf_ins_init, gf_ins_filter_check (see
 * gf_ins_gnss.h). */
#include "est/gf_ins_gnss.h"

#include <math.h>
#include <string.h>

#include "base/gf_linalg.h"
#include "base/gf_math.h"
#include "est/gf_ins_internal.h"
#include "est/gf_kalman.h"
#include "nav/gf_sins.h"

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
    ins_refresh_scale(f);
    ins_refresh_std(f);
    return GF_OK;
}

/* what sizes or indexes arrays in a filter handed in by a caller (cheap: every step) */
int ins_layout_is_valid(const gf_ins_filter *f)
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
        !ins_layout_is_valid(f))
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
