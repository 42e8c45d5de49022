/* Independent references for the C tests: WGS-84 and rotations written out from the
 * published definitions, never from the core (csrc/). One copy for every test file;
 * static inline so that a test using only some of them builds warning-free. */
#ifndef GF_REF_H
#define GF_REF_H

#include <math.h>
#include <stddef.h>
#include <string.h>

/* ---- independent reference: WGS-84 (NIMA TR8350.2 tables 3.1, 3.3) ------------------ */

#define REF_A 6378137.0
#define REF_INV_F 298.257223563
#define REF_W_IE 7.292115e-5
#define REF_GM 3.986004418e14
#define REF_GAMMA_E 9.7803253359
#define REF_GAMMA_P 9.8321849378
#define REF_K 0.00193185265241

#define REF_PI 3.14159265358979323846
static inline double ref_f(void) { return 1.0 / REF_INV_F; }
static inline double ref_e2(void) { return ref_f() * (2.0 - ref_f()); }
static inline double ref_b(void) { return REF_A * (1.0 - ref_f()); }

static inline void ref_radii(double lat, double *RM, double *RN)
{
    const double s = sin(lat);
    const double w2 = 1.0 - ref_e2() * s * s;
    *RN = REF_A / sqrt(w2);
    *RM = REF_A * (1.0 - ref_e2()) / (w2 * sqrt(w2));
}

/* Somigliana in the k form (TR8350.2 eq. 4-1) with the height expansion (eq. 4-3):
 * gamma_h = gamma [1 - 2/a (1 + f + m - 2 f sin^2 L) h + 3 h^2 / a^2], m = w^2 a^2 b / GM */
static inline double ref_gravity(double lat, double h)
{
    const double s2 = sin(lat) * sin(lat);
    const double g0 = REF_GAMMA_E * (1.0 + REF_K * s2) / sqrt(1.0 - ref_e2() * s2);
    const double m = REF_W_IE * REF_W_IE * REF_A * REF_A * ref_b() / REF_GM;
    return g0 * (1.0 - 2.0 * h / REF_A * (1.0 + ref_f() + m - 2.0 * ref_f() * s2) +
                 3.0 * h * h / (REF_A * REF_A));
}

/* Somigliana's original closed form on the ellipsoid (no k constant):
 * gamma = (a gamma_e cos^2 L + b gamma_p sin^2 L) / sqrt(a^2 cos^2 L + b^2 sin^2 L) */
static inline double ref_gravity_ab(double lat)
{
    const double c = cos(lat), s = sin(lat), a = REF_A, b = ref_b();
    return (a * REF_GAMMA_E * c * c + b * REF_GAMMA_P * s * s) / sqrt(a * a * c * c + b * b * s * s);
}

/* ---- independent reference: rotations --------------------------------------------- */

/* (matrix arguments are not const: ISO C11 cannot pass double[3][3] to const double[3][3]) */
static inline void mat_mul(double A[3][3], double B[3][3], double C[3][3])
{
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            C[i][j] = A[i][0] * B[0][j] + A[i][1] * B[1][j] + A[i][2] * B[2][j];
}

static inline void mat_vec(double A[3][3], const double v[3], double out[3])
{
    for (int i = 0; i < 3; ++i)
        out[i] = A[i][0] * v[0] + A[i][1] * v[1] + A[i][2] * v[2];
}

static inline void mat_t_vec(double A[3][3], const double v[3], double out[3])
{
    for (int i = 0; i < 3; ++i)
        out[i] = A[0][i] * v[0] + A[1][i] * v[1] + A[2][i] * v[2];
}

/* C_b^n = Rz(-psi) Rx(theta) Ry(gamma) (gf_sins.h), active rotation matrices */
static inline void ref_dcm_euler(const double e[3], double C[3][3])
{
    const double cp = cos(e[0]), sp = sin(e[0]), ct = cos(e[1]), st = sin(e[1]);
    const double cg = cos(e[2]), sg = sin(e[2]);
    double Rz[3][3] = {{cp, sp, 0}, {-sp, cp, 0}, {0, 0, 1}}; /* Rz(-psi) */
    double Rx[3][3] = {{1, 0, 0}, {0, ct, -st}, {0, st, ct}};
    double Ry[3][3] = {{cg, 0, sg}, {0, 1, 0}, {-sg, 0, cg}};
    double t[3][3];
    mat_mul(Rz, Rx, t);
    mat_mul(t, Ry, C);
}

/* q = qz(-psi) (x) qx(theta) (x) qy(gamma), expanded by hand */
static inline void ref_quat_euler(const double e[3], double q[4])
{
    const double cz = cos(0.5 * e[0]), sz = sin(0.5 * e[0]);
    const double cx = cos(0.5 * e[1]), sx = sin(0.5 * e[1]);
    const double cy = cos(0.5 * e[2]), sy = sin(0.5 * e[2]);
    q[0] = cz * cx * cy + sz * sx * sy;
    q[1] = cz * sx * cy + sz * cx * sy;
    q[2] = cz * cx * sy - sz * sx * cy;
    q[3] = cz * sx * sy - sz * cx * cy;
}

static inline void ref_quat_to_dcm(const double q[4], double C[3][3])
{
    const double a = q[0], b = q[1], c = q[2], d = q[3];
    C[0][0] = a * a + b * b - c * c - d * d;
    C[0][1] = 2 * (b * c - a * d);
    C[0][2] = 2 * (b * d + a * c);
    C[1][0] = 2 * (b * c + a * d);
    C[1][1] = a * a - b * b + c * c - d * d;
    C[1][2] = 2 * (c * d - a * b);
    C[2][0] = 2 * (b * d - a * c);
    C[2][1] = 2 * (c * d + a * b);
    C[2][2] = a * a - b * b - c * c + d * d;
}

/* rotation angle of p (x) q^* (Hamilton), robust for small angles */
static inline double quat_angle(const double p[4], const double q[4])
{
    const double w = p[0] * q[0] + p[1] * q[1] + p[2] * q[2] + p[3] * q[3];
    const double x = -p[0] * q[1] + p[1] * q[0] - p[2] * q[3] + p[3] * q[2];
    const double y = -p[0] * q[2] + p[1] * q[3] + p[2] * q[0] - p[3] * q[1];
    const double z = -p[0] * q[3] - p[1] * q[2] + p[2] * q[1] + p[3] * q[0];
    return 2.0 * atan2(sqrt(x * x + y * y + z * z), fabs(w));
}

/* ---- independent reference: the Kalman update (textbook Joseph form) ---------------- */

#define REF_KF_MAX 40   /* states and measurements: at least GF_KF_MAX_N (checked by the tests that include gf_kalman.h) */

/* x += K r, P <- (I - K H) P (I - K H)^T + K R K^T with K = P H^T S^-1 from an explicit
 * inverse of S = H P H^T + R (Gauss-Jordan with pivoting) */
static inline void ref_kalman_update(size_t n, size_t m, double *x, double *P, const double *r,
                                     const double *H, const double *R)
{
    double PHt[REF_KF_MAX * REF_KF_MAX], S[REF_KF_MAX * 2 * REF_KF_MAX];
    double K[REF_KF_MAX * REF_KF_MAX], A[REF_KF_MAX * REF_KF_MAX];
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < m; ++j) {
            double acc = 0.0;
            for (size_t k = 0; k < n; ++k)
                acc += P[i * n + k] * H[j * n + k];
            PHt[i * m + j] = acc;
        }
    const size_t w2 = 2 * m; /* [S | I] -> [I | S^-1] */
    for (size_t i = 0; i < m; ++i)
        for (size_t j = 0; j < m; ++j) {
            double acc = R[i * m + j];
            for (size_t k = 0; k < n; ++k)
                acc += H[i * n + k] * PHt[k * m + j];
            S[i * w2 + j] = acc;
            S[i * w2 + m + j] = i == j ? 1.0 : 0.0;
        }
    for (size_t c = 0; c < m; ++c) {
        size_t piv = c;
        for (size_t i = c + 1; i < m; ++i)
            if (fabs(S[i * w2 + c]) > fabs(S[piv * w2 + c]))
                piv = i;
        for (size_t j = 0; j < w2; ++j) {
            const double t = S[c * w2 + j];
            S[c * w2 + j] = S[piv * w2 + j];
            S[piv * w2 + j] = t;
        }
        const double d = S[c * w2 + c];
        for (size_t j = 0; j < w2; ++j)
            S[c * w2 + j] /= d;
        for (size_t i = 0; i < m; ++i)
            if (i != c) {
                const double f = S[i * w2 + c];
                for (size_t j = 0; j < w2; ++j)
                    S[i * w2 + j] -= f * S[c * w2 + j];
            }
    }
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < m; ++j) {
            double acc = 0.0;
            for (size_t k = 0; k < m; ++k)
                acc += PHt[i * m + k] * S[k * w2 + m + j];
            K[i * m + j] = acc;
        }
    for (size_t i = 0; i < n; ++i) {
        double acc = 0.0;
        for (size_t j = 0; j < m; ++j)
            acc += K[i * m + j] * r[j];
        x[i] += acc;
    }
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < n; ++j) {
            double acc = i == j ? 1.0 : 0.0;
            for (size_t k = 0; k < m; ++k)
                acc -= K[i * m + k] * H[k * n + j];
            A[i * n + j] = acc;
        }
    double AP[REF_KF_MAX * REF_KF_MAX], Pn[REF_KF_MAX * REF_KF_MAX];
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < n; ++j) {
            double acc = 0.0;
            for (size_t k = 0; k < n; ++k)
                acc += A[i * n + k] * P[k * n + j];
            AP[i * n + j] = acc;
        }
    for (size_t i = 0; i < n; ++i)
        for (size_t j = 0; j < n; ++j) {
            double acc = 0.0;
            for (size_t k = 0; k < n; ++k)
                acc += AP[i * n + k] * A[j * n + k];
            for (size_t a = 0; a < m; ++a)
                for (size_t b = 0; b < m; ++b)
                    acc += K[i * m + a] * R[a * m + b] * K[j * m + b];
            Pn[i * n + j] = acc;
        }
    memcpy(P, Pn, n * n * sizeof *P);
}

#endif /* GF_REF_H */
