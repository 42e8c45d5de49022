/* gf9.c — the 9-accelerometer gyro-free solver of seed 000. See gf9.h and gf_array.h
 * for the model and conventions. */
#include "gyrofree/gf9.h"

#include <math.h>
#include <string.h>

#include "base/gf_math.h"

/* Smallest lever arm accepted: below a micrometre the 1/l of eq. 4 and 6 turns
 * round-off of the outputs into absurd rates. */
#define GF_MIN_LEVER_ARM_M 1e-6

gf_status gf9_geometry(double lever_arm_m, gf_array_geometry *geometry)
{
    if (!geometry)
        return GF_ERR_NULL_POINTER;
    if (!(lever_arm_m >= GF_MIN_LEVER_ARM_M) || !isfinite(lever_arm_m))
        return GF_ERR_BAD_PARAMETER;
    const double l = lever_arm_m, r = 1.0 / GF_SQRT2;
    /* seed 000, section 1: positions u_i / l and directions theta_i */
    const double u[9][3] = {
        {1, 0, 0}, {0, 1, 0}, {0, 0, 1},
        {-1, 0, 0}, {0, -1, 0}, {0, 0, -1},
        {1, -1, 0}, {1, 0, -1}, {0, 1, -1},
    };
    const double t[9][3] = {
        {1, 0, 0}, {0, 1, 0}, {0, 0, 1},
        {-1, 0, 0}, {0, -1, 0}, {0, 0, -1},
        {r, r, 0}, {r, 0, r}, {0, r, r},
    };
    memset(geometry, 0, sizeof *geometry);
    geometry->n_sensors = 9;
    for (int i = 0; i < 9; ++i) {
        gf_v3_scale(u[i], l, geometry->u_m[i]);
        gf_v3_copy(t[i], geometry->theta[i]);
    }
    return GF_OK;
}

gf_status gf9_init(gf9_state *state, double lever_arm_m, const double *omega_init_rad_s)
{
    if (!state)
        return GF_ERR_NULL_POINTER;
    if (!(lever_arm_m >= GF_MIN_LEVER_ARM_M) || !isfinite(lever_arm_m))
        return GF_ERR_BAD_PARAMETER;
    if (omega_init_rad_s && (!gf_all_finite(omega_init_rad_s, 3) ||
                             !(gf_v3_dot(omega_init_rad_s, omega_init_rad_s) <=
                               (double)GF9_MAX_RATE_RAD_S * GF9_MAX_RATE_RAD_S)))
        return GF_ERR_BAD_PARAMETER;
    memset(state, 0, sizeof *state);
    state->lever_arm_m = lever_arm_m;
    if (omega_init_rad_s)
        gf_v3_copy(omega_init_rad_s, state->omega_ref_rad_s);
    return GF_OK;
}

/* Checks the parts of a state that a caller could have corrupted (the FMU sets
 * state from bytes it is handed). */
static int state_is_valid(const gf9_state *s)
{
    return s->lever_arm_m >= GF_MIN_LEVER_ARM_M && isfinite(s->lever_arm_m) &&
           gf_all_finite(s->omega_ref_rad_s, 3) && gf_all_finite(s->omega_dot_rad_s2, 3);
}

/* Whether one solved sample lies within the physical limits (gf9.h): finite,
 * |f| <= GF9_MAX_SPECIFIC_FORCE_M_S2, sum |omega_k^2| <= GF9_MAX_RATE_RAD_S^2 (the
 * measured |omega|^2, either sign: a negative omega_k^2 beyond it is no noise), and the
 * rate output within GF9_MAX_RATE_RAD_S (it is the reference rate where omega_k^2 < 0).
 * The reference rate alone is not limited (only required finite, by the callers): it
 * only gives signs, and on a long record its integral may drift (gf9_state) without
 * making the solution absurd. Finite samples whose solution overflows fail the same test. */
static int within_limits(const double f[3], const double omega[3], const double omega_dot[3],
                         const double omega_sq[3])
{
    const double w2_max = (double)GF9_MAX_RATE_RAD_S * GF9_MAX_RATE_RAD_S;
    const double f2_max = (double)GF9_MAX_SPECIFIC_FORCE_M_S2 * GF9_MAX_SPECIFIC_FORCE_M_S2;
    return gf_all_finite(omega_dot, 3) && gf_v3_dot(f, f) <= f2_max &&
           fabs(omega_sq[0]) + fabs(omega_sq[1]) + fabs(omega_sq[2]) <= w2_max &&
           gf_v3_dot(omega, omega) <= w2_max;
}

gf_status gf9_state_check(const gf9_state *state)
{
    if (!state)
        return GF_ERR_NULL_POINTER;
    return state_is_valid(state) ? GF_OK : GF_ERR_BAD_PARAMETER;
}

/* The solver for one sample; used by gf9_step and inlined in the gf9_solve loop.
 * Reads A (already checked finite); advances the reference rate omega_ref (in/out) by
 * the trapezoid of omega_dot over half_dt_s * 2 unless `first`; writes the solution. */
static inline void gf9_solve_sample(const double A[9], double inv_4l, double minus_inv_2l,
                                    int first, double half_dt_s, double omega_ref[3],
                                    const double omega_dot_prev[3], double f[3],
                                    double omega[3], double omega_dot[3], double omega_sq[3],
                                    uint32_t *flags)
{
    /* seed 000, eq. 3: specific force at the centre, constant biases cancel */
    f[0] = 0.5 * (A[0] - A[3]);
    f[1] = 0.5 * (A[1] - A[4]);
    f[2] = 0.5 * (A[2] - A[5]);
    /* seed 000, eq. 4: squared rates. With s_x = A1 + A4 = -2 l (w_y^2 + w_z^2) etc.,
     * w_x^2 = (s_x - s_y - s_z) / (4 l). */
    const double s_x = A[0] + A[3], s_y = A[1] + A[4], s_z = A[2] + A[5];
    omega_sq[0] = (s_x - s_y - s_z) * inv_4l;
    omega_sq[1] = (s_y - s_x - s_z) * inv_4l;
    omega_sq[2] = (s_z - s_x - s_y) * inv_4l;
    /* seed 000, eq. 6: angular acceleration */
    omega_dot[0] = minus_inv_2l * (A[1] - A[5] - GF_SQRT2 * A[8]);
    omega_dot[1] = minus_inv_2l * (-A[0] + A[5] + GF_SQRT2 * A[7]);
    omega_dot[2] = minus_inv_2l * (A[0] - A[4] - GF_SQRT2 * A[6]);

    /* Rate: magnitude from omega^2 (eq. 4), sign from omega_ref = omega_init + the
     * trapezoidal integral of omega_dot (eq. 6). Policy when noise makes omega_k^2 < 0:
     * the magnitude is not measured, so omega_ref is used and the sample is flagged. */
    uint32_t fl = 0;
    for (int k = 0; k < 3; ++k) {
        if (!first)
            omega_ref[k] += half_dt_s * (omega_dot_prev[k] + omega_dot[k]);
        const double pred = omega_ref[k];
        if (omega_sq[k] >= 0.0) {
            const double mag = sqrt(omega_sq[k]);
            if (pred < 0.0) {
                omega[k] = -mag;
            } else {
                omega[k] = mag;
                if (pred == 0.0 && mag > 0.0)
                    fl |= (uint32_t)GF9_FLAG_SIGN_UNKNOWN_X << k;
            }
        } else {
            omega[k] = pred;
            fl |= (uint32_t)GF9_FLAG_NEG_OMEGA_SQ_X << k;
        }
    }
    *flags = fl;
}

gf_status gf9_step(gf9_state *state, const double *A_m_s2, double dt_s, gf9_output *out)
{
    if (!state || !A_m_s2 || !out)
        return GF_ERR_NULL_POINTER;
    if (!state_is_valid(state))
        return GF_ERR_BAD_PARAMETER;
    const int first = state->n_samples == 0;
    if (!first && (!(dt_s > 0.0) || !isfinite(dt_s)))
        return GF_ERR_BAD_PARAMETER;
    if (!gf_all_finite(A_m_s2, 9))
        return GF_ERR_NONFINITE_INPUT;
    const double l = state->lever_arm_m;
    double ref[3];
    gf_v3_copy(state->omega_ref_rad_s, ref);
    gf9_output o;
    gf9_solve_sample(A_m_s2, 0.25 / l, -0.5 / l, first, first ? 0.0 : 0.5 * dt_s, ref,
                     state->omega_dot_rad_s2, o.f_m_s2, o.omega_rad_s, o.omega_dot_rad_s2,
                     o.omega_sq_rad2_s2, &o.flags);
    /* the reference rate itself may overflow over an absurd interval (found by fuzzing:
     * a state gf9_state_check refuses): refused like an absurd sample */
    if (!within_limits(o.f_m_s2, o.omega_rad_s, o.omega_dot_rad_s2, o.omega_sq_rad2_s2) ||
        !gf_all_finite(ref, 3))
        return GF_ERR_OUT_OF_RANGE; /* absurd or overflowing sample; state kept */
    *out = o;
    gf_v3_copy(ref, state->omega_ref_rad_s);
    gf_v3_copy(o.omega_dot_rad_s2, state->omega_dot_rad_s2);
    state->n_samples += 1;
    return GF_OK;
}

gf_status gf9_solve(gf9_state *state, size_t n_samples, const double *A_m_s2, double dt_s,
                    double *f_m_s2, double *omega_rad_s, double *omega_dot_rad_s2,
                    double *omega_sq_rad2_s2, uint8_t *flags, size_t *n_done)
{
    if (n_done)
        *n_done = 0;
    if (!state || !A_m_s2 || !f_m_s2 || !omega_rad_s || !omega_dot_rad_s2 ||
        !omega_sq_rad2_s2 || !flags)
        return GF_ERR_NULL_POINTER;
    if (!state_is_valid(state))
        return GF_ERR_BAD_PARAMETER;
    if (!(dt_s > 0.0) || !isfinite(dt_s))
        return GF_ERR_BAD_PARAMETER;

    const double l = state->lever_arm_m, inv_4l = 0.25 / l, minus_inv_2l = -0.5 / l;
    const double half_dt_s = 0.5 * dt_s;
    double omega_ref[3], omega_dot_prev[3];
    gf_v3_copy(state->omega_ref_rad_s, omega_ref);
    gf_v3_copy(state->omega_dot_rad_s2, omega_dot_prev);
    uint64_t n_before = state->n_samples;
    gf_status status = GF_OK;
    size_t k = 0;
    for (; k < n_samples; ++k) {
        const double *A = A_m_s2 + 9 * k;
        if (!gf_all_finite(A, 9)) {
            status = GF_ERR_NONFINITE_INPUT;
            break;
        }
        double *wd = omega_dot_rad_s2 + 3 * k;
        uint32_t fl;
        const int first = (n_before + k) == 0;
        double ref_before[3];
        gf_v3_copy(omega_ref, ref_before);
        gf9_solve_sample(A, inv_4l, minus_inv_2l, first, half_dt_s, omega_ref, omega_dot_prev,
                         f_m_s2 + 3 * k, omega_rad_s + 3 * k, wd, omega_sq_rad2_s2 + 3 * k, &fl);
        if (!within_limits(f_m_s2 + 3 * k, omega_rad_s + 3 * k, wd, omega_sq_rad2_s2 + 3 * k) ||
            !gf_all_finite(omega_ref, 3)) {
            gf_v3_copy(ref_before, omega_ref); /* absurd or overflowing sample */
            status = GF_ERR_OUT_OF_RANGE;
            break;
        }
        flags[k] = (uint8_t)fl;
        gf_v3_copy(wd, omega_dot_prev);
    }
    gf_v3_copy(omega_ref, state->omega_ref_rad_s);
    gf_v3_copy(omega_dot_prev, state->omega_dot_rad_s2);
    state->n_samples = n_before + k;
    if (n_done)
        *n_done = k;
    return status;
}
