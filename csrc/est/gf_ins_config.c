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
#include "nav/gf_earth.h"
#include "nav/gf_sins.h"

gf_status gf_ins_config_default(gf_ins_config *cfg)
{
    if (!cfg)
        return GF_ERR_NULL_POINTER;
    memset(cfg, 0, sizeof *cfg);
    cfg->input = GF_SINS_INPUT_INCREMENTS;
    cfg->coning = 1;
    cfg->filter = GF_INS_EKF;
    cfg->propagation_interval_s = 0.1;
    cfg->max_imu_gap_s = 0.5;
    cfg->max_rate_rad_s = 50.0;
    cfg->max_specific_force_m_s2 = 1000.0;
    /* seed 004: beta = 2 (Gaussian), kappa = 0, alpha "small": 0.5 keeps the points
     * within ~2 sigma; alpha -> 0 turns the UKF into an EKF with central differences */
    cfg->ukf_alpha = 0.5;
    cfg->ukf_beta = 2.0;
    cfg->ukf_kappa = 0.0;
    cfg->gate_probability = 0.9999;
    cfg->gate_reset_count = 5;
    cfg->nhc_std_m_s = 0.1;
    cfg->nhc_interval_s = 0.1;
    cfg->zupt_std_m_s = 0.01;
    cfg->zupt_interval_s = 0.1;
    cfg->standstill_window_s = 0.5;
    cfg->standstill_accel_std_m_s2 = 0.05;
    cfg->standstill_gyro_rad_s = 0.01;
    cfg->speed_min_m_s = 0.5;
    cfg->subsamples = 1;
    /* the optional states' models (the IMU's noise stays 0: set it from the datasheet) */
    cfg->noise.gyro_scale_std = 1e-3;
    cfg->noise.accel_scale_std = 1e-3;
    cfg->noise.baro_bias_std_m = 1.0;
    cfg->noise.baro_bias_tau_s = 3600.0;
    cfg->noise.odometer_scale_std = 0.01;
    cfg->noise.odometer_mount_std_rad = 0.035;
    /* flexure (off by default): 1 mrad over ~1 s, the order of a car's or a pod's mount */
    cfg->noise.flexure_std_rad = 1e-3;
    cfg->noise.flexure_tau_s = 1.0;
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

/* Every field gf_ins_init checks, by its member name; a refused configuration is reported
 * as the 1-based position of its first bad field here (gf_ins_init's *bad), which
 * gf_ins_config_field turns back into the name. The layers above look the name up in the
 * settings table (gfins_fmi/estimation/settings.py) for the Python name, the FMU parameter,
 * the unit and the bounds; a test checks that every row of that table is here and the
 * other way round. */
static const char *const kFields[] = {
    "input", "coning", "filter", "scale_factors", "baro_bias", "odometer_scale",
    "odometer_mount", "propagation_interval_s", "max_imu_gap_s", "max_rate_rad_s",
    "max_specific_force_m_s2", "ukf_alpha", "ukf_beta", "ukf_kappa",
    "noise.gyro_arw_rad_sqrt_s", "noise.accel_vrw_m_s_sqrt_s", "noise.gyro_bias_std_rad_s",
    "noise.gyro_bias_tau_s", "noise.accel_bias_std_m_s2", "noise.accel_bias_tau_s",
    "noise.gyro_scale_std", "noise.gyro_scale_tau_s", "noise.accel_scale_std",
    "noise.accel_scale_tau_s", "noise.baro_bias_std_m", "noise.baro_bias_tau_s",
    "noise.odometer_scale_std", "noise.odometer_scale_tau_s", "noise.odometer_mount_std_rad",
    "noise.odometer_mount_tau_s", "noise.flexure_std_rad", "noise.flexure_tau_s",
    "gnss_lever_arm_m", "odometer_lever_arm_m",
    "gnss_position_std_floor_m",
    "gate_probability", "gate_reset_count", "nhc", "nhc_std_m_s", "nhc_interval_s", "zupt",
    "zupt_std_m_s", "zaru_std_rad_s", "zupt_interval_s", "standstill_window_s",
    "standstill_accel_std_m_s2", "standstill_gyro_rad_s", "max_latency_s", "speed_min_m_s",
    "odometer_mount_rad", "subsamples", "master_mount", "master_lever", "master_time_offset",
    "flexure", "master_mount_rad", "master_lever_arm_m", "master_time_offset_s"};
#define N_FIELDS ((int32_t)(sizeof kFields / sizeof kFields[0]))

const char *gf_ins_config_field(int32_t code)
{
    return code >= 1 && code <= N_FIELDS ? kFields[code - 1] : NULL;
}

static int32_t field_code(const char *member)
{
    for (int32_t i = 0; i < N_FIELDS; ++i)
        if (strcmp(kFields[i], member) == 0)
            return i + 1;
    return -1; /* a check naming a field missing from kFields: test_ins_gnss.c finds it */
}

/* the code of a member of gf_ins_config c (the member must exist: it is compiled) */
#define BAD(member) ((void)sizeof(c->member), field_code(#member))

static int flag_ok(int32_t v)
{
    return v == 0 || v == 1;
}

/* 0 when valid, else the code of the first bad field (see kFields) */
static int32_t config_check(const gf_ins_config *c)
{
    if (c->input != GF_SINS_INPUT_INCREMENTS && c->input != GF_SINS_INPUT_RATES)
        return BAD(input);
    if (!flag_ok(c->coning))
        return BAD(coning);
    if (c->filter != GF_INS_EKF && c->filter != GF_INS_UKF)
        return BAD(filter);
    if (!flag_ok(c->scale_factors))
        return BAD(scale_factors);
    if (!flag_ok(c->baro_bias))
        return BAD(baro_bias);
    if (!flag_ok(c->odometer_scale))
        return BAD(odometer_scale);
    if (!flag_ok(c->odometer_mount))
        return BAD(odometer_mount);
    if (!nonneg_finite(c->propagation_interval_s))
        return BAD(propagation_interval_s);
    if (!pos_finite(c->max_imu_gap_s))
        return BAD(max_imu_gap_s);
    if (!pos_finite(c->max_rate_rad_s))
        return BAD(max_rate_rad_s);
    if (!pos_finite(c->max_specific_force_m_s2))
        return BAD(max_specific_force_m_s2);
    if (!pos_finite(c->ukf_alpha))
        return BAD(ukf_alpha);
    if (!isfinite(c->ukf_beta))
        return BAD(ukf_beta);
    if (!isfinite(c->ukf_kappa))
        return BAD(ukf_kappa);
    const gf_ins_noise *q = &c->noise;
    if (!nonneg_finite(q->gyro_arw_rad_sqrt_s))
        return BAD(noise.gyro_arw_rad_sqrt_s);
    if (!nonneg_finite(q->accel_vrw_m_s_sqrt_s))
        return BAD(noise.accel_vrw_m_s_sqrt_s);
    if (!nonneg_finite(q->gyro_bias_std_rad_s))
        return BAD(noise.gyro_bias_std_rad_s);
    if (!nonneg_finite(q->gyro_bias_tau_s))
        return BAD(noise.gyro_bias_tau_s);
    if (!nonneg_finite(q->accel_bias_std_m_s2))
        return BAD(noise.accel_bias_std_m_s2);
    if (!nonneg_finite(q->accel_bias_tau_s))
        return BAD(noise.accel_bias_tau_s);
    if (!nonneg_finite(q->gyro_scale_std))
        return BAD(noise.gyro_scale_std);
    if (!nonneg_finite(q->gyro_scale_tau_s))
        return BAD(noise.gyro_scale_tau_s);
    if (!nonneg_finite(q->accel_scale_std))
        return BAD(noise.accel_scale_std);
    if (!nonneg_finite(q->accel_scale_tau_s))
        return BAD(noise.accel_scale_tau_s);
    if (!nonneg_finite(q->baro_bias_std_m))
        return BAD(noise.baro_bias_std_m);
    if (!nonneg_finite(q->baro_bias_tau_s))
        return BAD(noise.baro_bias_tau_s);
    if (!nonneg_finite(q->odometer_scale_std))
        return BAD(noise.odometer_scale_std);
    if (!nonneg_finite(q->odometer_scale_tau_s))
        return BAD(noise.odometer_scale_tau_s);
    if (!nonneg_finite(q->odometer_mount_std_rad))
        return BAD(noise.odometer_mount_std_rad);
    if (!nonneg_finite(q->odometer_mount_tau_s))
        return BAD(noise.odometer_mount_tau_s);
    if (c->flexure == 1 && !pos_finite(q->flexure_std_rad))
        return BAD(noise.flexure_std_rad);
    if (c->flexure == 1 && !pos_finite(q->flexure_tau_s))
        return BAD(noise.flexure_tau_s);
    if (!gf_all_finite(c->gnss_lever_arm_m, 3))
        return BAD(gnss_lever_arm_m);
    if (!gf_all_finite(c->odometer_lever_arm_m, 3))
        return BAD(odometer_lever_arm_m);
    for (int i = 0; i < 3; ++i)
        if (!nonneg_finite(c->gnss_position_std_floor_m[i]))
            return BAD(gnss_position_std_floor_m);
    if (!(c->gate_probability == 0.0 || (c->gate_probability > 0.0 && c->gate_probability < 1.0)))
        return BAD(gate_probability);
    if (c->gate_reset_count < 0)
        return BAD(gate_reset_count);
    if (!flag_ok(c->nhc))
        return BAD(nhc);
    if (c->nhc && !pos_finite(c->nhc_std_m_s))
        return BAD(nhc_std_m_s);
    if (c->nhc && !nonneg_finite(c->nhc_interval_s))
        return BAD(nhc_interval_s);
    if (!flag_ok(c->zupt))
        return BAD(zupt);
    if (c->zupt && !pos_finite(c->zupt_std_m_s))
        return BAD(zupt_std_m_s);
    if (c->zupt && !nonneg_finite(c->zaru_std_rad_s))
        return BAD(zaru_std_rad_s);
    if (c->zupt && !nonneg_finite(c->zupt_interval_s))
        return BAD(zupt_interval_s);
    if (!pos_finite(c->standstill_window_s))
        return BAD(standstill_window_s);
    if (!pos_finite(c->standstill_accel_std_m_s2))
        return BAD(standstill_accel_std_m_s2);
    if (!pos_finite(c->standstill_gyro_rad_s))
        return BAD(standstill_gyro_rad_s);
    if (!nonneg_finite(c->max_latency_s))
        return BAD(max_latency_s);
    if (!nonneg_finite(c->speed_min_m_s))
        return BAD(speed_min_m_s);
    if (!(fabs(c->odometer_mount_rad[0]) < GF_HALF_PI) || !(fabs(c->odometer_mount_rad[1]) < GF_HALF_PI))
        return BAD(odometer_mount_rad);
    if (c->subsamples < 0 || c->subsamples > GF_SINS_MAX_SUBSAMPLES ||
        (c->subsamples > 1 && c->input != GF_SINS_INPUT_INCREMENTS))
        return BAD(subsamples);
    if (!flag_ok(c->master_mount))
        return BAD(master_mount);
    if (!flag_ok(c->master_lever))
        return BAD(master_lever);
    if (!flag_ok(c->master_time_offset))
        return BAD(master_time_offset);
    if (!flag_ok(c->flexure))
        return BAD(flexure);
    /* the mounting's Euler angles: pitch inside (-pi/2, pi/2), where heading and roll
     * stay distinct rotations */
    if (!gf_all_finite(c->master_mount_rad, 3) || !(fabs(c->master_mount_rad[1]) < GF_HALF_PI))
        return BAD(master_mount_rad);
    if (!gf_all_finite(c->master_lever_arm_m, 3))
        return BAD(master_lever_arm_m);
    if (!isfinite(c->master_time_offset_s))
        return BAD(master_time_offset_s);
    return 0;
}

gf_status gf_ins_config_check(const gf_ins_config *cfg, int32_t *bad)
{
    if (bad)
        *bad = 0;
    if (!cfg)
        return GF_ERR_NULL_POINTER;
    const int32_t code = config_check(cfg);
    if (bad)
        *bad = code;
    return code ? GF_ERR_BAD_PARAMETER : GF_OK;
}

/* The layout of a checked configuration: the optional blocks after the 15 base states in
 * the order of gf_ins_gnss.h (scale factors, barometer bias, odometer scale, boresight,
 * then transfer alignment: mounting, lever arm, time offset, flexure). */
static void layout_of(const gf_ins_config *cfg, gf_ins_layout *l)
{
    int32_t next = GF_INS_BASE_STATES;
    l->idx_vel = GF_INS_IDX_VEL;
    l->idx_pos = GF_INS_IDX_POS;
    l->idx_att = GF_INS_IDX_ATT;
    l->idx_bg = GF_INS_IDX_BG;
    l->idx_ba = GF_INS_IDX_BA;
    l->idx_sg = l->idx_sa = l->idx_baro = l->idx_odo = l->idx_mount = -1;
    l->idx_tmount = l->idx_tlever = l->idx_toffset = l->idx_flex = -1;
    if (cfg->scale_factors) {
        l->idx_sg = next;
        l->idx_sa = next + 3;
        next += 6;
    }
    if (cfg->baro_bias)
        l->idx_baro = next++;
    if (cfg->odometer_scale)
        l->idx_odo = next++;
    if (cfg->odometer_mount) {
        l->idx_mount = next;
        next += 2;
    }
    if (cfg->master_mount) {
        l->idx_tmount = next;
        next += 3;
    }
    if (cfg->master_lever) {
        l->idx_tlever = next;
        next += 3;
    }
    if (cfg->master_time_offset)
        l->idx_toffset = next++;
    if (cfg->flexure) {
        l->idx_flex = next;
        next += 6;
    }
    l->n_states = next;
}

gf_status gf_ins_state_layout(const gf_ins_config *cfg, gf_ins_layout *layout)
{
    if (!cfg || !layout)
        return GF_ERR_NULL_POINTER;
    if (config_check(cfg))
        return GF_ERR_BAD_PARAMETER;
    layout_of(cfg, layout);
    return GF_OK;
}

gf_status gf_ins_state_count(const gf_ins_config *cfg, int32_t *n_states)
{
    if (!n_states)
        return GF_ERR_NULL_POINTER;
    gf_ins_layout l;
    const gf_status st = gf_ins_state_layout(cfg, &l);
    if (st == GF_OK)
        *n_states = l.n_states;
    return st;
}

/* ---- initial covariance ----------------------------------------------------------------- */

/* The blocks of gf_ins_initial_std, in its order: the 1-based position of the first bad
 * one is gf_ins_initial_covariance's *bad (gf_ins_initial_std_field names it). */
static const char *const kStdFields[] = {
    "velocity_std_m_s", "position_std_m", "attitude_std_rad", "gyro_bias_std_rad_s",
    "accel_bias_std_m_s2", "gyro_scale_std", "accel_scale_std", "baro_bias_std_m",
    "odometer_scale_std", "odometer_mount_std_rad", "master_mount_std_rad", "master_lever_std_m",
    "master_time_offset_std_s"};

const char *gf_ins_initial_std_field(int32_t code)
{
    return code >= 1 && code <= (int32_t)(sizeof kStdFields / sizeof kStdFields[0])
               ? kStdFields[code - 1]
               : NULL;
}

static int all_positive(const double *x, int n)
{
    for (int i = 0; i < n; ++i)
        if (!(isfinite(x[i]) && x[i] > 0.0))
            return 0;
    return 1;
}

gf_status gf_ins_initial_covariance(const gf_ins_config *cfg, double lat_rad, double h_m,
                                    const gf_ins_initial_std *std, double *P0, int32_t *bad)
{
    if (bad)
        *bad = 0;
    if (!cfg || !std || !P0)
        return GF_ERR_NULL_POINTER;
    gf_ins_layout l;
    gf_status st = gf_ins_state_layout(cfg, &l);
    if (st != GF_OK)
        return st;
    /* near a pole the ENU error model (dlon, transport rate ~ tan L) is singular */
    if (!(fabs(lat_rad) < GF_INS_MAX_LAT_RAD) || !isfinite(h_m))
        return GF_ERR_OUT_OF_RANGE;
    const struct {
        const double *x;
        int n, used;
    } blocks[] = {
        {std->velocity_std_m_s, 3, 1},
        {std->position_std_m, 3, 1},
        {std->attitude_std_rad, 3, 1},
        {std->gyro_bias_std_rad_s, 3, 1},
        {std->accel_bias_std_m_s2, 3, 1},
        {std->gyro_scale_std, 3, cfg->scale_factors},
        {std->accel_scale_std, 3, cfg->scale_factors},
        {&std->baro_bias_std_m, 1, cfg->baro_bias},
        {&std->odometer_scale_std, 1, cfg->odometer_scale},
        {std->odometer_mount_std_rad, 2, cfg->odometer_mount},
        {std->master_mount_std_rad, 3, cfg->master_mount},
        {std->master_lever_std_m, 3, cfg->master_lever},
        {&std->master_time_offset_std_s, 1, cfg->master_time_offset},
    };
    double sd[GF_INS_MAX_STATES];
    int k = 0;
    for (int b = 0; b < (int)(sizeof blocks / sizeof blocks[0]); ++b) {
        if (!blocks[b].used)
            continue;
        if (!all_positive(blocks[b].x, blocks[b].n)) {
            if (bad)
                *bad = b + 1;
            return GF_ERR_BAD_PARAMETER;
        }
        for (int i = 0; i < blocks[b].n; ++i)
            sd[k++] = blocks[b].x[i];
    }
    if (cfg->flexure) {   /* stationary: var(f) = sigma^2, var(f') = b^2 sigma^2 */
        const double sg = cfg->noise.flexure_std_rad;
        const double b = GF_INS_FLEX_BETA_TAU / cfg->noise.flexure_tau_s;
        for (int i = 0; i < 3; ++i) {
            sd[k + i] = sg;
            sd[k + 3 + i] = b * sg;
        }
        k += 6;
    }
    gf_earth e;
    st = gf_earth_update(&e, lat_rad, h_m, NULL, 1.0);
    if (st != GF_OK)
        return st;
    /* position std east, north, up (m) -> dlat, dlon (rad), dh (m) */
    const double east = sd[GF_INS_IDX_POS], north = sd[GF_INS_IDX_POS + 1];
    sd[GF_INS_IDX_POS] = north / (e.R_M_m + h_m);
    sd[GF_INS_IDX_POS + 1] = east / ((e.R_N_m + h_m) * e.cos_lat);
    const int n = l.n_states;
    memset(P0, 0, (size_t)(n * n) * sizeof *P0);
    for (int i = 0; i < n; ++i)
        P0[i * n + i] = sd[i] * sd[i];
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
    const int32_t check = config_check(cfg);
    if (check) {
        if (bad)
            *bad = check;
        return GF_ERR_BAD_PARAMETER;
    }
    if (!isfinite(t0_s) || (sensors0 && !gf_all_finite(sensors0, GF_INS_N_SENSORS)))
        return GF_ERR_NONFINITE_INPUT;
    for (int i = 0; sensors0 && i < 2; ++i)
        if (!(fabs(cfg->odometer_mount_rad[i] + sensors0[S_MOUNT + i]) < GF_HALF_PI)) {
            if (bad)   /* the boresight angles used: odometer_mount_rad + the correction */
                *bad = field_code("odometer_mount_rad");
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
    gf_ins_layout lay;
    layout_of(cfg, &lay);
    const int32_t n = lay.n_states;
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
    f->idx_sg = lay.idx_sg;
    f->idx_sa = lay.idx_sa;
    f->idx_baro = lay.idx_baro;
    f->idx_odo = lay.idx_odo;
    f->idx_mount = lay.idx_mount;
    f->idx_tmount = lay.idx_tmount;
    f->idx_tlever = lay.idx_tlever;
    f->idx_toffset = lay.idx_toffset;
    f->idx_flex = lay.idx_flex;
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
            *bad = field_code("ukf_kappa");   /* n_states + ukf_kappa must be > 0 */
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
    const int32_t idx[9] = {f->idx_sg,     f->idx_sa,     f->idx_baro,    f->idx_odo,  f->idx_mount,
                            f->idx_tmount, f->idx_tlever, f->idx_toffset, f->idx_flex};
    const int len[9] = {3, 3, 1, 1, 2, 3, 3, 1, 6};
    for (int i = 0; i < 9; ++i)
        if (idx[i] != -1 && (idx[i] < GF_INS_BASE_STATES || idx[i] + len[i] > n))
            return 0;
    return f->ukf_w.n == (size_t)n && f->hist_head >= 0 && f->hist_head < GF_INS_HISTORY &&
           f->hist_count >= 0 && f->hist_count <= GF_INS_HISTORY;
}

gf_status gf_ins_filter_check(const gf_ins_filter *f)
{
    if (!f)
        return GF_ERR_NULL_POINTER;
    if (config_check(&f->cfg))
        return GF_ERR_BAD_SIZE;
    gf_ins_layout l;
    layout_of(&f->cfg, &l);
    const int32_t n = l.n_states;
    if (f->n_states != n || !ins_layout_is_valid(f) || f->idx_sg != l.idx_sg ||
        f->idx_sa != l.idx_sa || f->idx_baro != l.idx_baro || f->idx_odo != l.idx_odo ||
        f->idx_mount != l.idx_mount || f->idx_tmount != l.idx_tmount ||
        f->idx_tlever != l.idx_tlever || f->idx_toffset != l.idx_toffset ||
        f->idx_flex != l.idx_flex)
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
        !gf_all_finite(f->transfer, GF_INS_N_TRANSFER) || !(f->rate_lag_s >= 0.0) ||
        !isfinite(f->rate_lag_s) ||
        !gf_all_finite(f->kf.x, (size_t)n))
        return GF_ERR_NONFINITE_INPUT;
    for (int i = 0; i < n; ++i)
        if (!(f->kf.P[i * n + i] > 0.0) || !isfinite(f->kf.P[i * n + i]))
            return GF_ERR_BAD_PARAMETER;
    /* The floats (a crafted FMU state with a valid CRC and three words overwritten was
     * restored and stepped to a NaN standard deviation): P a covariance (finite,
     * symmetric, positive definite within round-off: gf_kalman_check), the UKF weights
     * those of the configuration (bit for bit: gf_ukf_weights_init is deterministic),
     * every other double finite, the kept stds >= 0, the scale corrections > 0, the
     * times of the last NHC / ZUPT finite or -Inf (none yet), the stored nominal states
     * of the delayed updates with unit quaternions and latitudes inside the poles. */
    if (gf_kalman_check(&f->kf) != GF_OK)
        return GF_ERR_BAD_PARAMETER;
    gf_ukf_weights w;
    if (gf_ukf_weights_init(&w, (size_t)n, f->cfg.ukf_alpha, f->cfg.ukf_beta, f->cfg.ukf_kappa) != GF_OK ||
        memcmp(&w, &f->ukf_w, sizeof w) != 0)
        return GF_ERR_BAD_PARAMETER;
    if (!gf_all_finite(f->sensors0, GF_INS_N_SENSORS) || !gf_all_finite(f->prev_gyro_raw, 3) ||
        !gf_all_finite(f->prev_accel_raw, 3) || !gf_all_finite(f->w_ib_b_rad_s, 3) ||
        !gf_all_finite(f->f_b_m_s2, 3) || !gf_all_finite(f->acc_dtheta_rad, 3) ||
        !gf_all_finite(f->acc_dv_m_s, 3) || !gf_all_finite(f->still_f, 3) ||
        !gf_all_finite(f->still_w, 3) || !isfinite(f->still_fn) || !isfinite(f->still_fn2) ||
        !isfinite(f->still_wn) || !isfinite(f->last_regular_t_s))
        return GF_ERR_NONFINITE_INPUT;
    if (!(f->acc_T_s >= 0.0 && isfinite(f->acc_T_s)) ||
        !(f->still_time_s >= 0.0 && isfinite(f->still_time_s)))
        return GF_ERR_BAD_PARAMETER;
    for (int i = 0; i < 9; ++i)
        if (!(f->std9[i] >= 0.0 && isfinite(f->std9[i])))
            return GF_ERR_BAD_PARAMETER;
    for (int i = 0; i < 6; ++i)
        if (!(f->inv_scale[i] > 0.0 && isfinite(f->inv_scale[i])))
            return GF_ERR_BAD_PARAMETER;
    const double last[2] = {f->last_nhc_t_s, f->last_zupt_t_s};
    for (int i = 0; i < 2; ++i)
        if (!(isfinite(last[i]) || last[i] == -INFINITY))
            return GF_ERR_BAD_PARAMETER;
    for (int k = 0; k < f->hist_count; ++k) {
        const gf_ins_history *h = f->hist + (f->hist_head - 1 - k + 2 * GF_INS_HISTORY) % GF_INS_HISTORY;
        const double qn = h->q_bn[0] * h->q_bn[0] + h->q_bn[1] * h->q_bn[1] +
                          h->q_bn[2] * h->q_bn[2] + h->q_bn[3] * h->q_bn[3];
        if (!isfinite(h->t_s) || !gf_all_finite(h->v_n_m_s, 3) || !gf_all_finite(h->w_ib_b_rad_s, 3) ||
            !(fabs(qn - 1.0) < 2e-6) || !(fabs(h->lat_rad) < GF_HALF_PI) || !isfinite(h->lon_rad) ||
            !isfinite(h->h_m))
            return GF_ERR_BAD_PARAMETER;
    }
    return GF_OK;
}
