/* gf_ins_internal.h — what the files of the INS/GNSS filter share and callers never see
 * (not read by cffi: the filter's one public header is gf_ins_gnss.h). The files, one
 * concern each (the equations are in gf_ins_gnss.h):
 *   gf_ins_config.c     configuration, its checks, the state layout; gf_ins_init
 *   gf_ins_state.c      error state <-> navigation hypotheses, feedback
 *   gf_ins_propagate.c  error model and covariance propagation (EKF, UKF)
 *   gf_ins_meas.c       the measurement models: one table, one section per kind
 *   gf_ins_master.c     the transfer-alignment kinds (master velocity, attitude, position)
 *                       and the flexure's mean between updates
 *   gf_ins_update.c     the update: gating, innovation log
 *   gf_ins_delayed.c    delayed measurements (the nominal's history)
 *   gf_ins_step.c       the sample step and the batch walks
 *   gf_ins_reverse.c    reverse-time filtering and forward-backward passes
 *   gf_ins_align.c      alignment at rest and the heading rotation
 *   gf_ins_smooth.c     smoother epochs, the RTS pass and the smoothed solution
 * Functions one file calls in another are hidden (the core is built with
 * -fvisibility=hidden) and named ins_* (no gf_: not entry points); the small ones every
 * file uses are static inline here. */
#ifndef GF_INS_INTERNAL_H
#define GF_INS_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "base/gf_math.h"
#include "base/gf_status.h"
#include "est/gf_ins_gnss.h"
#include "est/gf_kalman.h"
#include "nav/gf_sins.h"

#define NMAX GF_INS_MAX_STATES
/* the initial latitude must be inside +-89 deg (gf_ins_initial_covariance) */
#define GF_INS_MAX_LAT_RAD (89.0 * GF_PI / 180.0)
#define IV GF_INS_IDX_VEL
#define IP GF_INS_IDX_POS
#define IA GF_INS_IDX_ATT
#define IBG GF_INS_IDX_BG
#define IBA GF_INS_IDX_BA
/* where each block's estimates sit in the sensors[] array */
#define S_BG 0
#define S_BA 3
#define S_SG 6
#define S_SA 9
#define S_BARO 12
#define S_ODO 13
#define S_MOUNT 14   /* pitch, heading */
/* where each block's estimates sit in the transfer[] array */
#define T_MOUNT 0    /* heading, pitch, roll of the slave in master axes */
#define T_LEVER 3    /* x, y, z, master axes */
#define T_OFFSET 6   /* slave stamp - master stamp */
#define T_FLEX 7     /* flexure angles (heading, pitch, roll), then rates at T_FLEX + 3 */
#define T_FLEX_RATE 10
/* the flexure's b = 2.146 / tau (the transfer-alignment literature's second-order
 * Markov model; gf_ins_gnss.h) */
#define GF_INS_FLEX_BETA_TAU 2.146
/* two times closer than this are the same instant (s) */
#define GF_INS_TIME_EPS_S 1e-9

/* ---- navigation hypotheses: nominal (-) error (gf_ins_state.c) ----------------------- */

typedef struct nav_hyp {
    double q[4];
    gf_mat3 C;          /* C_b^n */
    double v[3];
    double lat, lon, h;
    double s[GF_INS_N_SENSORS];
    double t[GF_INS_N_TRANSFER];   /* transfer-alignment estimates + states */
} nav_hyp;

static inline double wrap_pi(double a)
{
    if (a > GF_PI)
        a -= 2.0 * GF_PI;
    else if (a <= -GF_PI)
        a += 2.0 * GF_PI;
    return a;
}

/* +1 forward in time, -1 after gf_ins_reverse (the nominal's Earth-rate sign) */
static inline double dir_of(const gf_ins_filter *f)
{
    return f->nav.earth_rate_sign < 0.0 ? -1.0 : 1.0;
}

/* the truth hypothesis of an error dx about a nominal state and sensor estimates */
void ins_hyp_from_state(const gf_ins_filter *f, const gf_sins_state *nav, const double *sens,
                        const double *dx, nav_hyp *out);
/* dx of a hypothesis about a nominal: the inverse of ins_hyp_from_state */
void ins_error_from_hyp(const gf_ins_filter *f, const gf_sins_state *nom, const double *sens,
                        const nav_hyp *hy, double *dx);
/* 1 / (1 + scale estimates), kept in the filter */
void ins_refresh_scale(gf_ins_filter *f);
/* the output standard deviations std9, kept in the filter */
void ins_refresh_std(gf_ins_filter *f);
/* the estimated errors into the nominal and the sensor estimates; x reset to zero */
gf_status ins_feedback(gf_ins_filter *f);

/* ---- configuration and layout (gf_ins_config.c) ------------------------------------ */

/* what sizes or indexes arrays in a filter handed in by a caller (cheap: every step) */
int ins_layout_is_valid(const gf_ins_filter *f);

/* ---- propagation (gf_ins_propagate.c) --------------------------------------------- */

/* every variance positive and finite, else GF_ERR_DIVERGED */
gf_status ins_check_covariance(const gf_kalman *kf);
/* the covariance over the accumulated interval (EKF or UKF), then a new accumulation */
gf_status ins_propagate(gf_ins_filter *f, gf_ins_epochs *ep);

/* ---- smoother epochs (gf_ins_smooth.c) ----------------------------------------------- */

/* opens an epoch at the filter's time with transition Phi (NULL: identity) */
gf_status ins_epoch_open(const gf_ins_filter *f, gf_ins_epochs *ep, const double *Phi);
/* after an accepted update: the correction dx (before the reset) joins the epoch */
gf_status ins_epoch_update(const gf_ins_filter *f, gf_ins_epochs *ep, const double *dx);

/* ---- measurement models (gf_ins_meas.c) -------------------------------------------- */

/* Local metric frame of the nominal for positions: ENU metres about (lat0, lon0, h0). */
typedef struct local_frame {
    double lat0, lon0, h0, kE, kN;
} local_frame;

/* What a measurement model reads besides the navigation hypothesis. */
typedef struct ins_meas_ctx {
    const gf_ins_filter *f;
    const local_frame *lf;          /* the nominal's local frame (positions) */
    const double *w_comp;           /* compensated rate w_ib^b at the time of validity (3) */
    const gf_ins_meas *ms;          /* the measurement; NULL for the internal kinds and for
                                       a model asked for without one (gf_ins_meas_model) */
    const nav_hyp *nom;             /* the nominal hypothesis (no error) at the time of
                                       validity: what the master kinds carry forward by tau */
    const double *f_comp;           /* compensated specific force f^b (3) */
} ins_meas_ctx;

/* One measurement kind (a row of the table in gf_ins_meas.c):
 *   predict   y (rows) = the full nonlinear prediction from a hypothesis hy, positions in
 *             the nominal's local frame;
 *   jacobian  H (rows x n_states, zeroed by the caller: write the non-zero entries) = the
 *             linearised model at the nominal nom, z_err = predicted - measured = H x;
 *   value     the measured value z (rows) in the prediction's units (NULL: ms->z);
 *   check     1 if a caller's measurement is valid beyond finite values and std > 0
 *             (NULL: no more checks);
 *   std       the stds (rows) the update uses for a caller's measurement (NULL: ms->std);
 *   refuse    0, or the GF_INS_REJECTED_* status of an update the model cannot make at
 *             the nominal ref (NULL: never refused). */
typedef struct ins_meas_model {
    int32_t kind;                   /* GF_INS_MEAS_* */
    const char *name;               /* as in the innovation logs of the Python layer */
    int32_t rows;                   /* m: rows of z, H and R */
    int32_t external;               /* 1: handed in by callers; 0: made by the filter */
    int32_t reverses;               /* 1: a velocity, negated in reverse time (gf_ins_reverse),
                                       with its aux (a rate) */
    int32_t aux;                    /* 1: reads ms->aux (checked finite) */
    void (*predict)(const ins_meas_ctx *c, const nav_hyp *hy, double *y);
    void (*jacobian)(const ins_meas_ctx *c, const nav_hyp *nom, double *H);
    void (*value)(const local_frame *lf, const gf_ins_meas *ms, double *z);
    int (*check)(const gf_ins_meas *ms);
    void (*std)(const gf_ins_filter *f, const gf_ins_meas *ms, double *sd);
    int32_t (*refuse)(const gf_ins_filter *f, const gf_sins_state *ref);
} ins_meas_model;

/* the transfer-alignment kinds (gf_ins_master.c), rows of the table */
void ins_master_vel_predict(const ins_meas_ctx *c, const nav_hyp *hy, double *y);
void ins_master_vel_jacobian(const ins_meas_ctx *c, const nav_hyp *nom, double *H);
void ins_master_att_predict(const ins_meas_ctx *c, const nav_hyp *hy, double *y);
void ins_master_att_jacobian(const ins_meas_ctx *c, const nav_hyp *nom, double *H);
void ins_master_pos_predict(const ins_meas_ctx *c, const nav_hyp *hy, double *y);
void ins_master_pos_jacobian(const ins_meas_ctx *c, const nav_hyp *nom, double *H);
int ins_master_pos_check(const gf_ins_meas *ms);
/* the flexure's 2 x 2 transition per axis over T (the series of gf_ins_propagate.c:
 * I + F T (+ (F T)^2 / 2 when second_order)): phi[0..3] = rows (angle, rate) */
void ins_flexure_transition(const gf_ins_filter *f, double T, int second_order, double phi[4]);
/* the flexure estimates carried over T by the same transition (their mean between
 * updates: a closed-loop filter resets the error, so the estimate must move) */
void ins_flexure_mean(gf_ins_filter *f, double T, int second_order);

/* the table's row of a kind; NULL for a code that is no kind */
const ins_meas_model *ins_meas_model_of(int32_t kind);
void ins_local_frame_of(const gf_sins_state *nav, local_frame *lf);
/* the measured value in the prediction's units (positions in the local frame) */
void ins_meas_value(const ins_meas_model *mm, const local_frame *lf, const gf_ins_meas *ms,
                    double *z);
/* H of a kind at the nominal: zeroed, then the kind's entries */
void ins_meas_jacobian(const ins_meas_model *mm, const ins_meas_ctx *c, const nav_hyp *nom,
                       double *H);
/* a caller's measurement: a kind handed in by callers, finite, std > 0, the kind's check */
gf_status ins_meas_check(const gf_ins_meas *ms);
/* the measurement as the filter uses it (velocities negated in reverse) */
void ins_meas_directed(const gf_ins_filter *f, const gf_ins_meas *in, gf_ins_meas *out);

/* ---- the update (gf_ins_update.c) ---------------------------------------------------- */

void ins_log_entry(gf_ins_log *log, double t, int32_t type, int32_t status, int m, double nis,
                   const double *r, const double *s_std);
/* one update predicted from the nominal ref with rate w_ref (a delayed measurement: their
 * past values), the correction to the current nominal */
gf_status ins_update_at(gf_ins_filter *f, int32_t type, const gf_ins_meas *ms, double std_int,
                        const gf_sins_state *ref, const double *w_ref, gf_ins_epochs *ep,
                        gf_ins_log *log);
/* one update at the filter's time */
gf_status ins_update(gf_ins_filter *f, int32_t type, const gf_ins_meas *ms, double std_int,
                     gf_ins_epochs *ep, gf_ins_log *log);

/* ---- delayed measurements (gf_ins_delayed.c) --------------------------------------- */

void ins_history_push(gf_ins_filter *f);
/* a measurement valid at or before the filter's time: a delayed update, or stale */
gf_status ins_past_measurement(gf_ins_filter *f, const gf_ins_meas *ms, gf_ins_epochs *ep,
                               gf_ins_log *log);

/* ---- the walks (gf_ins_step.c) ------------------------------------------------------- */

/* forward over a record, or backward over one stored in increasing time */
gf_status ins_walk(gf_ins_filter *f, int backward, size_t n, const double *t_s,
                   const double *gyro, const double *accel, double t_start_s, size_t n_meas,
                   const gf_ins_meas *meas, gf_ins_output *out, gf_ins_epochs *epochs,
                   gf_ins_log *log, size_t *n_done, size_t *meas_done);
/* checks of a record stored in increasing time, and of its measurements */
gf_status ins_record_check(size_t n, const double *t_s, size_t n_meas, const gf_ins_meas *meas);

#endif /* GF_INS_INTERNAL_H */
