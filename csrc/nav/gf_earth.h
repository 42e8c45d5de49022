/* gf_earth.h — the one Earth model of gfins_fmi: WGS-84 ellipsoid, normal gravity,
 * Earth rate and transport rate in the East-North-Up navigation frame.
 *
 * Radii of curvature are the exact WGS-84 expressions (seed 002 prints first-order
 * approximations with the names swapped; see docs/architecture.md):
 *   R_M = a (1 - e^2) / (1 - e^2 sin^2 L)^(3/2)    meridian
 *   R_N = a / (1 - e^2 sin^2 L)^(1/2)              prime vertical
 * Normal gravity: Somigliana's closed formula on the ellipsoid and the WGS-84
 * second-order expansion in height (NIMA TR8350.2, eq. 4-1 and 4-3), directed along
 * -Up (the small northward component above the ellipsoid is neglected).
 * Pure functions: no state.
 */
#ifndef GF_EARTH_H
#define GF_EARTH_H

#include <stddef.h>

#include "base/gf_status.h"

#ifdef __cplusplus
extern "C" {
#endif

#define GF_WGS84_A_M 6378137.0                 /* semi-major axis, m */
#define GF_WGS84_INV_F 298.257223563           /* inverse flattening */
#define GF_WGS84_OMEGA_IE_RAD_S 7.292115e-5    /* Earth rotation rate, rad/s */
#define GF_WGS84_GM_M3_S2 3.986004418e14       /* gravitational constant, m^3/s^2 */
#define GF_WGS84_GAMMA_E_M_S2 9.7803253359     /* normal gravity at the equator */
#define GF_WGS84_K_SOMIGLIANA 0.00193185265241 /* Somigliana's constant */

/* CDEF BEGIN */
/* Quantities of the Earth model at one position and velocity. */
typedef struct gf_earth {
    double sin_lat, cos_lat, tan_lat;
    double R_M_m;             /* meridian radius of curvature */
    double R_N_m;             /* prime-vertical radius of curvature */
    double gravity_m_s2;      /* normal gravity magnitude at (L, h) */
    double w_ie_n_rad_s[3];   /* Earth rate in ENU: [0, w cos L, w sin L] */
    double w_en_n_rad_s[3];   /* transport rate: [-vN/(R_M+h), vE/(R_N+h), vE tanL/(R_N+h)] */
} gf_earth;

/* Fills *earth at latitude lat_rad, height h_m, ENU velocity v_n_m_s (may be NULL:
 * zero transport rate). earth_rate_sign multiplies the Earth rate (+1 forward in
 * time, -1 for reverse navigation).
 * Errors: GF_ERR_NONFINITE_INPUT; GF_ERR_BAD_PARAMETER when |lat| >= 90 deg (the
 * ENU frame is singular at the poles) or h is below -a/2 or at or above a/3 (absurd:
 * above a/3 the second-order height expansion of the gravity, NIMA TR8350.2 eq. 4-3,
 * grows with height); GF_ERR_OUT_OF_RANGE when a finite velocity makes the transport
 * rate overflow. */
gf_status gf_earth_update(gf_earth *earth, double lat_rad, double h_m, const double *v_n_m_s,
                          double earth_rate_sign);

/* Normal gravity magnitude (m/s^2) at latitude lat_rad and height h_m. Errors as
 * gf_earth_update. */
gf_status gf_earth_gravity(double lat_rad, double h_m, double *gravity_m_s2);

/* For n positions: radii of curvature (m), normal gravity (m/s^2); for Python and
 * checks. Errors as gf_earth_update; *n_done = positions done. */
gf_status gf_earth_batch(size_t n, const double *lat_rad, const double *h_m, double *R_M_m,
                         double *R_N_m, double *gravity_m_s2, size_t *n_done);
/* CDEF END */

/* Internal to the core (not in the Python binding): gf_earth_update from sin and cos of
 * the latitude, which the mechanization keeps to save the trigonometry. No argument
 * checks: the caller has checked them. */
void gf_earth_from_sincos(gf_earth *earth, double sin_lat, double cos_lat, double h_m,
                          const double *v_n_m_s, double earth_rate_sign);

/* Internal to the core: the heights the model takes (m), as gf_earth_update checks them:
 * above -a/2 (R_N >= a, so R + h > a/2 > 0) and below a/3, where the second-order height
 * expansion of normal gravity (NIMA TR8350.2 eq. 4-3, 1 - 2/a (1 + f + m - 2 f sin^2 L) h
 * + 3 h^2 / a^2, a parabola in h) has its minimum and beyond which it grows with height.
 * The mechanization checks its mid-point and new heights with it (gf_sins.c), so that a
 * step never leaves the range gf_sins_state_check asks of a state. */
static inline int gf_earth_height_ok(double h_m)
{
    return h_m > -0.5 * GF_WGS84_A_M && h_m < GF_WGS84_A_M / 3.0;
}

/* Derivatives of the radii of curvature with respect to latitude (m/rad), from the
 * filled *earth: dR_N/dL = R_N e^2 sinL cosL / q, dR_M/dL = 3 R_M e^2 sinL cosL / q,
 * q = 1 - e^2 sin^2 L (differentiate R_N = a q^-1/2, R_M = a (1 - e^2) q^-3/2). */
void gf_earth_radii_dlat(const gf_earth *earth, double *dR_M_m, double *dR_N_m);

#ifdef __cplusplus
}
#endif

#endif /* GF_EARTH_H */
