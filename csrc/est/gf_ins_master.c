/* gf_ins_master.c — transfer alignment (issue 24): the measurement models of a master INS
 * seen from this filter's (the slave's) state — the master's velocity, attitude and
 * position, with the mounting, the lever arm, the time offset between the two streams and
 * the structural flexure — rows of the measurement table of gf_ins_meas.c. The equations
 * and their conventions are in gf_ins_gnss.h, "Transfer alignment"; the states are
 * true - estimated and z_err = predicted - measured = H dx, so H = -dy/d(dx) with the
 * hypothesis v = v_nom - dv, L = L_nom - dL, C = exp([phi x]) C_nom and the estimates +
 * the states (transfer[]). */
#include "est/gf_ins_gnss.h"

#include <math.h>
#include <string.h>

#include "base/gf_math.h"
#include "est/gf_ins_internal.h"
#include "nav/gf_earth.h"
#include "nav/gf_sins.h"

/* ---- the mounting: C_s^m = M(a) = Rz(-psi) Rx(theta) Ry(gamma) --------------------- */

typedef double m3[3][3];

/* M(a) and its partial derivatives dM[k] = dM/da_k (a = heading, pitch, roll; the
 * factors of gf_euler_to_quat as matrices: Rz(-psi) rotates by -psi about z) */
static void mount_matrices(const double a[3], gf_mat3 *M, gf_mat3 dM[3])
{
    const double cp = cos(a[0]), sp = sin(a[0]), ct = cos(a[1]), st = sin(a[1]);
    const double cg = cos(a[2]), sg = sin(a[2]);
    const gf_mat3 Rz = {{{cp, sp, 0.0}, {-sp, cp, 0.0}, {0.0, 0.0, 1.0}}};
    const gf_mat3 dRz = {{{-sp, cp, 0.0}, {-cp, -sp, 0.0}, {0.0, 0.0, 0.0}}};
    const gf_mat3 Rx = {{{1.0, 0.0, 0.0}, {0.0, ct, -st}, {0.0, st, ct}}};
    const gf_mat3 dRx = {{{0.0, 0.0, 0.0}, {0.0, -st, -ct}, {0.0, ct, -st}}};
    const gf_mat3 Ry = {{{cg, 0.0, sg}, {0.0, 1.0, 0.0}, {-sg, 0.0, cg}}};
    const gf_mat3 dRy = {{{-sg, 0.0, cg}, {0.0, 0.0, 0.0}, {-cg, 0.0, -sg}}};
    gf_mat3 t;
    gf_m3_mul(&Rz, &Rx, &t);
    gf_m3_mul(&t, &Ry, M);
    if (!dM)
        return;
    gf_m3_mul(&t, &dRy, &dM[2]);
    gf_m3_mul(&dRz, &Rx, &t);
    gf_m3_mul(&t, &Ry, &dM[0]);
    gf_m3_mul(&Rz, &dRx, &t);
    gf_m3_mul(&t, &Ry, &dM[1]);
}

/* the mounting angles of a hypothesis: configured + estimated + flexure */
static void mount_angles(const gf_ins_filter *f, const nav_hyp *hy, double a[3])
{
    for (int i = 0; i < 3; ++i)
        a[i] = f->cfg.master_mount_rad[i] + hy->t[T_MOUNT + i] + hy->t[T_FLEX + i];
}

/* ---- the master attitude predicted from a hypothesis ---------------------------------- */

/* What every master kind computes from a hypothesis: D = C_m^n at the master's instant,
 * its quaternion, the lever arm r and, from the nominal, the mean rate wbar (slave axes)
 * and its n-frame image Wn = C_s^n R_tau wbar; the master's rate wm (master axes). */
typedef struct master_geo {
    double qD[4];
    gf_mat3 D, CR;           /* C_m^n; C_s^n R_tau */
    double r[3], wm[3], Wn[3];
    double dir;
} master_geo;

static void master_geo_of(const ins_meas_ctx *c, const nav_hyp *hy, master_geo *g)
{
    const gf_ins_filter *f = c->f;
    const nav_hyp *nom = c->nom;
    g->dir = dir_of(f);
    /* the master's rate: measured, or (no measurement) the slave's in master axes */
    double a_nom[3];
    gf_mat3 Mg;
    mount_angles(f, nom, a_nom);
    mount_matrices(a_nom, &Mg, NULL);
    double (*Mn)[3] = Mg.m;
    const double *ws = c->w_comp;
    if (c->ms) {
        memcpy(g->wm, c->ms->aux, sizeof g->wm);
    } else {
        for (int i = 0; i < 3; ++i)
            g->wm[i] = Mn[i][0] * ws[0] + Mn[i][1] * ws[1] + Mn[i][2] * ws[2];
    }
    /* wbar: the mean rate over (t, t + dir tau) to second order (slave axes), interpolated
     * linearly between the slave's rate, which describes t - lag (the mean of the last
     * increment), and the master's at t + dir tau (with the nominal offset) */
    const double lag = f->rate_lag_s;
    const double tn = g->dir * (f->cfg.master_time_offset_s + nom->t[T_OFFSET]);
    const double wt = fabs(tn + lag) > 1e-9 ? (0.5 * tn + lag) / (tn + lag) : 0.5;
    /* ... less the navigation frame's turn w_in^n = w_ie^n + w_en^n (nominal; C_n^s of
     * the nominal): the attitude C_s^n changes at w_ns^s = w_is^s - C_n^s w_in^n, not at
     * the gyros' rate. Its value over tau is ~1e-6 rad, but it is the time offset's
     * column: on a straight road the gyros see the Earth rate (7e-5 rad/s) while the
     * attitude stands still, and with w_is the filter learnt the offset from nothing
     * (30 ms prior down to 6 ms in 100 s, its error 15 ms) */
    const double W = g->dir * GF_WGS84_OMEGA_IE_RAD_S;
    const double win[3] = {-nom->v[1] / c->lf->kN, W * cos(nom->lat) + nom->v[0] * cos(nom->lat) / c->lf->kE,
                           W * sin(nom->lat) + nom->v[0] * sin(nom->lat) / c->lf->kE};
    double wbar[3];
    for (int i = 0; i < 3; ++i) {
        const double wm_s = Mn[0][i] * g->wm[0] + Mn[1][i] * g->wm[1] + Mn[2][i] * g->wm[2];
        const double wn_s = nom->C.m[0][i] * win[0] + nom->C.m[1][i] * win[1] + nom->C.m[2][i] * win[2];
        wbar[i] = ws[i] + wt * (wm_s - ws[i]) - wn_s;
    }
    const double tau = f->cfg.master_time_offset_s + hy->t[T_OFFSET];
    double rv[3], qR[4], qCR[4], qM[4], qMc[4], a[3];
    gf_v3_scale(wbar, g->dir * tau, rv);
    gf_q_from_rotvec(rv, qR);
    gf_q_mul(hy->q, qR, qCR);
    mount_angles(f, hy, a);
    gf_euler_to_quat(a, qM);
    gf_q_conj(qM, qMc);
    gf_q_mul(qCR, qMc, g->qD);
    gf_q_to_dcm(g->qD, &g->D);
    gf_q_to_dcm(qCR, &g->CR);
    gf_m3_mul_v3(&g->CR, wbar, g->Wn);
    for (int i = 0; i < 3; ++i)
        g->r[i] = f->cfg.master_lever_arm_m[i] + hy->t[T_LEVER + i];
}

/* the Earth rate at latitude lat in the filter's direction of time, and d/dL of it */
static void earth_rate(const gf_ins_filter *f, double lat, double w[3], double dw[3])
{
    const double W = dir_of(f) * GF_WGS84_OMEGA_IE_RAD_S;
    w[0] = 0.0;
    w[1] = W * cos(lat);
    w[2] = W * sin(lat);
    dw[0] = 0.0;
    dw[1] = -W * sin(lat);
    dw[2] = W * cos(lat);
}

/* rows of [a x] */
static void skew3(const double a[3], m3 S)
{
    S[0][0] = 0.0;   S[0][1] = -a[2]; S[0][2] = a[1];
    S[1][0] = a[2];  S[1][1] = 0.0;   S[1][2] = -a[0];
    S[2][0] = -a[1]; S[2][1] = a[0];  S[2][2] = 0.0;
}

/* dD/da_k = C_s^n R_tau (dM/da_k)^T (n x m), for the three angles */
static void mount_derivatives(const ins_meas_ctx *c, const nav_hyp *nom, const master_geo *g,
                              m3 dD[3])
{
    double a[3];
    gf_mat3 M, dM[3];
    mount_angles(c->f, nom, a);
    mount_matrices(a, &M, dM);
    for (int k = 0; k < 3; ++k)
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                dD[k][i][j] = g->CR.m[i][0] * dM[k].m[j][0] + g->CR.m[i][1] * dM[k].m[j][1] +
                              g->CR.m[i][2] * dM[k].m[j][2];
}

/* the columns of the mounting and the flexure angles (the flexure adds to the mounting's
 * angles: the same column) get col[3][k] (rows i) */
static void put_angle_columns(const gf_ins_filter *f, double *H, double col[3][3])
{
    const int n = f->n_states;
    for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k) {
            if (f->idx_tmount >= 0)
                H[i * n + f->idx_tmount + k] = col[i][k];
            if (f->idx_flex >= 0)
                H[i * n + f->idx_flex + k] = col[i][k];
        }
}

/* the nominal's acceleration a = C_s^n f^s + g^n (filter's direction of time: f and C
 * are the same in reverse, and so is a), at the time f describes: t - lag, where the
 * body axes were turned back by w lag, C(t - lag) = C (I - [w lag x]) */
static void nominal_acceleration(const ins_meas_ctx *c, double acc[3])
{
    const nav_hyp *nom = c->nom;
    double wf[3], fl[3];
    gf_v3_cross(c->w_comp, c->f_comp, wf);
    gf_v3_axpy(c->f_comp, -c->f->rate_lag_s, wf, fl);
    gf_m3_mul_v3(&nom->C, fl, acc);
    double g = 0.0;
    if (gf_earth_gravity(nom->lat, nom->h, &g) == GF_OK)
        acc[2] -= g;
}

/* ---- master velocity ----------------------------------------------------------------- */

void ins_master_vel_predict(const ins_meas_ctx *c, const nav_hyp *hy, double *y)
{
    master_geo g;
    master_geo_of(c, hy, &g);
    double wr[3], vlev[3], u[3], wie[3], dwie[3], cor[3], acc[3];
    gf_v3_cross(g.wm, g.r, wr);
    gf_m3_mul_v3(&g.D, wr, vlev);
    gf_m3_mul_v3(&g.D, g.r, u);
    earth_rate(c->f, hy->lat, wie, dwie);
    gf_v3_cross(wie, u, cor);
    nominal_acceleration(c, acc);
    const double tau = c->f->cfg.master_time_offset_s + hy->t[T_OFFSET];
    for (int i = 0; i < 3; ++i)
        y[i] = hy->v[i] + g.dir * tau * acc[i] - vlev[i] + cor[i];
}

#define HH(i, j) H[(i) * n + (j)]

void ins_master_vel_jacobian(const ins_meas_ctx *c, const nav_hyp *nom, double *H)
{
    const gf_ins_filter *f = c->f;
    const int n = f->n_states;
    master_geo g;
    master_geo_of(c, nom, &g);
    double wr[3], vlev[3], u[3], wie[3], dwie[3], acc[3];
    gf_v3_cross(g.wm, g.r, wr);
    gf_m3_mul_v3(&g.D, wr, vlev);
    gf_m3_mul_v3(&g.D, g.r, u);
    earth_rate(f, nom->lat, wie, dwie);
    m3 Sv, Su, Sw, Swm;
    skew3(vlev, Sv);
    skew3(u, Su);
    skew3(wie, Sw);
    skew3(g.wm, Swm);
    double du[3];
    gf_v3_cross(dwie, u, du);
    for (int i = 0; i < 3; ++i) {
        HH(i, IV + i) = 1.0;
        HH(i, IP) = du[i];                     /* d(w_ie)/dL x u, L_hyp = L - dL */
        for (int j = 0; j < 3; ++j) {          /* -[vlev x] + [w_ie x][u x] */
            double wu = 0.0;
            for (int k = 0; k < 3; ++k)
                wu += Sw[i][k] * Su[k][j];
            HH(i, IA + j) = -Sv[i][j] + wu;
        }
    }
    if (f->idx_tmount >= 0 || f->idx_flex >= 0) {
        m3 dD[3];
        mount_derivatives(c, nom, &g, dD);
        double col[3][3];
        for (int k = 0; k < 3; ++k) {           /* dD_k w - w_ie x (dD_k r) */
            double a1[3], a2[3], a3[3];
            for (int i = 0; i < 3; ++i) {
                a1[i] = dD[k][i][0] * wr[0] + dD[k][i][1] * wr[1] + dD[k][i][2] * wr[2];
                a2[i] = dD[k][i][0] * g.r[0] + dD[k][i][1] * g.r[1] + dD[k][i][2] * g.r[2];
            }
            gf_v3_cross(wie, a2, a3);
            for (int i = 0; i < 3; ++i)
                col[i][k] = a1[i] - a3[i];
        }
        put_angle_columns(f, H, col);
    }
    if (f->idx_tlever >= 0)                    /* D [wm x] - [w_ie x] D */
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                double a = 0.0, b = 0.0;
                for (int k = 0; k < 3; ++k) {
                    a += g.D.m[i][k] * Swm[k][j];
                    b += Sw[i][k] * g.D.m[k][j];
                }
                HH(i, f->idx_tlever + j) = a - b;
            }
    if (f->idx_toffset >= 0) {                 /* -dir (a - Wn x vlev + w_ie x (Wn x u)) */
        double t1[3], t2[3], t3[3];
        nominal_acceleration(c, acc);
        gf_v3_cross(g.Wn, vlev, t1);
        gf_v3_cross(g.Wn, u, t2);
        gf_v3_cross(wie, t2, t3);
        for (int i = 0; i < 3; ++i)
            HH(i, f->idx_toffset) = -g.dir * (acc[i] - t1[i] + t3[i]);
    }
}

/* ---- master attitude ------------------------------------------------------------------ */

void ins_master_att_predict(const ins_meas_ctx *c, const nav_hyp *hy, double *y)
{
    master_geo g;
    master_geo_of(c, hy, &g);
    double qref[4], qc[4], qe[4];
    if (c->ms) {
        gf_euler_to_quat(c->ms->z, qref);
    } else {
        master_geo gn;                         /* no measurement: the nominal's own D */
        master_geo_of(c, c->nom, &gn);
        memcpy(qref, gn.qD, sizeof qref);
    }
    gf_q_conj(qref, qc);
    gf_q_mul(g.qD, qc, qe);                    /* D C_ref^T as a quaternion */
    gf_q_to_rotvec(qe, y);
}

/* J_l^-1(y) of SO(3) (rows): log(exp([d x]) exp([y x])) = y + J_l^-1(y) d + O(d^2),
 * J_l^-1 = I - [y x] / 2 + (1 / t^2 - (1 + cos t) / (2 t sin t)) [y x]^2, t = |y|
 * (Barfoot, State Estimation for Robotics, 2017, eq. 7.77; the coefficient's series
 * 1/12 + t^2/720 below 1e-4 rad) */
static void left_jacobian_inverse(const double y[3], double J[3][3])
{
    const double t2 = gf_v3_dot(y, y), t = sqrt(t2);
    const double k = t < 1e-4 ? 1.0 / 12.0 + t2 / 720.0
                              : 1.0 / t2 - (1.0 + cos(t)) / (2.0 * t * sin(t));
    m3 S;
    skew3(y, S);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            double s2 = 0.0;
            for (int l = 0; l < 3; ++l)
                s2 += S[i][l] * S[l][j];
            J[i][j] = (i == j ? 1.0 : 0.0) - 0.5 * S[i][j] + k * s2;
        }
}

void ins_master_att_jacobian(const ins_meas_ctx *c, const nav_hyp *nom, double *H)
{
    const gf_ins_filter *f = c->f;
    const int n = f->n_states;
    master_geo g;
    master_geo_of(c, nom, &g);
    /* every column below is a small rotation of D on the left (n frame); at a residual
     * y0 = log(D C_meas^T) away from 0 (the start of an alignment: degrees) log moves by
     * J_l^-1(y0) of it: the columns are taken through it, so that H is the derivative of
     * the prediction at the nominal, not only where D = C_meas */
    double y0[3] = {0.0, 0.0, 0.0}, J[3][3];
    if (c->ms)
        ins_master_att_predict(c, nom, y0);
    left_jacobian_inverse(y0, J);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            HH(i, IA + j) = -J[i][j];
    if (f->idx_tmount >= 0 || f->idx_flex >= 0) {
        m3 dD[3];
        mount_derivatives(c, nom, &g, dD);
        double col[3][3];
        for (int k = 0; k < 3; ++k) {           /* -J vee(dD_k D^T) */
            m3 S;
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j)
                    S[i][j] = dD[k][i][0] * g.D.m[j][0] + dD[k][i][1] * g.D.m[j][1] +
                              dD[k][i][2] * g.D.m[j][2];
            const double v[3] = {0.5 * (S[2][1] - S[1][2]), 0.5 * (S[0][2] - S[2][0]),
                                 0.5 * (S[1][0] - S[0][1])};
            for (int i = 0; i < 3; ++i)
                col[i][k] = -(J[i][0] * v[0] + J[i][1] * v[1] + J[i][2] * v[2]);
        }
        put_angle_columns(f, H, col);
    }
    if (f->idx_toffset >= 0)
        for (int i = 0; i < 3; ++i)
            HH(i, f->idx_toffset) = -g.dir * (J[i][0] * g.Wn[0] + J[i][1] * g.Wn[1] + J[i][2] * g.Wn[2]);
}

/* ---- master position (the nominal's local ENU metres) --------------------------------- */

void ins_master_pos_predict(const ins_meas_ctx *c, const nav_hyp *hy, double *y)
{
    const local_frame *lf = c->lf;
    master_geo g;
    master_geo_of(c, hy, &g);
    double u[3];
    gf_m3_mul_v3(&g.D, g.r, u);
    const double tau = c->f->cfg.master_time_offset_s + hy->t[T_OFFSET];
    const double p[3] = {wrap_pi(hy->lon - lf->lon0) * lf->kE, (hy->lat - lf->lat0) * lf->kN,
                         hy->h - lf->h0};
    for (int i = 0; i < 3; ++i)
        y[i] = p[i] + g.dir * tau * c->nom->v[i] - u[i];
}

void ins_master_pos_jacobian(const ins_meas_ctx *c, const nav_hyp *nom, double *H)
{
    const gf_ins_filter *f = c->f;
    const local_frame *lf = c->lf;
    const int n = f->n_states;
    master_geo g;
    master_geo_of(c, nom, &g);
    double u[3];
    gf_m3_mul_v3(&g.D, g.r, u);
    m3 Su;
    skew3(u, Su);
    HH(0, IP + 1) = lf->kE;
    HH(1, IP + 0) = lf->kN;
    HH(2, IP + 2) = 1.0;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            HH(i, IA + j) = -Su[i][j];
    if (f->idx_tmount >= 0 || f->idx_flex >= 0) {
        m3 dD[3];
        mount_derivatives(c, nom, &g, dD);
        double col[3][3];
        for (int k = 0; k < 3; ++k)             /* dD_k r */
            for (int i = 0; i < 3; ++i)
                col[i][k] = dD[k][i][0] * g.r[0] + dD[k][i][1] * g.r[1] + dD[k][i][2] * g.r[2];
        put_angle_columns(f, H, col);
    }
    if (f->idx_tlever >= 0)
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                HH(i, f->idx_tlever + j) = g.D.m[i][j];
    if (f->idx_toffset >= 0) {                 /* -dir (v - Wn x u) */
        double t1[3];
        gf_v3_cross(g.Wn, u, t1);
        for (int i = 0; i < 3; ++i)
            HH(i, f->idx_toffset) = -g.dir * (nom->v[i] - t1[i]);
    }
}

#undef HH

/* a latitude the local frame can take */
int ins_master_pos_check(const gf_ins_meas *ms)
{
    return fabs(ms->z[0]) < GF_HALF_PI;
}

/* ---- the prior of a start from the master's attitude (gf_ins_gnss.h) ------------------ */

gf_status gf_ins_master_start_covariance(const gf_ins_config *cfg, const double *q_bn, double *P0)
{
    if (!cfg || !q_bn || !P0)
        return GF_ERR_NULL_POINTER;
    gf_ins_layout l;
    if (gf_ins_state_layout(cfg, &l) != GF_OK || l.idx_tmount < 0)
        return GF_ERR_BAD_PARAMETER;
    if (!gf_all_finite(q_bn, 4))
        return GF_ERR_NONFINITE_INPUT;
    const int n = l.n_states, a0 = l.idx_tmount;
    double q[4];
    if (!gf_q_normalize(q_bn, q))
        return GF_ERR_BAD_PARAMETER;
    gf_mat3 C, M, dM[3];
    gf_q_to_dcm(q, &C);
    mount_matrices(cfg->master_mount_rad, &M, dM);
    double G[3][3];   /* column k: the n-frame turn of the slave's axes per unit da_k */
    for (int k = 0; k < 3; ++k) {
        gf_mat3 S, Mt;
        gf_m3_transpose(&M, &Mt);
        gf_m3_mul(&Mt, &dM[k], &S);
        const double v[3] = {0.5 * (S.m[2][1] - S.m[1][2]), 0.5 * (S.m[0][2] - S.m[2][0]),
                             0.5 * (S.m[1][0] - S.m[0][1])};
        double w[3];
        gf_m3_mul_v3(&C, v, w);
        for (int i = 0; i < 3; ++i)
            G[i][k] = w[i];
    }
    double GP[3][3];   /* G P_aa */
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            GP[i][j] = G[i][0] * P0[(a0 + 0) * n + a0 + j] + G[i][1] * P0[(a0 + 1) * n + a0 + j] +
                       G[i][2] * P0[(a0 + 2) * n + a0 + j];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const double gpg = GP[i][0] * G[j][0] + GP[i][1] * G[j][1] + GP[i][2] * G[j][2];
            P0[(IA + i) * n + IA + j] += gpg;
            P0[(IA + i) * n + a0 + j] = GP[i][j];
            P0[(a0 + j) * n + IA + i] = GP[i][j];
        }
    for (int i = 0; i < 3; ++i)       /* exactly symmetric (G P G^T is, up to rounding) */
        for (int j = i + 1; j < 3; ++j) {
            const double m = 0.5 * (P0[(IA + i) * n + IA + j] + P0[(IA + j) * n + IA + i]);
            P0[(IA + i) * n + IA + j] = P0[(IA + j) * n + IA + i] = m;
        }
    return GF_OK;
}
