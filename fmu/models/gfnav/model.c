/* model.c — the gyro-free navigator as an FMU model (FMI-agnostic): one array sample per
 * doStep through gf_gfnav_run. The sample set at t is solved and navigated; the
 * outputs after the step describe t (the first sample starts the record, as in the
 * batch navigator); the interval is the previous communication step, so a fixed step h
 * reproduces GyroFreeNavigator.run(A, h) exactly. */
#include <math.h>
#include <string.h>

#include "fmu_model.h"
#include "base/gf_math.h"
#include "gyrofree/gf9.h"
#include "gyrofree/gf_array.h"
#include "gyrofree/gf_gfins.h"
#include "gyrofree/gf_gfnav.h"
#include "gyrofree/gf_layout.h"
#include "model.h"
#include "skip_steps.h"

#ifndef GFNAV_LAYOUT
#error "GFNAV_LAYOUT must be defined (0 cube6, 1 qin9, 2 twelve)"
#endif

static gf_status make_geometry(double l, gf_array_geometry *g)
{
#if GFNAV_LAYOUT == 0
    return gf_layout_cube6(l, g);
#elif GFNAV_LAYOUT == 1
    return gf9_geometry(l, g);
#else
    return gf_layout_12(l, g);
#endif
}

/* Number of accelerometers of the layout (the A input holds up to 12). */
#define GFNAV_N_SENSORS (GFNAV_LAYOUT == 0 ? 6 : GFNAV_LAYOUT == 1 ? 9 : 12)

static void publish(ModelData *d)
{
    const gf_sins_state *s = &d->nav.nav;
    memcpy(d->q_bn, s->q_bn, sizeof d->q_bn);
    gf_quat_to_euler(s->q_bn, d->euler_rad);
    memcpy(d->v_n_m_s, s->v_n_m_s, sizeof d->v_n_m_s);
    d->lat_rad = s->lat_rad;
    d->lon_rad = s->lon_rad;
    d->h_m = s->h_m;
    memcpy(d->pos_m, s->flat_pos_m, sizeof d->pos_m);
    d->nav_time_s = s->time_s;
}

/* Logs the parameter at fault when the initialisation is refused: the parameters are
 * checked one by one in the order the core checks them (rate configuration, mechanization
 * configuration, initial state), so the message names the one to change; only when all
 * are valid is the strategy blamed for needing products the layout does not measure. */
static void log_refusal(FmuInstance *instance, const ModelData *d, gf_status st)
{
    const double *w = d->omega_init_rad_s, *q = d->q0, *v = d->v0_m_s, *p = d->pos0_m;
    const double min_h_m = -0.5 * GF_WGS84_A_M;
    if (d->strategy < 0 || d->strategy > 3)
        fmu_log_error(instance, "parameter strategy = %d must be 0..3", (int)d->strategy);
    else if (!(d->accel_noise_m_s2 > 0.0) || !isfinite(d->accel_noise_m_s2))
        fmu_log_error(instance, "parameter accel_noise = %g m/s2 must be finite and > 0",
                      d->accel_noise_m_s2);
    else if (!gf_all_finite(w, 3))
        fmu_log_error(instance, "parameter omega_init = [%g, %g, %g] rad/s must be finite",
                      w[0], w[1], w[2]);
    else if (d->earth != GF_SINS_EARTH_WGS84 && d->earth != GF_SINS_EARTH_FLAT)
        fmu_log_error(instance, "parameter earth = %d must be 0 (WGS-84) or 1 (fixed frame)",
                      (int)d->earth);
    else if (!(d->flat_gravity_m_s2 >= 0.0) || !isfinite(d->flat_gravity_m_s2))
        fmu_log_error(instance, "parameter flat_gravity = %g m/s2 must be finite and >= 0",
                      d->flat_gravity_m_s2);
    else if (d->vertical_mode < 0 || d->vertical_mode > 2)
        fmu_log_error(instance, "parameter vertical_mode = %d must be 0, 1 or 2",
                      (int)d->vertical_mode);
    else if (!(d->baro_tau_s > 0.0) || !isfinite(d->baro_tau_s))
        fmu_log_error(instance, "parameter baro_tau = %g s must be finite and > 0", d->baro_tau_s);
    else if (!(d->hold_height_m > min_h_m) || !isfinite(d->hold_height_m))
        fmu_log_error(instance, "parameter hold_height = %g m must be finite and above -a/2",
                      d->hold_height_m);
    else if (!gf_all_finite(q, 4) || !(gf_q_norm(q) > 0.0))
        fmu_log_error(instance, "parameter q0 = [%g, %g, %g, %g] must be a finite, non-zero "
                      "quaternion", q[0], q[1], q[2], q[3]);
    else if (!gf_all_finite(v, 3))
        fmu_log_error(instance, "parameter v0 = [%g, %g, %g] m/s must be finite", v[0], v[1], v[2]);
    else if (!(fabs(d->lat0_rad) < GF_SINS_LAT_LIMIT_RAD))
        fmu_log_error(instance, "parameter lat0 = %g rad is outside the latitude limit +-89.9 deg "
                      "of the ENU mechanization", d->lat0_rad);
    else if (!isfinite(d->lon0_rad))
        fmu_log_error(instance, "parameter lon0 = %g rad must be finite", d->lon0_rad);
    else if (!(d->h0_m > min_h_m) || !isfinite(d->h0_m))
        fmu_log_error(instance, "parameter h0 = %g m must be finite and above -a/2", d->h0_m);
    else if (d->earth == GF_SINS_EARTH_FLAT && !gf_all_finite(p, 3))
        fmu_log_error(instance, "parameter pos0 = [%g, %g, %g] m must be finite", p[0], p[1], p[2]);
    else if (st == GF_ERR_BAD_PARAMETER && d->strategy == GF_RATE_EIGEN)
        fmu_log_error(instance, "parameter strategy = %d needs all products w w^T (diagonal and "
                      "off-diagonal), which this layout does not measure", (int)d->strategy);
    else if (st == GF_ERR_BAD_PARAMETER && d->strategy != GF_RATE_INTEGRATE)
        fmu_log_error(instance, "parameter strategy = %d needs the squared rates (the diagonal of "
                      "w w^T), which this layout does not measure", (int)d->strategy);
    else
        fmu_log_error(instance, "initialisation refused: %s", gf_status_string(st));
}

/* Validates the parameters and starts the navigation at start_time_s (also used to
 * restart it after skip_steps ignored doSteps). */
static FmuStatus start_navigation(FmuInstance *instance, ModelData *d, double start_time_s)
{
    gf_array_geometry g;
    if (make_geometry(d->lever_arm_m, &g) != GF_OK) {
        fmu_log_error(instance, "parameter l = %g m: the lever arm must be finite and >= 1e-6 m",
                      d->lever_arm_m);
        return FMU_ERROR;
    }
    gf_rate_config rc;
    gf_rate_config_default(&rc);
    rc.strategy = d->strategy;
    rc.accel_noise_m_s2 = d->accel_noise_m_s2;
    gf_sins_config sc;
    gf_sins_config_default(&sc);
    sc.input = GF_SINS_INPUT_RATES;
    sc.earth = d->earth;
    sc.flat_gravity_m_s2 = d->flat_gravity_m_s2;
    sc.vertical = d->vertical_mode;
    sc.hold_height_m = d->hold_height_m;
    sc.baro_tau_s = d->baro_tau_s;
    uint32_t unobservable = 0;
    gf_status st = gf_gfnav_init(&d->nav, &g, &rc, d->omega_init_rad_s, &sc, d->q0, d->v0_m_s,
                                 d->lat0_rad, d->lon0_rad, d->h0_m, start_time_s, &unobservable);
    if (st == GF_OK && d->earth == GF_SINS_EARTH_FLAT)
        st = gf_sins_set_flat_position(&d->nav.nav, d->pos0_m);
    if (st != GF_OK) {
        log_refusal(instance, d, st);
        return FMU_ERROR;
    }
    memset(d->omega_rad_s, 0, sizeof d->omega_rad_s);
    memcpy(d->omega_rad_s, d->omega_init_rad_s, sizeof d->omega_rad_s);
    memset(d->f_m_s2, 0, sizeof d->f_m_s2);
    d->flags = 0;
    d->previous_step_s = 0.0;
    d->started = 0;
    publish(d);
    return FMU_OK;
}

FmuStatus model_exit_initialization(FmuInstance *instance, ModelData *d, double start_time_s)
{
    return fmu_nav_exit_initialization(instance, d, start_time_s, start_navigation);
}

FmuStatus model_do_step(FmuInstance *instance, ModelData *d, double t_s, double h_s)
{
    FmuStatus skipped;
    if (fmu_nav_skip_step(instance, d, t_s + h_s, start_navigation, &skipped))
        return skipped; /* inputs ignored; navigation (re)started for the next sample */
    double q[4], v[3], pos[3], w[3], f[3];
    uint8_t flags = 0;
    size_t done = 0;
    const double dt = d->started ? d->previous_step_s : h_s; /* first: dt unused */
    const gf_status st = gf_gfnav_run(&d->nav, 1, d->A_m_s2, dt, &d->h_ext_m, q, v, pos, w, f,
                                      &flags, &done);
    if (st != GF_OK) {
        if (st == GF_ERR_NONFINITE_INPUT)
            fmu_log_error(instance, "t = %.9g s: an input A[i] is not finite (or h_ext is "
                          "infinite); the outputs keep the last good sample", t_s);
        else
            fmu_log_error(instance, "t = %.9g s: navigation step failed: %s", t_s,
                          gf_status_string(st));
        return FMU_ERROR;
    }
    memcpy(d->omega_rad_s, w, sizeof w);
    memcpy(d->f_m_s2, f, sizeof f);
    d->flags = flags;
    d->previous_step_s = h_s;
    d->started = 1;
    publish(d);
    return FMU_OK;
}

const char *model_validate_state(const ModelData *d)
{
    const char *why = fmu_nav_counters_invalid(d->skip_steps, d->skipped, d->started,
                                               d->previous_step_s);
    if (why)
        return why;
    if (gf_gfins_state_check(&d->nav.rate) != GF_OK)
        return "the rate solver state (array solver, strategy, filter) is invalid";
    if (d->nav.rate.solver.n_sensors != GFNAV_N_SENSORS)
        return "the rate solver's sensor count is not the layout's";
    if (gf_sins_state_check(&d->nav.nav) != GF_OK || d->nav.nav.cfg.input != GF_SINS_INPUT_RATES)
        return "the navigation state (configuration, attitude, position) is invalid";
    /* the outputs a restored state carries (returned by a get before any step) */
    if (!gf_all_finite(d->q_bn, 4) || !gf_all_finite(d->euler_rad, 3) || !gf_all_finite(d->v_n_m_s, 3) ||
        !isfinite(d->lat_rad) || !isfinite(d->lon_rad) || !isfinite(d->h_m) || !gf_all_finite(d->pos_m, 3) ||
        !gf_all_finite(d->omega_rad_s, 3) || !gf_all_finite(d->f_m_s2, 3) || !isfinite(d->nav_time_s))
        return "an output (attitude, velocity, position, rate, specific force, time) is not finite";
    if (!isfinite(d->lever_arm_m) || !isfinite(d->accel_noise_m_s2) || !gf_all_finite(d->omega_init_rad_s, 3) ||
        !isfinite(d->flat_gravity_m_s2) || !isfinite(d->hold_height_m) || !isfinite(d->baro_tau_s) ||
        !gf_all_finite(d->q0, 4) || !gf_all_finite(d->v0_m_s, 3) || !isfinite(d->lat0_rad) ||
        !isfinite(d->lon0_rad) || !isfinite(d->h0_m) || !gf_all_finite(d->pos0_m, 3))
        return "a parameter (array, strategy, initial state, vertical channel) is not finite";
    return NULL;
}
