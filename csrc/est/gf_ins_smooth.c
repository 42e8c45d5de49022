/* gf_ins_smooth.c — what the smoother of the INS/GNSS filter needs and does: the epochs a
 * forward run records (propagation and measurement instants), the Rauch-Tung-Striebel
 * backward pass over them and the smoothed solution (see gf_ins_gnss.h). */
#include "est/gf_ins_gnss.h"

#include <math.h>
#include <string.h>

#include "base/gf_math.h"
#include "est/gf_ins_internal.h"
#include "est/gf_kalman.h"

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
gf_status ins_epoch_open(const gf_ins_filter *f, gf_ins_epochs *ep, const double *Phi)
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
gf_status ins_epoch_update(const gf_ins_filter *f, gf_ins_epochs *ep, const double *dx)
{
    if (!ep)
        return GF_OK;
    if (ep->count == 0 || fabs(ep->t_s[ep->count - 1] - f->t_s) > GF_INS_TIME_EPS_S) {
        const gf_status st = ins_epoch_open(f, ep, NULL);
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

gf_status gf_ins_epochs_begin(gf_ins_filter *f, gf_ins_epochs *epochs)
{
    if (!f || !epochs || !epochs->t_s || !epochs->nav || !epochs->sensors || !epochs->dx ||
        !epochs->P_prior || !epochs->P_post || !epochs->Phi)
        return GF_ERR_NULL_POINTER;
    return ins_epoch_open(f, epochs, NULL);
}

/* The RTS recursion (Rauch, Tung & Striebel 1965, docs/references.md) over epochs
 * 0..count-2 of *ep, from the smoothed error and covariance of its last epoch, given in
 * xs and Ps: x^s_e = G_e (x^s_e+1 + dx_e+1), P^s_e = P+_e + G_e (P^s_e+1 - P-_e+1) G_e^T,
 * G_e = P+_e Phi_e+1^T (P-_e+1)^-1 (gf_kalman_rts_step). The one loop of both entry
 * points: a pass in blocks is the one-call pass, bit for bit. */
static gf_status smooth_back(size_t n, const gf_ins_epochs *ep, double *xs, double *Ps)
{
    const size_t E = ep->count, tri = n * (n + 1) / 2;
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

static gf_status smooth_args(size_t n, const gf_ins_epochs *ep, const double *xs, const double *Ps)
{
    if (!ep || !xs || !Ps || !ep->P_post || !ep->P_prior || !ep->Phi || !ep->dx)
        return GF_ERR_NULL_POINTER;
    if (n == 0 || n > NMAX || ep->count > ep->capacity)
        return GF_ERR_BAD_SIZE;
    return GF_OK;
}

gf_status gf_ins_smooth(size_t n, const gf_ins_epochs *ep, double *xs, double *Ps)
{
    const gf_status st = smooth_args(n, ep, xs, Ps);
    if (st != GF_OK)
        return st;
    const size_t E = ep->count, tri = n * (n + 1) / 2;
    if (E == 0)
        return GF_OK;
    memset(xs + n * (E - 1), 0, n * sizeof *xs);
    if (Ps != ep->P_post)
        memcpy(Ps + tri * (E - 1), ep->P_post + tri * (E - 1), tri * sizeof *Ps);
    return smooth_back(n, ep, xs, Ps);
}

gf_status gf_ins_smooth_block(size_t n, const gf_ins_epochs *ep, double *xs, double *Ps)
{
    const gf_status st = smooth_args(n, ep, xs, Ps);
    if (st != GF_OK)
        return st;
    const size_t E = ep->count, tri = n * (n + 1) / 2;
    if (E == 0)
        return GF_ERR_BAD_SIZE;
    /* the given smoothed epoch: finite, its variances >= 0 */
    for (size_t i = 0; i < n; ++i)
        if (!isfinite(xs[n * (E - 1) + i]))
            return GF_ERR_NONFINITE_INPUT;
    for (size_t k = 0; k < tri; ++k)
        if (!isfinite(Ps[tri * (E - 1) + k]))
            return GF_ERR_NONFINITE_INPUT;
    for (size_t i = 0, k = 0; i < n; k += n - i, ++i)
        if (Ps[tri * (E - 1) + k] < 0.0)
            return GF_ERR_BAD_PARAMETER;
    return smooth_back(n, ep, xs, Ps);
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
