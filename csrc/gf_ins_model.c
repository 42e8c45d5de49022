/* gf_ins_model.c — navigation blocks of the INS error model; see gf_ins_model.h. The
 * arithmetic follows gf_ins_gnss.c's error_model() operation for operation. */
#include "gf_ins_model.h"

#include <math.h>
#include <string.h>

#include "gf_earth.h"

void gf_ins_nav_blocks(const gf_mat3 *C, const double v[3], double lat, double h,
                       const double f_b[3], size_t ld, size_t ia, size_t iv, size_t ip,
                       double *F)
{
#define FF(i, j) F[(i) * ld + (j)]
    const size_t blk[3] = {ia, iv, ip};
    for (int r = 0; r < 3; ++r)
        for (int i = 0; i < 3; ++i)
            for (int c = 0; c < 3; ++c)
                for (int j = 0; j < 3; ++j)
                    FF(blk[r] + (size_t)i, blk[c] + (size_t)j) = 0.0;
    gf_earth ea;
    gf_earth_from_sincos(&ea, sin(lat), cos(lat), h, v, 1.0);
    const double sL = ea.sin_lat, cL = ea.cos_lat, tL = ea.tan_lat;
    const double RMh = ea.R_M_m + h, RNh = ea.R_N_m + h, Re = sqrt(ea.R_M_m * ea.R_N_m) + h;
    const double g = ea.gravity_m_s2;
    const double W = GF_WGS84_OMEGA_IE_RAD_S;
    const double vE = v[0], vN = v[1];
    double w_in[3], f_n[3];
    gf_v3_add(ea.w_ie_n_rad_s, ea.w_en_n_rad_s, w_in);
    gf_m3_mul_v3(C, f_b, f_n);
    /* derivatives of w_ie and w_en (columns: dvE, dvN | dL, dh) */
    const double dwie_dL[3] = {0.0, -W * sL, W * cL};
    const double dwen_dvE[3] = {0.0, 1.0 / RNh, tL / RNh};
    const double dwen_dvN[3] = {-1.0 / RMh, 0.0, 0.0};
    const double dwen_dL[3] = {0.0, 0.0, vE / (RNh * cL * cL)};
    const double dwen_dh[3] = {vN / (RMh * RMh), -vE / (RNh * RNh), -vE * tL / (RNh * RNh)};
    /* attitude: phi' = -w_in x phi + d(w_in) */
    for (size_t i = 0; i < 3; ++i) {
        FF(ia + i, iv + 0) = dwen_dvE[i];
        FF(ia + i, iv + 1) = dwen_dvN[i];
        FF(ia + i, ip + 0) = dwie_dL[i] + dwen_dL[i];
        FF(ia + i, ip + 2) = dwen_dh[i];
    }
    FF(ia + 0, ia + 1) = w_in[2];
    FF(ia + 0, ia + 2) = -w_in[1];
    FF(ia + 1, ia + 0) = -w_in[2];
    FF(ia + 1, ia + 2) = w_in[0];
    FF(ia + 2, ia + 0) = w_in[1];
    FF(ia + 2, ia + 1) = -w_in[0];
    /* velocity: dv' = f^n x phi + v x (2 dw_ie + dw_en) - (2 w_ie + w_en) x dv + dg */
    FF(iv + 0, ia + 1) = -f_n[2];
    FF(iv + 0, ia + 2) = f_n[1];
    FF(iv + 1, ia + 0) = f_n[2];
    FF(iv + 1, ia + 2) = -f_n[0];
    FF(iv + 2, ia + 0) = -f_n[1];
    FF(iv + 2, ia + 1) = f_n[0];
    double w2[3];
    gf_v3_axpy(ea.w_en_n_rad_s, 2.0, ea.w_ie_n_rad_s, w2); /* 2 w_ie + w_en */
    FF(iv + 0, iv + 1) = w2[2];
    FF(iv + 0, iv + 2) = -w2[1];
    FF(iv + 1, iv + 0) = -w2[2];
    FF(iv + 1, iv + 2) = w2[0];
    FF(iv + 2, iv + 0) = w2[1];
    FF(iv + 2, iv + 1) = -w2[0];
    double c[3], d[3], dL_col[3], t3[3], dh_col[3];
    gf_v3_cross(v, dwen_dvE, c);
    gf_v3_cross(v, dwen_dvN, d);
    gf_v3_axpy(dwen_dL, 2.0, dwie_dL, t3);
    gf_v3_cross(v, t3, dL_col);
    gf_v3_cross(v, dwen_dh, dh_col);
    for (size_t i = 0; i < 3; ++i) {
        FF(iv + i, iv + 0) += c[i];
        FF(iv + i, iv + 1) += d[i];
        FF(iv + i, ip + 0) = dL_col[i];
        FF(iv + i, ip + 2) = dh_col[i];
    }
    FF(iv + 2, ip + 2) += 2.0 * g / Re;
    /* position */
    FF(ip + 0, iv + 1) = 1.0 / RMh;
    FF(ip + 0, ip + 2) = -vN / (RMh * RMh);
    FF(ip + 1, iv + 0) = 1.0 / (RNh * cL);
    FF(ip + 1, ip + 0) = vE * tL / (RNh * cL);
    FF(ip + 1, ip + 2) = -vE / (RNh * RNh * cL);
    FF(ip + 2, iv + 2) = 1.0;
#undef FF
}

static int overlap(int32_t a, int32_t b)
{
    return a < b + 3 && b < a + 3;
}

gf_status gf_ins_nav_error_model(const double *q_bn, const double *v_n_m_s, double lat_rad,
                                 double h_m, const double *f_b_m_s2, size_t ld, int32_t ia,
                                 int32_t iv, int32_t ip, double *F)
{
    if (!q_bn || !v_n_m_s || !f_b_m_s2 || !F)
        return GF_ERR_NULL_POINTER;
    if (!gf_all_finite(q_bn, 4) || !gf_all_finite(v_n_m_s, 3) || !isfinite(lat_rad) ||
        !isfinite(h_m) || !gf_all_finite(f_b_m_s2, 3))
        return GF_ERR_NONFINITE_INPUT;
    const int32_t b[3] = {ia, iv, ip};
    for (int i = 0; i < 3; ++i)
        if (b[i] < 0 || (size_t)b[i] + 3 > ld)
            return GF_ERR_BAD_SIZE;
    if (overlap(ia, iv) || overlap(ia, ip) || overlap(iv, ip))
        return GF_ERR_BAD_SIZE;
    double q[4];
    if (!(fabs(lat_rad) < GF_HALF_PI) || !gf_q_normalize(q_bn, q) || !(h_m > -0.5 * GF_WGS84_A_M))
        return GF_ERR_BAD_PARAMETER;
    gf_mat3 C;
    gf_q_to_dcm(q, &C);
    gf_ins_nav_blocks(&C, v_n_m_s, lat_rad, h_m, f_b_m_s2, ld, (size_t)ia, (size_t)iv,
                      (size_t)ip, F);
    return GF_OK;
}
