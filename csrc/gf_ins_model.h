/* gf_ins_model.h — the navigation blocks of the continuous INS error model, in one place
 * for every error-state filter of the core (the 36-state calibration filter gf_syscal
 * uses it; the integrated-navigation filter gf_ins_gnss implements the same equations in
 * its own error_model() today and can switch to this function: its arithmetic is the
 * same, operation for operation, so the switch changes no bit).
 *
 * Convention (gf_ins_gnss.h; gfins_fmi.error_models.ins_error_matrices is the
 * definition): C_b^n(computed) = (I - [phi x]) C_b^n(true); velocity and position errors
 * computed - true; b is the frame whose rate and specific force the IMU measures (the
 * vehicle body for a strapdown IMU, the IMU frame m of a rotating INS). Titterton &
 * Weston, Strapdown Inertial Navigation Technology, 2nd ed., ch. 12.3; seed 001 step S2
 * (its error equations, in the same convention):
 *   phi' = -w_in x phi + d(w_in)                               [- C_b^n dw_ib: caller]
 *   dv'  = f^n x phi + v x (2 d(w_ie) + d(w_en)) - (2 w_ie + w_en) x dv + dg
 *                                                              [+ C_b^n df: caller]
 *   dL'  = dv_N / (R_M + h) - v_N dh / (R_M + h)^2
 *   dlambda' = (dv_E + v_E tan L dL - v_E dh / (R_N + h)) / ((R_N + h) cos L)
 *   dh'  = dv_U,      dg = [0, 0, 2 g dh / (sqrt(R_M R_N) + h)]
 * with d(w_ie), d(w_en) the changes of the Earth and transport rates with dv, dL, dh
 * (derivatives of the radii and of gravity with latitude neglected: relative size e^2 ~
 * 0.7% of terms that are themselves small). The sensor-error columns (-C_b^n into phi,
 * C_b^n into dv, times each filter's own sensor model) are the caller's.
 */
#ifndef GF_INS_MODEL_H
#define GF_INS_MODEL_H

#include <stddef.h>
#include <stdint.h>

#include "gf_math.h"
#include "gf_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* CDEF BEGIN */
/* Writes the 9 x 9 navigation blocks (rows and columns ia..ia+2 = phi, iv..iv+2 = dv,
 * ip..ip+2 = dL, dlambda, dh) of the error model at attitude q_bn (normalised here),
 * ENU velocity v_n_m_s, latitude lat_rad, height h_m and specific force f_b_m_s2 (b
 * axes) into F, an n x n row-major matrix with row stride ld (>= n): those 81 entries
 * are overwritten (zeros included), no other entry is touched. Errors:
 * GF_ERR_NULL_POINTER, GF_ERR_NONFINITE_INPUT, GF_ERR_BAD_SIZE (a block beyond ld or
 * blocks that overlap), GF_ERR_BAD_PARAMETER (|lat| >= 90 deg, q_bn not normalisable). */
gf_status gf_ins_nav_error_model(const double *q_bn, const double *v_n_m_s, double lat_rad,
                                 double h_m, const double *f_b_m_s2, size_t ld, int32_t ia,
                                 int32_t iv, int32_t ip, double *F);
/* CDEF END */

/* Internal to the core: the same without the checks, with C_b^n given (the filters'
 * propagation calls it every interval). */
void gf_ins_nav_blocks(const gf_mat3 *C_bn, const double v[3], double lat_rad, double h_m,
                       const double f_b[3], size_t ld, size_t ia, size_t iv, size_t ip,
                       double *F);

#ifdef __cplusplus
}
#endif

#endif /* GF_INS_MODEL_H */
