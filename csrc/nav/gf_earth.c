/* gf_earth.c — WGS-84 Earth model; see gf_earth.h. */
#include "nav/gf_earth.h"

#include <math.h>
#include <stddef.h>

#include "base/gf_math.h"

#define GF_WGS84_F (1.0 / GF_WGS84_INV_F)
#define GF_WGS84_E2 (GF_WGS84_F * (2.0 - GF_WGS84_F))
#define GF_WGS84_B_M (GF_WGS84_A_M * (1.0 - GF_WGS84_F))
/* m = w^2 a^2 b / GM (NIMA TR8350.2, table 3.1 derived constant) */
#define GF_WGS84_M                                                                            \
    (GF_WGS84_OMEGA_IE_RAD_S * GF_WGS84_OMEGA_IE_RAD_S * GF_WGS84_A_M * GF_WGS84_A_M *       \
     GF_WGS84_B_M / GF_WGS84_GM_M3_S2)

/* Normal gravity from sin^2(lat), 1/sqrt(1 - e^2 sin^2(lat)) and height: Somigliana
 * (NIMA TR8350.2 eq. 4-1) times the second-order height expansion (eq. 4-3). One
 * expression for every caller, so all agree to the bit. */
static double gravity_of(double s2, double inv_sq, double h_m)
{
    const double a = GF_WGS84_A_M, f = GF_WGS84_F, m = GF_WGS84_M;
    const double g0 = GF_WGS84_GAMMA_E_M_S2 * (1.0 + GF_WGS84_K_SOMIGLIANA * s2) * inv_sq;
    return g0 * (1.0 - 2.0 / a * (1.0 + f + m - 2.0 * f * s2) * h_m + 3.0 / (a * a) * h_m * h_m);
}

gf_status gf_earth_gravity(double lat_rad, double h_m, double *gravity_m_s2)
{
    if (!gravity_m_s2)
        return GF_ERR_NULL_POINTER;
    if (!isfinite(lat_rad) || !isfinite(h_m))
        return GF_ERR_NONFINITE_INPUT;
    /* the heights the model takes (fuzzing: h = 1.8e308 m gave gravity +Inf with GF_OK) */
    if (!(fabs(lat_rad) <= 0.5 * GF_PI) || !gf_earth_height_ok(h_m))
        return GF_ERR_BAD_PARAMETER;
    const double s = sin(lat_rad), s2 = s * s;
    *gravity_m_s2 = gravity_of(s2, 1.0 / sqrt(1.0 - GF_WGS84_E2 * s2), h_m);
    return GF_OK;
}

void gf_earth_from_sincos(gf_earth *earth, double sin_lat, double cos_lat, double h_m,
                          const double *v_n_m_s, double earth_rate_sign)
{
    const double s = sin_lat, c = cos_lat, s2 = s * s;
    const double q = 1.0 - GF_WGS84_E2 * s2;
    const double inv_sq = 1.0 / sqrt(q);
    earth->sin_lat = s;
    earth->cos_lat = c;
    earth->tan_lat = s / c;
    earth->R_N_m = GF_WGS84_A_M * inv_sq;
    earth->R_M_m = GF_WGS84_A_M * (1.0 - GF_WGS84_E2) * inv_sq * inv_sq * inv_sq;
    earth->gravity_m_s2 = gravity_of(s2, inv_sq, h_m);
    const double w = earth_rate_sign * GF_WGS84_OMEGA_IE_RAD_S;
    earth->w_ie_n_rad_s[0] = 0.0;
    earth->w_ie_n_rad_s[1] = w * c;
    earth->w_ie_n_rad_s[2] = w * s;
    if (v_n_m_s) {
        const double inv_RMh = 1.0 / (earth->R_M_m + h_m), inv_RNh = 1.0 / (earth->R_N_m + h_m);
        earth->w_en_n_rad_s[0] = -v_n_m_s[1] * inv_RMh;
        earth->w_en_n_rad_s[1] = v_n_m_s[0] * inv_RNh;
        earth->w_en_n_rad_s[2] = v_n_m_s[0] * earth->tan_lat * inv_RNh;
    } else {
        earth->w_en_n_rad_s[0] = earth->w_en_n_rad_s[1] = earth->w_en_n_rad_s[2] = 0.0;
    }
}

gf_status gf_earth_update(gf_earth *earth, double lat_rad, double h_m, const double *v_n_m_s,
                          double earth_rate_sign)
{
    if (!earth)
        return GF_ERR_NULL_POINTER;
    if (!isfinite(lat_rad) || !isfinite(h_m) || !isfinite(earth_rate_sign) ||
        (v_n_m_s && !(isfinite(v_n_m_s[0]) && isfinite(v_n_m_s[1]) && isfinite(v_n_m_s[2]))))
        return GF_ERR_NONFINITE_INPUT;
    if (!(fabs(lat_rad) < GF_HALF_PI))
        return GF_ERR_BAD_PARAMETER;
    if (!gf_earth_height_ok(h_m))
        return GF_ERR_BAD_PARAMETER;
    gf_earth_from_sincos(earth, sin(lat_rad), cos(lat_rad), h_m, v_n_m_s, earth_rate_sign);
    /* a finite but absurd velocity or rate sign (near the pole, v tan L) can overflow */
    if (!(isfinite(earth->w_en_n_rad_s[0]) && isfinite(earth->w_en_n_rad_s[1]) &&
          isfinite(earth->w_en_n_rad_s[2]) && isfinite(earth->w_ie_n_rad_s[1]) &&
          isfinite(earth->w_ie_n_rad_s[2])))
        return GF_ERR_OUT_OF_RANGE;
    return GF_OK;
}

gf_status gf_earth_batch(size_t n, const double *lat_rad, const double *h_m, double *R_M_m,
                         double *R_N_m, double *gravity_m_s2, size_t *n_done)
{
    if (n_done)
        *n_done = 0;
    if (!lat_rad || !h_m || !R_M_m || !R_N_m || !gravity_m_s2)
        return GF_ERR_NULL_POINTER;
    for (size_t k = 0; k < n; ++k) {
        gf_earth e;
        const gf_status st = gf_earth_update(&e, lat_rad[k], h_m[k], NULL, 1.0);
        if (st != GF_OK) {
            if (n_done)
                *n_done = k;
            return st;
        }
        R_M_m[k] = e.R_M_m;
        R_N_m[k] = e.R_N_m;
        gravity_m_s2[k] = e.gravity_m_s2;
    }
    if (n_done)
        *n_done = n;
    return GF_OK;
}

void gf_earth_radii_dlat(const gf_earth *earth, double *dR_M_m, double *dR_N_m)
{
    const double s = earth->sin_lat, c = earth->cos_lat;
    const double k = GF_WGS84_E2 * s * c / (1.0 - GF_WGS84_E2 * s * s);
    *dR_N_m = earth->R_N_m * k;
    *dR_M_m = 3.0 * earth->R_M_m * k;
}
