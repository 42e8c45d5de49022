/* gf_vehicle.c — rigid ground vehicle and its exact sensor outputs; see gf_vehicle.h. */
#include "sim/gf_vehicle.h"

#include <math.h>
#include <string.h>

#include "base/gf_math.h"
#include "base/gf_quad.h"
#include "nav/gf_earth.h"
#include "nav/gf_sins.h"

#define PIECE_MAX_S 0.25                 /* longest quadrature piece */
#define LAT_MAX_RAD (89.0 * GF_PI / 180.0)

/* Integration matrix of the Gauss-Legendre rule of gf_quad.h: int_{-1}^{x_j} g =
 * sum_i GL_S[j][i] g(x_i) for g a polynomial of degree <= 7 (the Lagrange interpolant through the nodes, integrated);
 * on a piece of <= 0.25 s the displacement at the nodes is then exact to round-off. */
static const double GL_S[8][8] = {
    {0.0506142681451881, -0.018211886611940037, 0.012561662294061027, -0.008966031226109283,
     0.006156982736653542, -0.003835350509274062, 0.0019455153281187389, -0.0005550166542337644},
    {0.1095186435351087, 0.11119051722668685, -0.02727959247156292, 0.016299417716720832,
     -0.010430704178293511, 0.006279505970927043, -0.0031298698218975582, 0.0008856046086844836},
    {0.09717507199782581, 0.24171904999434582, 0.156853322938944, -0.031950206723757535,
     0.01674346544045311, -0.009286931724209392, 0.004451429550570223, -0.0012376113905010302},
    {0.10373104194116252, 0.21238698029669628, 0.34134226854910765, 0.18134189168918033,
     -0.03204208264204926, 0.01448241312244411, -0.006395628620721124, 0.001718473168529707},
    {0.09951006312184661, 0.2287766630740955, 0.2992242327554432, 0.3947258660204113,
     0.18134189168918172, -0.027635622671220373, 0.009994054156678074, -0.0025025056507862104},
    {0.10246614768087735, 0.21792960490280414, 0.3229935776020966, 0.34594031793790897,
     0.39463399010211964, 0.15685332293894333, -0.019338015540971466, 0.004053464292550507},
    {0.10034293168169181, 0.22551090427527193, 0.30742713990696, 0.3731144875566557,
     0.3463843656616414, 0.3409862383494502, 0.11119051722668753, -0.008290107244732371},
    {0.10178355294461006, 0.22043551912525552, 0.3175419963871615, 0.35652680064170883,
     0.37164981460447216, 0.3011449835838263, 0.24059292106531532, 0.050614268145188296}};

/* Speed, heading and their derivatives at one time. */
typedef struct kin {
    double u, du;                /* m/s, m/s^2 */
    double psi, dpsi, ddpsi;     /* rad, rad/s, rad/s^2 */
} kin;

static kin kinematics(const gf_vehicle_state *st, double t_s)
{
    const gf_vehicle_segment *g = &st->active;
    const double tau = t_s - st->active_t0_s, r0 = st->heading_rate0_rad_s;
    kin k = {st->speed0_m_s, 0.0, st->heading0_rad + r0 * tau, r0, 0.0};
    if (g->duration_s > 0.0) {
        const double T = g->duration_s;
        double S, dS, ddS, I;
        gf_smooth_step(tau / T, &S, &dS, &ddS, &I);
        k.u += g->dspeed_m_s * S;
        k.du = g->dspeed_m_s * dS / T;
        k.psi += g->dheading_rate_rad_s * T * I + g->dheading_rad * S;
        k.dpsi += g->dheading_rate_rad_s * S + g->dheading_rad * dS / T;
        k.ddpsi = g->dheading_rate_rad_s * dS / T + g->dheading_rad * ddS / (T * T);
    }
    return k;
}

/* Truth and sensor rates at t_s, with the kinematics k at t_s and the displacement
 * (E, N); increments untouched. */
static gf_status evaluate(const gf_vehicle_state *st, double t_s, kin k, double E, double N,
                          gf_vehicle_sample *out)
{
    const gf_vehicle_profile *p = &st->profile;
    const double h = p->h0_m;
    const double kN = 1.0 / (st->R_M0_m + h), kE = 1.0 / ((st->R_N0_m + h) * cos(p->lat0_rad));
    const double sp = sin(k.psi), cp = cos(k.psi);
    const double vE = k.u * sp, vN = k.u * cp;
    const double aE = k.du * sp + k.u * cp * k.dpsi, aN = k.du * cp - k.u * sp * k.dpsi;
    const double L = p->lat0_rad + N * kN, lam = p->lon0_rad + E * kE;
    if (!(fabs(L) < LAT_MAX_RAD))
        return GF_ERR_DIVERGED;
    const double dL = vN * kN, dlam = vE * kE, ddL = aN * kN, ddlam = aE * kE;
    gf_earth e;
    gf_status st_e = gf_earth_update(&e, L, h, NULL, 1.0);
    if (st_e != GF_OK)
        return st_e;
    double dRM, dRN;
    gf_earth_radii_dlat(&e, &dRM, &dRN);
    const double s = e.sin_lat, c = e.cos_lat, RNh = e.R_N_m + h, RMh = e.R_M_m + h;
    const double W = GF_WGS84_OMEGA_IE_RAD_S;
    const double v[3] = {RNh * c * dlam, RMh * dL, 0.0};
    const double dv[3] = {dRN * dL * c * dlam - RNh * s * dL * dlam + RNh * c * ddlam,
                          dRM * dL * dL + RMh * ddL, 0.0};
    const double w_ie[3] = {0.0, W * c, W * s};
    const double w_en[3] = {-dL, dlam * c, dlam * s};
    double w_in[3], two_ie_en[3], cor[3], f_n[3];
    gf_v3_add(w_ie, w_en, w_in);
    gf_v3_axpy(w_en, 2.0, w_ie, two_ie_en); /* w_en + 2 w_ie */
    gf_v3_cross(two_ie_en, v, cor);
    f_n[0] = dv[0] + cor[0];
    f_n[1] = dv[1] + cor[1];
    f_n[2] = dv[2] + cor[2] + e.gravity_m_s2; /* - g^n, g^n = [0, 0, -gamma] */
    /* d(w_ie + w_en)/dt */
    const double w_in_dot[3] = {-ddL, -W * s * dL + ddlam * c - dlam * s * dL,
                                W * c * dL + ddlam * s + dlam * c * dL};
    /* attitude: heading psi, level; C_n^b = (C_b^n)^T rotates ENU vectors into the body */
    const double euler[3] = {k.psi, 0.0, 0.0};
    st_e = gf_euler_to_quat(euler, out->q_bn);
    if (st_e == GF_OK)
        st_e = gf_quat_to_euler(out->q_bn, out->euler_rad);
    if (st_e != GF_OK)
        return st_e;
    gf_mat3 C_bn;
    gf_q_to_dcm(out->q_bn, &C_bn);
    double w_in_b[3], w_in_dot_b[3], tmp[3];
    gf_m3t_mul_v3(&C_bn, w_in, w_in_b);
    gf_m3t_mul_v3(&C_bn, w_in_dot, w_in_dot_b);
    gf_m3t_mul_v3(&C_bn, f_n, out->accel_m_s2);
    const double w_nb[3] = {0.0, 0.0, -k.dpsi};
    gf_v3_add(w_nb, w_in_b, out->gyro_rad_s);
    gf_v3_cross(w_nb, w_in_b, tmp);
    out->gyro_dot_rad_s2[0] = w_in_dot_b[0] - tmp[0];
    out->gyro_dot_rad_s2[1] = w_in_dot_b[1] - tmp[1];
    out->gyro_dot_rad_s2[2] = -k.ddpsi + w_in_dot_b[2] - tmp[2];
    gf_v3_copy(v, out->v_n_m_s);
    out->time_s = t_s;
    out->lat_rad = L;
    out->lon_rad = lam;
    out->h_m = h;
    out->east_m = E;
    out->north_m = N;
    out->speed_m_s = k.u;
    out->heading_rate_rad_s = k.dpsi;
    return GF_OK;
}

/* Makes the next profile segment (or cruising) active at time t_s, continuing speed,
 * heading and heading rate. */
static void activate_next(gf_vehicle_state *st, double t_s)
{
    const kin k = kinematics(st, t_s);
    st->speed0_m_s = k.u;
    st->heading0_rad = k.psi;
    st->heading_rate0_rad_s = k.dpsi;
    st->active_t0_s = t_s;
    if (st->next_segment < st->profile.n_segments)
        st->active = st->profile.segment[st->next_segment++];
    else
        memset(&st->active, 0, sizeof st->active);
}

static double active_end(const gf_vehicle_state *st)
{
    return st->active.duration_s > 0.0 ? st->active_t0_s + st->active.duration_s : INFINITY;
}

/* Integrates displacement and increments over [a, b] inside the active segment: the
 * velocity at the 8 nodes gives the displacement at each node (GL_S) and at b (GF_GL8_W);
 * the sensor rates at the nodes give the increments (body, and through the mount, if
 * any, those of the mounted sensor: msum = [dtheta_s, dv_s]). */
static gf_status integrate_piece(gf_vehicle_state *st, double a, double b, double dth[3],
                                 double dv[3], const gf_vehicle_mount *mount, double msum[6])
{
    const double half = 0.5 * (b - a);
    double tj[8], vE[8], vN[8];
    kin kj[8];
    for (int j = 0; j < 8; ++j) {
        tj[j] = a + half * (GF_GL8_X[j] + 1.0);
        kj[j] = kinematics(st, tj[j]);
        vE[j] = kj[j].u * sin(kj[j].psi);
        vN[j] = kj[j].u * cos(kj[j].psi);
    }
    for (int j = 0; j < 8; ++j) {
        double dE = 0.0, dN = 0.0;
        for (int i = 0; i < 8; ++i) {
            dE += GL_S[j][i] * vE[i];
            dN += GL_S[j][i] * vN[i];
        }
        gf_vehicle_sample s;
        gf_status status = evaluate(st, tj[j], kj[j], st->east_m + half * dE,
                                    st->north_m + half * dN, &s);
        if (status != GF_OK)
            return status;
        for (int i = 0; i < 3; ++i) {
            dth[i] += half * GF_GL8_W[j] * s.gyro_rad_s[i];
            dv[i] += half * GF_GL8_W[j] * s.accel_m_s2[i];
        }
        if (mount) {
            double ws[3], fs[3];
            status = mount->fn(mount->ctx, tj[j], s.gyro_rad_s, s.accel_m_s2, ws, fs);
            if (status != GF_OK)
                return status;
            for (int i = 0; i < 3; ++i) {
                msum[i] += half * GF_GL8_W[j] * ws[i];
                msum[3 + i] += half * GF_GL8_W[j] * fs[i];
            }
        }
    }
    double e = 0.0, n = 0.0;
    for (int j = 0; j < 8; ++j) {
        e += GF_GL8_W[j] * vE[j];
        n += GF_GL8_W[j] * vN[j];
    }
    st->east_m += half * e;
    st->north_m += half * n;
    return GF_OK;
}

gf_status gf_vehicle_init(gf_vehicle_state *state, const gf_vehicle_profile *profile,
                          double start_time_s, gf_vehicle_sample *first, int *bad)
{
    if (bad)
        *bad = 0;
    if (!state || !profile)
        return GF_ERR_NULL_POINTER;
    const gf_vehicle_profile *p = profile;
    if (!isfinite(p->lat0_rad) || !isfinite(p->lon0_rad) || !isfinite(p->h0_m) ||
        !isfinite(p->heading0_rad) || !isfinite(p->speed0_m_s) ||
        !isfinite(p->heading_rate0_rad_s) || !isfinite(start_time_s))
        return GF_ERR_NONFINITE_INPUT;
    if (p->n_segments > GF_VEHICLE_MAX_SEGMENTS)
        return GF_ERR_BAD_SIZE;
    int which = 0;
    if (!(fabs(p->lat0_rad) < LAT_MAX_RAD))
        which = 1;
    else if (!(p->h0_m >= -1000.0 && p->h0_m <= 1e5))
        which = 2;
    else if (p->speed0_m_s < 0.0)
        which = 3;
    double u = p->speed0_m_s;
    for (size_t k = 0; k < p->n_segments && !which; ++k) {
        const gf_vehicle_segment *g = &p->segment[k];
        if (!isfinite(g->duration_s) || !isfinite(g->dspeed_m_s) ||
            !isfinite(g->dheading_rate_rad_s) || !isfinite(g->dheading_rad))
            return GF_ERR_NONFINITE_INPUT;
        u += g->dspeed_m_s; /* S is monotonic: the end speed is the extreme */
        if (!(g->duration_s > 0.0) || u < 0.0)
            which = 100 + (int)k;
    }
    if (which) {
        if (bad)
            *bad = which;
        return GF_ERR_BAD_PARAMETER;
    }
    gf_vehicle_state s;
    memset(&s, 0, sizeof s);
    s.profile = *p;
    s.time_s = start_time_s;
    s.speed0_m_s = p->speed0_m_s;
    s.heading0_rad = p->heading0_rad;
    s.heading_rate0_rad_s = p->heading_rate0_rad_s;
    s.active_t0_s = start_time_s;
    if (p->n_segments > 0)
        s.active = p->segment[s.next_segment++];
    gf_earth e;
    gf_status status = gf_earth_update(&e, p->lat0_rad, p->h0_m, NULL, 1.0);
    if (status != GF_OK)
        return status;
    s.R_M0_m = e.R_M_m;
    s.R_N0_m = e.R_N_m;
    gf_vehicle_sample first_sample;
    status = gf_vehicle_truth(&s, &first_sample);
    if (status != GF_OK)
        return status;
    *state = s;
    if (first)
        *first = first_sample;
    return GF_OK;
}

/* What a step or a command uses to index the profile or size its loops: the segment
 * counts (n_segments within the array, next_segment not beyond it). Integer compares. */
static int indices_valid(const gf_vehicle_state *st)
{
    return st->profile.n_segments <= GF_VEHICLE_MAX_SEGMENTS &&
           st->next_segment <= st->profile.n_segments;
}

/* The state's time inside its active segment, to a tolerance above the FMI masters'
 * time rounding (1e-9 relative). A restored or hand-made state may break it: a step from
 * a time far beyond the active segment's end would integrate from that end, unbounded by
 * GF_VEHICLE_MAX_STEP_S (found by fuzz_fmu_vehicle: a 10^6 s jump, 46 s of CPU). */
static int time_in_segment(const gf_vehicle_state *st)
{
    const double tol = 1e-6 * fmax(1.0, fabs(st->time_s));
    return st->time_s >= st->active_t0_s - tol && st->time_s <= active_end(st) + tol;
}

gf_status gf_vehicle_state_check(const gf_vehicle_state *st)
{
    if (!st)
        return GF_ERR_NULL_POINTER;
    if (!indices_valid(st))
        return GF_ERR_BAD_SIZE;
    const gf_vehicle_profile *p = &st->profile;
    const double nums[] = {p->lat0_rad, p->lon0_rad, p->h0_m, p->heading0_rad, p->speed0_m_s,
                           p->heading_rate0_rad_s, st->time_s, st->active.duration_s,
                           st->active.dspeed_m_s, st->active.dheading_rate_rad_s,
                           st->active.dheading_rad, st->active_t0_s, st->speed0_m_s,
                           st->heading0_rad, st->heading_rate0_rad_s, st->east_m, st->north_m,
                           st->R_M0_m, st->R_N0_m};
    if (!gf_all_finite(nums, sizeof nums / sizeof nums[0]))
        return GF_ERR_NONFINITE_INPUT;
    for (size_t k = 0; k < p->n_segments; ++k) {
        const gf_vehicle_segment *g = &p->segment[k];
        if (!isfinite(g->duration_s) || !isfinite(g->dspeed_m_s) ||
            !isfinite(g->dheading_rate_rad_s) || !isfinite(g->dheading_rad))
            return GF_ERR_NONFINITE_INPUT;
    }
    if (!(fabs(p->lat0_rad) < LAT_MAX_RAD) || !(p->h0_m >= -1000.0 && p->h0_m <= 1e5) ||
        !(st->R_M0_m > 0.0) || !(st->R_N0_m > 0.0) || !time_in_segment(st))
        return GF_ERR_BAD_PARAMETER;
    return GF_OK;
}

gf_status gf_vehicle_truth(const gf_vehicle_state *state, gf_vehicle_sample *sample)
{
    if (!state || !sample)
        return GF_ERR_NULL_POINTER;
    if (!indices_valid(state))
        return GF_ERR_BAD_SIZE;
    gf_vehicle_sample out;
    const gf_status status = evaluate(state, state->time_s, kinematics(state, state->time_s),
                                      state->east_m, state->north_m, &out);
    if (status != GF_OK)
        return status;
    memset(out.dtheta_rad, 0, sizeof out.dtheta_rad);
    memset(out.dv_m_s, 0, sizeof out.dv_m_s);
    *sample = out;
    return GF_OK;
}

gf_status gf_vehicle_command(gf_vehicle_state *state, double speed_m_s,
                             double heading_rate_rad_s, double duration_s)
{
    if (!state)
        return GF_ERR_NULL_POINTER;
    if (!indices_valid(state))
        return GF_ERR_BAD_SIZE;
    if (!isfinite(speed_m_s) || !isfinite(heading_rate_rad_s) || !isfinite(duration_s))
        return GF_ERR_NONFINITE_INPUT;
    if (speed_m_s < 0.0 || !(duration_s > 0.0))
        return GF_ERR_BAD_PARAMETER;
    const kin k = kinematics(state, state->time_s);
    state->speed0_m_s = k.u;
    state->heading0_rad = k.psi;
    state->heading_rate0_rad_s = k.dpsi;
    state->active_t0_s = state->time_s;
    state->active.duration_s = duration_s;
    state->active.dspeed_m_s = speed_m_s - k.u;
    state->active.dheading_rate_rad_s = heading_rate_rad_s - k.dpsi;
    state->active.dheading_rad = 0.0;
    state->next_segment = state->profile.n_segments; /* then cruise */
    return GF_OK;
}

gf_status gf_vehicle_step_mounted(gf_vehicle_state *state, double t_end_s,
                                  const gf_vehicle_mount *mount, gf_vehicle_sample *sample,
                                  double *mounted)
{
    if (!state || !sample || (mount && (!mount->fn || !mounted)))
        return GF_ERR_NULL_POINTER;
    if (!indices_valid(state))
        return GF_ERR_BAD_SIZE;
    if (!(t_end_s > state->time_s) || !isfinite(t_end_s) || !(t_end_s - state->time_s <= GF_VEHICLE_MAX_STEP_S))
        return GF_ERR_BAD_TIME;
    if (!time_in_segment(state))
        return GF_ERR_BAD_PARAMETER;
    gf_vehicle_state s = *state;
    const double t_end = t_end_s;
    double dth[3] = {0.0, 0.0, 0.0}, dv[3] = {0.0, 0.0, 0.0}, msum[6] = {0.0};
    double a = s.time_s;
    while (a < t_end) {
        const double seg_end = active_end(&s);
        const double b_seg = seg_end < t_end ? seg_end : t_end;
        const int pieces = (int)ceil((b_seg - a) / PIECE_MAX_S);
        for (int m = 0; m < pieces; ++m) {
            const double pa = a + (b_seg - a) * m / pieces;
            const double pb = m + 1 == pieces ? b_seg : a + (b_seg - a) * (m + 1) / pieces;
            const gf_status status = integrate_piece(&s, pa, pb, dth, dv, mount, msum);
            if (status != GF_OK)
                return status;
        }
        a = b_seg;
        if (seg_end <= t_end)
            activate_next(&s, seg_end);
    }
    gf_vehicle_sample out;
    gf_status status = evaluate(&s, t_end, kinematics(&s, t_end), s.east_m, s.north_m, &out);
    if (status != GF_OK)
        return status;
    double m_out[12] = {0.0};
    if (mount) {
        status = mount->fn(mount->ctx, t_end, out.gyro_rad_s, out.accel_m_s2, m_out, m_out + 3);
        if (status != GF_OK)
            return status;
        memcpy(m_out + 6, msum, sizeof msum);
    }
    memcpy(out.dtheta_rad, dth, sizeof dth);
    memcpy(out.dv_m_s, dv, sizeof dv);
    s.time_s = t_end;
    *state = s;
    *sample = out;
    if (mount)
        memcpy(mounted, m_out, sizeof m_out);
    return GF_OK;
}

gf_status gf_vehicle_step(gf_vehicle_state *state, double t_end_s, gf_vehicle_sample *sample)
{
    return gf_vehicle_step_mounted(state, t_end_s, NULL, sample, NULL);
}

gf_status gf_vehicle_run(gf_vehicle_state *state, size_t n, double dt_s,
                         gf_vehicle_sample *samples, size_t *n_done)
{
    if (n_done)
        *n_done = 0;
    if (!state || (n && !samples))
        return GF_ERR_NULL_POINTER;
    if (!(dt_s > 0.0) || !isfinite(dt_s))
        return GF_ERR_BAD_TIME;
    const double t0 = state->time_s;
    for (size_t k = 0; k < n; ++k) {
        const gf_status status = gf_vehicle_step(state, t0 + (double)(k + 1) * dt_s, &samples[k]);
        if (status != GF_OK)
            return status;
        if (n_done)
            *n_done = k + 1;
    }
    return GF_OK;
}
