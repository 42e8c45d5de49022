/* gf_layout.c — array layouts of the literature; see gf_layout.h. */
#include "gyrofree/gf_layout.h"

#include <math.h>
#include <string.h>

#include "base/gf_math.h"
#include "gyrofree/gf9.h"

gf_status gf_layout_cube6(double l, gf_array_geometry *g)
{
    if (!g)
        return GF_ERR_NULL_POINTER;
    if (!(l > 0.0) || !isfinite(l))
        return GF_ERR_BAD_PARAMETER;
    const double r = GF_SQRT1_2;
    /* mission digest, table "6-accelerometer cube (Tan & Park 2005)" */
    const double u[18] = {l, 0, 0, 0, l, 0, 0, 0, l, -l, 0, 0, 0, -l, 0, 0, 0, -l};
    const double t[18] = {0, r, r, r, 0, r, r, r, 0, 0, r, -r, -r, 0, r, r, -r, 0};
    return gf_array_geometry_set(g, 6, u, t, NULL);
}

gf_status gf_layout_12(double l, gf_array_geometry *g)
{
    if (!g)
        return GF_ERR_NULL_POINTER;
    gf_array_geometry g9;
    const gf_status st = gf9_geometry(l, &g9);
    if (st != GF_OK)
        return st;
    double u[36], t[36];
    for (int i = 0; i < 9; ++i) {
        gf_v3_copy(g9.u_m[i], u + 3 * i);
        gf_v3_copy(g9.theta[i], t + 3 * i);
    }
    const double extra_u[9] = {l, 0, 0, 0, l, 0, 0, 0, l};
    const double extra_t[9] = {0, 1, 0, 0, 0, 1, 1, 0, 0};
    memcpy(u + 27, extra_u, sizeof extra_u);
    memcpy(t + 27, extra_t, sizeof extra_t);
    return gf_array_geometry_set(g, 12, u, t, NULL);
}

