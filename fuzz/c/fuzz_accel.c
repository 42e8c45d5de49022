/* fuzz_accel.c — libFuzzer target: accelerometer arrays and the gyro-free solvers
 * (gyrofree/: gf_array, gf9, gf_layout, gf_array_solver, gf_gfins, gf_gfnav): geometries
 * (given, seed 000's nine, cube6, layout 12), the forward model, the 9-accelerometer
 * solver, the general array solver, the rate strategies and the gyro-free navigator, with
 * any parameters and samples, and damaged solver states (as an FMU state restored from
 * bytes).
 * Oracles (fuzz_data.h): valid statuses; finite outputs on GF_OK and in the rows before
 * *n_done; a failed gf9_step or gf_gfins_step leaves the state unchanged; a state made
 * by init or a GF_OK step passes its gf_*_check. */
#include "fuzz_data.h"
#include "gyrofree/gf9.h"
#include "gyrofree/gf_array.h"
#include "gyrofree/gf_array_solver.h"
#include "gyrofree/gf_gfins.h"
#include "gyrofree/gf_gfnav.h"
#include "gyrofree/gf_layout.h"
#include "nav/gf_sins.h"

#define MAX_RUN 8

static int make_geometry(fz *d, gf_array_geometry *g)
{
    gf_status st;
    switch (fz_u8(d) % 4) {
    case 0:
        st = gf9_geometry(fz_pos(d, 0.1), g);
        break;
    case 1:
        st = gf_layout_cube6(fz_pos(d, 0.1), g);
        break;
    case 2:
        st = gf_layout_12(fz_pos(d, 0.1), g);
        break;
    default: {
        const size_t n = fz_u8(d) % (GF_ARRAY_MAX_SENSORS + 2);
        double u[3 * (GF_ARRAY_MAX_SENSORS + 1)], th[3 * (GF_ARRAY_MAX_SENSORS + 1)];
        fz_nums(d, u, 3 * n, 0.1);
        for (size_t i = 0; i < n; ++i) { /* mostly unit directions */
            fz_nums(d, th + 3 * i, 3, 1.0);
            const double nn = sqrt(th[3 * i] * th[3 * i] + th[3 * i + 1] * th[3 * i + 1] +
                                   th[3 * i + 2] * th[3 * i + 2]);
            if ((fz_u8(d) & 3) && nn > 0.0 && isfinite(nn))
                for (int k = 0; k < 3; ++k)
                    th[3 * i + k] /= nn;
        }
        size_t bad = 0;
        st = gf_array_geometry_set(g, n, u, th, &bad);
        FZ_REQUIRE(st == GF_OK || st == GF_ERR_BAD_SIZE || bad < n, "bad_sensor %zu of %zu", bad, n);
    }
    }
    FZ_STATUS(st, "geometry");
    return st == GF_OK;
}

static void fuzz_forward(fz *d, const gf_array_geometry *g)
{
    const size_t n = 1 + fz_index(d, MAX_RUN);
    double f[3 * MAX_RUN], w[3 * MAX_RUN], wd[3 * MAX_RUN], A[GF_ARRAY_MAX_SENSORS * MAX_RUN];
    fz_nums(d, f, 3 * n, 20.0);
    fz_nums(d, w, 3 * n, 5.0);
    fz_nums(d, wd, 3 * n, 10.0);
    size_t done = 999;
    const gf_status st = gf_array_forward(g, n, f, w, wd, A, &done);
    FZ_STATUS(st, "gf_array_forward");
    FZ_REQUIRE(done <= n && (st != GF_OK || done == n), "gf_array_forward n_done");
    FZ_REQUIRE(fz_all_finite(A, done * g->n_sensors), "gf_array_forward: non-finite rows done");
}

static void fuzz_gf9(fz *d)
{
    gf9_state s, before;
    double w0[3];
    fz_nums(d, w0, 3, 5.0);
    gf_status st = gf9_init(&s, fz_pos(d, 0.1), (fz_u8(d) & 1) ? w0 : NULL);
    FZ_STATUS(st, "gf9_init");
    if (st != GF_OK)
        return;
    FZ_REQUIRE(gf9_state_check(&s) == GF_OK, "gf9_init made a state gf9_state_check refuses");
    for (int op = 0; op < 8 && d->n > 0; ++op) {
        double A[9 * MAX_RUN];
        if (fz_u8(d) & 1) {
            fz_nums(d, A, 9, 20.0);
            gf9_output out;
            before = s;
            st = gf9_step(&s, A, fz_pos(d, 0.01), &out);
            FZ_STATUS(st, "gf9_step");
            if (st == GF_OK) {
                FZ_REQUIRE(fz_all_finite(out.f_m_s2, 12), "gf9_step: GF_OK with a non-finite output");
                FZ_REQUIRE(gf9_state_check(&s) == GF_OK, "gf9_step made a state gf9_state_check refuses");
            } else {
                FZ_REQUIRE(memcmp(&s, &before, sizeof s) == 0, "gf9_step error changed the state");
            }
        } else {
            const size_t n = 1 + fz_index(d, MAX_RUN);
            fz_nums(d, A, 9 * n, 20.0);
            double f[3 * MAX_RUN], w[3 * MAX_RUN], wd[3 * MAX_RUN], w2[3 * MAX_RUN];
            uint8_t flags[MAX_RUN];
            size_t done = 999;
            st = gf9_solve(&s, n, A, fz_pos(d, 0.01), f, w, wd, w2, flags, &done);
            FZ_STATUS(st, "gf9_solve");
            FZ_REQUIRE(done <= n && (st != GF_OK || done == n), "gf9_solve n_done");
            FZ_REQUIRE(fz_all_finite(f, 3 * done) && fz_all_finite(w, 3 * done) &&
                           fz_all_finite(wd, 3 * done) && fz_all_finite(w2, 3 * done),
                       "gf9_solve: non-finite rows done");
            FZ_REQUIRE(gf9_state_check(&s) == GF_OK, "gf9_solve left a state gf9_state_check refuses");
        }
    }
    /* a damaged state */
    for (int j = 0, k = 1 + fz_u8(d) % 4; j < k; ++j)
        ((uint8_t *)&s)[fz_index(d, sizeof s)] = fz_u8(d);
    FZ_STATUS(gf9_state_check(&s), "gf9_state_check");
    double A[9];
    gf9_output out;
    fz_nums(d, A, 9, 20.0);
    FZ_STATUS(gf9_step(&s, A, fz_pos(d, 0.01), &out), "gf9_step on a damaged state");
}

static void fuzz_rate(fz *d, const gf_array_geometry *g)
{
    gf_array_solver solver;
    uint32_t unobs = 0;
    gf_status st = gf_array_solver_init(&solver, g, &unobs);
    FZ_STATUS(st, "gf_array_solver_init");
    if (st == GF_OK) {
        double A[GF_ARRAY_MAX_SENSORS], wp[3], x[GF_X_N];
        fz_nums(d, A, g->n_sensors, 20.0);
        fz_nums(d, wp, 3, 5.0);
        st = gf_array_solve(&solver, A, (fz_u8(d) & 1) ? wp : NULL, x);
        FZ_STATUS(st, "gf_array_solve");
    }
    gf_rate_config cfg;
    gf_rate_config_default(&cfg);
    const uint8_t pick = fz_u8(d);
    cfg.strategy = pick % 5 == 4 ? (int32_t)fz_u32(d) : pick % 5;
    if (pick & 0x80) {
        cfg.accel_noise_m_s2 = fz_pos(d, 0.01);
        cfg.bias_walk_rad_s2_sqrt_s = fz_pos(d, 0.01);
        cfg.init_std_rad_s = fz_pos(d, 0.1);
        cfg.init_bias_std_rad_s2 = fz_pos(d, 0.1);
    }
    double w0[3];
    fz_nums(d, w0, 3, 5.0);
    if (fz_u8(d) & 1) { /* the navigator */
        gf_sins_config sc;
        gf_sins_config_default(&sc);
        sc.input = GF_SINS_INPUT_RATES;
        sc.earth = fz_u8(d) & 1;
        const double q[4] = {1.0, 0.0, 0.0, 0.0};
        double v[3];
        fz_nums(d, v, 3, 30.0);
        gf_gfnav_state nav;
        st = gf_gfnav_init(&nav, g, &cfg, w0, &sc, q, v, fz_num(d, 1.5), fz_num(d, 3.0),
                           fz_num(d, 1e3), 0.0, &unobs);
        FZ_STATUS(st, "gf_gfnav_init");
        if (st != GF_OK)
            return;
        const size_t n = 1 + fz_index(d, MAX_RUN);
        double A[GF_ARRAY_MAX_SENSORS * MAX_RUN], h[MAX_RUN], q_o[4 * MAX_RUN], v_o[3 * MAX_RUN],
            p_o[3 * MAX_RUN], w_o[3 * MAX_RUN], f_o[3 * MAX_RUN];
        uint8_t fl[MAX_RUN];
        fz_nums(d, A, g->n_sensors * n, 20.0);
        fz_nums(d, h, n, 100.0);
        size_t done = 999;
        st = gf_gfnav_run(&nav, n, A, fz_pos(d, 0.01), (fz_u8(d) & 1) ? h : NULL, q_o, v_o, p_o,
                          w_o, f_o, fl, &done);
        FZ_STATUS(st, "gf_gfnav_run");
        FZ_REQUIRE(done <= n && (st != GF_OK || done == n), "gf_gfnav_run n_done");
        FZ_REQUIRE(fz_all_finite(q_o, 4 * done) && fz_all_finite(v_o, 3 * done) &&
                       fz_all_finite(p_o, 3 * done) && fz_all_finite(w_o, 3 * done) &&
                       fz_all_finite(f_o, 3 * done), "gf_gfnav_run: non-finite rows done");
        return;
    }
    static gf_gfins_state s, before; /* 60 kB: off the stack (the harness, not the core) */
    st = gf_gfins_init(&s, g, &cfg, (fz_u8(d) & 1) ? w0 : NULL, &unobs);
    FZ_STATUS(st, "gf_gfins_init");
    if (st != GF_OK)
        return;
    FZ_REQUIRE(gf_gfins_state_check(&s) == GF_OK, "gf_gfins_init made a state its check refuses: %d (strategy %d noise %g walk %g std %g %g cond %g)", (int)gf_gfins_state_check(&s), (int)cfg.strategy, cfg.accel_noise_m_s2, cfg.bias_walk_rad_s2_sqrt_s, cfg.init_std_rad_s, cfg.init_bias_std_rad_s2, s.solver.cond);
    for (int op = 0; op < 6 && d->n > 0; ++op) {
        double A[GF_ARRAY_MAX_SENSORS * MAX_RUN], f[3 * MAX_RUN], w[3 * MAX_RUN], wd[3 * MAX_RUN],
            W[6 * MAX_RUN];
        uint8_t fl[MAX_RUN];
        if (fz_u8(d) & 1) {
            fz_nums(d, A, g->n_sensors, 20.0);
            before = s;
            st = gf_gfins_step(&s, A, fz_pos(d, 0.01), f, w, wd, W, fl);
            FZ_STATUS(st, "gf_gfins_step");
            if (st == GF_OK) {
                FZ_REQUIRE(fz_all_finite(f, 3) && fz_all_finite(w, 3) && fz_all_finite(wd, 3) &&
                               fz_all_finite(W, 6),
                           "gf_gfins_step: GF_OK with a non-finite output (strategy %d, n %zu; f %g %g %g "
                           "w %g %g %g wd %g %g %g W %g %g %g %g %g %g)", (int)s.cfg.strategy,
                           s.solver.n_sensors, f[0], f[1], f[2], w[0], w[1], w[2], wd[0], wd[1], wd[2],
                           W[0], W[1], W[2], W[3], W[4], W[5]);
                FZ_REQUIRE(gf_gfins_state_check(&s) == GF_OK, "gf_gfins_step made a state its check refuses");
            } else {
                FZ_REQUIRE(memcmp(&s, &before, sizeof s) == 0, "gf_gfins_step error changed the state");
            }
        } else {
            const size_t n = 1 + fz_index(d, MAX_RUN);
            fz_nums(d, A, g->n_sensors * n, 20.0);
            size_t done = 999;
            st = gf_gfins_run(&s, n, A, fz_pos(d, 0.01), f, w, wd, (fz_u8(d) & 1) ? W : NULL, fl, &done);
            FZ_STATUS(st, "gf_gfins_run");
            FZ_REQUIRE(done <= n && (st != GF_OK || done == n), "gf_gfins_run n_done");
            FZ_REQUIRE(fz_all_finite(f, 3 * done) && fz_all_finite(w, 3 * done) &&
                           fz_all_finite(wd, 3 * done), "gf_gfins_run: non-finite rows done");
        }
    }
    for (int j = 0, k = 1 + fz_u8(d) % 4; j < k; ++j)
        ((uint8_t *)&s)[fz_index(d, sizeof s)] = fz_u8(d);
    FZ_STATUS(gf_gfins_state_check(&s), "gf_gfins_state_check");
    double A[GF_ARRAY_MAX_SENSORS], f[3], w[3], wd[3], W[6];
    uint8_t fl;
    fz_nums(d, A, GF_ARRAY_MAX_SENSORS, 20.0);
    FZ_STATUS(gf_gfins_step(&s, A, fz_pos(d, 0.01), f, w, wd, W, &fl), "gf_gfins_step on a damaged state");
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz d = {data, size};
    const uint8_t what = fz_u8(&d);
    if (what & 1) {
        fuzz_gf9(&d);
        return 0;
    }
    gf_array_geometry g;
    if (!make_geometry(&d, &g))
        return 0;
    if (what & 2)
        fuzz_forward(&d, &g);
    else
        fuzz_rate(&d, &g);
    return 0;
}
