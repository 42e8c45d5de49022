/* gf_rot.h — the rotating IMU of seed 001: the two-axis indexing mechanism,
 * rotation schedules (calibration paths, indexing and continuous modulation schemes) and
 * the exact outputs of an IMU riding the mechanism, on a static base or on gf_vehicle.
 *
 * Frames (seed 001 step S1; gf_sins.h conventions): n = East-North-Up; base b = the
 * mechanism's base, fixed to the vehicle (right-front-up: the vehicle body of
 * gf_vehicle); IMU frame m = the orthogonal frame of the gyro triad (x_m = x_g, y_m in
 * the x_g-y_g plane; the sensing axes and their misalignment angles: gf_imu_error.h and
 * gf_syscal.h).
 *
 * Mechanism. The middle (outer) axis is fixed in the base along x_b; the inner axis is
 * fixed in the IMU along z_m and carried by the middle frame. With the middle angle
 * alpha and the inner angle beta, both right-handed (the seed's "clockwise", seen
 * looking along the axis),
 *     C_m^b = R_x(alpha) R_z(beta)                                                  (1)
 * (R_k(a): right-handed rotation by a about axis k). alpha = beta = 0 puts m on b: with
 * the base level and heading north, x_m E, y_m N, z_m U (seed 001, path position 0, middle
 * axis East, inner axis Up). Each row of the seed's 18-position path follows from the
 * previous one by (1) (checked in tests/test_rotation.py; docs/rotating_ins.md).
 *
 * Schedules. Segment k turns the IMU over move_s about a base axis by base_angle (the
 * turn premultiplies C_m^b) and/or about an IMU axis by imu_angle (postmultiplies), both
 * by the same normalised profile p(tau) in [0, 1], then rests dwell_s:
 *     C_m^b(tau) = R_base(base_angle p(tau)) C_k R_imu(imu_angle p(tau))              (2)
 * The mechanism's turns are base x (middle axis) and IMU z (inner axis); other axes model
 * a turntable (paths about the IMU's own axes). The profile's rate is
 * p' = W S(tau / ramp) over the ramp up, W in the cruise and W S((move - tau) / ramp) over
 * the ramp down (S: the C2 smooth step of gf_math.h, so the angular acceleration is
 * continuous; W = 1 / (move - ramp); ramp = 0: a constant rate). Rate of m relative to b:
 *     w_bm^m = p' (base_angle C_b^m e_base + imu_angle e_imu)                        (3)
 * A schedule may repeat (repeat = 1) when one cycle returns the IMU to its start attitude
 * (indexing and continuous schemes). With only middle and inner turns and an identity
 * start attitude the schedule drives the mechanism: alpha and beta are the sums of the
 * base-x and IMU-z turns (reported in (-pi, pi]); otherwise no gimbal angles exist
 * (gimbal = 0 in the state, angles reported as 0).
 *
 * IMU outputs (IMU centre on both axes; the accelerometers' own offsets from it are the
 * inner lever arms of gf_imu_error):
 *     w_im^m = C_b^m w_ib^b + w_bm^m,      f^m = C_b^m f^b                            (4)
 * integrated over each sample interval with the 8-node Gauss-Legendre rule (gf_quad.h)
 * on pieces of at most 0.25 s split at the schedule's phase boundaries (round-off level
 * on these smooth pieces). On a static base (attitude q_bn at latitude L, height h):
 * w_ib^b = C_n^b w_ie^n, f^b = C_n^b [0, 0, g(L, h)] (gf_earth). The static simulation may
 * delay the accelerometer samples by a fixed time (gyro-accelerometer asynchrony): dv_k
 * then integrates f^m over (t_(k-1) - delay, t_k - delay]. On a vehicle (gf_vehicle) the
 * same quadrature integrates (4) with the vehicle's body rates at the nodes.
 */
#ifndef GF_ROT_H
#define GF_ROT_H

#include <stddef.h>
#include <stdint.h>

#include "base/gf_status.h"
#include "sim/gf_vehicle.h"

#ifdef __cplusplus
extern "C" {
#endif

/* CDEF BEGIN */
#define GF_ROT_MAX_SEGMENTS 64
#define GF_ROT_AXIS_NONE -1
#define GF_ROT_MAX_RATE_MDEG_S 600000 /* a turn faster than 600 deg/s is refused */

/* Why gf_rot_init refused a schedule (*bad). */
#define GF_ROT_BAD_START 1         /* q_mb0 not a unit quaternion (within 1e-6) */
#define GF_ROT_BAD_REPEAT 2        /* repeat = 1 but one cycle does not return to q_mb0 */
#define GF_ROT_BAD_EMPTY_CYCLE 3   /* repeat = 1 with a cycle of zero duration */
#define GF_ROT_BAD_SEGMENT 100     /* + k: segment k (axis, angle, durations or rate) */

typedef struct gf_rot_segment {
    int32_t base_axis;        /* GF_ROT_AXIS_NONE or 0, 1, 2: about base x, y, z (middle = x) */
    int32_t imu_axis;         /* GF_ROT_AXIS_NONE or 0, 1, 2: about IMU x, y, z (inner = z) */
    double base_angle_rad;    /* 0 when base_axis is none */
    double imu_angle_rad;     /* 0 when imu_axis is none */
    double move_s;            /* duration of the turn; 0 only for a pure rest */
    double ramp_s;            /* acceleration time and deceleration time, 2 ramp <= move */
    double dwell_s;           /* rest after the turn */
} gf_rot_segment;

typedef struct gf_rot_schedule {
    double q_mb0[4];          /* C_m^b at the start (scalar first) */
    size_t n_segments;        /* 0 .. GF_ROT_MAX_SEGMENTS (0: the IMU stays at q_mb0) */
    int32_t repeat;           /* 1: the segments repeat (a cycle must return to q_mb0) */
    gf_rot_segment segment[GF_ROT_MAX_SEGMENTS];
} gf_rot_schedule;

/* What gf_rot_init derives; afterwards evaluation is a pure function of (state, t). */
typedef struct gf_rot_state {
    gf_rot_schedule sched;
    double t0_s;                                   /* start of the schedule */
    double cycle_s;                                /* duration of all segments */
    double seg_t0_s[GF_ROT_MAX_SEGMENTS + 1];      /* segment starts from t0 (last: cycle_s) */
    double seg_q0[GF_ROT_MAX_SEGMENTS + 1][4];     /* C_m^b at each segment start (last: end) */
    double seg_gimbal0[GF_ROT_MAX_SEGMENTS + 1][2]; /* alpha, beta there (unwrapped) */
    int32_t gimbal;                                /* 1: a mechanism schedule (see above) */
} gf_rot_state;

/* The mechanism at one time. */
typedef struct gf_rot_pose {
    double q_mb[4];               /* C_m^b */
    double w_bm_m_rad_s[3];       /* rate of m relative to b, IMU axes */
    double gimbal_rad[2];         /* middle alpha, inner beta in (-pi, pi]; 0 if no gimbal */
    double gimbal_rate_rad_s[2];
    int32_t segment;              /* active segment (-1 before the start) */
    int32_t moving;               /* 1 during a turn */
} gf_rot_pose;

/* Checks the schedule and derives the segment start attitudes. Errors:
 * GF_ERR_NULL_POINTER, GF_ERR_NONFINITE_INPUT, GF_ERR_BAD_SIZE (n_segments),
 * GF_ERR_BAD_PARAMETER with *bad (may be NULL) = GF_ROT_BAD_*: an axis not in
 * {-1, 0, 1, 2}, a non-zero angle about no axis, move_s < 0 or 0 with a non-zero angle,
 * ramp_s < 0 or 2 ramp > move, dwell_s < 0, a segment of zero duration, a peak rate
 * above GF_ROT_MAX_RATE_MDEG_S; a repeated cycle that does not close (1e-9) or lasts 0. */
gf_status gf_rot_init(gf_rot_state *state, const gf_rot_schedule *schedule, double t0_s,
                      int *bad);

/* The pose at t_s (before t0: the start pose, at rest; after a non-repeated schedule:
 * the end pose, at rest). Errors: GF_ERR_NULL_POINTER, GF_ERR_NONFINITE_INPUT,
 * GF_ERR_BAD_SIZE (a state whose n_segments or a segment axis is out of range). */
gf_status gf_rot_eval(const gf_rot_state *state, double t_s, gf_rot_pose *pose);

/* Poses at n times: q_mb (n x 4), w_bm (n x 3), gimbal (n x 2); each may be NULL. */
gf_status gf_rot_poses(const gf_rot_state *state, size_t n, const double *t_s, double *q_mb,
                       double *w_bm_m_rad_s, double *gimbal_rad, size_t *n_done);

/* The IMU on a static base (attitude q_bn_base, latitude lat_rad, height h_m): n samples
 * of increments dtheta (rad), dv (m/s) (n x 3 each) over the intervals
 * (t_start + k dt, t_start + (k + 1) dt]; dv delayed by accel_delay_s (|delay| <= dt_s).
 * Optional outputs at each interval's end: q_mn (n x 4, C_m^n), gimbal (n x 2).
 * Errors: GF_ERR_NULL_POINTER, GF_ERR_NONFINITE_INPUT, GF_ERR_BAD_TIME (dt_s <= 0 or
 * above GF_ROT_MAX_DT_S),
 * GF_ERR_BAD_PARAMETER (|lat| >= 89 deg, base quaternion not unit, |delay| > dt_s). */
gf_status gf_rot_imu_static(const gf_rot_state *state, const double *q_bn_base, double lat_rad,
                            double h_m, double t_start_s, size_t n, double dt_s,
                            double accel_delay_s, double *dtheta_rad, double *dv_m_s,
                            double *q_mn, double *gimbal_rad, size_t *n_done);

/* The IMU on the vehicle: advances *vehicle n steps of dt_s (times t + (k + 1) dt, t the
 * vehicle's time) and writes the IMU increments dtheta, dv (n x 3) and rates w_im^m,
 * f^m at the step ends (n x 3; may be NULL), gimbal angles (n x 2, may be NULL), C_m^n
 * (n x 4, may be NULL) and the vehicle's truth (may be NULL: its body increments are the
 * step's). The vehicle state is advanced sample by sample; *n_done = samples written.
 * Errors: those of gf_vehicle_step and gf_rot_eval. */
gf_status gf_rot_imu_vehicle(const gf_rot_state *state, gf_vehicle_state *vehicle, size_t n,
                             double dt_s, double *dtheta_rad, double *dv_m_s, double *w_rad_s,
                             double *f_m_s2, double *gimbal_rad, double *q_mn,
                             gf_vehicle_sample *truth, size_t *n_done);

/* One step of the vehicle to t_end_s with the rotating IMU (for the vehicle FMU):
 * *truth as gf_vehicle_step gives it (body increments over the whole step), imu (12):
 * w_im^m and f^m at t_end_s, then dtheta and dv over the step. The vehicle is advanced
 * only on GF_OK. Errors: GF_ERR_BAD_TIME (t_end_s not after the vehicle's time, or more
 * than GF_VEHICLE_MAX_STEP_S after it, as gf_vehicle_step), those of gf_vehicle_step and
 * gf_rot_eval. */
gf_status gf_rot_vehicle_step(const gf_rot_state *state, gf_vehicle_state *vehicle,
                              double t_end_s, gf_vehicle_sample *truth, double *imu);

/* Vehicle attitude from the navigated IMU attitude and the gimbal angles (encoders),
 * by (1): C_b^n = C_m^n (C_m^b)^T. q_mn, q_bn (n x 4), gimbal (n x 2). */
gf_status gf_rot_vehicle_attitude(size_t n, const double *q_mn, const double *gimbal_rad,
                                  double *q_bn, size_t *n_done);
/* CDEF END */

/* Longest IMU sample interval of gf_rot_imu_static (s; outside the CDEF block: cffi
 * takes integer constants only). */
#define GF_ROT_MAX_DT_S 10.0

/* Internal to the core: (4) at t_s for the base's rate w_b and specific force f_b (base
 * axes): the IMU's w_im^m, f^m and the pose at t_s. The caller has checked the state
 * (n_segments within the array) and t_s (finite). */
void gf_rot_imu_outputs(const gf_rot_state *state, double t_s, const double w_b[3],
                        const double f_b[3], double w_m[3], double f_m[3], gf_rot_pose *pose);

/* Checks a state handed in by a caller: sizes (GF_ERR_BAD_SIZE), finite numbers and the
 * schedule as gf_rot_init checks it (GF_ERR_BAD_PARAMETER). */
gf_status gf_rot_state_check(const gf_rot_state *state);

#ifdef __cplusplus
}
#endif

#endif /* GF_ROT_H */
