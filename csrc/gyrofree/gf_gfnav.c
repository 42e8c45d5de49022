/* gf_gfnav.c — the gyro-free navigator; see gf_gfnav.h. */
#include "gyrofree/gf_gfnav.h"

#include <math.h>
#include <string.h>

#include "base/gf_math.h"
#include "gyrofree/gf_gfins_internal.h"

gf_status gf_gfnav_init(gf_gfnav_state *st, const gf_array_geometry *g, const gf_rate_config *rc,
                        const double *omega_init, const gf_sins_config *sc, const double *q_bn,
                        const double *v_n, double lat, double lon, double h, double t0,
                        uint32_t *unobservable)
{
    if (!st || !sc)
        return GF_ERR_NULL_POINTER;
    if (sc->input != GF_SINS_INPUT_RATES)
        return GF_ERR_BAD_PARAMETER;
    /* both parts into a copy, committed only when both start (found by fuzzing: a refused
     * strapdown start left a new rate solver beside the old navigation state) */
    gf_gfnav_state fresh;
    memset(&fresh, 0, sizeof fresh);   /* padding included: states are compared and hashed as bytes */
    gf_status status = gf_gfins_init(&fresh.rate, g, rc, omega_init, unobservable);
    if (status != GF_OK)
        return status;
    fresh.integration = GF_GFNAV_HERMITE;
    status = gf_sins_init(&fresh.nav, sc, q_bn, v_n, lat, lon, h, t0);
    if (status == GF_OK)
        *st = fresh;
    return status;
}

gf_status gf_gfnav_set_integration(gf_gfnav_state *st, int32_t integration)
{
    if (!st)
        return GF_ERR_NULL_POINTER;
    if (integration != GF_GFNAV_LINEAR && integration != GF_GFNAV_HERMITE)
        return GF_ERR_BAD_PARAMETER;
    st->integration = integration;
    return GF_OK;
}

/* the body-rate commutator [a, b] = b x a (gf_gfnav.h) */
static void commutator(const double a[3], const double b[3], double out[3])
{
    gf_v3_cross(b, a, out);
}

/* The increments of gf_gfnav.h, and the quaternion q(phi) of the rotation. With
 * m = (w0 + w1)/2, D = w1 - w0 and u = tau - 1/2, the Hermite rate is
 *   w = m + (3u/2 - 2u^3) D + T [(1/8 - u^2/2)(w_dot0 - w_dot1) + (u^3 - u/4)(w_dot0 + w_dot1)],
 * so at the nodes u = 0, +-sqrt(15)/10 the Magnus terms reduce to
 *   B1 = T (m + T (w_dot0 - w_dot1) / 8),
 *   B2 = T (6 D / 5 - T (w_dot0 + w_dot1) / 10),
 *   B3 = -T^2 (w_dot0 - w_dot1) / 2. */
static void hermite_increments(const double w0[3], const double wd0[3], const double f0[3],
                               const double w1[3], const double wd1[3], const double f1[3],
                               double T, double phi[3], double dv_b[3], double q[4])
{
    double B1[3], B2[3], B3[3], C1[3], C2[3], t1[3], t2[3];
    for (int i = 0; i < 3; ++i) {
        const double dd = wd0[i] - wd1[i], sd = wd0[i] + wd1[i];
        B1[i] = T * (0.5 * (w0[i] + w1[i]) + 0.125 * T * dd);
        B2[i] = T * (1.2 * (w1[i] - w0[i]) - 0.1 * T * sd);
        B3[i] = -0.5 * T * T * dd;
    }
    commutator(B1, B2, C1);
    for (int i = 0; i < 3; ++i)
        t1[i] = 2.0 * B3[i] + C1[i];
    commutator(B1, t1, C2);
    /* (multiplications by the reciprocals: divisions would lengthen the dependent chain) */
    for (int i = 0; i < 3; ++i) {
        t1[i] = -20.0 * B1[i] - B3[i] + C1[i];
        t2[i] = B2[i] - C2[i] * (1.0 / 60.0);
    }
    commutator(t1, t2, C1);
    for (int i = 0; i < 3; ++i)
        phi[i] = B1[i] + B3[i] * (1.0 / 12.0) + C1[i] * (1.0 / 240.0);
    /* specific force in the body frame at the start: trapezoid of h(t) = R(t) f(t) */
    double h1[3];
    gf_q_from_rotvec_fast(phi, q);
    gf_q_rotate(q, f1, h1);
    for (int i = 0; i < 3; ++i)
        dv_b[i] = 0.5 * T * (f0[i] + h1[i]);
}

gf_status gf_hermite_increments(const double *w0, const double *wd0, const double *f0,
                                const double *w1, const double *wd1, const double *f1, double T,
                                double *phi, double *dv_b)
{
    if (!w0 || !wd0 || !f0 || !w1 || !wd1 || !f1 || !phi || !dv_b)
        return GF_ERR_NULL_POINTER;
    if (!(T > 0.0 && isfinite(T)))
        return GF_ERR_BAD_TIME;
    if (!gf_v3_isfinite(w0) || !gf_v3_isfinite(wd0) || !gf_v3_isfinite(f0) ||
        !gf_v3_isfinite(w1) || !gf_v3_isfinite(wd1) || !gf_v3_isfinite(f1))
        return GF_ERR_NONFINITE_INPUT;
    double q[4];
    hermite_increments(w0, wd0, f0, w1, wd1, f1, T, phi, dv_b, q);
    return GF_OK;
}

/* What rate_commit changes in a rate state, to undo commits */
typedef struct rate_snapshot {
    double w[3], ref[3], wd[3], wd_prev[3], dt_prev, kf_x[6], kf_P[36];
    uint64_t n_samples;
} rate_snapshot;

static rate_snapshot rate_save(const gf_gfins_state *st)
{
    rate_snapshot s;
    gf_v3_copy(st->omega_rad_s, s.w);
    gf_v3_copy(st->omega_ref_rad_s, s.ref);
    gf_v3_copy(st->omega_dot_rad_s2, s.wd);
    gf_v3_copy(st->omega_dot_prev_rad_s2, s.wd_prev);
    s.dt_prev = st->dt_prev_s;
    memcpy(s.kf_x, st->kf.x, sizeof s.kf_x);
    memcpy(s.kf_P, st->kf.P, sizeof s.kf_P);
    s.n_samples = st->n_samples;
    return s;
}

static void rate_restore(gf_gfins_state *st, const rate_snapshot *s)
{
    gf_v3_copy(s->w, st->omega_rad_s);
    gf_v3_copy(s->ref, st->omega_ref_rad_s);
    gf_v3_copy(s->wd, st->omega_dot_rad_s2);
    gf_v3_copy(s->wd_prev, st->omega_dot_prev_rad_s2);
    st->dt_prev_s = s->dt_prev;
    memcpy(st->kf.x, s->kf_x, sizeof s->kf_x);
    memcpy(st->kf.P, s->kf_P, sizeof s->kf_P);
    st->n_samples = s->n_samples;
}

gf_status gf_gfnav_run(gf_gfnav_state *st, size_t n, const double *A, double dt,
                       const double *h_ext, double *q_bn, double *v_n, double *pos, double *w_out,
                       double *f_out, uint8_t *flags, size_t *n_done)
{
    if (n_done)
        *n_done = 0;
    if (!st || !A || !q_bn || !v_n || !pos)
        return GF_ERR_NULL_POINTER;
    if (!gfins_rate_state_valid(&st->rate))
        return GF_ERR_BAD_SIZE;
    if (st->integration != GF_GFNAV_LINEAR && st->integration != GF_GFNAV_HERMITE)
        return GF_ERR_BAD_PARAMETER;
    if (!gf_sins_state_valid(&st->nav))
        return GF_ERR_BAD_PARAMETER;
    if (!(dt > 0.0 && isfinite(dt)))
        return GF_ERR_BAD_TIME;
    /* In blocks of samples, three passes each: the rate solutions (their own recursion),
     * then the Hermite increments (no recursion: the processor overlaps the samples'
     * dependent chains), then the mechanization (its recursion). The results are those of
     * one sample at a time, bit for bit: the rate commits are replayed from the block's
     * start up to a failed mechanization step, so that an error leaves both states after
     * the last good sample. */
    enum { BLOCK = 32 };
    const size_t ns = st->rate.solver.n_sensors;
    const int hermite = st->integration == GF_GFNAV_HERMITE;
    const int fused = st->rate.cfg.strategy == GF_RATE_FUSED;
    gf_status status = GF_OK;
    size_t k = 0;
    gf_sins_state nav = st->nav;
    while (k < n && status == GF_OK) {
        const size_t m = n - k < BLOCK ? n - k : BLOCK;
        rate_step_result R[BLOCK];
        double wd0[BLOCK][3], phi[BLOCK][3], dv_b[BLOCK][3], q_phi[BLOCK][4];
        const rate_snapshot start = rate_save(&st->rate);
        size_t got = 0;
        for (; got < m; ++got) {
            /* the rate's derivative at the interval's start, less the fused filter's bias */
            gf_v3_copy(st->rate.omega_dot_rad_s2, wd0[got]);
            if (fused)
                gf_v3_sub(wd0[got], st->rate.kf.x + 3, wd0[got]);
            status = gfins_rate_step(&st->rate, A + ns * (k + got), dt, R + got);
            if (status != GF_OK)
                break;
            rate_commit(&st->rate, R + got);
        }
        const int had_prev = nav.have_prev;
        if (hermite)
            for (size_t j = had_prev ? 0 : 1; j < got; ++j) {
                const double *w0 = j ? R[j - 1].w : nav.prev_gyro;
                const double *f0 = j ? R[j - 1].f : nav.prev_accel;
                double wd1[3];
                gf_v3_copy(R[j].wd, wd1);
                if (fused)
                    gf_v3_sub(wd1, R[j].kf_x + 3, wd1);
                hermite_increments(w0, wd0[j], f0, R[j].w, wd1, R[j].f, dt, phi[j], dv_b[j],
                                   q_phi[j]);
            }
        size_t j = 0;
        for (; j < got; ++j) {
            const double he = h_ext ? h_ext[k + j] : NAN;
            /* the state was checked at the start of the call (gf_sins_state_valid) and is
             * written only by the mechanization since */
            const gf_status e =
                hermite && (j || had_prev)
                    ? gf_sins_step_compensated_trusted(&nav, phi[j], q_phi[j], dv_b[j], R[j].w,
                                                       R[j].f, dt, he)
                    : gf_sins_step(&nav, R[j].w, R[j].f, dt, he);
            if (e != GF_OK) {
                status = e;
                break;
            }
            memcpy(q_bn + 4 * (k + j), nav.q_bn, sizeof nav.q_bn);
            gf_v3_copy(nav.v_n_m_s, v_n + 3 * (k + j));
            gf_sins_position(&nav, pos + 3 * (k + j));
            if (w_out)
                gf_v3_copy(R[j].w, w_out + 3 * (k + j));
            if (f_out)
                gf_v3_copy(R[j].f, f_out + 3 * (k + j));
            if (flags)
                flags[k + j] = R[j].flags;
        }
        if (j < got) { /* the mechanization refused sample k + j: rates up to k + j - 1 */
            rate_restore(&st->rate, &start);
            for (size_t i = 0; i < j; ++i)
                rate_commit(&st->rate, R + i);
        }
        k += j;
    }
    st->nav = nav;
    if (n_done)
        *n_done = k;
    return status;
}
