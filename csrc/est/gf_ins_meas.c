/* gf_ins_meas.c — the measurement models of the INS/GNSS filter (equations in
 * gf_ins_gnss.h, "Measurements"): one section per kind, its prediction and its Jacobian
 * together, and one table of the kinds that the update, the checks of a caller's
 * measurements and gf_ins_meas_model read. A new kind: its code in gf_ins_gnss.h
 * (GF_INS_MEAS_*, GF_INS_N_MEAS_KINDS one more), one section here, one row of kModels. */
#include "est/gf_ins_gnss.h"

#include <math.h>
#include <string.h>

#include "base/gf_math.h"
#include "est/gf_ins_internal.h"
#include "nav/gf_earth.h"
#include "nav/gf_sins.h"

/* ---- what the models share ----------------------------------------------------------- */

void ins_local_frame_of(const gf_sins_state *nav, local_frame *lf)
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

/* rows of [a x] */
static void skew_rows(const double a[3], double S[3][3])
{
    S[0][0] = 0.0;   S[0][1] = -a[2]; S[0][2] = a[1];
    S[1][0] = a[2];  S[1][1] = 0.0;   S[1][2] = -a[0];
    S[2][0] = -a[1]; S[2][1] = a[0];  S[2][2] = 0.0;
}

#define HH(i, j) H[(i) * n + (j)]

/* ---- GNSS position (antenna at the lever arm, the nominal's local ENU frame) --------- */

static void gnss_pos_predict(const ins_meas_ctx *c, const nav_hyp *hy, double *y)
{
    const gf_ins_filter *f = c->f;
    const local_frame *lf = c->lf;
    double cl[3];
    gf_m3_mul_v3(&hy->C, f->cfg.gnss_lever_arm_m, cl);
    double p[3];
    to_local(lf, hy->lat, hy->lon, hy->h, p);
    /* p_ant = p + C l (the lever arm is metres in ENU directly) */
    gf_v3_add(p, cl, y);
}

static void gnss_pos_jacobian(const ins_meas_ctx *c, const nav_hyp *nom, double *H)
{
    const gf_ins_filter *f = c->f;
    const local_frame *lf = c->lf;
    const int n = f->n_states;
    double cl[3], S[3][3];
    gf_m3_mul_v3(&nom->C, f->cfg.gnss_lever_arm_m, cl);
    skew_rows(cl, S);                                  /* [(C l) x] phi */
    HH(0, IP + 1) = lf->kE;
    HH(1, IP + 0) = lf->kN;
    HH(2, IP + 2) = 1.0;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            HH(i, IA + j) = S[i][j];
}

/* the measured antenna position (lat, lon, h) in the local frame */
static void gnss_pos_value(const local_frame *lf, const gf_ins_meas *ms, double *z)
{
    to_local(lf, ms->z[0], ms->z[1], ms->z[2], z);
}

/* a latitude the local frame can take */
static int gnss_pos_check(const gf_ins_meas *ms)
{
    return fabs(ms->z[0]) < GF_HALF_PI;
}

/* the reported stds, raised to the configured floor */
static void gnss_pos_std(const gf_ins_filter *f, const gf_ins_meas *ms, double *sd)
{
    for (int i = 0; i < 3; ++i)
        sd[i] = fmax(ms->std[i], f->cfg.gnss_position_std_floor_m[i]);
}

/* ---- GNSS velocity (antenna velocity, lever-arm rotation term) ----------------------- */

static void gnss_vel_predict(const ins_meas_ctx *c, const nav_hyp *hy, double *y)
{
    const gf_ins_filter *f = c->f;
    const double *w_comp = c->w_comp;
    double w_ib[3], w_eb[3], wl[3], cwl[3];
    hyp_rate(f, hy, w_comp, w_ib, w_eb);
    gf_v3_cross(w_eb, f->cfg.gnss_lever_arm_m, wl);
    gf_m3_mul_v3(&hy->C, wl, cwl);
    gf_v3_add(hy->v, cwl, y);
}

static void gnss_vel_jacobian(const ins_meas_ctx *c, const nav_hyp *nom, double *H)
{
    const gf_ins_filter *f = c->f;
    const double *w = c->w_comp;
    const int n = f->n_states;
    double w_ib[3], w_eb[3], wl[3], cwl[3], S[3][3], Lx[3][3];
    hyp_rate(f, nom, w, w_ib, w_eb);
    gf_v3_cross(w_eb, f->cfg.gnss_lever_arm_m, wl);
    gf_m3_mul_v3(&nom->C, wl, cwl);
    skew_rows(cwl, S);
    skew_rows(f->cfg.gnss_lever_arm_m, Lx);
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
}

/* ---- barometer (height + bias) ------------------------------------------------------- */

static void baro_predict(const ins_meas_ctx *c, const nav_hyp *hy, double *y)
{
    (void)c;
    y[0] = hy->h + hy->s[S_BARO];
}

static void baro_jacobian(const ins_meas_ctx *c, const nav_hyp *nom, double *H)
{
    const gf_ins_filter *f = c->f;
    const int n = f->n_states;
    (void)nom;
    HH(0, IP + 2) = 1.0;
    if (f->idx_baro >= 0)
        HH(0, f->idx_baro) = -1.0;
}

/* ---- the odometer point: velocity in the odometer's axes (odometer, NHC) ------------- */

/* C_b^m of the odometer's mounting: the transpose of C_m^b = Rz(-heading_m) Rx(pitch_m)
 * (the Euler convention of gf_sins.h without roll) at pitch_m = cfg.odometer_mount_rad[0] +
 * s[S_MOUNT], heading_m = cfg.odometer_mount_rad[1] + s[S_MOUNT + 1] (s: the hypothesis'
 * sensor estimates); identity for zero angles (exactly: cos 0 = 1, sin 0 = 0, so the
 * products below keep their bits). dMp, dMh (may be NULL) receive dM/dpitch_m and
 * dM/dheading_m, entry by entry (rad^-1). */
static void odo_mount(const gf_ins_filter *f, const double *s, double M[3][3], double dMp[3][3],
                      double dMh[3][3])
{
    const double p = f->cfg.odometer_mount_rad[0] + s[S_MOUNT];
    const double hd = f->cfg.odometer_mount_rad[1] + s[S_MOUNT + 1];
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
    gf_v3_cross(w_eb, f->cfg.odometer_lever_arm_m, wl);
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

/* H of the odometer point's components: u_y scaled by (1 + k) (GF_INS_MEAS_ODO) or u_x
 * and u_z (GF_INS_MEAS_NHC) */
static void odo_point_jacobian(const ins_meas_ctx *c, const nav_hyp *nom, int32_t type,
                               double *H)
{
    const gf_ins_filter *f = c->f;
    const double *w_comp = c->w_comp, *w = w_comp;
    const int n = f->n_states, m = type == GF_INS_MEAS_ODO ? 1 : 2;
    /* u = C_b^m (C^T v + w_eb x l): du = C_b^m (C^T dv - C^T [v x] phi - [l x] dw)
     * + (dM/dpitch_m ub) dpitch_m + (dM/dheading_m ub) dheading_m, ub = C^T v + w_eb x l
     * the odometer point's body velocity and dM/d. the entry-wise derivatives of
     * M = C_b^m (odo_mount). The states are true - estimated and z_err = predicted -
     * measured, so the boresight columns are -k1 (dM/d. ub)_a; the other terms as
     * before (dv, phi, dw are computed - true). */
    double Vx[3][3], Lx[3][3], CtV[3][3], M[3][3], MCt[3][3], MCtV[3][3], MLx[3][3];
    skew_rows(nom->v, Vx);
    skew_rows(f->cfg.odometer_lever_arm_m, Lx);
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
}

/* ---- odometer (forward speed of the wheel, scale state) ------------------------------ */

static void odo_predict(const ins_meas_ctx *c, const nav_hyp *hy, double *y)
{
    const gf_ins_filter *f = c->f;
    const double *w_comp = c->w_comp;
    double u[3];
    odo_point_velocity(f, hy, w_comp, u);
    y[0] = (1.0 + hy->s[S_ODO]) * u[1];
}

static void odo_jacobian(const ins_meas_ctx *c, const nav_hyp *nom, double *H)
{
    odo_point_jacobian(c, nom, GF_INS_MEAS_ODO, H);
}

/* ---- non-holonomic constraint (no lateral, no vertical wheel velocity) --------------- */

static void nhc_predict(const ins_meas_ctx *c, const nav_hyp *hy, double *y)
{
    const gf_ins_filter *f = c->f;
    const double *w_comp = c->w_comp;
    double u[3];
    odo_point_velocity(f, hy, w_comp, u);
    y[0] = u[0];
    y[1] = u[2];
}

static void nhc_jacobian(const ins_meas_ctx *c, const nav_hyp *nom, double *H)
{
    odo_point_jacobian(c, nom, GF_INS_MEAS_NHC, H);
}

/* ---- zero velocity at standstill ----------------------------------------------------- */

static void zupt_predict(const ins_meas_ctx *c, const nav_hyp *hy, double *y)
{
    (void)c;
    gf_v3_copy(hy->v, y);
}

static void zupt_jacobian(const ins_meas_ctx *c, const nav_hyp *nom, double *H)
{
    const int n = c->f->n_states;
    (void)nom;
    for (int i = 0; i < 3; ++i)
        HH(i, IV + i) = 1.0;
}

/* ---- zero angular rate w.r.t. the Earth at standstill (the detector's mean rate) ----- */

static void zaru_predict(const ins_meas_ctx *c, const nav_hyp *hy, double *y)
{
    const gf_ins_filter *f = c->f;
    double w_ib[3], w_eb[3];
    hyp_rate(f, hy, f->still_w, w_ib, w_eb);
    gf_v3_copy(w_eb, y);
}

static void zaru_jacobian(const ins_meas_ctx *c, const nav_hyp *nom, double *H)
{
    const gf_ins_filter *f = c->f;
    const double *w = f->still_w;
    const int n = f->n_states;
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
}

/* ---- speed (tachometer, seed 003) ---------------------------------------------------- */

static void speed_predict(const ins_meas_ctx *c, const nav_hyp *hy, double *y)
{
    (void)c;
    /* seed 003 eq. 7: the SINS horizontal speed, scaled by the speed-scale estimate */
    y[0] = (1.0 + hy->s[S_ODO]) * hypot(hy->v[0], hy->v[1]);
}

static void speed_jacobian(const ins_meas_ctx *c, const nav_hyp *nom, double *H)
{
    const gf_ins_filter *f = c->f;
    const int n = f->n_states;
    /* seed 003 eq. 8 (Taylor expansion at the nominal), derived in the header:
     * dy = (1 + k) (v_E dv_E + v_N dv_N) / |v_h| - |v_h| dk; speed_refuse has refused
     * |v_h| < speed_min_m_s */
    const double sp = hypot(nom->v[0], nom->v[1]), k1 = 1.0 + nom->s[S_ODO];
    HH(0, IV + 0) = k1 * nom->v[0] / sp;
    HH(0, IV + 1) = k1 * nom->v[1] / sp;
    if (f->idx_odo >= 0)
        HH(0, f->idx_odo) = -sp;
}

/* the direction v_h / |v_h| is undefined or poorly known at low INS horizontal speed */
static int32_t speed_refuse(const gf_ins_filter *f, const gf_sins_state *ref)
{
    return hypot(ref->v_n_m_s[0], ref->v_n_m_s[1]) > f->cfg.speed_min_m_s
               ? 0
               : GF_INS_REJECTED_LOW_SPEED;
}

#undef HH

/* a kind whose prediction is already the difference from the measurement (the master's
 * attitude: the small angle between predicted and measured) */
static void zero_value(const local_frame *lf, const gf_ins_meas *ms, double *z)
{
    (void)lf;
    (void)ms;
    z[0] = z[1] = z[2] = 0.0;
}

/* ---- the table ----------------------------------------------------------------------- */

/* One row per kind, at the index of its code. */
static const ins_meas_model kModels[GF_INS_N_MEAS_KINDS] = {
    [GF_INS_MEAS_GNSS_POS] = {.kind = GF_INS_MEAS_GNSS_POS, .name = "gnss_pos", .rows = 3,
                              .external = 1, .predict = gnss_pos_predict,
                              .jacobian = gnss_pos_jacobian, .value = gnss_pos_value,
                              .check = gnss_pos_check, .std = gnss_pos_std},
    [GF_INS_MEAS_GNSS_VEL] = {.kind = GF_INS_MEAS_GNSS_VEL, .name = "gnss_vel", .rows = 3,
                              .external = 1, .reverses = 1, .predict = gnss_vel_predict,
                              .jacobian = gnss_vel_jacobian},
    [GF_INS_MEAS_BARO] = {.kind = GF_INS_MEAS_BARO, .name = "baro", .rows = 1, .external = 1,
                          .predict = baro_predict, .jacobian = baro_jacobian},
    [GF_INS_MEAS_ODO] = {.kind = GF_INS_MEAS_ODO, .name = "odometer", .rows = 1, .external = 1,
                         .reverses = 1, .predict = odo_predict, .jacobian = odo_jacobian},
    [GF_INS_MEAS_NHC] = {.kind = GF_INS_MEAS_NHC, .name = "nhc", .rows = 2,
                         .predict = nhc_predict, .jacobian = nhc_jacobian},
    [GF_INS_MEAS_ZUPT] = {.kind = GF_INS_MEAS_ZUPT, .name = "zupt", .rows = 3,
                          .predict = zupt_predict, .jacobian = zupt_jacobian},
    [GF_INS_MEAS_ZARU] = {.kind = GF_INS_MEAS_ZARU, .name = "zaru", .rows = 3,
                          .predict = zaru_predict, .jacobian = zaru_jacobian},
    [GF_INS_MEAS_SPEED] = {.kind = GF_INS_MEAS_SPEED, .name = "speed", .rows = 1, .external = 1,
                           .predict = speed_predict, .jacobian = speed_jacobian,
                           .refuse = speed_refuse},
    /* transfer alignment against a master INS: gf_ins_master.c */
    [GF_INS_MEAS_MASTER_VEL] = {.kind = GF_INS_MEAS_MASTER_VEL, .name = "master_vel", .rows = 3,
                                .external = 1, .reverses = 1, .aux = 1,
                                .predict = ins_master_vel_predict,
                                .jacobian = ins_master_vel_jacobian},
    [GF_INS_MEAS_MASTER_ATT] = {.kind = GF_INS_MEAS_MASTER_ATT, .name = "master_att", .rows = 3,
                                .external = 1, .aux = 1, .predict = ins_master_att_predict,
                                .jacobian = ins_master_att_jacobian, .value = zero_value},
    [GF_INS_MEAS_MASTER_POS] = {.kind = GF_INS_MEAS_MASTER_POS, .name = "master_pos", .rows = 3,
                                .external = 1, .aux = 1, .predict = ins_master_pos_predict,
                                .jacobian = ins_master_pos_jacobian, .value = gnss_pos_value,
                                .check = ins_master_pos_check},
};

const ins_meas_model *ins_meas_model_of(int32_t kind)
{
    if (kind < 1 || kind >= GF_INS_N_MEAS_KINDS || kModels[kind].kind != kind)
        return NULL;
    return kModels + kind;
}

void ins_meas_value(const ins_meas_model *mm, const local_frame *lf, const gf_ins_meas *ms,
                    double *z)
{
    if (mm->value)
        mm->value(lf, ms, z);
    else
        memcpy(z, ms->z, 3 * sizeof *z);
}

void ins_meas_jacobian(const ins_meas_model *mm, const ins_meas_ctx *c, const nav_hyp *nom,
                       double *H)
{
    memset(H, 0, (size_t)(mm->rows * c->f->n_states) * sizeof *H);
    mm->jacobian(c, nom, H);
}

/* ---- a caller's measurements --------------------------------------------------------- */

gf_status ins_meas_check(const gf_ins_meas *ms)
{
    const ins_meas_model *mm = ins_meas_model_of(ms->type);
    if (!mm || !mm->external)
        return GF_ERR_BAD_PARAMETER;
    const int m = mm->rows;
    if (!isfinite(ms->t_s) || !gf_all_finite(ms->z, (size_t)m) || !gf_all_finite(ms->std, (size_t)m) ||
        (mm->aux && !gf_all_finite(ms->aux, 3)))
        return GF_ERR_NONFINITE_INPUT;
    for (int i = 0; i < m; ++i)
        if (!(ms->std[i] > 0.0))
            return GF_ERR_BAD_PARAMETER;
    if (mm->check && !mm->check(ms))
        return GF_ERR_BAD_PARAMETER;
    return GF_OK;
}

/* the measurement as the filter uses it: in reverse (gf_ins_reverse) velocities change
 * sign (GNSS and master velocity, odometer forward speed: the rows with `reverses`), and
 * so do the master's rates (aux) of every master kind; positions, heights, attitudes and
 * the tachometer's speed magnitude do not */
void ins_meas_directed(const gf_ins_filter *f, const gf_ins_meas *in, gf_ins_meas *out)
{
    const ins_meas_model *mm = ins_meas_model_of(in->type);
    *out = *in;
    if (dir_of(f) < 0.0 && mm && mm->reverses)
        for (int i = 0; i < 3; ++i)
            out->z[i] = -in->z[i];
    if (dir_of(f) < 0.0 && mm && mm->aux)
        for (int i = 0; i < 3; ++i)
            out->aux[i] = -in->aux[i];
}

/* ---- entry points -------------------------------------------------------------------- */

gf_status gf_ins_meas_kind_info(int32_t kind, int32_t *rows, const char **name)
{
    const ins_meas_model *mm = ins_meas_model_of(kind);
    if (!mm)
        return GF_ERR_BAD_PARAMETER;
    if (rows)
        *rows = mm->rows;
    if (name)
        *name = mm->name;
    return GF_OK;
}

gf_status gf_ins_meas_model(const gf_ins_filter *f, int32_t kind, const gf_ins_meas *ms,
                            const double *dx, double *z_pred, double *H, int32_t *rows)
{
    if (!f)
        return GF_ERR_NULL_POINTER;
    const ins_meas_model *mm = ins_meas_model_of(kind);
    if (!mm || !ins_layout_is_valid(f))
        return GF_ERR_BAD_PARAMETER;
    if (ms && (ms->type != kind || ins_meas_check(ms) != GF_OK))
        return GF_ERR_BAD_PARAMETER;
    const int n = f->n_states;
    if (dx && !gf_all_finite(dx, (size_t)n))
        return GF_ERR_NONFINITE_INPUT;
    if (rows)
        *rows = mm->rows;
    if (mm->refuse && mm->refuse(f, &f->nav))
        return GF_ERR_SINGULAR_GEOMETRY;
    /* as the update builds them: the nominal's local frame, the filter's latest
     * compensated rate, the measurement as the filter uses it (in reverse, velocities
     * negated) */
    local_frame lf;
    ins_local_frame_of(&f->nav, &lf);
    gf_ins_meas msd;
    if (ms)
        ins_meas_directed(f, ms, &msd);
    const double zero[NMAX] = {0};
    nav_hyp nom, hy;
    ins_hyp_from_state(f, &f->nav, f->sensors, zero, &nom);
    const ins_meas_ctx mc = {f, &lf, f->w_ib_b_rad_s, ms ? &msd : NULL, &nom, f->f_b_m_s2};
    if (z_pred) {
        ins_hyp_from_state(f, &f->nav, f->sensors, dx ? dx : zero, &hy);
        mm->predict(&mc, &hy, z_pred);
    }
    if (H)
        ins_meas_jacobian(mm, &mc, &nom, H);
    return GF_OK;
}
