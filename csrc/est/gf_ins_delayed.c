/* gf_ins_delayed.c — measurements that arrive late: the nominal's recent history (one
 * entry per IMU sample) and the update of a measurement from the nominal of its time of
 * validity (see gf_ins_gnss.h, max_latency_s). */
#include "est/gf_ins_gnss.h"

#include <math.h>
#include <string.h>

#include "base/gf_math.h"
#include "est/gf_ins_internal.h"
#include "nav/gf_sins.h"

void ins_history_push(gf_ins_filter *f)
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
gf_status ins_past_measurement(gf_ins_filter *f, const gf_ins_meas *ms, gf_ins_epochs *ep,
                               gf_ins_log *log)
{
    gf_sins_state ref;
    double w[3];
    if (f->cfg.max_latency_s > 0.0 && dir_of(f) > 0.0 && f->t_s - ms->t_s <= f->cfg.max_latency_s &&
        history_at(f, ms->t_s, &ref, w)) {
        const gf_status st = ins_propagate(f, ep);
        if (st != GF_OK)
            return st;
        return ins_update_at(f, ms->type, ms, 0.0, &ref, w, ep, log);
    }
    f->n_rejected++;
    ins_log_entry(log, ms->t_s, ms->type, GF_INS_REJECTED_STALE, ins_meas_model_of(ms->type)->rows,
                  NAN, NULL, NULL);
    return GF_OK;
}

