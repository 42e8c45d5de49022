/* gf_earth: the WGS-84 model against the closed forms of gf_ref.h, written from the
 * published constants (NIMA TR8350.2: a = 6378137 m, 1/f = 298.257223563, normal gravity
 * 9.7803253359 m/s^2 at the equator and 9.8321849378 m/s^2 at the poles), not from the
 * module's macros; its range checks; the latitude derivatives of the radii against
 * central differences of the closed-form radii. */
#include <math.h>

#include "nav/gf_earth.h"
#include "gf_ref.h"
#include "gf_test.h"

#define PI REF_PI
#define A REF_A

static double r_n(double lat)
{
    double rm, rn;
    ref_radii(lat, &rm, &rn);
    return rn;
}

static double r_m(double lat)
{
    double rm, rn;
    ref_radii(lat, &rm, &rn);
    return rm;
}

int main(void)
{
    /* radii: closed forms; tolerance 1e-6 m = 1.6e-13 relative, a few ulp of the
     * operations on 6.4e6 m */
    for (int k = -8; k <= 8; ++k) {
        const double lat = k * (PI / 18.0) * 0.99;
        gf_earth e;
        CHECK(gf_earth_update(&e, lat, 0.0, NULL, 1.0) == GF_OK, "update at lat %g", lat);
        CHECK_CLOSE(e.R_M_m, r_m(lat), 1e-6, "R_M");
        CHECK_CLOSE(e.R_N_m, r_n(lat), 1e-6, "R_N");
        /* d R / d lat against central differences of the closed forms, step 1e-4 rad:
         * truncation R''' d^2 / 6, measured at most 4.3e-4 m/rad over these latitudes
         * (numpy, the analytic derivatives against the same differences), round-off
         * 2 ulp(6.4e6 m) / 2e-4 rad = 1e-5 m/rad; tolerance 1e-3 m/rad, a 2.3x margin
         * (the derivatives reach 6.4e4 m/rad: a wrong factor is off by ~1e4 m/rad) */
        const double d = 1e-4;
        double dRM, dRN;
        gf_earth_radii_dlat(&e, &dRM, &dRN);
        CHECK_CLOSE(dRM, (r_m(lat + d) - r_m(lat - d)) / (2 * d), 1e-3, "dR_M/dlat");
        CHECK_CLOSE(dRN, (r_n(lat + d) - r_n(lat - d)) / (2 * d), 1e-3, "dR_N/dlat");
    }
    /* the published normal gravity at the equator and at the poles, on the ellipsoid;
     * tolerance 1e-9 m/s^2: the published values have 10 decimals */
    double g;
    CHECK(gf_earth_gravity(0.0, 0.0, &g) == GF_OK, "gravity at the equator");
    CHECK_CLOSE(g, REF_GAMMA_E, 1e-9, "normal gravity at the equator");
    CHECK(gf_earth_gravity(0.5 * PI, 0.0, &g) == GF_OK, "gravity at the pole");
    CHECK_CLOSE(g, REF_GAMMA_P, 1e-9, "normal gravity at the pole");

    /* heights: the model's range is (-a/2, a/3); beyond it the series in h is meaningless
     * and both entry points refuse, inside it they answer */
    const double h_bad[] = {A / 3.0 + 1.0, 1e7, -0.5 * A - 1.0};
    for (int k = 0; k < 3; ++k) {
        gf_earth e;
        CHECK(gf_earth_update(&e, 0.3, h_bad[k], NULL, 1.0) == GF_ERR_BAD_PARAMETER,
              "gf_earth_update refuses h = %g m", h_bad[k]);
        CHECK(gf_earth_gravity(0.3, h_bad[k], &g) == GF_ERR_BAD_PARAMETER,
              "gf_earth_gravity refuses h = %g m", h_bad[k]);
    }
    {
        gf_earth e;
        CHECK(gf_earth_update(&e, 0.3, A / 3.0 - 1.0, NULL, 1.0) == GF_OK, "h just below a/3");
        CHECK(gf_earth_update(&e, 0.3, -0.5 * A + 1.0, NULL, 1.0) == GF_OK, "h just above -a/2");
    }
    /* latitude: the poles themselves are refused by the update (tan lat), accepted by
     * the gravity alone */
    {
        gf_earth e;
        CHECK(gf_earth_update(&e, 0.5 * PI, 0.0, NULL, 1.0) == GF_ERR_BAD_PARAMETER, "pole");
        CHECK(gf_earth_gravity(0.5 * PI + 1e-9, 0.0, &g) == GF_ERR_BAD_PARAMETER, "beyond the pole");
    }
    TEST_MAIN_END();
}
