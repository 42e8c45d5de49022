/* gf_ins_reverse.c — reverse-time filtering of the INS/GNSS filter and the
 * forward-backward processing of a stored record (seed 003 section 2; derivation in
 * gf_ins_gnss.h, "Reverse-time filtering"). */
#include "est/gf_ins_gnss.h"

#include <math.h>
#include <string.h>

#include "base/gf_math.h"
#include "est/gf_ins_internal.h"
#include "nav/gf_sins.h"

gf_status gf_ins_reverse(gf_ins_filter *f)
{
    if (!f)
        return GF_ERR_NULL_POINTER;
    if (!ins_layout_is_valid(f))
        return GF_ERR_BAD_PARAMETER;
    /* the covariance at the turning point (no epochs: the smoother does not cross it) */
    gf_status st = ins_propagate(f, NULL);
    if (st != GF_OK)
        return st;
    st = gf_sins_reverse(&f->nav);
    if (st != GF_OK)
        return st;
    /* x_r = D x, P_r = D P D, D = -1 on dv, dbg and the flexure rates (derivation in the
     * header) */
    const int n = f->n_states;
    double d[NMAX];
    for (int i = 0; i < n; ++i)
        d[i] = 1.0;
    for (int i = 0; i < 3; ++i) {
        d[IV + i] = d[IBG + i] = -1.0;
        if (f->idx_flex >= 0)
            d[f->idx_flex + 3 + i] = -1.0;
    }
    for (int i = 0; i < n; ++i) {
        f->kf.x[i] *= d[i];
        for (int j = 0; j < n; ++j)
            f->kf.P[i * n + j] *= d[i] * d[j];
    }
    for (int i = 0; i < 3; ++i) {
        f->sensors[S_BG + i] = -f->sensors[S_BG + i];
        f->transfer[T_FLEX_RATE + i] = -f->transfer[T_FLEX_RATE + i];
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
    ins_refresh_scale(f);
    ins_refresh_std(f);
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
    if (!ins_layout_is_valid(f) || dir_of(f) < 0.0 || n_fb < 0 || n_fb > 10000)
        return GF_ERR_BAD_PARAMETER;
    if (n < 2)
        return GF_ERR_BAD_SIZE;
    gf_status st = ins_record_check(n, t_s, n_meas, meas);
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
            st = ins_walk(f, 1, n, t_s, gyro, accel, t_start, n_before_end, meas, NULL, NULL, log,
                          NULL, NULL);
        else if (p == 0)
            st = ins_walk(f, 0, n, t_s, gyro, accel, t_start, n_meas, meas, NULL, NULL, log, NULL,
                          NULL);
        else
            st = ins_walk(f, 0, n, t_s, gyro, accel, t_start, n_meas - j_first, meas + j_first,
                          NULL, NULL, log, NULL, NULL);
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
