/* gf_ins_step.c — the INS/GNSS filter's sample: compensation and mechanization (the
 * interval split at measurement instants), the standstill detector, the regular grid of
 * propagations and internal updates; the batch walks over a record, forward
 * (gf_ins_run, grouped samples) and backward (gf_ins_run_backward). See gf_ins_gnss.h. */
#include "est/gf_ins_gnss.h"

#include <math.h>
#include <string.h>

#include "base/gf_math.h"
#include "est/gf_ins_internal.h"
#include "nav/gf_sins.h"

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
        f->rate_lag_s = 0.5 * dt;
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
    const double a = fmin(1.0, T / f->cfg.standstill_window_s);   /* exponential average */
    for (int i = 0; i < 3; ++i) {
        f->still_f[i] += a * (fb[i] - f->still_f[i]);
        f->still_w[i] += a * (w[i] - f->still_w[i]);
    }
    f->still_fn += a * (fn - f->still_fn);
    f->still_fn2 += a * (fn * fn - f->still_fn2);
    f->still_wn += a * (wn - f->still_wn);
    const double sd = sqrt(fmax(0.0, f->still_fn2 - f->still_fn * f->still_fn));
    const double ta = f->cfg.standstill_accel_std_m_s2, tg = f->cfg.standstill_gyro_rad_s;
    const int quiet = sd < ta && f->still_wn < tg && wn < 3.0 * tg && fabs(fn - f->still_fn) < 3.0 * ta;
    f->still_time_s = quiet ? f->still_time_s + T : 0.0;
    f->standstill = f->still_time_s >= f->cfg.standstill_window_s;
}

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
    if (!(dir * (t_s - f->last_regular_t_s) >= f->cfg.propagation_interval_s - GF_INS_TIME_EPS_S))
        return GF_OK;
    f->last_regular_t_s = t_s;
    gf_status st = ins_propagate(f, epochs);
    if (st == GF_OK && f->cfg.nhc &&
        dir * (t_s - f->last_nhc_t_s) >= f->cfg.nhc_interval_s - GF_INS_TIME_EPS_S) {
        f->last_nhc_t_s = t_s;
        st = ins_update(f, GF_INS_MEAS_NHC, NULL, f->cfg.nhc_std_m_s, epochs, log);
    }
    if (st == GF_OK && f->cfg.zupt && f->standstill &&
        dir * (t_s - f->last_zupt_t_s) >= f->cfg.zupt_interval_s - GF_INS_TIME_EPS_S) {
        f->last_zupt_t_s = t_s;
        st = ins_update(f, GF_INS_MEAS_ZUPT, NULL, f->cfg.zupt_std_m_s, epochs, log);
        if (st == GF_OK && f->cfg.zaru_std_rad_s > 0.0)
            st = ins_update(f, GF_INS_MEAS_ZARU, NULL, f->cfg.zaru_std_rad_s, epochs, log);
    }
    return st;
}

/* gf_ins_step after its checks of the pointers and of the filter's layout (gf_ins_run
 * makes them once for its whole record: nothing in a step changes the layout). The
 * measurements are meas[0], meas[stride], ... (stride -1: a backward walk over a record
 * stored in increasing time). Times are compared in the filter's direction: with
 * dir = -1 (reversed) time decreases, and every difference below is dir * (a - b). */
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
        const gf_status st = ins_meas_check(MS(j));
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
        if (f->cfg.zupt && f->n_imu == 0)
            standstill_update(f, 0.0);   /* seeds the detector's averages with this sample */
        for (size_t j = 0; j < n_meas && st == GF_OK; ++j) {
            gf_ins_meas ms;
            ins_meas_directed(f, MS(j), &ms);
            st = fabs(ms.t_s - f->t_s) <= GF_INS_TIME_EPS_S
                     ? ins_update(f, ms.type, &ms, 0.0, epochs, log)
                     : ins_past_measurement(f, &ms, epochs, log);
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
            ins_meas_directed(f, MS(j), &msd);
            const gf_ins_meas *ms = &msd;
            if (dir * (ms->t_s - t_prev) <= GF_INS_TIME_EPS_S) {
                /* valid at the filter's time (the first sample of a record whose first
                 * measurement is at its start): applied there; earlier: delayed or stale */
                if (fabs(ms->t_s - t_prev) <= GF_INS_TIME_EPS_S) {
                    st = ins_propagate(f, epochs);
                    if (st == GF_OK)
                        st = ins_update(f, ms->type, ms, 0.0, epochs, log);
                } else {
                    st = ins_past_measurement(f, ms, epochs, log);
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
                st = ins_propagate(f, epochs);
            if (st == GF_OK)
                st = ins_update(f, ms->type, ms, 0.0, epochs, log);
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
        ins_history_push(f);
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
        !(t_s[m - 2] - f->last_regular_t_s < c->propagation_interval_s - GF_INS_TIME_EPS_S))
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
    f->rate_lag_s = 0.5 * dt[l];
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
    if (!ins_layout_is_valid(f))
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
    if (out->transfer) {
        double *t = out->transfer + GF_INS_N_TRANSFER * k;
        memcpy(t, f->transfer, sizeof f->transfer);
        gf_v3_scale(f->transfer + T_FLEX_RATE, dir, t + T_FLEX_RATE);
    }
    if (out->state_std) {
        const int n = f->n_states;
        double *sd = out->state_std + (size_t)n * k;
        for (int i = 0; i < n; ++i)
            sd[i] = sqrt(f->kf.P[i * n + i]);
    }
}

static int output_ok(const gf_ins_output *out)
{
    return !out || (out->t_s && out->q_bn && out->v_n_m_s && out->pos);
}

/* Forward over samples 0..n-1 in the order given (gf_ins_run), or backward over a record
 * stored in increasing time (gf_ins_run_backward: sample k = n-1 .. 0 takes the state to
 * t_s[k-1], t_start_s for k = 0, with increments; to t_s[k] with rates). out may be NULL. */
gf_status ins_walk(gf_ins_filter *f, int backward, size_t n, const double *t_s,
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
    if (!ins_layout_is_valid(f))
        return GF_ERR_BAD_PARAMETER;
    const double dir = dir_of(f);
    for (size_t j = 1; j < n_meas; ++j)
        if (!(dir * (meas[j].t_s - meas[j - 1].t_s) >= 0.0))
            return GF_ERR_BAD_TIME;
    return ins_walk(f, 0, n, t_s, gyro, accel, 0.0, n_meas, meas, out, epochs, log, n_done,
                    meas_done);
}

/* checks of a record stored in increasing time, and of its measurements */
gf_status ins_record_check(size_t n, const double *t_s, size_t n_meas, const gf_ins_meas *meas)
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
    if (!ins_layout_is_valid(f) || dir_of(f) > 0.0)
        return GF_ERR_BAD_PARAMETER;
    if (n == 0)
        return GF_OK;
    gf_status st = ins_record_check(n, t_s, n_meas, meas);
    if (st != GF_OK)
        return st;
    const int rates = f->cfg.input == GF_SINS_INPUT_RATES;
    if (!isfinite(t_start_s) || (!rates && !(t_start_s < t_s[0])))
        return GF_ERR_BAD_TIME;
    if (fabs(f->t_s - t_s[n - 1]) > GF_INS_TIME_EPS_S)
        return GF_ERR_BAD_TIME;
    return ins_walk(f, 1, n, t_s, gyro, accel, t_start_s, n_meas, meas, out, NULL, log, n_done,
                    meas_done);
}
