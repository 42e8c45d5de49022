/* gf_rot.c — rotating IMU: mechanism, schedules, exact IMU outputs; see gf_rot.h. */
#include "sim/gf_rot.h"

#include <float.h>
#include <math.h>
#include <string.h>

#include "base/gf_math.h"
#include "base/gf_quad.h"
#include "nav/gf_earth.h"

#define PIECE_MAX_S 0.25                    /* longest quadrature piece */
#define LAT_MAX_RAD (89.0 * GF_PI / 180.0)  /* the static base, as gf_vehicle */
#define CLOSE_TOL 1e-9                      /* a repeated cycle must close to this */
#define BREAK_EPS_S 1e-12                   /* a step ending this close to a boundary ends there */
#define MAX_RATE_RAD_S (GF_ROT_MAX_RATE_MDEG_S * (GF_PI / 180000.0))

/* quaternion of a right-handed rotation by angle about axis (none: identity) */
static void q_axis(int axis, double angle_rad, double q[4])
{
    q[0] = cos(0.5 * angle_rad);
    q[1] = q[2] = q[3] = 0.0;
    if (axis >= 0)
        q[1 + axis] = sin(0.5 * angle_rad);
    else
        q[0] = 1.0;
}

/* normalised turn fraction p and its rate dp (1/s) at tau into segment g (gf_rot.h) */
static void turn_profile(const gf_rot_segment *g, double tau, double *p, double *dp)
{
    const double T = g->move_s, Ta = g->ramp_s;
    *dp = 0.0;
    if (!(T > 0.0) || tau >= T) {
        *p = 1.0;
        return;
    }
    if (tau <= 0.0) {
        *p = 0.0;
        return;
    }
    const double W = 1.0 / (T - Ta);
    double S, dS, ddS, I;
    if (Ta > 0.0 && tau < Ta) {
        gf_smooth_step(tau / Ta, &S, &dS, &ddS, &I);
        *p = W * Ta * I;
        *dp = W * S;
    } else if (Ta > 0.0 && tau > T - Ta) {
        gf_smooth_step((T - tau) / Ta, &S, &dS, &ddS, &I);
        *p = 1.0 - W * Ta * I;
        *dp = W * S;
    } else {
        *p = W * (tau - 0.5 * Ta);
        *dp = W;
    }
}

static double wrap_pi(double a)
{
    const double r = remainder(a, 2.0 * GF_PI);
    return r <= -GF_PI ? r + 2.0 * GF_PI : r;
}

static int axis_ok(int32_t a)
{
    return a >= GF_ROT_AXIS_NONE && a <= 2;
}

static int segment_ok(const gf_rot_segment *g)
{
    if (!axis_ok(g->base_axis) || !axis_ok(g->imu_axis))
        return 0;
    if ((g->base_axis < 0 && g->base_angle_rad != 0.0) || (g->imu_axis < 0 && g->imu_angle_rad != 0.0))
        return 0;
    const int turns = g->base_angle_rad != 0.0 || g->imu_angle_rad != 0.0;
    if (!(g->move_s >= 0.0) || (turns && !(g->move_s > 0.0)) || !(g->ramp_s >= 0.0) ||
        !(2.0 * g->ramp_s <= g->move_s) || !(g->dwell_s >= 0.0) || !(g->move_s + g->dwell_s > 0.0))
        return 0;
    if (turns) {
        const double peak = (fabs(g->base_angle_rad) + fabs(g->imu_angle_rad)) / (g->move_s - g->ramp_s);
        if (!(peak <= MAX_RATE_RAD_S))
            return 0;
    }
    return 1;
}

static int q_close(const double a[4], const double b[4], double tol)
{
    double dp = 0.0, dm = 0.0;
    for (int i = 0; i < 4; ++i) {
        dp = fmax(dp, fabs(a[i] - b[i]));
        dm = fmax(dm, fabs(a[i] + b[i]));
    }
    return dp < tol || dm < tol;
}

/* q normalised, or kept as it is when already unit to round-off: idempotent, so that
 * gf_rot_state_check, which runs gf_rot_init again on the stored (normalised) schedule,
 * derives the same tables bit for bit (found by fuzzing: normalising twice moved the
 * last bit and a state gf_rot_init had made was refused) */
static int unit_quaternion(const double q[4], double out[4])
{
    const double n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
    if (fabs(n2 - 1.0) <= 8.0 * DBL_EPSILON) {
        memcpy(out, q, 4 * sizeof *q);
        return 1;
    }
    return gf_q_normalize(q, out);
}

gf_status gf_rot_init(gf_rot_state *state, const gf_rot_schedule *s, double t0_s, int *bad)
{
    if (bad)
        *bad = 0;
    if (!state || !s)
        return GF_ERR_NULL_POINTER;
    if (s->n_segments > GF_ROT_MAX_SEGMENTS)
        return GF_ERR_BAD_SIZE;
    if (!gf_all_finite(s->q_mb0, 4) || !isfinite(t0_s))
        return GF_ERR_NONFINITE_INPUT;
    for (size_t k = 0; k < s->n_segments; ++k) {
        const gf_rot_segment *g = &s->segment[k];
        const double v[5] = {g->base_angle_rad, g->imu_angle_rad, g->move_s, g->ramp_s, g->dwell_s};
        if (!gf_all_finite(v, 5))
            return GF_ERR_NONFINITE_INPUT;
    }
    int which = 0;
    double q0[4];
    if (!(fabs(gf_q_norm(s->q_mb0) - 1.0) <= 1e-6) || !unit_quaternion(s->q_mb0, q0))
        which = GF_ROT_BAD_START;
    for (size_t k = 0; k < s->n_segments && !which; ++k)
        if (!segment_ok(&s->segment[k]))
            which = GF_ROT_BAD_SEGMENT + (int)k;
    if (which) {
        if (bad)
            *bad = which;
        return GF_ERR_BAD_PARAMETER;
    }
    gf_rot_state st;
    memset(&st, 0, sizeof st);
    st.sched = *s;
    memcpy(st.sched.q_mb0, q0, sizeof q0);
    st.t0_s = t0_s;
    const double ident[4] = {1.0, 0.0, 0.0, 0.0};
    st.gimbal = q_close(q0, ident, 1e-12);
    double t = 0.0, q[4], g[2] = {0.0, 0.0};
    memcpy(q, q0, sizeof q);
    for (size_t k = 0; k < s->n_segments; ++k) {
        const gf_rot_segment *sg = &s->segment[k];
        st.seg_t0_s[k] = t;
        memcpy(st.seg_q0[k], q, sizeof q);
        st.seg_gimbal0[k][0] = g[0];
        st.seg_gimbal0[k][1] = g[1];
        if (!(sg->base_axis == GF_ROT_AXIS_NONE || sg->base_axis == 0) ||
            !(sg->imu_axis == GF_ROT_AXIS_NONE || sg->imu_axis == 2))
            st.gimbal = 0;
        t += sg->move_s + sg->dwell_s;
        double qa[4], qb[4];
        q_axis(sg->base_axis, sg->base_angle_rad, qa);
        q_axis(sg->imu_axis, sg->imu_angle_rad, qb);
        gf_q_mul(qa, q, q);
        gf_q_mul(q, qb, q);
        gf_q_normalize(q, q);
        g[0] += sg->base_axis == 0 ? sg->base_angle_rad : 0.0;
        g[1] += sg->imu_axis == 2 ? sg->imu_angle_rad : 0.0;
    }
    const size_t n = s->n_segments;
    st.seg_t0_s[n] = t;
    memcpy(st.seg_q0[n], q, sizeof q);
    st.seg_gimbal0[n][0] = g[0];
    st.seg_gimbal0[n][1] = g[1];
    st.cycle_s = t;
    if (s->repeat) {
        if (!(t > 0.0))
            which = GF_ROT_BAD_EMPTY_CYCLE;
        else if (!q_close(q, q0, CLOSE_TOL))
            which = GF_ROT_BAD_REPEAT;
        if (which) {
            if (bad)
                *bad = which;
            return GF_ERR_BAD_PARAMETER;
        }
    }
    *state = st;
    return GF_OK;
}

/* The indices a caller's state uses to address arrays: the segment count and each
 * segment's axes (a damaged struct must not index out of bounds; found by fuzzing: an
 * axis of 55 wrote beyond a quaternion). O(segments): cheap beside one evaluation. */
static int indices_valid(const gf_rot_state *st)
{
    if (st->sched.n_segments > GF_ROT_MAX_SEGMENTS)
        return 0;
    for (size_t k = 0; k < st->sched.n_segments; ++k) {
        const gf_rot_segment *g = &st->sched.segment[k];
        if (g->base_axis < GF_ROT_AXIS_NONE || g->base_axis > 2 || g->imu_axis < GF_ROT_AXIS_NONE ||
            g->imu_axis > 2)
            return 0;
    }
    return 1;
}

gf_status gf_rot_state_check(const gf_rot_state *state)
{
    if (!state)
        return GF_ERR_NULL_POINTER;
    if (state->sched.n_segments > GF_ROT_MAX_SEGMENTS)
        return GF_ERR_BAD_SIZE;
    gf_rot_state fresh;
    const gf_status st = gf_rot_init(&fresh, &state->sched, state->t0_s, NULL);
    if (st == GF_ERR_NONFINITE_INPUT)
        return st;
    if (st != GF_OK)
        return GF_ERR_BAD_PARAMETER;
    /* the derived tables are a deterministic function of the schedule */
    if (memcmp(fresh.seg_t0_s, state->seg_t0_s, sizeof fresh.seg_t0_s) != 0 ||
        memcmp(fresh.seg_q0, state->seg_q0, sizeof fresh.seg_q0) != 0 ||
        memcmp(fresh.seg_gimbal0, state->seg_gimbal0, sizeof fresh.seg_gimbal0) != 0 ||
        fresh.cycle_s != state->cycle_s || fresh.gimbal != state->gimbal)
        return GF_ERR_BAD_PARAMETER;
    return GF_OK;
}

/* segment containing tau in [0, cycle): the last k with seg_t0[k] <= tau */
static size_t find_segment(const gf_rot_state *st, double tau)
{
    size_t lo = 0, hi = st->sched.n_segments; /* seg_t0[lo] <= tau < seg_t0[hi] */
    while (hi - lo > 1) {
        const size_t mid = (lo + hi) / 2;
        if (st->seg_t0_s[mid] <= tau)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* time into the schedule's cycle; -1: before the start; 1: after a non-repeated end */
static int locate(const gf_rot_state *st, double t_s, double *tau, double *cycle_start)
{
    double x = t_s - st->t0_s;
    *cycle_start = st->t0_s;
    if (x < 0.0) {
        *tau = 0.0;
        return -1;
    }
    if (st->sched.repeat) {
        const double c = floor(x / st->cycle_s);
        x -= c * st->cycle_s;
        *cycle_start += c * st->cycle_s;
        if (x >= st->cycle_s) /* round-off at a cycle boundary */
            x = 0.0;
        *tau = x;
        return 0;
    }
    *tau = x;
    return x >= st->cycle_s ? 1 : 0;
}

static void eval_pose(const gf_rot_state *st, double t_s, gf_rot_pose *p)
{
    memset(p, 0, sizeof *p);
    double tau, c0;
    const int where = locate(st, t_s, &tau, &c0);
    const size_t n = st->sched.n_segments;
    if (where != 0 || n == 0) {
        const size_t k = where < 0 || n == 0 ? 0 : n;
        memcpy(p->q_mb, where < 0 || n == 0 ? st->sched.q_mb0 : st->seg_q0[k], sizeof p->q_mb);
        if (st->gimbal && where > 0) {
            p->gimbal_rad[0] = wrap_pi(st->seg_gimbal0[n][0]);
            p->gimbal_rad[1] = wrap_pi(st->seg_gimbal0[n][1]);
        }
        p->segment = where < 0 || n == 0 ? -1 : (int32_t)n - 1;
        return;
    }
    const size_t k = find_segment(st, tau);
    const gf_rot_segment *g = &st->sched.segment[k];
    const double local = tau - st->seg_t0_s[k];
    double f, df;
    turn_profile(g, local, &f, &df);
    double qa[4], qb[4];
    q_axis(g->base_axis, g->base_angle_rad * f, qa);
    q_axis(g->imu_axis, g->imu_angle_rad * f, qb);
    gf_q_mul(qa, st->seg_q0[k], p->q_mb);
    gf_q_mul(p->q_mb, qb, p->q_mb);
    if (df != 0.0) {
        /* (3): w_bm^m = p' (base_angle C_b^m e_base + imu_angle e_imu) */
        double e[3] = {0.0, 0.0, 0.0}, qc[4], eb[3] = {0.0, 0.0, 0.0};
        if (g->base_axis >= 0) {
            e[g->base_axis] = 1.0;
            gf_q_conj(p->q_mb, qc);
            gf_q_rotate(qc, e, eb);
        }
        for (int i = 0; i < 3; ++i)
            p->w_bm_m_rad_s[i] = df * g->base_angle_rad * eb[i];
        if (g->imu_axis >= 0)
            p->w_bm_m_rad_s[g->imu_axis] += df * g->imu_angle_rad;
    }
    if (st->gimbal) {
        const double da = g->base_axis == 0 ? g->base_angle_rad : 0.0;
        const double db = g->imu_axis == 2 ? g->imu_angle_rad : 0.0;
        p->gimbal_rad[0] = wrap_pi(st->seg_gimbal0[k][0] + da * f);
        p->gimbal_rad[1] = wrap_pi(st->seg_gimbal0[k][1] + db * f);
        p->gimbal_rate_rad_s[0] = da * df;
        p->gimbal_rate_rad_s[1] = db * df;
    }
    p->segment = (int32_t)k;
    p->moving = local > 0.0 && local < g->move_s && (g->base_angle_rad != 0.0 || g->imu_angle_rad != 0.0);
}

gf_status gf_rot_eval(const gf_rot_state *state, double t_s, gf_rot_pose *pose)
{
    if (!state || !pose)
        return GF_ERR_NULL_POINTER;
    if (!indices_valid(state))
        return GF_ERR_BAD_SIZE;
    if (!isfinite(t_s))
        return GF_ERR_NONFINITE_INPUT;
    eval_pose(state, t_s, pose);
    return GF_OK;
}

gf_status gf_rot_poses(const gf_rot_state *state, size_t n, const double *t_s, double *q_mb,
                       double *w_bm_m_rad_s, double *gimbal_rad, size_t *n_done)
{
    if (n_done)
        *n_done = 0;
    if (!state || (n && !t_s))
        return GF_ERR_NULL_POINTER;
    if (!indices_valid(state))
        return GF_ERR_BAD_SIZE;
    for (size_t k = 0; k < n; ++k) {
        if (!isfinite(t_s[k]))
            return GF_ERR_NONFINITE_INPUT;
        gf_rot_pose p;
        eval_pose(state, t_s[k], &p);
        if (q_mb)
            memcpy(q_mb + 4 * k, p.q_mb, sizeof p.q_mb);
        if (w_bm_m_rad_s)
            gf_v3_copy(p.w_bm_m_rad_s, w_bm_m_rad_s + 3 * k);
        if (gimbal_rad) {
            gimbal_rad[2 * k] = p.gimbal_rad[0];
            gimbal_rad[2 * k + 1] = p.gimbal_rad[1];
        }
        if (n_done)
            *n_done = k + 1;
    }
    return GF_OK;
}

/* the next phase boundary of the schedule strictly after t_s (INFINITY: none) */
static double next_break(const gf_rot_state *st, double t_s)
{
    double tau, c0;
    const int where = locate(st, t_s, &tau, &c0);
    if (where < 0)
        return st->t0_s;
    if (where > 0 || st->sched.n_segments == 0)
        return INFINITY;
    const size_t k = find_segment(st, tau);
    const gf_rot_segment *g = &st->sched.segment[k];
    const double s0 = st->seg_t0_s[k];
    const double marks[4] = {s0 + g->ramp_s, s0 + g->move_s - g->ramp_s, s0 + g->move_s,
                             st->seg_t0_s[k + 1]};
    /* a boundary within a few ulp of tau is the present one */
    const double eps = 1e-14 * fmax(1.0, tau);
    for (int i = 0; i < 4; ++i)
        if (marks[i] > tau + eps)
            return c0 + marks[i];
    return INFINITY; /* not reached: the segment ends after tau */
}

void gf_rot_imu_outputs(const gf_rot_state *st, double t_s, const double w_b[3],
                        const double f_b[3], double w_m[3], double f_m[3], gf_rot_pose *pose)
{
    eval_pose(st, t_s, pose);
    double qc[4];
    gf_q_conj(pose->q_mb, qc);
    gf_q_rotate(qc, w_b, w_m);
    gf_v3_add(w_m, pose->w_bm_m_rad_s, w_m);
    gf_q_rotate(qc, f_b, f_m);
}

/* integral of (4) over [a, b] for constant base quantities; which: 1 rate, 2 force */
static void integrate_static(const gf_rot_state *st, const double w_b[3], const double f_b[3],
                             double a, double b, int which, double out[3])
{
    out[0] = out[1] = out[2] = 0.0;
    double x = a;
    while (x < b) {
        double end = next_break(st, x);
        if (!(end > x) || end > b)
            end = b;
        const int pieces = (int)ceil((end - x) / PIECE_MAX_S);
        for (int m = 0; m < pieces; ++m) {
            const double pa = x + (end - x) * m / pieces;
            const double pb = m + 1 == pieces ? end : x + (end - x) * (m + 1) / pieces;
            const double half = 0.5 * (pb - pa);
            for (int j = 0; j < 8; ++j) {
                double wm[3], fm[3];
                gf_rot_pose pose;
                gf_rot_imu_outputs(st, pa + half * (GF_GL8_X[j] + 1.0), w_b, f_b, wm, fm, &pose);
                const double *v = which == 1 ? wm : fm;
                for (int i = 0; i < 3; ++i)
                    out[i] += half * GF_GL8_W[j] * v[i];
            }
        }
        x = end;
    }
}

gf_status gf_rot_imu_static(const gf_rot_state *state, const double *q_bn_base, double lat_rad,
                            double h_m, double t_start_s, size_t n, double dt_s,
                            double accel_delay_s, double *dtheta_rad, double *dv_m_s,
                            double *q_mn, double *gimbal_rad, size_t *n_done)
{
    if (n_done)
        *n_done = 0;
    if (!state || !q_bn_base || (n && (!dtheta_rad || !dv_m_s)))
        return GF_ERR_NULL_POINTER;
    if (!indices_valid(state))
        return GF_ERR_BAD_SIZE;
    if (!gf_all_finite(q_bn_base, 4) || !isfinite(lat_rad) || !isfinite(h_m) ||
        !isfinite(t_start_s) || !isfinite(accel_delay_s) || !isfinite(dt_s))
        return GF_ERR_NONFINITE_INPUT;
    /* an interval beyond GF_ROT_MAX_DT_S is no IMU sample (and would integrate millions
     * of quadrature pieces; found by fuzzing: 1e300 s overflowed the piece count) */
    if (!(dt_s > 0.0) || !(dt_s <= GF_ROT_MAX_DT_S))
        return GF_ERR_BAD_TIME;
    double qb[4];
    if (!(fabs(lat_rad) < LAT_MAX_RAD) || !(fabs(gf_q_norm(q_bn_base) - 1.0) <= 1e-6) ||
        !gf_q_normalize(q_bn_base, qb) || !(fabs(accel_delay_s) <= dt_s))
        return GF_ERR_BAD_PARAMETER;
    gf_earth e;
    const gf_status st = gf_earth_update(&e, lat_rad, h_m, NULL, 1.0);
    if (st != GF_OK)
        return st;
    const double g_up[3] = {0.0, 0.0, e.gravity_m_s2};
    double qc[4], w_b[3], f_b[3];
    gf_q_conj(qb, qc);
    gf_q_rotate(qc, e.w_ie_n_rad_s, w_b);
    gf_q_rotate(qc, g_up, f_b);
    for (size_t k = 0; k < n; ++k) {
        const double a = t_start_s + (double)k * dt_s, b = t_start_s + (double)(k + 1) * dt_s;
        integrate_static(state, w_b, f_b, a, b, 1, dtheta_rad + 3 * k);
        integrate_static(state, w_b, f_b, a - accel_delay_s, b - accel_delay_s, 2, dv_m_s + 3 * k);
        if (q_mn || gimbal_rad) {
            gf_rot_pose p;
            eval_pose(state, b, &p);
            if (q_mn)
                gf_q_mul(qb, p.q_mb, q_mn + 4 * k);
            if (gimbal_rad) {
                gimbal_rad[2 * k] = p.gimbal_rad[0];
                gimbal_rad[2 * k + 1] = p.gimbal_rad[1];
            }
        }
        if (n_done)
            *n_done = k + 1;
    }
    return GF_OK;
}

/* the mount of gf_vehicle: (4) with the vehicle's body quantities */
static gf_status mount_fn(const void *ctx, double t_s, const double w_b[3], const double f_b[3],
                          double w_s[3], double f_s[3])
{
    gf_rot_pose pose;
    gf_rot_imu_outputs((const gf_rot_state *)ctx, t_s, w_b, f_b, w_s, f_s, &pose);
    return GF_OK;
}

gf_status gf_rot_vehicle_step(const gf_rot_state *state, gf_vehicle_state *vehicle,
                              double t_end_s, gf_vehicle_sample *truth, double *imu)
{
    if (!state || !vehicle || !truth || !imu)
        return GF_ERR_NULL_POINTER;
    if (!indices_valid(state))
        return GF_ERR_BAD_SIZE;
    /* the whole step within the vehicle's limit (each piece below is; a longer step in
     * pieces would be unbounded work: found by fuzz_fmu_vehicle, 94 s of CPU) */
    if (!isfinite(t_end_s) || !(t_end_s > vehicle->time_s) ||
        !(t_end_s - vehicle->time_s <= GF_VEHICLE_MAX_STEP_S))
        return GF_ERR_BAD_TIME;
    const gf_vehicle_mount mount = {mount_fn, state};
    gf_vehicle_state v = *vehicle;
    gf_vehicle_sample s;
    double body[6] = {0.0}, sum[6] = {0.0}, m[12] = {0.0};
    while (v.time_s < t_end_s) {
        double end = next_break(state, v.time_s);
        if (!(end > v.time_s) || end > t_end_s || t_end_s - end < BREAK_EPS_S)
            end = t_end_s;
        const gf_status st = gf_vehicle_step_mounted(&v, end, &mount, &s, m);
        if (st != GF_OK)
            return st;
        for (int i = 0; i < 3; ++i) {
            body[i] += s.dtheta_rad[i];
            body[3 + i] += s.dv_m_s[i];
            sum[i] += m[6 + i];
            sum[3 + i] += m[9 + i];
        }
    }
    memcpy(s.dtheta_rad, body, 3 * sizeof *body);
    memcpy(s.dv_m_s, body + 3, 3 * sizeof *body);
    memcpy(imu, m, 6 * sizeof *m);
    memcpy(imu + 6, sum, 6 * sizeof *sum);
    *vehicle = v;
    *truth = s;
    return GF_OK;
}

gf_status gf_rot_imu_vehicle(const gf_rot_state *state, gf_vehicle_state *vehicle, size_t n,
                             double dt_s, double *dtheta_rad, double *dv_m_s, double *w_rad_s,
                             double *f_m_s2, double *gimbal_rad, double *q_mn,
                             gf_vehicle_sample *truth, size_t *n_done)
{
    if (n_done)
        *n_done = 0;
    if (!state || !vehicle || (n && (!dtheta_rad || !dv_m_s)))
        return GF_ERR_NULL_POINTER;
    if (!(dt_s > 0.0) || !isfinite(dt_s))
        return GF_ERR_BAD_TIME;
    const double t0 = vehicle->time_s;
    for (size_t k = 0; k < n; ++k) {
        gf_vehicle_sample s;
        double imu[12];
        const double t_end = t0 + (double)(k + 1) * dt_s;
        const gf_status st = gf_rot_vehicle_step(state, vehicle, t_end, &s, imu);
        if (st != GF_OK)
            return st;
        gf_v3_copy(imu + 6, dtheta_rad + 3 * k);
        gf_v3_copy(imu + 9, dv_m_s + 3 * k);
        if (w_rad_s)
            gf_v3_copy(imu, w_rad_s + 3 * k);
        if (f_m_s2)
            gf_v3_copy(imu + 3, f_m_s2 + 3 * k);
        if (gimbal_rad || q_mn) {
            gf_rot_pose p;
            eval_pose(state, t_end, &p);
            if (gimbal_rad) {
                gimbal_rad[2 * k] = p.gimbal_rad[0];
                gimbal_rad[2 * k + 1] = p.gimbal_rad[1];
            }
            if (q_mn)
                gf_q_mul(s.q_bn, p.q_mb, q_mn + 4 * k);
        }
        if (truth)
            truth[k] = s;
        if (n_done)
            *n_done = k + 1;
    }
    return GF_OK;
}

gf_status gf_rot_vehicle_attitude(size_t n, const double *q_mn, const double *gimbal_rad,
                                  double *q_bn, size_t *n_done)
{
    if (n_done)
        *n_done = 0;
    if (n && (!q_mn || !gimbal_rad || !q_bn))
        return GF_ERR_NULL_POINTER;
    for (size_t k = 0; k < n; ++k) {
        const double *qm = q_mn + 4 * k, *g = gimbal_rad + 2 * k;
        if (!gf_all_finite(qm, 4) || !gf_all_finite(g, 2))
            return GF_ERR_NONFINITE_INPUT;
        /* (1): q_mb = q_x(alpha) q_z(beta); C_b^n = C_m^n C_b^m */
        double qa[4], qz[4], qmb[4], qbm[4], out[4];
        q_axis(0, g[0], qa);
        q_axis(2, g[1], qz);
        gf_q_mul(qa, qz, qmb);
        gf_q_conj(qmb, qbm);
        gf_q_mul(qm, qbm, out);
        if (!gf_q_normalize(out, q_bn + 4 * k))
            return GF_ERR_BAD_PARAMETER;
        if (n_done)
            *n_done = k + 1;
    }
    return GF_OK;
}
