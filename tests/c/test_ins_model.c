/* test_ins_model.c — the shared navigation blocks of the INS error model (gf_ins_model):
 *   - equal, bit for bit, to the navigation blocks of the integrated-navigation filter's
 *     own error model (gf_ins_error_model: a peer implementation of the same equations,
 *     in another state order), at random moving states; the blocks land at any offsets
 *     and nothing else in F is touched;
 *   - the filter's F holds gf_ins_nav_blocks_sparse's blocks bit for bit, forward and
 *     after gf_ins_reverse (Earth-rate sign -1), at its own navigation state after a few
 *     hundred samples (sin and cos of the latitude from the navigation state);
 *   - the row masks of gf_ins_nav_blocks_sparse name the entries it writes, and every
 *     entry the dense form makes non-zero is among them (the structured covariance
 *     propagation skips the others);
 *   - against a numerical linearisation of the ENU velocity equation at rest written
 *     here (the f^n x phi block and the Coriolis block: independent truth);
 *   - bad arguments refused.
 * (tests/test_ins_model.py compares it with gfins_fmi.error_models.ins_error_matrices,
 * the definition.) */
#include <math.h>
#include <string.h>

#include "est/gf_ins_gnss.h"
#include "est/gf_ins_model.h"
#include "gf_ref.h"
#include "gf_test.h"

static gf_ins_filter filt; /* large: static storage in the test only */

static void test_equals_ins_gnss(void)
{
    test_rng r = {0x1234567u};
    gf_ins_config cfg;
    gf_ins_config_default(&cfg);
    double P0[15 * 15] = {0.0};
    for (int i = 0; i < 15; ++i)
        P0[i * 15 + i] = 1.0;
    for (int trial = 0; trial < 20; ++trial) {
        const double e[3] = {test_rng_uniform(&r, 0, 6.28), test_rng_uniform(&r, -1.2, 1.2),
                             test_rng_uniform(&r, -3, 3)};
        double q[4];
        ref_quat_euler(e, q);
        const double v[3] = {test_rng_uniform(&r, -200, 200), test_rng_uniform(&r, -200, 200),
                             test_rng_uniform(&r, -5, 5)};
        const double lat = test_rng_uniform(&r, -1.3, 1.3), h = test_rng_uniform(&r, -100, 9000);
        const double fb[3] = {test_rng_uniform(&r, -20, 20), test_rng_uniform(&r, -20, 20),
                              test_rng_uniform(&r, -20, 20)};
        const double wb[3] = {0.1, -0.2, 0.3};
        CHECK(gf_ins_init(&filt, &cfg, 0.0, q, v, lat, 0.5, h, NULL, P0, NULL) == GF_OK, "ins init");
        double Fi[15 * 15];
        CHECK(gf_ins_error_model(&filt, fb, wb, Fi, NULL, NULL) == GF_OK, "ins error model");
        /* ours into a 20 x 20 matrix (stride 21) at phi 11, dv 2, dp 5, prefilled */
        enum { LD = 21 };
        double F[20 * LD];
        for (int i = 0; i < 20 * LD; ++i)
            F[i] = 7.0;
        /* the core's form, with the filter's own C_b^n: what gf_ins_gnss would call */
        gf_mat3 C;
        gf_q_to_dcm(filt.nav.q_bn, &C);
        gf_ins_nav_blocks(&C, v, lat, h, fb, LD, 11, 2, 5, F);
        /* the checked entry point normalises q again (last-bit changes of C): 1e-15 */
        double G[20 * LD];
        memcpy(G, F, sizeof G);
        CHECK(gf_ins_nav_error_model(q, v, lat, h, fb, LD, 11, 2, 5, G) == GF_OK, "checked form");
        double worst = 0.0;
        for (int i = 0; i < 20 * LD; ++i)
            worst = fmax(worst, fabs(G[i] - F[i]) / fmax(1.0, fabs(F[i])));
        CHECK(worst < 1e-14, "trial %d: checked form vs core form %.3g", trial, worst);
        /* ins_gnss order: dv 0, dp 3, phi 6 */
        const int ours[3] = {11, 2, 5}, theirs[3] = {6, 0, 3};
        int same = 1, untouched = 1;
        for (int rb = 0; rb < 3; ++rb)
            for (int cb = 0; cb < 3; ++cb)
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j)
                        same &= F[(ours[rb] + i) * LD + ours[cb] + j] ==
                                Fi[(theirs[rb] + i) * 15 + theirs[cb] + j];
        for (int i = 0; i < 20; ++i)
            for (int j = 0; j < LD; ++j) {
                const int in_r = (i >= 2 && i < 8) || (i >= 11 && i < 14);
                const int in_c = (j >= 2 && j < 8) || (j >= 11 && j < 14);
                if (!(in_r && in_c))
                    untouched &= F[i * LD + j] == 7.0;
            }
        CHECK(same, "trial %d: the navigation blocks equal gf_ins_gnss's bit for bit", trial);
        CHECK(untouched, "trial %d: entries outside the blocks untouched", trial);
    }
}

/* the navigation blocks of the filter's F (state order dv 0, dp 3, phi 6) against
 * gf_ins_nav_blocks_sparse at the filter's navigation state, bit for bit */
static int filter_blocks_equal(const gf_ins_filter *fl, const double fb[3], const double wb[3],
                               double earth_rate_sign)
{
    double Fi[15 * 15];
    if (gf_ins_error_model(fl, fb, wb, Fi, NULL, NULL) != GF_OK)
        return 0;
    gf_mat3 C;
    gf_q_to_dcm(fl->nav.q_bn, &C);
    double F[15 * 15] = {0.0};
    uint64_t mask[15] = {0};
    gf_ins_nav_blocks_sparse(&C, fl->nav.v_n_m_s, fl->nav.sin_lat, fl->nav.cos_lat,
                             fl->nav.h_m, earth_rate_sign, fb, 15, GF_INS_IDX_ATT,
                             GF_INS_IDX_VEL, GF_INS_IDX_POS, F, mask);
    int same = 1;
    for (int i = 0; i < 9; ++i)
        for (int j = 0; j < 9; ++j)
            same &= memcmp(&F[i * 15 + j], &Fi[i * 15 + j], sizeof F[0]) == 0;
    return same;
}

static void test_filter_uses_the_blocks(void)
{
    test_rng r = {0x2468aceu};
    gf_ins_config cfg;
    gf_ins_config_default(&cfg);
    cfg.propagation_interval_s = 0.0;
    double P0[15 * 15] = {0.0};
    for (int i = 0; i < 15; ++i)
        P0[i * 15 + i] = 1e-6;
    const double dt = 0.005;
    for (int trial = 0; trial < 6; ++trial) {
        const double e[3] = {test_rng_uniform(&r, 0, 6.28), test_rng_uniform(&r, -0.3, 0.3),
                             test_rng_uniform(&r, -0.3, 0.3)};
        double q[4];
        ref_quat_euler(e, q);
        const double v[3] = {test_rng_uniform(&r, -60, 60), test_rng_uniform(&r, -60, 60),
                             test_rng_uniform(&r, -1, 1)};
        const double lat = test_rng_uniform(&r, -1.3, 1.3), h = test_rng_uniform(&r, -100, 3000);
        CHECK(gf_ins_init(&filt, &cfg, 0.0, q, v, lat, 0.5, h, NULL, P0, NULL) == GF_OK, "init");
        /* 300 samples of a turn with a steady acceleration: the latitude moves (its sine
         * and cosine are the navigation state's), all blocks non-zero */
        const double dth[3] = {1e-3 * dt, -2e-3 * dt, 0.05 * dt};
        const double dv[3] = {0.3 * dt, -0.2 * dt, 9.8 * dt};
        gf_status st = GF_OK;
        for (int k = 0; k < 300 && st == GF_OK; ++k)
            st = gf_ins_step(&filt, dt * (k + 1), dth, dv, 0, NULL, NULL, NULL);
        CHECK(st == GF_OK, "steps: status %d", (int)st);
        const double fb[3] = {test_rng_uniform(&r, -20, 20), test_rng_uniform(&r, -20, 20),
                              test_rng_uniform(&r, -20, 20)};
        const double wb[3] = {0.1, -0.2, 0.3};
        CHECK(filter_blocks_equal(&filt, fb, wb, 1.0), "trial %d: forward, bit for bit", trial);
        CHECK(gf_ins_reverse(&filt) == GF_OK, "reverse");
        CHECK(filter_blocks_equal(&filt, fb, wb, -1.0), "trial %d: reversed, bit for bit", trial);
        /* the sign is wired: with +1 the reversed filter's blocks differ */
        CHECK(!filter_blocks_equal(&filt, fb, wb, 1.0), "trial %d: reversed uses sign -1", trial);
    }
}

static void test_structure(void)
{
    test_rng r = {0x97531u};
    enum { N = 20, LD = 21 };
    const size_t ia = 11, iv = 2, ip = 5;
    for (int trial = 0; trial < 50; ++trial) {
        const double e[3] = {test_rng_uniform(&r, 0, 6.28), test_rng_uniform(&r, -1.2, 1.2),
                             test_rng_uniform(&r, -3, 3)};
        double q[4];
        ref_quat_euler(e, q);
        gf_mat3 C;
        gf_q_to_dcm(q, &C);
        /* at rest as well as moving: the mask is the model's, not the state's */
        const double k = trial % 5 == 0 ? 0.0 : 1.0;
        const double v[3] = {k * test_rng_uniform(&r, -200, 200),
                             k * test_rng_uniform(&r, -200, 200), k * test_rng_uniform(&r, -5, 5)};
        const double lat = test_rng_uniform(&r, -1.3, 1.3), h = test_rng_uniform(&r, -100, 9000);
        const double sgn = trial % 2 ? -1.0 : 1.0;
        const double fb[3] = {test_rng_uniform(&r, -20, 20), test_rng_uniform(&r, -20, 20),
                              test_rng_uniform(&r, -20, 20)};
        double F[N * LD];
        uint64_t mask[N] = {0};
        for (int i = 0; i < N * LD; ++i)
            F[i] = 7.0; /* no entry of the model can equal it at these states */
        gf_ins_nav_blocks_sparse(&C, v, sin(lat), cos(lat), h, sgn, fb, LD, ia, iv, ip, F, mask);
        /* an entry changed is in the mask; moving, every masked entry changed (at rest a
         * few masked entries are exact zeros: v x d(w_en)/dv, added to a 7.0) */
        int changed_is_masked = 1, masked_is_changed = 1;
        for (int i = 0; i < N; ++i)
            for (int j = 0; j < LD; ++j) {
                const int changed = F[i * LD + j] != 7.0;
                const int masked = (int)((mask[i] >> j) & 1u);
                changed_is_masked &= !changed || masked;
                masked_is_changed &= !masked || changed || k == 0.0;
            }
        CHECK(changed_is_masked, "trial %d: entries changed are in the mask", trial);
        CHECK(masked_is_changed, "trial %d: mask bits name entries written", trial);
        /* the dense form (zeros included): a non-zero entry outside the mask would be
         * skipped by the structured propagation */
        double D[N * LD];
        memset(D, 0, sizeof D);
        if (sgn > 0.0) {
            gf_ins_nav_blocks(&C, v, lat, h, fb, LD, ia, iv, ip, D);
            int nonzero_is_masked = 1;
            for (int i = 0; i < N; ++i)
                for (int j = 0; j < LD; ++j)
                    if (D[i * LD + j] != 0.0)
                        nonzero_is_masked &= (int)((mask[i] >> j) & 1u);
            CHECK(nonzero_is_masked, "trial %d: every non-zero entry in the mask", trial);
        }
    }
}

static void test_rest_linearisation(void)
{
    /* at rest, level: dv' = f^n x phi - 2 w_ie x dv (+ gravity on dh). With C(computed) =
     * (I - [phi x]) C, the computed f^n_c = (I - [phi x]) f^n, so d(dv')/dphi = [f^n x],
     * written here from the definition */
    const double lat = 0.7, g = ref_gravity(lat, 0.0), W = REF_W_IE;
    const double q[4] = {1.0, 0.0, 0.0, 0.0}, v[3] = {0.0, 0.0, 0.0}, fb[3] = {0.0, 0.0, g};
    double F[81];
    CHECK(gf_ins_nav_error_model(q, v, lat, 0.0, fb, 9, 0, 3, 6, F) == GF_OK, "at rest");
    /* phi -> dv: [f^n x] with f^n = [0, 0, g]: row E: -g phi_N, row N: +g phi_E */
    CHECK_CLOSE(F[3 * 9 + 1], -g, 1e-12, "dvE/phiN");
    CHECK_CLOSE(F[4 * 9 + 0], g, 1e-12, "dvN/phiE");
    CHECK_CLOSE(F[5 * 9 + 0], 0.0, 0.0, "dvU/phiE");
    /* Coriolis: -2 w_ie x dv, w_ie = W [0, cos L, sin L] */
    CHECK_CLOSE(F[3 * 9 + 4], 2 * W * sin(lat), 1e-18, "dvE/dvN");
    CHECK_CLOSE(F[3 * 9 + 5], -2 * W * cos(lat), 1e-18, "dvE/dvU");
    /* attitude: -w_ie x phi; phi_N' from dL: -W sin L */
    CHECK_CLOSE(F[0 * 9 + 1], W * sin(lat), 1e-18, "phiE/phiN");
    CHECK_CLOSE(F[1 * 9 + 6], -W * sin(lat), 1e-18, "phiN/dL");
    CHECK_CLOSE(F[2 * 9 + 6], W * cos(lat), 1e-18, "phiU/dL");
    double RM, RN;
    ref_radii(lat, &RM, &RN);
    CHECK_CLOSE(F[6 * 9 + 4], 1.0 / RM, 1e-15 / RM, "dL/dvN");
    CHECK_CLOSE(F[7 * 9 + 3], 1.0 / (RN * cos(lat)), 1e-15 / RN, "dlon/dvE");
    CHECK_CLOSE(F[5 * 9 + 8], 2 * g / sqrt(RM * RN), 1e-18, "dvU/dh: 2 g / R");
}

static void test_bad(void)
{
    const double q[4] = {1, 0, 0, 0}, v[3] = {0, 0, 0}, f[3] = {0, 0, 9.8};
    double F[81];
    CHECK(gf_ins_nav_error_model(q, v, 0.1, 0.0, f, 8, 0, 3, 6, F) == GF_ERR_BAD_SIZE, "ld too small");
    CHECK(gf_ins_nav_error_model(q, v, 0.1, 0.0, f, 9, 0, 2, 6, F) == GF_ERR_BAD_SIZE, "overlap");
    CHECK(gf_ins_nav_error_model(q, v, 0.1, 0.0, f, 9, -1, 3, 6, F) == GF_ERR_BAD_SIZE, "negative");
    CHECK(gf_ins_nav_error_model(q, v, 1.6, 0.0, f, 9, 0, 3, 6, F) == GF_ERR_BAD_PARAMETER, "pole");
    const double q0[4] = {0, 0, 0, 0};
    CHECK(gf_ins_nav_error_model(q0, v, 0.1, 0.0, f, 9, 0, 3, 6, F) == GF_ERR_BAD_PARAMETER, "q = 0");
    const double vn[3] = {NAN, 0, 0};
    CHECK(gf_ins_nav_error_model(q, vn, 0.1, 0.0, f, 9, 0, 3, 6, F) == GF_ERR_NONFINITE_INPUT, "NaN");
    CHECK(gf_ins_nav_error_model(q, v, 0.1, 0.0, NULL, 9, 0, 3, 6, F) == GF_ERR_NULL_POINTER, "NULL");
}

int main(void)
{
    test_equals_ins_gnss();
    test_filter_uses_the_blocks();
    test_structure();
    test_rest_linearisation();
    test_bad();
    TEST_MAIN_END();
}
