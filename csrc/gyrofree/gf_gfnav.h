/* gf_gfnav.h — the gyro-free navigator (seed 000): an accelerometer array's rate solver
 * (gf_gfins.h) feeding the strapdown mechanization (gf_sins.h). It integrates
 * (w, w_dot, f) over each interval with a cubic Hermite rate model
 * (gf_hermite_increments) and hands the increments to the mechanization
 * (gf_sins_step_compensated), or feeds it the rates (GF_GFNAV_LINEAR).
 */
#ifndef GF_GFNAV_H
#define GF_GFNAV_H

#include <stddef.h>
#include <stdint.h>

#include "base/gf_status.h"
#include "gyrofree/gf_array.h"
#include "gyrofree/gf_gfins.h"
#include "nav/gf_sins.h"

#ifdef __cplusplus
extern "C" {
#endif

/* CDEF BEGIN */
/* ---- navigator: array -> (w, f) -> strapdown ------------------------------------- */
/* Attitude and velocity over one sampling interval [0, T]. The array measures w and
 * w_dot at both ends, so the navigator models the rate as the cubic Hermite polynomial
 * through (w0, w_dot0) and (w1, w_dot1), tau = t / T:
 *   w(t) = (2tau^3 - 3tau^2 + 1) w0 + (tau^3 - 2tau^2 + tau) T w_dot0
 *        + (-2tau^3 + 3tau^2) w1 + (tau^3 - tau^2) T w_dot1,
 * whose increment and (second-order Magnus, "coning") term are, exactly,
 *   dtheta = T (w0 + w1) / 2 + T^2 (w_dot0 - w_dot1) / 12,
 *   cone   = 1/2 int_0^T theta(t) x w(t) dt
 *          = T^2 [ w0 x w1 / 10 + (w0 x T w_dot0 + w1 x T w_dot1) / 168
 *                  - (w0 x T w_dot1 + w1 x T w_dot0) / 70 - T w_dot0 x T w_dot1 / 560 ]
 * (for a linear rate, w_dot0 = w_dot1 = (w1 - w0) / T, this is T^2 w0 x w1 / 12, the
 * mechanization's own two-sample term). The rotation vector of the interval is the
 * sixth-order Magnus series of that polynomial, evaluated at the three Gauss-Legendre
 * nodes c = 1/2 -+ sqrt(15)/10, 1/2 (Blanes, Casas & Ros, BIT 40 (2000) 434, the
 * sixth-order method; commutators [a, b] = b x a for the body rate, q' = q (x) w / 2):
 *   a_i = w(c_i T),  B1 = T a_2,  B2 = sqrt(15) T (a_3 - a_1) / 3,
 *   B3 = 10 T (a_3 - 2 a_2 + a_1) / 3,  C1 = [B1, B2],  C2 = -[B1, 2 B3 + C1] / 60,
 *   phi = B1 + B3 / 12 + [-20 B1 - B3 + C1, B2 + C2] / 240,
 * which holds dtheta exactly and the coning term and all higher commutator terms to
 * O(T^7) (local error of the rotation vector against the attitude ODE under the cubic
 * rate; tests/c/test_gfins.c and tests/test_gyrofree.py check both).
 * The specific force is not differentiated by the array, but expressed in the body
 * frame at the start of the interval, h(t) = R(t) f(t) (R(T) = exp([phi x])), it is the
 * specific force in a non-rotating frame, free of the body rate: its trapezoid
 *   dv_b = T (f0 + R(T) f1) / 2
 * has the error T^3 h''/12 of the vehicle's own acceleration changes only, whatever the
 * body rate (the mechanization's linear model errs by ~T^3 |w|^2 |f| / 12 a step).
 * Inputs w (rad/s), w_dot (rad/s^2), f (m/s^2) at both ends; outputs phi_rad (body at
 * 0 -> body at T) and dv_b_m_s (body frame at 0). Errors: GF_ERR_NULL_POINTER,
 * GF_ERR_BAD_TIME (T not > 0), GF_ERR_NONFINITE_INPUT. */
gf_status gf_hermite_increments(const double *w0_rad_s, const double *w_dot0_rad_s2,
                                const double *f0_m_s2, const double *w1_rad_s,
                                const double *w_dot1_rad_s2, const double *f1_m_s2, double T_s,
                                double *phi_rad, double *dv_b_m_s);

#define GF_GFNAV_LINEAR 0     /* rates linear between samples: the mechanization's own rate
                                 input with its two-sample coning and sculling (second order) */
#define GF_GFNAV_HERMITE 1    /* cubic Hermite rate model from w and w_dot (default) */

typedef struct gf_gfnav_state {
    gf_gfins_state rate;
    gf_sins_state nav;              /* rate input */
    int32_t integration;            /* GF_GFNAV_* */
} gf_gfnav_state;

/* sins_cfg->input must be GF_SINS_INPUT_RATES. The integration is GF_GFNAV_HERMITE. */
gf_status gf_gfnav_init(gf_gfnav_state *state, const gf_array_geometry *geometry,
                        const gf_rate_config *rate_cfg, const double *omega_init_rad_s,
                        const gf_sins_config *sins_cfg, const double *q_bn,
                        const double *v_n_m_s, double lat_rad, double lon_rad, double h_m,
                        double t0_s, uint32_t *unobservable);

/* Chooses the attitude and velocity integration (GF_GFNAV_*; GF_ERR_BAD_PARAMETER
 * otherwise); may be changed between runs. */
gf_status gf_gfnav_set_integration(gf_gfnav_state *state, int32_t integration);

/* Batch navigation of n array samples (the first one at t0): rows of q_bn (n x 4),
 * v_n_m_s (n x 3), pos (n x 3), and optionally omega_rad_s, f_m_s2 (n x 3, may be NULL)
 * and flags (n, may be NULL). Errors as gf_gfins_run and gf_sins_run. */
gf_status gf_gfnav_run(gf_gfnav_state *state, size_t n, const double *A_m_s2, double dt_s,
                       const double *h_ext_m, double *q_bn, double *v_n_m_s, double *pos,
                       double *omega_rad_s, double *f_m_s2, uint8_t *flags, size_t *n_done);
/* CDEF END */

#ifdef __cplusplus
}
#endif

#endif /* GF_GFNAV_H */
