/* test_ins_meas.c — the measurement models of the INS/GNSS filter through their table
 * (gf_ins_meas_kind_info, gf_ins_meas_model; csrc/est/gf_ins_meas.c).
 *
 * Truth never comes from the code under test's linearisation: every kind the enumeration
 * returns has its Jacobian H checked against central differences of its own nonlinear C
 * prediction, column by column, at random (seeded) states with every optional state
 * enabled (scale factors, barometer bias, odometer scale, boresight, and the transfer
 * alignment's mounting, lever arm, time offset and flexure: 38 states), non-zero lever
 * arms, boresight and mounting angles, time offset and flexure estimates, forward and
 * after gf_ins_reverse. A kind added to the
 * table is enumerated and checked like the others, with no allowance (below) unless one
 * is written for it here. The sign convention (gf_ins_gnss.h): z_pred(dx) is the
 * prediction from the nominal corrected by dx, z_err = predicted - measured = H dx, so
 * H = -(z_pred(+h e_j) - z_pred(-h e_j)) / 2h.
 *
 * Tolerance, per entry: |H_ij - CD_ij| <= 1e-6 |H_ij| + 1e3 eps (1 + |z_i|) / h_j + E_ij
 *   - 1e-6 |H_ij|: the central difference's truncation error h^2 |z'''| / 6; with the
 *     steps below (1e-5 rad on angles, 1e-3 m/s on velocities at |v_h| >= 2 m/s, ...) it
 *     is below 1e-7 of |z'| for every model (rotations: h^2 / 6 ~ 2e-11; the speed's
 *     sqrt: h^2 / (6 |v_h|^2) ~ 4e-8), so 1e-6 has a margin of 10;
 *   - 1e3 eps (1 + |z_i|) / h_j: rounding. A prediction is a few dozen operations on
 *     quantities of at most 1 + |z| in its unit (lever-arm and rate terms are below the
 *     unit floor), each rounding by eps relative: the difference of two predictions is
 *     off by less than 1e3 eps (1 + |z|), and its quotient by 2 h_j by less than that
 *     over h_j;
 *   - E_ij: the term the models' H leaves out on purpose (gf_ins_gnss.h, "Measurements"):
 *     the Earth rate in w_eb^b = w_ib^b - C_n^b w_ie^n turns with the attitude phi and
 *     moves with the latitude, by |w_ie| per rad of either, so a prediction that carries
 *     w_eb^b x l (GNSS velocity, odometer, NHC) differs from H's first order by at most
 *     (1 + k_odo) |w_ie| |l| per rad in the attitude and latitude columns, and ZARU's
 *     (w_eb^b itself) by |w_ie| per rad of latitude. Elsewhere E = 0.
 * With these, the largest |H - CD| / tolerance seen is printed per kind. */
#include <float.h>
#include <math.h>
#include <string.h>

#include "est/gf_ins_gnss.h"
#include "gf_test.h"
#include "nav/gf_sins.h"

#define PI 3.14159265358979323846
#define OMEGA_IE 7.292115e-5          /* rad/s, WGS-84 (written out: not from the core) */
#define N_TRIALS 12
#define KIND_SCAN 64                  /* codes enumerated: -1 .. KIND_SCAN - 1 */

typedef struct kind_info {
    int32_t kind, rows;
    const char *name;
} kind_info;

/* every code the table answers for, in [-1, KIND_SCAN) */
static int enumerate(kind_info *out)
{
    int n = 0;
    for (int32_t k = -1; k < KIND_SCAN; ++k) {
        int32_t rows = -1;
        const char *name = NULL;
        const gf_status st = gf_ins_meas_kind_info(k, &rows, &name);
        CHECK(st == GF_OK || st == GF_ERR_BAD_PARAMETER, "kind %d: status %d", k, st);
        if (st != GF_OK)
            continue;
        out[n++] = (kind_info){k, rows, name};
    }
    return n;
}

static void test_enumeration(void)
{
    kind_info kinds[KIND_SCAN + 1];
    const int n = enumerate(kinds);
    /* today's kinds, as gf_ins_gnss.h numbers them, and nothing outside 1 .. N - 1 */
    const int32_t expected[] = {GF_INS_MEAS_GNSS_POS, GF_INS_MEAS_GNSS_VEL, GF_INS_MEAS_BARO,
                                GF_INS_MEAS_ODO, GF_INS_MEAS_NHC, GF_INS_MEAS_ZUPT,
                                GF_INS_MEAS_ZARU, GF_INS_MEAS_SPEED, GF_INS_MEAS_MASTER_VEL,
                                GF_INS_MEAS_MASTER_ATT, GF_INS_MEAS_MASTER_POS};
    const int32_t rows[] = {3, 3, 1, 1, 2, 3, 3, 1, 3, 3, 3};
    CHECK(n >= 11, "%d kinds enumerated", n);
    for (int e = 0; e < 11; ++e) {
        int found = 0;
        for (int i = 0; i < n; ++i)
            if (kinds[i].kind == expected[e]) {
                found = 1;
                CHECK(kinds[i].rows == rows[e], "kind %d: %d rows", expected[e], kinds[i].rows);
            }
        CHECK(found, "kind %d not enumerated", expected[e]);
    }
    for (int i = 0; i < n; ++i) {
        CHECK(kinds[i].kind >= 1 && kinds[i].kind < GF_INS_N_MEAS_KINDS,
              "kind %d outside 1 .. GF_INS_N_MEAS_KINDS - 1 (gate_run has one slot per kind)",
              kinds[i].kind);
        CHECK(kinds[i].rows >= 1 && kinds[i].rows <= 3, "kind %d: %d rows (the update's z, r "
              "and the innovation log hold 3)", kinds[i].kind, kinds[i].rows);
        CHECK(kinds[i].name && kinds[i].name[0], "kind %d: no name", kinds[i].kind);
        for (int j = 0; j < i; ++j)
            CHECK(strcmp(kinds[i].name, kinds[j].name) != 0, "kinds %d and %d: one name %s",
                  kinds[j].kind, kinds[i].kind, kinds[i].name);
    }
    /* NULL outputs are allowed */
    CHECK(gf_ins_meas_kind_info(GF_INS_MEAS_BARO, NULL, NULL) == GF_OK, "NULL outputs");
}

/* a random filter with every optional state, its rates set (reversed when asked) */
static void random_filter(test_rng *rng, int reversed, gf_ins_filter *f)
{
    gf_ins_config c;
    gf_ins_config_default(&c);
    c.scale_factors = c.baro_bias = c.odometer_scale = c.odometer_mount = 1;
    c.master_mount = c.master_lever = c.master_time_offset = c.flexure = 1;
    c.noise.gyro_arw_rad_sqrt_s = 1e-4;
    c.noise.accel_vrw_m_s_sqrt_s = 1e-3;
    for (int i = 0; i < 3; ++i) {
        c.gnss_lever_arm_m[i] = test_rng_uniform(rng, -1.5, 1.5);
        c.odometer_lever_arm_m[i] = test_rng_uniform(rng, -2.0, 2.0);
    }
    c.odometer_mount_rad[0] = test_rng_uniform(rng, -0.05, 0.05);
    c.odometer_mount_rad[1] = test_rng_uniform(rng, -0.05, 0.05);
    /* a slave mounted anyhow on its master (heading any, pitch and roll up to 60 deg) */
    c.master_mount_rad[0] = test_rng_uniform(rng, -PI, PI);
    c.master_mount_rad[1] = test_rng_uniform(rng, -1.0, 1.0);
    c.master_mount_rad[2] = test_rng_uniform(rng, -1.0, 1.0);
    for (int i = 0; i < 3; ++i)
        c.master_lever_arm_m[i] = test_rng_uniform(rng, -3.0, 3.0);
    c.master_time_offset_s = test_rng_uniform(rng, -0.05, 0.05);
    c.noise.flexure_std_rad = 2e-3;
    c.noise.flexure_tau_s = 0.7;
    int32_t n = 0;
    CHECK(gf_ins_state_count(&c, &n) == GF_OK && n == GF_INS_MAX_STATES, "38 states: %d", n);
    const double e[3] = {test_rng_uniform(rng, -PI, PI), test_rng_uniform(rng, -0.5, 0.5),
                         test_rng_uniform(rng, -0.5, 0.5)};
    double q[4];
    gf_euler_to_quat(e, q);
    const double speed = test_rng_uniform(rng, 2.0, 20.0), course = test_rng_uniform(rng, -PI, PI);
    const double v[3] = {speed * sin(course), speed * cos(course), test_rng_uniform(rng, -1, 1)};
    double s[GF_INS_N_SENSORS];
    for (int i = 0; i < 3; ++i) {
        s[i] = test_rng_uniform(rng, -1e-4, 1e-4);            /* gyro bias, rad/s */
        s[3 + i] = test_rng_uniform(rng, -0.05, 0.05);        /* accelerometer bias */
        s[6 + i] = test_rng_uniform(rng, -1e-3, 1e-3);        /* scale factors */
        s[9 + i] = test_rng_uniform(rng, -1e-3, 1e-3);
    }
    s[12] = test_rng_uniform(rng, -5.0, 5.0);                 /* barometer bias, m */
    s[13] = test_rng_uniform(rng, -0.02, 0.02);               /* odometer scale */
    s[14] = test_rng_uniform(rng, -0.02, 0.02);               /* boresight correction */
    s[15] = test_rng_uniform(rng, -0.02, 0.02);
    double P[GF_INS_MAX_STATES * GF_INS_MAX_STATES];
    memset(P, 0, sizeof P);
    for (int i = 0; i < n; ++i)
        P[i * n + i] = 1e-4;
    int32_t bad = 0;
    const gf_status st = gf_ins_init(f, &c, 100.0, q, v, test_rng_uniform(rng, -1.2, 1.2),
                                     test_rng_uniform(rng, -PI, PI),
                                     test_rng_uniform(rng, -50.0, 3000.0), s, P, &bad);
    CHECK(st == GF_OK, "init: %d (bad %d)", st, bad);
    /* the rates the models read: the latest compensated rate, the detector's mean rate;
     * the specific force (the master kinds' time offset) */
    for (int i = 0; i < 3; ++i) {
        f->w_ib_b_rad_s[i] = test_rng_uniform(rng, -0.3, 0.3);
        f->still_w[i] = test_rng_uniform(rng, -0.05, 0.05);
        f->f_b_m_s2[i] = test_rng_uniform(rng, -3.0, 3.0) + (i == 2 ? 9.8 : 0.0);
    }
    /* transfer-alignment estimates: mounting, lever arm, offset corrections, flexure */
    for (int i = 0; i < GF_INS_N_TRANSFER; ++i)
        f->transfer[i] = test_rng_uniform(rng, -0.01, 0.01);
    if (reversed)
        CHECK(gf_ins_reverse(f) == GF_OK, "reverse");
}

/* central-difference step of state j (its unit) */
static double step_of(const gf_ins_filter *f, int j)
{
    if (j < GF_INS_IDX_POS)
        return 1e-3;                                           /* m/s */
    if (j < GF_INS_IDX_ATT)
        return j == GF_INS_IDX_POS + 2 ? 1e-2 : 1e-7;          /* m; rad of latitude, longitude */
    if (j < GF_INS_IDX_BG)
        return 1e-5;                                           /* rad */
    if (j < GF_INS_IDX_BA)
        return 1e-6;                                           /* rad/s */
    if (j < GF_INS_BASE_STATES)
        return 1e-4;                                           /* m/s^2 */
    if (j == f->idx_baro)
        return 1e-2;                                           /* m */
    if (f->idx_tlever >= 0 && j >= f->idx_tlever && j < f->idx_tlever + 3)
        return 1e-4;                                           /* m */
    return 1e-5;            /* scales, boresight and mounting rad, offset s, flexure rad(/s) */
}

/* E_ij: the Earth-rate terms H leaves out (see the top of the file) */
static double neglected(const gf_ins_filter *f, int32_t kind, int j)
{
    const int att = j >= GF_INS_IDX_ATT && j < GF_INS_IDX_ATT + 3, lat = j == GF_INS_IDX_POS;
    const double *lg = f->cfg.gnss_lever_arm_m, *lo = f->cfg.odometer_lever_arm_m;
    const double k1 = 1.0 + fabs(f->sensors[13]);
    switch (kind) {
    case GF_INS_MEAS_GNSS_VEL:
        return att || lat ? OMEGA_IE * sqrt(lg[0] * lg[0] + lg[1] * lg[1] + lg[2] * lg[2]) : 0.0;
    case GF_INS_MEAS_ODO:
    case GF_INS_MEAS_NHC:
        return att || lat ? k1 * OMEGA_IE * sqrt(lo[0] * lo[0] + lo[1] * lo[1] + lo[2] * lo[2])
                          : 0.0;
    case GF_INS_MEAS_ZARU:
        return lat ? OMEGA_IE : 0.0;
    default:
        return 0.0;     /* a new kind: no allowance unless one is written here */
    }
}

static void test_jacobians(void)
{
    kind_info kinds[KIND_SCAN + 1];
    const int nk = enumerate(kinds);
    double worst[KIND_SCAN + 1];
    int checked[KIND_SCAN + 1];
    for (int k = 0; k < nk; ++k)
        worst[k] = 0.0, checked[k] = 0;
    test_rng rng = {0x1f3a5c7e9b2d4f61ULL};
    for (int trial = 0; trial < N_TRIALS; ++trial) {
        gf_ins_filter f;
        random_filter(&rng, trial % 2, &f);
        const int n = f.n_states;
        for (int k = 0; k < nk; ++k) {
            const int32_t kind = kinds[k].kind;
            double z0[3], H[3 * GF_INS_MAX_STATES], zp[3], zm[3], dx[GF_INS_MAX_STATES];
            int32_t rows = 0;
            gf_status st = gf_ins_meas_model(&f, kind, NULL, NULL, z0, H, &rows);
            CHECK(st == GF_OK && rows == kinds[k].rows, "kind %d: model %d, rows %d", kind, st,
                  rows);
            if (st != GF_OK)
                continue;
            for (int j = 0; j < n; ++j) {
                const double h = step_of(&f, j);
                memset(dx, 0, sizeof dx);
                dx[j] = h;
                st = gf_ins_meas_model(&f, kind, NULL, dx, zp, NULL, NULL);
                dx[j] = -h;
                st |= gf_ins_meas_model(&f, kind, NULL, dx, zm, NULL, NULL);
                CHECK(st == GF_OK, "kind %d state %d: %d", kind, j, st);
                for (int i = 0; i < rows; ++i) {
                    const double cd = -(zp[i] - zm[i]) / (2.0 * h), hij = H[i * n + j];
                    const double tol = 1e-6 * fabs(hij) + 1e3 * DBL_EPSILON * (1.0 + fabs(z0[i])) / h +
                                       neglected(&f, kind, j);
                    CHECK(fabs(hij - cd) <= tol,
                          "trial %d kind %d (%s) H[%d][%d] = %.12g, central difference %.12g "
                          "(tol %.3g)", trial, kind, kinds[k].name, i, j, hij, cd, tol);
                    worst[k] = fmax(worst[k], fabs(hij - cd) / tol);
                    checked[k]++;
                }
            }
        }
    }
    for (int k = 0; k < nk; ++k) {
        CHECK(checked[k] == N_TRIALS * kinds[k].rows * GF_INS_MAX_STATES,
              "kind %d: %d entries checked", kinds[k].kind, checked[k]);
        printf("kind %d %-9s %d rows: max |H - CD| / tol = %.3f over %d entries\n",
               kinds[k].kind, kinds[k].name, kinds[k].rows, worst[k], checked[k]);
    }
}

/* gf_ins_meas_model's prediction is the one the update makes: an external measurement at
 * the filter's time is applied before the sample, and its logged residual is
 * z_pred - z (GNSS position: z at the nominal's own position, 0 in the local frame) */
static void test_model_is_the_update(void)
{
    kind_info kinds[KIND_SCAN + 1];
    const int nk = enumerate(kinds);
    test_rng rng = {0x5eed1234abcd9876ULL};
    int n_external = 0;
    for (int k = 0; k < nk; ++k) {
        gf_ins_filter f;
        random_filter(&rng, 0, &f);
        const int32_t kind = kinds[k].kind;
        gf_ins_meas ms = {kind, f.t_s, {0.5, -0.2, 0.1}, {1.0, 1.0, 1.0}, {0.02, -0.03, 0.05}};
        if (kind == GF_INS_MEAS_GNSS_POS || kind == GF_INS_MEAS_MASTER_POS) {
            ms.z[0] = f.nav.lat_rad;
            ms.z[1] = f.nav.lon_rad;
            ms.z[2] = f.nav.h_m;
        }
        double z[3];
        int32_t rows = 0;
        gf_status st = gf_ins_meas_model(&f, kind, &ms, NULL, z, NULL, &rows);
        if (st == GF_ERR_BAD_PARAMETER)     /* an internal kind: no caller's measurement */
            continue;
        CHECK(st == GF_OK, "kind %d: %d", kind, st);
        ++n_external;
        gf_ins_innovation entry[4];
        gf_ins_log log = {4, 0, 0, entry};
        const double g[3] = {0, 0, 0}, a[3] = {0, 0, 9.8e-2};
        st = gf_ins_step(&f, f.t_s + 0.01, g, a, 1, &ms, NULL, &log);
        CHECK(st == GF_OK && log.count >= 1 && entry[0].type == kind, "kind %d: step %d", kind,
              st);
        if (st != GF_OK || log.count < 1)
            continue;
        for (int i = 0; i < rows; ++i) {
            /* the kinds whose value is not ms.z: positions (the local frame about the
             * nominal, where z sits) and the master's attitude (the prediction is the
             * small angle from it) */
            const int local = kind == GF_INS_MEAS_GNSS_POS || kind == GF_INS_MEAS_MASTER_POS ||
                              kind == GF_INS_MEAS_MASTER_ATT;
            const double zi = local ? 0.0 : ms.z[i];
            CHECK(entry[0].r[i] == z[i] - zi, "kind %d row %d: residual %.17g, model %.17g",
                  kind, i, entry[0].r[i], z[i] - zi);
        }
    }
    CHECK(n_external == 8, "%d kinds a caller hands in (GNSS position and velocity, "
          "barometer, odometer, speed, master velocity, attitude and position)", n_external);
}

static void test_errors(void)
{
    test_rng rng = {42};
    gf_ins_filter f;
    random_filter(&rng, 0, &f);
    double z[3], H[3 * GF_INS_MAX_STATES], dx[GF_INS_MAX_STATES] = {0};
    CHECK(gf_ins_meas_model(NULL, GF_INS_MEAS_BARO, NULL, NULL, z, H, NULL) == GF_ERR_NULL_POINTER,
          "NULL filter");
    CHECK(gf_ins_meas_model(&f, 0, NULL, NULL, z, H, NULL) == GF_ERR_BAD_PARAMETER, "kind 0");
    CHECK(gf_ins_meas_model(&f, GF_INS_N_MEAS_KINDS, NULL, NULL, z, H, NULL) ==
              GF_ERR_BAD_PARAMETER, "kind N");
    CHECK(gf_ins_meas_kind_info(0, NULL, NULL) == GF_ERR_BAD_PARAMETER &&
              gf_ins_meas_kind_info(GF_INS_N_MEAS_KINDS, NULL, NULL) == GF_ERR_BAD_PARAMETER,
          "kind_info outside the kinds");
    const gf_ins_meas baro = {GF_INS_MEAS_BARO, f.t_s, {10.0, 0, 0}, {1.0, 0, 0}, {0, 0, 0}};
    CHECK(gf_ins_meas_model(&f, GF_INS_MEAS_ODO, &baro, NULL, z, H, NULL) == GF_ERR_BAD_PARAMETER,
          "a measurement of another kind");
    gf_ins_meas bad = baro;
    bad.std[0] = 0.0;
    CHECK(gf_ins_meas_model(&f, GF_INS_MEAS_BARO, &bad, NULL, z, H, NULL) == GF_ERR_BAD_PARAMETER,
          "std 0");
    const gf_ins_meas nhc = {GF_INS_MEAS_NHC, f.t_s, {0, 0, 0}, {1.0, 1.0, 0}, {0, 0, 0}};
    CHECK(gf_ins_meas_model(&f, GF_INS_MEAS_NHC, &nhc, NULL, z, H, NULL) == GF_ERR_BAD_PARAMETER,
          "an internal kind is not handed in");
    dx[3] = NAN;
    CHECK(gf_ins_meas_model(&f, GF_INS_MEAS_BARO, NULL, dx, z, H, NULL) == GF_ERR_NONFINITE_INPUT,
          "NaN in dx");
    gf_ins_filter broken = f;
    broken.n_states = 99;
    CHECK(gf_ins_meas_model(&broken, GF_INS_MEAS_BARO, NULL, NULL, z, H, NULL) ==
              GF_ERR_BAD_PARAMETER, "a layout out of range");
    /* the speed model is refused where the update refuses it */
    gf_ins_filter slow = f;
    slow.nav.v_n_m_s[0] = 0.1;
    slow.nav.v_n_m_s[1] = -0.2;
    int32_t rows = 0;
    CHECK(gf_ins_meas_model(&slow, GF_INS_MEAS_SPEED, NULL, NULL, z, H, &rows) ==
              GF_ERR_SINGULAR_GEOMETRY && rows == 1, "speed below speed_min_m_s");
    CHECK(gf_ins_meas_model(&slow, GF_INS_MEAS_BARO, NULL, NULL, NULL, NULL, NULL) == GF_OK,
          "nothing asked for");
}

int main(void)
{
    test_enumeration();
    test_jacobians();
    test_model_is_the_update();
    test_errors();
    TEST_MAIN_END();
}
