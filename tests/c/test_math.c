/* test_math.c — the vector/matrix/quaternion library against closed-form rotations. */
#include "base/gf_math.h"
#include "gf_test.h"

#define PI 3.14159265358979323846

int main(void)
{
    /* i x j = k, and the cross product is anti-symmetric */
    const double ex[3] = {1, 0, 0}, ey[3] = {0, 1, 0};
    double c[3];
    gf_v3_cross(ex, ey, c);
    CHECK(c[0] == 0 && c[1] == 0 && c[2] == 1, "e_x x e_y = e_z, got [%g %g %g]", c[0], c[1], c[2]);

    /* skew(a) b = a x b for random vectors (exact: same products, same sums) */
    test_rng rng = {0x9E3779B97F4A7C15ULL};
    for (int n = 0; n < 100; ++n) {
        double a[3], b[3], sb[3], axb[3];
        gf_mat3 s;
        for (int k = 0; k < 3; ++k) {
            a[k] = test_rng_uniform(&rng, -2, 2);
            b[k] = test_rng_uniform(&rng, -2, 2);
        }
        gf_m3_skew(a, &s);
        gf_m3_mul_v3(&s, b, sb);
        gf_v3_cross(a, b, axb);
        for (int k = 0; k < 3; ++k)
            CHECK_CLOSE(sb[k], axb[k], 1e-15, "skew(a) b = a x b");
    }

    /* A rotation of +90 deg about z (q = [cos45, 0, 0, sin45]) takes e_x to e_y. Closed
     * form; tolerance: a few ulp of the cos/sin values. */
    double qz[4] = {cos(PI / 4), 0, 0, sin(PI / 4)}, r[3];
    gf_q_rotate(qz, ex, r);
    CHECK_CLOSE(r[0], 0.0, 1e-15, "Rz(90) e_x . x");
    CHECK_CLOSE(r[1], 1.0, 1e-15, "Rz(90) e_x . y");
    CHECK_CLOSE(r[2], 0.0, 1e-15, "Rz(90) e_x . z");

    /* The DCM of q rotates like q; DCM is orthonormal; q (x) q* = identity. */
    for (int n = 0; n < 100; ++n) {
        double q[4], v[3], mv[3], qv[3], qc[4], qq[4];
        gf_mat3 m, mt, mtm;
        for (int k = 0; k < 4; ++k)
            q[k] = test_rng_uniform(&rng, -1, 1);
        CHECK(gf_q_normalize(q, q), "normalisable quaternion");
        for (int k = 0; k < 3; ++k)
            v[k] = test_rng_uniform(&rng, -3, 3);
        gf_q_to_dcm(q, &m);
        gf_m3_mul_v3(&m, v, mv);
        gf_q_rotate(q, v, qv);
        for (int k = 0; k < 3; ++k)
            CHECK_CLOSE(mv[k], qv[k], 1e-14, "C(q) v = q v q*");
        gf_m3_transpose(&m, &mt);
        gf_m3_mul(&mt, &m, &mtm);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                /* each entry of C carries ~4 eps from |q| = 1 +- eps and 4 products; a
                 * sum of 3 products of them stays below ~24 eps = 5.3e-15 */
                CHECK_CLOSE(mtm.m[i][j], i == j ? 1.0 : 0.0, 24 * 2.3e-16, "C^T C = I");
        gf_q_conj(q, qc);
        gf_q_mul(q, qc, qq);
        CHECK_CLOSE(qq[0], 1.0, 1e-15, "q q* = 1");
    }

    /* Rotation vector: phi about a fixed axis equals the closed-form half-angle
     * quaternion; composing two rotations about the same axis adds the angles. */
    const double axis[3] = {0.6, 0.0, 0.8};
    const double angles[] = {1e-9, 1e-5, 1e-3, 0.3, 2.0};
    for (size_t n = 0; n < sizeof angles / sizeof angles[0]; ++n) {
        const double a = angles[n];
        double phi[3], q[4];
        gf_v3_scale(axis, a, phi);
        gf_q_from_rotvec(phi, q);
        CHECK_CLOSE(q[0], cos(a / 2), 1e-16, "rotvec q0");
        CHECK_CLOSE(q[1], 0.6 * sin(a / 2), 1e-16, "rotvec q1");
        CHECK_CLOSE(q[3], 0.8 * sin(a / 2), 1e-16, "rotvec q3");
        double q2[4];
        gf_q_mul(q, q, q2);
        CHECK_CLOSE(q2[0], cos(a), 1e-15, "two half-turns compose");
    }

    /* Normalisation refuses a zero or non-finite quaternion. */
    double zero[4] = {0, 0, 0, 0}, out[4] = {5, 5, 5, 5};
    CHECK(!gf_q_normalize(zero, out) && out[0] == 5, "zero quaternion rejected, output untouched");
    double bad[4] = {NAN, 0, 0, 1};
    CHECK(!gf_q_normalize(bad, out), "NaN quaternion rejected");

    /* quaternion -> rotation vector: q and -q are one attitude and give the same, short
     * rotation vector (angle 0.3 rad about a unit axis; closed form, tolerance a few ulp
     * of the atan2 and the products) */
    {
        const double ang = 0.3, ax[3] = {2.0 / 3.0, -1.0 / 3.0, 2.0 / 3.0};
        const double ch = cos(0.5 * ang), sh = sin(0.5 * ang);
        const double qp[4] = {ch, sh * ax[0], sh * ax[1], sh * ax[2]};
        const double qm[4] = {-ch, -sh * ax[0], -sh * ax[1], -sh * ax[2]};
        double rp[3], rm[3];
        gf_q_to_rotvec(qp, rp);
        gf_q_to_rotvec(qm, rm);
        for (int k = 0; k < 3; ++k) {
            CHECK_CLOSE(rp[k], ang * ax[k], 1e-15, "rotvec of q");
            CHECK_CLOSE(rm[k], ang * ax[k], 1e-15, "rotvec of -q (the same attitude)");
        }
    }
    TEST_MAIN_END();
}
