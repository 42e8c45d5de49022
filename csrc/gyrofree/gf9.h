/* gf9.h — the 9-accelerometer gyro-free solver of seed 000 (Qin, Xu, Li, "A new
 * 9-accelerometer gyro-free INS solution"): its layout and the closed-form solution of
 * each sample (eq. 3, 4, 6), on the array model of gf_array.h.
 *
 * Nothing here allocates or keeps global state: a solver's whole state is its
 * gf9_state struct, so any number of instances can run side by side.
 */
#ifndef GF9_H
#define GF9_H

#include <stddef.h>
#include <stdint.h>

#include "base/gf_status.h"
#include "gyrofree/gf_array.h"

#ifdef __cplusplus
extern "C" {
#endif

/* CDEF BEGIN */
/* The 9-accelerometer layout of seed 000 (table in eq. 1-2, with u_7..u_9 = l[...]
 * as the equations require; the scan's "sqrt(l)" is an OCR artefact).
 * Error: GF_ERR_BAD_PARAMETER unless 1e-6 m <= lever_arm_m < inf. */
gf_status gf9_geometry(double lever_arm_m, gf_array_geometry *geometry);

/* Per-sample flags of the 9-accelerometer solver (bit k refers to axis k = x, y, z). */
#define GF9_FLAG_NEG_OMEGA_SQ_X 1    /* omega_x^2 < 0 (noise): omega_x = integrated reference */
#define GF9_FLAG_NEG_OMEGA_SQ_Y 2
#define GF9_FLAG_NEG_OMEGA_SQ_Z 4
#define GF9_FLAG_SIGN_UNKNOWN_X 8    /* reference omega_x exactly 0: sign taken positive */
#define GF9_FLAG_SIGN_UNKNOWN_Y 16
#define GF9_FLAG_SIGN_UNKNOWN_Z 32

/* Physical limits of the 9-accelerometer solver: the navigators' defaults
 * (gf_sins_config_default). A sample whose specific force exceeds
 * GF9_MAX_SPECIFIC_FORCE_M_S2, or whose rate (|omega|^2 = sum |omega_k^2| as measured,
 * or the rate output, which is the integrated reference where omega_k^2 < 0) exceeds
 * GF9_MAX_RATE_RAD_S, is refused as absurd (GF_ERR_OUT_OF_RANGE), as gf_sins refuses
 * it. Integers so that cffi exports them. */
#define GF9_MAX_RATE_RAD_S 50
#define GF9_MAX_SPECIFIC_FORCE_M_S2 1000

/* State of one 9-accelerometer solver instance. Pointer-free: copying the struct
 * copies the solver (used by FMU get/set/serialize state).
 *
 * Signs (seed 000, after eq. 6: "the sign follows from integrating eq. 6"): the solver
 * integrates omega_dot with the trapezoid rule from omega_init into a reference rate
 * omega_ref, which is never reset to the solved rate. Re-anchoring it to the solved
 * rate would feed the noise of sqrt(omega^2), large near omega_k = 0, back into the
 * sign and can lock a component on the wrong sign after a zero crossing (measured in
 * the gfins demo scenario: rate RMS error 0.12-2.0 rad/s per axis re-anchored, 1.2e-3 to
 * 2.9e-3 rad/s with the pure integral). The price is
 * the drift of the integral (random walk of omega_dot noise, ramp of its bias), which
 * only matters where |omega_k| is below that drift; the fused estimator of gf_gfins
 * bounds it. */
typedef struct gf9_state {
    double lever_arm_m;            /* l of seed 000, > 0 */
    double omega_ref_rad_s[3];     /* omega_init + integral of omega_dot (signs) */
    double omega_dot_rad_s2[3];    /* last solved angular acceleration */
    uint64_t n_samples;            /* samples processed so far */
} gf9_state;

/* Solution of one sample. */
typedef struct gf9_output {
    double f_m_s2[3];              /* specific force at the array centre, eq. 3 */
    double omega_rad_s[3];         /* angular rate: |.| from eq. 4, sign from eq. 6 */
    double omega_dot_rad_s2[3];    /* angular acceleration, eq. 6 */
    double omega_sq_rad2_s2[3];    /* omega_k^2 as measured, eq. 4 (may be < 0) */
    uint32_t flags;                /* GF9_FLAG_* */
} gf9_output;

/* Initialises *state. omega_init_rad_s (may be NULL = zero) is the rate at the first
 * sample: its signs are the first signs and the integration of omega_dot starts from
 * it. Error: GF_ERR_BAD_PARAMETER unless 1e-6 m <= lever_arm_m < inf and omega_init is
 * finite with |omega_init| <= GF9_MAX_RATE_RAD_S. */
gf_status gf9_init(gf9_state *state, double lever_arm_m, const double *omega_init_rad_s);

/* Solves one sample A_m_s2[9] taken dt_s after the previous one (dt_s is ignored on
 * the first sample). The state is updated only on GF_OK.
 * Errors: GF_ERR_NONFINITE_INPUT, GF_ERR_BAD_PARAMETER (dt_s <= 0 or not finite after
 * the first sample), GF_ERR_OUT_OF_RANGE (a sample beyond the physical limits
 * GF9_MAX_*, or finite samples whose solution overflows), GF_ERR_NULL_POINTER. */
gf_status gf9_step(gf9_state *state, const double *A_m_s2, double dt_s, gf9_output *out);

/* Batch solve of n_samples rows of A_m_s2 (n x 9) at a fixed interval dt_s, in one
 * call, continuing from *state. Outputs are n x 3 arrays and n flags. On an error the
 * run stops at the bad sample: *n_done (may be NULL) = samples solved, rows before it
 * are valid and *state is the state after the last good sample. */
gf_status gf9_solve(gf9_state *state, size_t n_samples, const double *A_m_s2, double dt_s,
                    double *f_m_s2, double *omega_rad_s, double *omega_dot_rad_s2,
                    double *omega_sq_rad2_s2, uint8_t *flags, size_t *n_done);
/* CDEF END */

/* Checks a state handed in by a caller (e.g. restored from saved bytes); gf9_step and
 * gf9_solve do it before using one: lever arm finite and >= 1e-6 m, reference rate and
 * angular acceleration finite. Error: GF_ERR_BAD_PARAMETER. */
gf_status gf9_state_check(const gf9_state *state);

#ifdef __cplusplus
}
#endif

#endif /* GF9_H */
