/* gf_ins_update.c — one update of the INS/GNSS filter: the kind's model from the table
 * (gf_ins_meas.c), the NIS gate with its reset, the EKF or UKF update on gf_kalman, the
 * feedback, and the innovation log (see gf_ins_gnss.h). */
#include "est/gf_ins_gnss.h"

#include <math.h>
#include <string.h>

#include "base/gf_math.h"
#include "base/gf_stats.h"
#include "est/gf_ins_internal.h"
#include "est/gf_kalman.h"

_Static_assert(GF_CHI2_MAX_DOF == GF_KF_MAX_M, "the gate's quantile covers every update size");

void ins_log_entry(gf_ins_log *log, double t, int32_t type, int32_t status, int m, double nis,
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
gf_status ins_update_at(gf_ins_filter *f, int32_t type, const gf_ins_meas *ms, double std_int,
                        const gf_sins_state *ref, const double *w_ref, gf_ins_epochs *ep,
                        gf_ins_log *log)
{
    const ins_meas_model *mm = ins_meas_model_of(type);
    const int n = f->n_states, m = mm->rows;
    const int32_t refused = mm->refuse ? mm->refuse(f, ref) : 0;
    if (refused) {
        f->n_rejected++;
        ins_log_entry(log, ms ? ms->t_s : f->t_s, type, refused, m, NAN, NULL, NULL);
        return GF_OK;
    }
    local_frame lf;
    ins_local_frame_of(ref, &lf);
    const double zero[NMAX] = {0};
    nav_hyp nom;
    ins_hyp_from_state(f, ref, f->sensors, zero, &nom);
    const ins_meas_ctx mc = {f, &lf, w_ref, ms, &nom, f->f_b_m_s2};
    double y_nom[3], z[3] = {0, 0, 0}, r[3], R[9] = {0}, s_std[3];
    mm->predict(&mc, &nom, y_nom);
    if (ms)
        ins_meas_value(mm, &lf, ms, z);
    double sd[3] = {std_int, std_int, std_int};
    if (ms && mm->std)
        mm->std(f, ms, sd);
    else if (ms)
        memcpy(sd, ms->std, sizeof sd);
    for (int i = 0; i < m; ++i) {
        R[i * m + i] = sd[i] * sd[i];
        r[i] = y_nom[i] - z[i];
    }
    double gate = 0.0;
    int forced = 0;
    if (f->cfg.gate_probability > 0.0) {
        gf_chi2_quantile(m, f->cfg.gate_probability, &gate);
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
            ins_hyp_from_state(f, ref, f->sensors, X + p * n, &hy);
            mm->predict(&mc, &hy, y);
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
        ins_meas_jacobian(mm, &mc, &nom, H);
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
        ins_log_entry(log, t, type, GF_INS_REJECTED_SINGULAR, m, nis, r, s_std);
        return GF_OK;
    }
    if (st != GF_OK)
        return st;
    if (!accepted) {
        f->n_rejected++;
        f->gate_run[type]++;
        ins_log_entry(log, t, type, GF_INS_REJECTED_GATE, m, nis, r, s_std);
        return GF_OK;
    }
    f->n_updates++;
    f->gate_run[type] = 0;
    ins_log_entry(log, t, type, forced ? GF_INS_FORCED : GF_INS_ACCEPTED, m, nis, r, s_std);
    double dx[NMAX];
    memcpy(dx, f->kf.x, (size_t)n * sizeof *dx);
    st = ins_feedback(f);
    if (st != GF_OK)
        return st;
    st = ins_check_covariance(&f->kf);
    if (st != GF_OK)
        return st;
    f->nav0 = f->nav;
    memcpy(f->sensors0, f->sensors, sizeof f->sensors);
    ins_refresh_std(f);
    return ins_epoch_update(f, ep, dx);
}

gf_status ins_update(gf_ins_filter *f, int32_t type, const gf_ins_meas *ms, double std_int,
                     gf_ins_epochs *ep, gf_ins_log *log)
{
    return ins_update_at(f, type, ms, std_int, &f->nav, f->w_ib_b_rad_s, ep, log);
}
