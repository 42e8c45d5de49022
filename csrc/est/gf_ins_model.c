/* gf_ins_model.c — navigation blocks of the INS error model: the dense and the checked
 * forms of gf_ins_nav_blocks_sparse (gf_ins_model.h, which holds the equations). */
#include "est/gf_ins_model.h"

#include <math.h>
#include <string.h>

#include "nav/gf_earth.h"

void gf_ins_nav_blocks(const gf_mat3 *C, const double v[3], double lat, double h,
                       const double f_b[3], size_t ld, size_t ia, size_t iv, size_t ip,
                       double *F)
{
    const size_t blk[3] = {ia, iv, ip};
    for (int r = 0; r < 3; ++r)
        for (size_t i = 0; i < 3; ++i)
            for (int c = 0; c < 3; ++c)
                memset(F + (blk[r] + i) * ld + blk[c], 0, 3 * sizeof *F);
    gf_ins_nav_blocks_sparse(C, v, sin(lat), cos(lat), h, 1.0, f_b, ld, ia, iv, ip, F, NULL);
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
