/* gf_array.c — accelerometer-array geometry and forward model (seed 000 eq. 1-2). See
 * gf_array.h for the model and conventions. */
#include "gyrofree/gf_array.h"

#include <math.h>
#include <string.h>

#include "base/gf_math.h"

/* Largest tolerated deviation of |theta_i| from 1. Directions are usually typed in
 * as decimals or built from 1/sqrt(2); 1e-9 accepts those and rejects a forgotten
 * normalisation. */
#define GF_THETA_NORM_TOL 1e-9

gf_status gf_array_geometry_set(gf_array_geometry *geometry, size_t n_sensors,
                                const double *u_m, const double *theta,
                                size_t *bad_sensor)
{
    if (!geometry || !u_m || !theta)
        return GF_ERR_NULL_POINTER;
    if (n_sensors == 0 || n_sensors > GF_ARRAY_MAX_SENSORS)
        return GF_ERR_BAD_SIZE;
    for (size_t i = 0; i < n_sensors; ++i) {
        const double *u = u_m + 3 * i, *t = theta + 3 * i;
        gf_status status = GF_OK;
        if (!gf_v3_isfinite(u) || !gf_v3_isfinite(t)) {
            status = GF_ERR_NONFINITE_INPUT;
        } else {
            const double norm = gf_v3_norm(t);
            if (norm == 0.0)
                status = GF_ERR_SINGULAR_GEOMETRY;
            else if (fabs(norm - 1.0) > GF_THETA_NORM_TOL)
                status = GF_ERR_BAD_PARAMETER;
        }
        if (status != GF_OK) {
            if (bad_sensor)
                *bad_sensor = i;
            return status;
        }
    }
    memset(geometry, 0, sizeof *geometry);
    geometry->n_sensors = n_sensors;
    for (size_t i = 0; i < n_sensors; ++i) {
        gf_v3_copy(u_m + 3 * i, geometry->u_m[i]);
        gf_v3_copy(theta + 3 * i, geometry->theta[i]);
    }
    return GF_OK;
}

gf_status gf_array_forward(const gf_array_geometry *geometry, size_t n_samples,
                           const double *f_m_s2, const double *omega_rad_s,
                           const double *omega_dot_rad_s2, double *A_m_s2,
                           size_t *n_done)
{
    if (n_done)
        *n_done = 0;
    if (!geometry || !f_m_s2 || !omega_rad_s || !omega_dot_rad_s2 || !A_m_s2)
        return GF_ERR_NULL_POINTER;
    const size_t n_sensors = geometry->n_sensors;
    if (n_sensors == 0 || n_sensors > GF_ARRAY_MAX_SENSORS)
        return GF_ERR_BAD_SIZE;
    for (size_t k = 0; k < n_samples; ++k) {
        const double *f = f_m_s2 + 3 * k, *w = omega_rad_s + 3 * k,
                     *wd = omega_dot_rad_s2 + 3 * k;
        if (!gf_all_finite(f, 3) || !gf_all_finite(w, 3) || !gf_all_finite(wd, 3)) {
            if (n_done)
                *n_done = k;
            return GF_ERR_NONFINITE_INPUT;
        }
        double *A = A_m_s2 + n_sensors * k;
        for (size_t i = 0; i < n_sensors; ++i) {
            const double *u = geometry->u_m[i];
            double a[3], t1[3], t2[3];
            /* a = f + omega_dot x u + omega x (omega x u)   (seed 000, eq. 1-2) */
            gf_v3_cross(wd, u, t1);
            gf_v3_add(f, t1, a);
            gf_v3_cross(w, u, t1);
            gf_v3_cross(w, t1, t2);
            gf_v3_add(a, t2, a);
            A[i] = gf_v3_dot(geometry->theta[i], a);
        }
        if (!gf_all_finite(A, n_sensors)) { /* finite inputs too large for a double */
            if (n_done)
                *n_done = k;
            return GF_ERR_OUT_OF_RANGE;
        }
    }
    if (n_done)
        *n_done = n_samples;
    return GF_OK;
}
