/* gf_vehicle.h — a rigid ground vehicle on the WGS-84 ellipsoid and the exact outputs of
 * the inertial sensors riding it: the truth source of the vehicle FMU.
 *
 * Motion. The vehicle stays level (pitch = roll = 0) at constant height; its speed u
 * and heading psi (clockwise from north, gf_sins.h conventions) follow a profile of
 * segments. Within a segment of duration T, with tau in [0, T] and s = tau / T,
 *     u(tau)       = u0 + du S(s)
 *     dpsi/dt(tau) = r0 + dr S(s) + dpsi S'(s) / T
 *     psi(tau)     = psi0 + r0 tau + dr T I(s) + dpsi S(s)
 * with the C2 smooth step S(s) = s - sin(2 pi s) / (2 pi) (S', S'' vanish at both ends,
 * so the acceleration and the yaw acceleration are continuous: what a gyro-free
 * navigator needs, since it integrates the angular acceleration) and
 * I(s) = int_0^s S = s^2/2 + (cos 2 pi s - 1) / (4 pi^2). A 180 deg turn is
 * dpsi = pi (seed 001's vehicle test); a circle is a constant heading rate r0 (seed
 * 000). After the last segment the vehicle cruises (constant u and heading rate).
 * A command (gf_vehicle_command) replaces the rest of the profile by one segment that
 * reaches a commanded speed and heading rate.
 *
 * Position. The local displacement E(t), N(t) (m) is the integral of u [sin psi,
 * cos psi] (8-node Gauss-Legendre, pieces of at most 0.25 s split at segment ends:
 * error below round-off for these smooth profiles); geodetic coordinates are
 *     L = L0 + N / (R_M(L0) + h0),  lambda = lambda0 + E / ((R_N(L0) + h0) cos L0)
 * (the mapping of gfins_fmi.trajectory: a closed-form geodetic path whose derivatives
 * are exact, so the sensor outputs below are exact for that path). The true ENU speed
 * is therefore u scaled by the mapping, 1 + O(tan(L) N / R): 1.6e-7 after 30 m north,
 * 1.6e-4 after 30 km; u is the speed along the local plane.
 *
 * Sensors (same formulas as gfins_fmi/trajectory.py; seed 002's ENU mechanization
 * inverted):
 *     v^n = [(R_N + h) cos L dlambda, (R_M + h) dL, 0]
 *     f^n = dv^n/dt + (2 w_ie^n + w_en^n) x v^n - g^n,      f^b = C_n^b f^n
 *     w_ib^b = w_nb^b + C_n^b (w_ie^n + w_en^n),           w_nb^b = [0, 0, -dpsi/dt]
 *     dw_ib^b/dt = dw_nb^b/dt + C_n^b d(w_ie^n + w_en^n)/dt - w_nb^b x C_n^b (w_ie^n + w_en^n)
 * Increments are the integrals of w_ib^b and f^b over the step (Gauss-Legendre, the
 * displacement at each node from the same nodes' velocities by the rule's integration
 * matrix: exact for degree 7, round-off on pieces of <= 0.25 s).
 */
#ifndef GF_VEHICLE_H
#define GF_VEHICLE_H

#include <stddef.h>

#include "base/gf_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* longest step of gf_vehicle_step (up to 4e5 quadrature pieces); outside the cffi
 * declarations, which take integer constants only */
#define GF_VEHICLE_MAX_STEP_S 1e5

/* CDEF BEGIN */
#define GF_VEHICLE_MAX_SEGMENTS 32

typedef struct gf_vehicle_segment {
    double duration_s;            /* > 0 */
    double dspeed_m_s;            /* speed change over the segment (smooth step) */
    double dheading_rate_rad_s;   /* heading-rate change (smooth step) */
    double dheading_rad;          /* heading change on top of the rate (smooth step: turns) */
} gf_vehicle_segment;

typedef struct gf_vehicle_profile {
    double lat0_rad, lon0_rad, h0_m;        /* start position = reference of E, N */
    double heading0_rad;                    /* clockwise from north */
    double speed0_m_s;                      /* >= 0 */
    double heading_rate0_rad_s;
    size_t n_segments;                      /* 0 .. GF_VEHICLE_MAX_SEGMENTS */
    gf_vehicle_segment segment[GF_VEHICLE_MAX_SEGMENTS];
} gf_vehicle_profile;

typedef struct gf_vehicle_state {
    gf_vehicle_profile profile;
    double time_s;                          /* time of the last sample */
    size_t next_segment;                    /* profile index after the active segment */
    gf_vehicle_segment active;              /* duration <= 0: cruising */
    double active_t0_s;                     /* start time of the active segment */
    double speed0_m_s, heading0_rad, heading_rate0_rad_s; /* at active_t0_s */
    double east_m, north_m;                 /* displacement at time_s */
    double R_M0_m, R_N0_m;                  /* radii at the start position */
} gf_vehicle_state;

/* One sample: the truth at time_s and the ideal sensor outputs. */
typedef struct gf_vehicle_sample {
    double time_s;
    double q_bn[4];
    double euler_rad[3];                    /* heading [0, 2 pi), pitch, roll */
    double v_n_m_s[3];                      /* ENU */
    double lat_rad, lon_rad, h_m;
    double east_m, north_m;                 /* displacement from the start */
    double speed_m_s, heading_rate_rad_s;
    double gyro_rad_s[3];                   /* w_ib^b at time_s */
    double accel_m_s2[3];                   /* f^b at time_s */
    double gyro_dot_rad_s2[3];              /* d w_ib^b / dt at time_s */
    double dtheta_rad[3];                   /* integral of w_ib^b over the last step */
    double dv_m_s[3];                       /* integral of f^b over the last step */
} gf_vehicle_sample;

/* Checks the profile and starts the motion at start_time_s; *first (may be NULL)
 * receives the sample at the start (zero increments).
 * Errors: GF_ERR_NONFINITE_INPUT; GF_ERR_BAD_SIZE (n_segments > max);
 * GF_ERR_BAD_PARAMETER with *bad (may be NULL): 1 latitude (|L| >= 89 deg, where the
 * ENU frame degenerates), 2 height (below -1000 m or above 1e5 m), 3 negative start
 * speed, 100 + k segment k (duration <= 0 or the speed would become negative). */
gf_status gf_vehicle_init(gf_vehicle_state *state, const gf_vehicle_profile *profile,
                          double start_time_s, gf_vehicle_sample *first, int *bad);

/* From now on, reach speed_m_s and heading_rate_rad_s over duration_s (smooth step),
 * then cruise; the rest of the profile is dropped. Errors: GF_ERR_NONFINITE_INPUT,
 * GF_ERR_BAD_PARAMETER (speed < 0 or duration <= 0). */
gf_status gf_vehicle_command(gf_vehicle_state *state, double speed_m_s,
                             double heading_rate_rad_s, double duration_s);

/* Advances to t_end_s (> the state's time) and fills *sample there, increments over the
 * step. Times are absolute so that long runs do not accumulate a time drift.
 * Errors: GF_ERR_BAD_TIME (t_end not after the state's time, non-finite, or more than
 * 1e5 s after it: one step integrates up to 4e5 quadrature pieces), GF_ERR_DIVERGED
 * (latitude beyond +-89 deg), GF_ERR_BAD_SIZE (segment counts of the state out of
 * range, see gf_vehicle_state_check), GF_ERR_BAD_PARAMETER (the state's time outside its
 * active segment: a damaged or hand-made state); the state is unchanged on error. */
gf_status gf_vehicle_step(gf_vehicle_state *state, double t_end_s, gf_vehicle_sample *sample);

/* The truth at the state's own time (state->time_s): pose, velocity and sensor rates,
 * zero increments; the state is not changed. For evaluating a copy of a vehicle that has
 * been stepped to a time (gf_aiding_sim measures its epochs so).
 * Errors: GF_ERR_DIVERGED (latitude beyond +-89 deg). */
gf_status gf_vehicle_truth(const gf_vehicle_state *state, gf_vehicle_sample *sample);

/* n steps: samples[k] at t + (k + 1) dt_s, t the state's time (times computed, not
 * accumulated). *n_done = samples written. */
gf_status gf_vehicle_run(gf_vehicle_state *state, size_t n, double dt_s,
                         gf_vehicle_sample *samples, size_t *n_done);
/* CDEF END */

/* Internal to the core (not in the Python binding): a sensor mounted on the vehicle
 * whose frame s moves relative to the body (the rotating IMU of gf_rot). fn maps the
 * body rate w_ib^b and specific force f^b at t_s to the sensor's w_is^s and f^s; it must
 * not change anything (ctx is const) and returns GF_OK or an error that stops the step. */
typedef gf_status (*gf_vehicle_mount_fn)(const void *ctx, double t_s, const double w_b[3],
                                         const double f_b[3], double w_s[3], double f_s[3]);
typedef struct gf_vehicle_mount {
    gf_vehicle_mount_fn fn;
    const void *ctx;
} gf_vehicle_mount;

/* gf_vehicle_step with a mounted sensor (mount may be NULL: gf_vehicle_step): the same
 * quadrature also integrates the sensor's outputs; mounted (12) receives w_is^s and f^s
 * at t_end_s, then the increments dtheta_s, dv_s over the step. The caller splits the
 * step where the mount's motion is not smooth (the quadrature assumes smooth integrands
 * on each piece). */
gf_status gf_vehicle_step_mounted(gf_vehicle_state *state, double t_end_s,
                                  const gf_vehicle_mount *mount, gf_vehicle_sample *sample,
                                  double *mounted);

/* Checks a state handed in by a caller (e.g. restored from saved bytes). gf_vehicle_step
 * and gf_vehicle_command check before every call what indexes the profile (n_segments
 * <= GF_VEHICLE_MAX_SEGMENTS, next_segment <= n_segments: GF_ERR_BAD_SIZE); this also
 * checks every number finite (GF_ERR_NONFINITE_INPUT), the start position and radii
 * as gf_vehicle_init would and the time inside the active segment (GF_ERR_BAD_PARAMETER). */
gf_status gf_vehicle_state_check(const gf_vehicle_state *state);

#ifdef __cplusplus
}
#endif

#endif /* GF_VEHICLE_H */
