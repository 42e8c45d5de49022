/* gf_ins_model.h — the navigation blocks of the continuous INS error model, in one place
 * for every error-state filter of the core: the integrated-navigation filter gf_ins_gnss
 * (every propagation, forward and reversed in time) and the 36-state calibration filter
 * gf_syscal both take them from here.
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
 *
 * Reverse-time filtering (seed 003, gf_ins_reverse): the nominal runs with the Earth rate
 * negated (gf_sins earth_rate_sign = -1), and so does w_ie in these blocks.
 */
#ifndef GF_INS_MODEL_H
#define GF_INS_MODEL_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "base/gf_math.h"
#include "base/gf_status.h"
#include "nav/gf_earth.h"

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

/* Internal to the core: the same without the checks, with C_b^n given and the latitude
 * as an angle (sin and cos taken here), Earth rate forward (the calibration filter). */
void gf_ins_nav_blocks(const gf_mat3 *C_bn, const double v[3], double lat_rad, double h_m,
                       const double f_b[3], size_t ld, size_t ia, size_t iv, size_t ip,
                       double *F);

/* Internal to the core: entry (i, j) of F (row stride ld), marked in the row masks when
 * mask is not NULL (bit j of mask[i], j < 64): a model's structure (which entries it can
 * make non-zero) comes out of the code that fills it, so a covariance propagation can
 * skip the rest without scanning F (gf_kalman_predict_masked). */
static inline double *gf_ins_f_entry(double *F, size_t ld, uint64_t *mask, size_t i, size_t j)
{
    if (mask)
        mask[i] |= (uint64_t)1 << j;
    return F + i * ld + j;
}

/* Internal to the core: the one implementation of the blocks (gf_ins_nav_blocks and the
 * integrated filter's propagation call it): attitude C = C_b^n, ENU velocity v (m/s),
 * latitude by its sine and cosine (the navigation state keeps them: gf_sins), height h
 * (m), specific force f_b (m/s^2, b axes); earth_rate_sign +1 forward in time, -1 in
 * reverse (the nominal's gf_sins_state.earth_rate_sign). Writes only the entries the
 * model can make non-zero, the zeros of the equations skipped: the caller zero-fills the
 * 81 entries first. mask (may be NULL; needs ld <= 64): bit j of mask[i] is set for each
 * entry (i, j) written (gf_ins_f_entry). Inline: the integrated filter calls it every
 * IMU sample with constant offsets, which the compiler folds into the stores and the
 * mask bits (no more instructions than the filter's former copy of these equations). */
static inline void gf_ins_nav_blocks_sparse(const gf_mat3 *C, const double v[3],
                                            double sin_lat, double cos_lat, double h,
                                            double earth_rate_sign, const double f_b[3],
                                            size_t ld, size_t ia, size_t iv, size_t ip,
                                            double *F, uint64_t *mask)
{
#define GF_FF_(i, j) (*gf_ins_f_entry(F, ld, mask, (i), (j)))
/* the 3 x 3 block at (r, c) = s [a x] (s = +1 or -1: exact) */
#define GF_SKEW_(r, c, a, s)                                                                \
    do {                                                                                    \
        GF_FF_((r) + 0, (c) + 1) = -(s) * (a)[2];                                           \
        GF_FF_((r) + 0, (c) + 2) = (s) * (a)[1];                                            \
        GF_FF_((r) + 1, (c) + 0) = (s) * (a)[2];                                            \
        GF_FF_((r) + 1, (c) + 2) = -(s) * (a)[0];                                           \
        GF_FF_((r) + 2, (c) + 0) = -(s) * (a)[1];                                           \
        GF_FF_((r) + 2, (c) + 1) = (s) * (a)[0];                                            \
    } while (0)
    gf_earth ea;
    gf_earth_from_sincos(&ea, sin_lat, cos_lat, h, v, earth_rate_sign);
    const double sL = ea.sin_lat, cL = ea.cos_lat, tL = ea.tan_lat;
    const double RMh = ea.R_M_m + h, RNh = ea.R_N_m + h, Re = sqrt(ea.R_M_m * ea.R_N_m) + h;
    const double g = ea.gravity_m_s2;
    const double W = earth_rate_sign * GF_WGS84_OMEGA_IE_RAD_S;
    const double vE = v[0], vN = v[1];
    double w_in[3], f_n[3];
    gf_v3_add(ea.w_ie_n_rad_s, ea.w_en_n_rad_s, w_in);
    gf_m3_mul_v3(C, f_b, f_n);
    /* derivatives of w_ie and w_en (columns: dvE, dvN | dL, dh); the entries listed as
     * zero are not written below */
    const double dwie_dL[3] = {0.0, -W * sL, W * cL};
    const double dwen_dvE[3] = {0.0, 1.0 / RNh, tL / RNh};
    const double dwen_dvN[3] = {-1.0 / RMh, 0.0, 0.0};
    const double dwen_dL[3] = {0.0, 0.0, vE / (RNh * cL * cL)};
    const double dwen_dh[3] = {vN / (RMh * RMh), -vE / (RNh * RNh), -vE * tL / (RNh * RNh)};
    /* attitude: phi' = -w_in x phi + d(w_in) */
    GF_FF_(ia + 1, iv + 0) = dwen_dvE[1];
    GF_FF_(ia + 2, iv + 0) = dwen_dvE[2];
    GF_FF_(ia + 0, iv + 1) = dwen_dvN[0];
    GF_FF_(ia + 1, ip + 0) = dwie_dL[1] + dwen_dL[1];
    GF_FF_(ia + 2, ip + 0) = dwie_dL[2] + dwen_dL[2];
    for (size_t i = 0; i < 3; ++i)
        GF_FF_(ia + i, ip + 2) = dwen_dh[i];
    GF_SKEW_(ia, ia, w_in, -1.0);    /* -[w_in x] */
    /* velocity: dv' = f^n x phi + v x (2 dw_ie + dw_en) - (2 w_ie + w_en) x dv + dg */
    GF_SKEW_(iv, ia, f_n, 1.0);      /* [f^n x] */
    double w2[3];
    gf_v3_axpy(ea.w_en_n_rad_s, 2.0, ea.w_ie_n_rad_s, w2); /* 2 w_ie + w_en */
    GF_SKEW_(iv, iv, w2, -1.0);      /* -[(2 w_ie + w_en) x] */
    /* v x (d w_en / dv) columns E, N; v x (2 dw_ie/dL + dw_en/dL), v x dw_en/dh */
    double c[3], d[3], dL_col[3], t3[3], dh_col[3];
    gf_v3_cross(v, dwen_dvE, c);
    gf_v3_cross(v, dwen_dvN, d);
    gf_v3_axpy(dwen_dL, 2.0, dwie_dL, t3);
    gf_v3_cross(v, t3, dL_col);
    gf_v3_cross(v, dwen_dh, dh_col);
    for (size_t i = 0; i < 3; ++i) {
        GF_FF_(iv + i, iv + 0) += c[i];
        GF_FF_(iv + i, iv + 1) += d[i];
        GF_FF_(iv + i, ip + 0) = dL_col[i];
        GF_FF_(iv + i, ip + 2) = dh_col[i];
    }
    GF_FF_(iv + 2, ip + 2) += 2.0 * g / Re;
    /* position */
    GF_FF_(ip + 0, iv + 1) = 1.0 / RMh;
    GF_FF_(ip + 0, ip + 2) = -vN / (RMh * RMh);
    GF_FF_(ip + 1, iv + 0) = 1.0 / (RNh * cL);
    GF_FF_(ip + 1, ip + 0) = vE * tL / (RNh * cL);
    GF_FF_(ip + 1, ip + 2) = -vE / (RNh * RNh * cL);
    GF_FF_(ip + 2, iv + 2) = 1.0;
#undef GF_SKEW_
#undef GF_FF_
}

#ifdef __cplusplus
}
#endif

#endif /* GF_INS_MODEL_H */
