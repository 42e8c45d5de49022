/* test_ins_smooth.c — the INS/GNSS filter's Rauch-Tung-Striebel smoother (gf_ins_smooth,
 * csrc/est/gf_ins_smooth.c) against an independent computation.
 *
 * Data: the vehicle truth of turn_drive.h (15 s: rest, start, a 180 deg turn) at
 * 100 Hz, GNSS position and velocity at 1 Hz on the truth (distinct stds per axis); the
 * filter (EKF and UKF, 21 states: scale factors on) starts 3 m east, 2 m north and 10
 * mrad of heading off the truth, so the smoother has errors to correct.
 *   1. the textbook RTS recursion written here (Gauss-Jordan elimination with partial
 *      pivoting on the scaled prior covariance, where the core uses a Cholesky
 *      factorisation inside gf_kalman_rts_step) over the stored epochs reproduces the
 *      smoothed states and covariances at every epoch;
 *   2. every smoothed variance is finite, > 0 and <= the filtered one (P^s = P+ +
 *      G (P^s' - P-') G^T with P^s' <= P-'), state by state and epoch by epoch;
 *   3. the pass in blocks from the end (gf_ins_smooth_block, blocks of 1, 7 and 64 epochs
 *      overlapping by one, each copied to its own buffers as a reader from disk would)
 *      equals the one-call pass bit for bit; its refusals.
 * (tests/estimation/test_smoother.py does the same through Python with numpy, adds the
 * consistency of the stored transitions and the NEES of a Monte Carlo.) */
#include <string.h>

#include "est/gf_ins_gnss.h"
#include "gf_test.h"
#include "nav/gf_earth.h"
#include "turn_drive.h"

#define H_S 0.01
enum { N = 1500, NS = 21, TRI = NS * (NS + 1) / 2, EMAX = 400 };

static gf_vehicle_sample g_truth[N];
static double g_t[EMAX], g_nav[EMAX * 10], g_sens[EMAX * GF_INS_N_SENSORS], g_dx[EMAX * NS];
static double g_Pm[EMAX * TRI], g_Pp[EMAX * TRI], g_Phi[EMAX * NS * NS];
static double g_xs[EMAX * NS], g_Ps[EMAX * TRI];
static double g_xr[EMAX * NS], g_Pr[EMAX * NS * NS];
static double g_bx[EMAX * NS], g_bP[EMAX * TRI];
static gf_ins_filter g_f;

static void unpack(const double *tri, double *P)
{
    int k = 0;
    for (int i = 0; i < NS; ++i)
        for (int j = i; j < NS; ++j)
            P[i * NS + j] = P[j * NS + i] = tri[k++];
}

/* X = A^-1 B (A, B: NS x NS, row-major; A and B overwritten), Gauss-Jordan elimination
 * with partial pivoting */
static int solve(double *A, double *B, double *X)
{
    for (int c = 0; c < NS; ++c) {
        int p = c;
        for (int r = c + 1; r < NS; ++r)
            if (fabs(A[r * NS + c]) > fabs(A[p * NS + c]))
                p = r;
        if (A[p * NS + c] == 0.0)
            return 0;
        for (int j = 0; j < NS; ++j) {
            double t = A[c * NS + j];
            A[c * NS + j] = A[p * NS + j];
            A[p * NS + j] = t;
            t = B[c * NS + j];
            B[c * NS + j] = B[p * NS + j];
            B[p * NS + j] = t;
        }
        const double d = A[c * NS + c];
        for (int j = 0; j < NS; ++j) {
            A[c * NS + j] /= d;
            B[c * NS + j] /= d;
        }
        for (int r = 0; r < NS; ++r) {
            if (r == c)
                continue;
            const double m = A[r * NS + c];
            for (int j = 0; j < NS; ++j) {
                A[r * NS + j] -= m * A[c * NS + j];
                B[r * NS + j] -= m * B[c * NS + j];
            }
        }
    }
    memcpy(X, B, sizeof(double) * NS * NS);
    return 1;
}

/* the RTS pass, textbook form: G_k = P+_k Phi_k+1^T (P-_k+1)^-1, x^s_k = G_k (x^s_k+1 +
 * dx_k+1) (closed loop: x+_k = 0, x-_k+1 = 0 about the prior nominal, whose smoothed
 * error is the posterior nominal's + the correction dx_k+1 fed back there), P^s_k =
 * P+_k + G_k (P^s_k+1 - P-_k+1) G_k^T; the system solved on P- scaled to unit diagonal */
static void reference_rts(size_t E)
{
    static double Pp[NS * NS], Pm[NS * NS], A[NS * NS], B[NS * NS], Gt[NS * NS], D[NS * NS];
    memset(g_xr + (E - 1) * NS, 0, NS * sizeof *g_xr);
    unpack(g_Pp + (E - 1) * TRI, g_Pr + (E - 1) * NS * NS);
    for (size_t k = E - 1; k-- > 0;) {
        unpack(g_Pp + k * TRI, Pp);
        unpack(g_Pm + (k + 1) * TRI, Pm);
        const double *Phi = g_Phi + (k + 1) * NS * NS;
        double s[NS];
        for (int i = 0; i < NS; ++i)
            s[i] = 1.0 / sqrt(Pm[i * NS + i]);
        /* G^T = D (D P- D)^-1 D Phi P+ */
        for (int i = 0; i < NS; ++i)
            for (int j = 0; j < NS; ++j) {
                A[i * NS + j] = s[i] * Pm[i * NS + j] * s[j];
                double acc = 0.0;
                for (int l = 0; l < NS; ++l)
                    acc += Phi[i * NS + l] * Pp[l * NS + j];
                B[i * NS + j] = s[i] * acc;
            }
        CHECK(solve(A, B, Gt), "epoch %zu: singular prior covariance", k + 1);
        for (int i = 0; i < NS; ++i)
            for (int j = 0; j < NS; ++j)
                Gt[i * NS + j] *= s[i];
        /* states */
        for (int i = 0; i < NS; ++i) {
            double acc = 0.0;
            for (int l = 0; l < NS; ++l)
                acc += Gt[l * NS + i] * (g_xr[(k + 1) * NS + l] + g_dx[(k + 1) * NS + l]);
            g_xr[k * NS + i] = acc;
        }
        /* D = P^s_k+1 - P-_k+1, then P^s_k = P+ + G D G^T */
        const double *Psn = g_Pr + (k + 1) * NS * NS;
        for (int i = 0; i < NS * NS; ++i)
            D[i] = Psn[i] - Pm[i];
        double *Ps = g_Pr + k * NS * NS;
        for (int a = 0; a < NS; ++a)            /* B = D G^T */
            for (int j = 0; j < NS; ++j) {
                double acc = 0.0;
                for (int b = 0; b < NS; ++b)
                    acc += D[a * NS + b] * Gt[b * NS + j];
                B[a * NS + j] = acc;
            }
        for (int i = 0; i < NS; ++i)
            for (int j = 0; j < NS; ++j) {
                double acc = 0.0;
                for (int a = 0; a < NS; ++a)
                    acc += Gt[a * NS + i] * B[a * NS + j];
                Ps[i * NS + j] = Pp[i * NS + j] + acc;
            }
    }
}

static size_t forward_run(int filter)
{
    gf_ins_config c;
    gf_ins_config_default(&c);
    c.filter = filter;
    c.scale_factors = 1;
    c.noise.gyro_arw_rad_sqrt_s = 3e-5;
    c.noise.accel_vrw_m_s_sqrt_s = 1e-3;
    c.noise.gyro_bias_std_rad_s = 1e-5;
    c.noise.gyro_bias_tau_s = 3600.0;
    c.noise.accel_bias_std_m_s2 = 1e-3;
    c.noise.accel_bias_tau_s = 3600.0;
    c.gate_probability = 0.0;         /* no gate: the start error is corrected, not refused */
    const gf_vehicle_sample *x0 = &g_truth[0];
    gf_earth e;
    CHECK(gf_earth_update(&e, x0->lat_rad, x0->h_m, NULL, 1.0) == GF_OK, "earth");
    const double de = 3.0, dn = 2.0, RMh = e.R_M_m + x0->h_m;
    const double RNh = (e.R_N_m + x0->h_m) * e.cos_lat;
    double q[4], eul[3];
    gf_quat_to_euler(x0->q_bn, eul);
    eul[0] += 0.01;
    gf_euler_to_quat(eul, q);
    const double sd[NS] = {0.1, 0.12, 0.14, 4.0 / RMh, 5.0 / RNh, 3.0, 0.004, 0.005, 0.03,
                           1e-4, 1.1e-4, 1.2e-4, 0.01, 0.011, 0.012,
                           1e-3, 1.1e-3, 1.2e-3, 5e-4, 6e-4, 7e-4};
    static double P0[NS * NS];
    memset(P0, 0, sizeof P0);
    for (int i = 0; i < NS; ++i)
        P0[i * NS + i] = sd[i] * sd[i];
    int32_t bad = 0;
    CHECK(gf_ins_init(&g_f, &c, 0.0, q, x0->v_n_m_s, x0->lat_rad + dn / RMh,
                      x0->lon_rad + de / RNh, x0->h_m, NULL, P0, &bad) == GF_OK && bad == 0,
          "init (bad %d)", bad);
    gf_ins_epochs ep = {EMAX, 0, g_t, g_nav, g_sens, g_dx, g_Pm, g_Pp, g_Phi};
    CHECK(gf_ins_epochs_begin(&g_f, &ep) == GF_OK, "epochs begin");
    static const double pos_std[3] = {0.5, 0.6, 1.0}, vel_std[3] = {0.05, 0.06, 0.1};
    for (int k = 1; k < N; ++k) {
        gf_ins_meas m[2];
        size_t nm = 0;
        if (k % 100 == 37) {             /* between the 0.1 s propagation epochs */
            const gf_vehicle_sample *x = &g_truth[k];
            m[nm++] = (gf_ins_meas){GF_INS_MEAS_GNSS_POS, k * H_S, {x->lat_rad, x->lon_rad, x->h_m},
                                    {pos_std[0], pos_std[1], pos_std[2]}, {0, 0, 0}};
            m[nm++] = (gf_ins_meas){GF_INS_MEAS_GNSS_VEL, k * H_S,
                                    {x->v_n_m_s[0], x->v_n_m_s[1], x->v_n_m_s[2]},
                                    {vel_std[0], vel_std[1], vel_std[2]}, {0, 0, 0}};
        }
        const gf_status st = gf_ins_step(&g_f, k * H_S, g_truth[k].dtheta_rad, g_truth[k].dv_m_s,
                                         nm, m, &ep, NULL);
        CHECK(st == GF_OK, "step %d: %d", k, st);
        if (st != GF_OK)
            break;
    }
    return ep.count;
}

static void test_blocks(int filter, size_t E, size_t B);
static void test_block_refusals(void);

static void test_smoother(int filter)
{
    const size_t E = forward_run(filter);
    /* one epoch per 0.1 s propagation, one more per GNSS epoch, and the first */
    CHECK(E > 160 && E < EMAX, "filter %d: %zu epochs", filter, E);
    if (!(E > 160 && E < EMAX))
        return;
    const gf_ins_epochs ep = {EMAX, E, g_t, g_nav, g_sens, g_dx, g_Pm, g_Pp, g_Phi};
    CHECK(gf_ins_smooth(NS, &ep, g_xs, g_Ps) == GF_OK, "gf_ins_smooth");
    reference_rts(E);
    /* 1. against the recursion above, in units of the smoothed std: the scaled prior
     * covariances have condition numbers ~1e3 (tests/estimation/test_smoother.py
     * measures them), so the two eliminations differ by ~1e3 eps per step, which the
     * contractive recursion does not accumulate; 1e-9 leaves a margin of 100 */
    double worst_x = 0.0, worst_P = 0.0, most = 0.0;
    int n_bad = 0;
    static double Ps[NS * NS], Pp[NS * NS];
    for (size_t k = 0; k < E; ++k) {
        unpack(g_Ps + k * TRI, Ps);
        unpack(g_Pp + k * TRI, Pp);
        const double *Pr = g_Pr + k * NS * NS;
        for (int i = 0; i < NS; ++i) {
            const double si = sqrt(Pr[i * NS + i]);
            worst_x = fmax(worst_x, fabs(g_xs[k * NS + i] - g_xr[k * NS + i]) / si);
            most = fmax(most, fabs(g_xr[k * NS + i]) / si);
            for (int j = 0; j < NS; ++j)
                worst_P = fmax(worst_P, fabs(Ps[i * NS + j] - Pr[i * NS + j]) /
                                            (si * sqrt(Pr[j * NS + j])));
            /* 2. 0 < P^s_ii <= P+_ii (1e-9: round-off where they are equal) */
            const double vs = Ps[i * NS + i], vf = Pp[i * NS + i];
            if (!(isfinite(vs) && vs > 0.0 && vs <= vf * (1.0 + 1e-9)) && n_bad++ == 0)
                CHECK(0, "filter %d epoch %zu state %d: smoothed variance %.6g, filtered %.6g "
                      "(the first of the bad ones)", filter, k, i, vs, vf);
        }
    }
    CHECK(n_bad == 0, "filter %d: %d smoothed variances not in (0, filtered]", filter, n_bad);
    CHECK(worst_x < 1e-9, "filter %d: smoothed states differ from the reference RTS by %.3g "
          "sigma", filter, worst_x);
    CHECK(worst_P < 1e-9, "filter %d: smoothed covariances differ by %.3g", filter, worst_P);
    /* the start error is corrected backwards: the smoother moves states by sigmas */
    CHECK(most > 1.0, "filter %d: largest smoothed correction %.3g sigma", filter, most);
    printf("filter %d: %zu epochs, max |xs - ref| %.3g sigma, max |Ps - ref| %.3g, largest "
           "correction %.3g sigma\n", filter, E, worst_x, worst_P, most);
    static const size_t blocks[] = {1, 7, 64};
    for (size_t i = 0; i < sizeof blocks / sizeof *blocks; ++i)
        test_blocks(filter, E, blocks[i]);
    test_block_refusals();
}

/* 3. the block pass: blocks [a, b] (b = the first epoch after the block, smoothed by the
 * previous call) copied into buffers of their own, smoothed, compared bit for bit */
static void test_blocks(int filter, size_t E, size_t B)
{
    static double t[EMAX], dx[EMAX * NS], Pm[EMAX * TRI], Pp[EMAX * TRI], Phi[EMAX * NS * NS];
    static double xs[EMAX * NS], Ps[EMAX * TRI];
    /* the record's last epoch: x^s = 0, P^s = P+ (what gf_ins_smooth starts from) */
    memset(g_bx + NS * (E - 1), 0, NS * sizeof *g_bx);
    memcpy(g_bP + TRI * (E - 1), g_Pp + TRI * (E - 1), TRI * sizeof *g_bP);
    int calls = 0;
    for (size_t b = E - 1; b > 0;) {
        const size_t a = b > B ? b - B : 0, m = b - a + 1;
        memcpy(t, g_t + a, m * sizeof *t);
        memcpy(dx, g_dx + NS * a, m * NS * sizeof *dx);
        memcpy(Pm, g_Pm + TRI * a, m * TRI * sizeof *Pm);
        memcpy(Pp, g_Pp + TRI * a, m * TRI * sizeof *Pp);
        memcpy(Phi, g_Phi + NS * NS * a, m * NS * NS * sizeof *Phi);
        memcpy(xs + NS * (m - 1), g_bx + NS * b, NS * sizeof *xs);
        memcpy(Ps + TRI * (m - 1), g_bP + TRI * b, TRI * sizeof *Ps);
        const gf_ins_epochs blk = {m, m, t, NULL, NULL, dx, Pm, Pp, Phi};
        const gf_status st = gf_ins_smooth_block(NS, &blk, xs, Ps);
        CHECK(st == GF_OK, "filter %d block [%zu, %zu]: %d", filter, a, b, st);
        if (st != GF_OK)
            return;
        memcpy(g_bx + NS * a, xs, (m - 1) * NS * sizeof *xs);
        memcpy(g_bP + TRI * a, Ps, (m - 1) * TRI * sizeof *Ps);
        b = a;
        ++calls;
    }
    CHECK(memcmp(g_bx, g_xs, E * NS * sizeof *g_xs) == 0,
          "filter %d, blocks of %zu: smoothed states differ from the one-call pass", filter, B);
    CHECK(memcmp(g_bP, g_Ps, E * TRI * sizeof *g_Ps) == 0,
          "filter %d, blocks of %zu: smoothed covariances differ from the one-call pass", filter, B);
    printf("filter %d: blocks of %zu epochs (%d calls) = the one-call pass, bit for bit\n", filter, B,
           calls);
}

static void test_block_refusals(void)
{
    static double xs[2 * NS], Ps[2 * TRI];
    gf_ins_epochs blk = {2, 2, g_t, NULL, NULL, g_dx, g_Pm, g_Pp, g_Phi};
    memset(xs, 0, sizeof xs);
    memcpy(Ps, g_Pp, sizeof Ps);
    CHECK(gf_ins_smooth_block(NS, NULL, xs, Ps) == GF_ERR_NULL_POINTER, "NULL epochs");
    CHECK(gf_ins_smooth_block(NS, &blk, NULL, Ps) == GF_ERR_NULL_POINTER, "NULL xs");
    CHECK(gf_ins_smooth_block(0, &blk, xs, Ps) == GF_ERR_BAD_SIZE, "n = 0");
    CHECK(gf_ins_smooth_block(GF_INS_MAX_STATES + 1, &blk, xs, Ps) == GF_ERR_BAD_SIZE, "n = 41");
    blk.count = 3;
    CHECK(gf_ins_smooth_block(NS, &blk, xs, Ps) == GF_ERR_BAD_SIZE, "count > capacity");
    blk.count = 0;
    CHECK(gf_ins_smooth_block(NS, &blk, xs, Ps) == GF_ERR_BAD_SIZE, "count 0");
    blk.count = 2;
    xs[NS + 4] = NAN;
    CHECK(gf_ins_smooth_block(NS, &blk, xs, Ps) == GF_ERR_NONFINITE_INPUT, "NaN in the given x^s");
    xs[NS + 4] = 0.0;
    Ps[TRI + 3] = INFINITY;
    CHECK(gf_ins_smooth_block(NS, &blk, xs, Ps) == GF_ERR_NONFINITE_INPUT, "Inf in the given P^s");
    Ps[TRI + 3] = g_Pp[TRI + 3];
    Ps[TRI + NS] = -1.0;    /* row 1's diagonal element in the packed upper triangle */
    CHECK(gf_ins_smooth_block(NS, &blk, xs, Ps) == GF_ERR_BAD_PARAMETER, "a negative given variance");
    Ps[TRI + NS] = g_Pp[TRI + NS];
    CHECK(gf_ins_smooth_block(NS, &blk, xs, Ps) == GF_OK, "the same block, repaired");
}

int main(void)
{
    turn_drive(g_truth, N, H_S);
    test_smoother(GF_INS_EKF);
    test_smoother(GF_INS_UKF);
    TEST_MAIN_END();
}
