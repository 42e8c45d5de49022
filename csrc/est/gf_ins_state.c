/* gf_ins_state.c — the error state of the INS/GNSS filter and the navigation hypotheses
 * it stands for (nominal (-) error, and back), the feedback that closes the loop, and
 * what the filter keeps from its state (see gf_ins_gnss.h: states, closed loop). */
#include "est/gf_ins_gnss.h"

#include <math.h>
#include <string.h>

#include "base/gf_math.h"
#include "est/gf_ins_internal.h"
#include "nav/gf_earth.h"
#include "nav/gf_sins.h"

/* error-state block -> first index of its estimates in sensors[] (transfer = 0) or in
 * transfer[] (transfer = 1), for the blocks present */
typedef struct sensor_block {
    int idx, sens, len, transfer;
} sensor_block;

#define MAX_BLOCKS 11

static int sensor_blocks(const gf_ins_filter *f, sensor_block b[MAX_BLOCKS])
{
    int nb = 0;
    b[nb++] = (sensor_block){IBG, S_BG, 3, 0};
    b[nb++] = (sensor_block){IBA, S_BA, 3, 0};
    if (f->idx_sg >= 0)
        b[nb++] = (sensor_block){f->idx_sg, S_SG, 3, 0};
    if (f->idx_sa >= 0)
        b[nb++] = (sensor_block){f->idx_sa, S_SA, 3, 0};
    if (f->idx_baro >= 0)
        b[nb++] = (sensor_block){f->idx_baro, S_BARO, 1, 0};
    if (f->idx_odo >= 0)
        b[nb++] = (sensor_block){f->idx_odo, S_ODO, 1, 0};
    if (f->idx_mount >= 0)
        b[nb++] = (sensor_block){f->idx_mount, S_MOUNT, 2, 0};
    if (f->idx_tmount >= 0)
        b[nb++] = (sensor_block){f->idx_tmount, T_MOUNT, 3, 1};
    if (f->idx_tlever >= 0)
        b[nb++] = (sensor_block){f->idx_tlever, T_LEVER, 3, 1};
    if (f->idx_toffset >= 0)
        b[nb++] = (sensor_block){f->idx_toffset, T_OFFSET, 1, 1};
    if (f->idx_flex >= 0)
        b[nb++] = (sensor_block){f->idx_flex, T_FLEX, 6, 1};
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
    memcpy(out->t, f->transfer, sizeof out->t);
    sensor_block b[MAX_BLOCKS];
    const int nb = sensor_blocks(f, b);
    for (int k = 0; k < nb; ++k) {
        double *est = b[k].transfer ? out->t : out->s;
        for (int i = 0; i < b[k].len; ++i)
            est[b[k].sens + i] += dx[b[k].idx + i];
    }
}

void ins_hyp_from_state(const gf_ins_filter *f, const gf_sins_state *nav, const double *sens,
                        const double *dx, nav_hyp *out)
{
    hyp_from_error(f, nav->q_bn, nav->v_n_m_s, nav->lat_rad, nav->lon_rad, nav->h_m, sens, dx,
                   out);
}

/* dx of a hypothesis about a nominal: the inverse of hyp_from_error */
void ins_error_from_hyp(const gf_ins_filter *f, const gf_sins_state *nom, const double *sens,
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
    sensor_block b[MAX_BLOCKS];
    const int nb = sensor_blocks(f, b);
    for (int k = 0; k < nb; ++k)
        for (int i = 0; i < b[k].len; ++i)
            dx[b[k].idx + i] = b[k].transfer ? hy->t[b[k].sens + i] - f->transfer[b[k].sens + i]
                                             : hy->s[b[k].sens + i] - sens[b[k].sens + i];
}

/* ---- what the filter keeps from its state ------------------------------------------ */

void ins_refresh_scale(gf_ins_filter *f)
{
    for (int i = 0; i < 3; ++i) {
        f->inv_scale[i] = 1.0 / (1.0 + f->sensors[S_SG + i]);
        f->inv_scale[3 + i] = 1.0 / (1.0 + f->sensors[S_SA + i]);
    }
}

void ins_refresh_std(gf_ins_filter *f)
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

gf_status ins_feedback(gf_ins_filter *f)
{
    nav_hyp hy;
    ins_hyp_from_state(f, &f->nav, f->sensors, f->kf.x, &hy);
    const gf_status st = gf_sins_set_navigation(&f->nav, hy.q, hy.v, hy.lat, hy.lon, hy.h);
    if (st != GF_OK)
        return GF_ERR_DIVERGED;
    memcpy(f->sensors, hy.s, sizeof f->sensors);
    memcpy(f->transfer, hy.t, sizeof f->transfer);
    memset(f->kf.x, 0, sizeof f->kf.x);
    ins_refresh_scale(f);
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
