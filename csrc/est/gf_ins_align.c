/* gf_ins_align.c — alignment at rest for the INS/GNSS filter (the FMU's alignment phase,
 * docs/alignment.md): coarse alignment from gravity and the Earth rate, levelling
 * without a heading, and the turn of a navigation state about the vertical. */
#include "est/gf_ins_gnss.h"

#include <math.h>

#include "base/gf_math.h"

/* q_bn of C_b^n whose rows are the east, north and up unit vectors in body axes */
static void q_from_enu_axes(const double *e, const double *n, const double *u, double *q_bn)
{
    gf_mat3 C;
    for (int j = 0; j < 3; ++j) {
        C.m[0][j] = e[j];
        C.m[1][j] = n[j];
        C.m[2][j] = u[j];
    }
    gf_q_from_dcm(&C, q_bn);
    gf_q_normalize(q_bn, q_bn);
}

gf_status gf_ins_coarse_align(const double *f_b_m_s2, const double *w_b_rad_s, double *q_bn)
{
    if (!f_b_m_s2 || !w_b_rad_s || !q_bn)
        return GF_ERR_NULL_POINTER;
    if (!gf_all_finite(f_b_m_s2, 3) || !gf_all_finite(w_b_rad_s, 3))
        return GF_ERR_NONFINITE_INPUT;
    const double fn = gf_v3_norm(f_b_m_s2), wn = gf_v3_norm(w_b_rad_s);
    if (!(fn > 5.0 && fn < 15.0))
        return GF_ERR_SINGULAR_GEOMETRY;
    double e[3], u[3], nn[3];
    gf_v3_cross(w_b_rad_s, f_b_m_s2, e);
    const double en = gf_v3_norm(e);
    if (!(en > 1e-3 * wn * fn) || !(wn > 0.0))
        return GF_ERR_SINGULAR_GEOMETRY;
    gf_v3_scale(e, 1.0 / en, e);
    gf_v3_scale(f_b_m_s2, 1.0 / fn, u);
    gf_v3_cross(u, e, nn);
    q_from_enu_axes(e, nn, u, q_bn);
    return GF_OK;
}

gf_status gf_ins_level_align(const double *f_b_m_s2, double *q_bn)
{
    if (!f_b_m_s2 || !q_bn)
        return GF_ERR_NULL_POINTER;
    if (!gf_all_finite(f_b_m_s2, 3))
        return GF_ERR_NONFINITE_INPUT;
    const double fn = gf_v3_norm(f_b_m_s2);
    if (!(fn > 5.0 && fn < 15.0))
        return GF_ERR_SINGULAR_GEOMETRY;
    double u[3], nn[3], e[3];
    gf_v3_scale(f_b_m_s2, 1.0 / fn, u);
    /* north: the forward axis y = (0, 1, 0) minus its vertical part */
    nn[0] = -u[1] * u[0];
    nn[1] = 1.0 - u[1] * u[1];
    nn[2] = -u[1] * u[2];
    const double nnn = gf_v3_norm(nn);
    if (!(nnn > 1e-3))   /* |horizontal part of y| = sqrt(1 - u_y^2): pitch within 0.06 deg of 90 */
        return GF_ERR_SINGULAR_GEOMETRY;
    gf_v3_scale(nn, 1.0 / nnn, nn);
    gf_v3_cross(nn, u, e);
    q_from_enu_axes(e, nn, u, q_bn);
    return GF_OK;
}

gf_status gf_ins_rotate_heading(double *q_bn, double *v_n_m_s, double dpsi_rad)
{
    if (!q_bn)
        return GF_ERR_NULL_POINTER;
    if (!gf_all_finite(q_bn, 4) || !isfinite(dpsi_rad) || (v_n_m_s && !gf_all_finite(v_n_m_s, 3)))
        return GF_ERR_NONFINITE_INPUT;
    /* the heading is clockwise from north: a rotation by -dpsi about up */
    const double r[4] = {cos(0.5 * dpsi_rad), 0.0, 0.0, -sin(0.5 * dpsi_rad)};
    gf_q_mul(r, q_bn, q_bn);
    gf_q_normalize(q_bn, q_bn);
    if (v_n_m_s) {
        const double c = cos(dpsi_rad), s = sin(dpsi_rad), ve = v_n_m_s[0], vn = v_n_m_s[1];
        v_n_m_s[0] = c * ve + s * vn;
        v_n_m_s[1] = -s * ve + c * vn;
    }
    return GF_OK;
}
