/* gf_aiding.c — GNSS receiver, barometer and odometer riding gf_vehicle; see
 * gf_aiding.h. */
#include "sim/gf_aiding.h"

#include <math.h>
#include <string.h>

#include "base/gf_math.h"
#include "nav/gf_earth.h"

/* per-sensor streams of one seed (fractional parts of sqrt 2, 3, 5: nothing up the sleeve) */
#define SEED_GNSS 0x6A09E667F3BCC908ULL
#define SEED_BARO 0xBB67AE8584CAA73BULL
#define SEED_ODO 0x3C6EF372FE94F82BULL

/* An epoch at time t is reached by time t_end when t <= t_end + tol(t_end): the FMU
 * glue's tolerance on communication points (fmu_common.c), so that an epoch at a
 * communication point is delivered in the step that ends there whatever the master's
 * clock rounding. */
static double tol(double t_s) { return 1e-9 * fmax(1.0, fabs(t_s)); }

static double reach(double t_end_s) { return t_end_s + tol(t_end_s); }

/* t_end may fall short of the time already reached by the tolerance (a master's clock) */
static int time_ok(const gf_aiding_sim *s, double t_end_s)
{
    return isfinite(t_end_s) && t_end_s >= s->t_s - tol(s->t_s);
}

static double epoch_time(double t0_s, double offset_s, double rate_hz, uint64_t k)
{
    return (t0_s + offset_s) + (double)k / rate_hz;
}

static double next_gnss(const gf_aiding_sim *s)
{
    const gf_gnss_params *g = &s->p.gnss;
    return g->enabled ? epoch_time(s->t0_s, g->offset_s, g->rate_hz, s->gnss_k) : INFINITY;
}

static double next_baro(const gf_aiding_sim *s)
{
    const gf_baro_params *b = &s->p.baro;
    return b->enabled ? epoch_time(s->t0_s, b->offset_s, b->rate_hz, s->baro_k) : INFINITY;
}

static double next_odo(const gf_aiding_sim *s)
{
    const gf_odo_params *o = &s->p.odo;
    return o->enabled ? epoch_time(s->t0_s, o->offset_s, o->rate_hz, s->odo_k) : INFINITY;
}

static double next_epoch(const gf_aiding_sim *s)
{
    return fmin(next_gnss(s), fmin(next_baro(s), next_odo(s)));
}

static int in_outage(const gf_gnss_params *g, double t_s)
{
    for (int32_t i = 0; i < g->n_outages; ++i)
        if (t_s >= g->outage_start_s[i] && t_s < g->outage_end_s[i])
            return 1;
    return g->outage_duration_s > 0.0 && t_s >= g->outage_first_s &&
           fmod(t_s - g->outage_first_s, g->outage_period_s) < g->outage_duration_s;
}

/* ENU offset d (m) at the IMU -> latitude and longitude offsets (rad), with the radii at
 * the IMU (the mapping of gf_aiding.h, for the lever arm and the errors alike). */
static void enu_to_geodetic(const gf_earth *e, double h_m, const double d_enu_m[3],
                            double *dlat_rad, double *dlon_rad)
{
    *dlat_rad = d_enu_m[1] / (e->R_M_m + h_m);
    *dlon_rad = d_enu_m[0] / ((e->R_N_m + h_m) * e->cos_lat);
}

/* Noise-free measurements at truth x; *e receives the Earth quantities at the IMU. */
static gf_status geometry(const gf_vehicle_sample *x, const double l_gnss[3], const double l_odo[3],
                          gf_earth *e, double *lat, double *lon, double *h, double vel[3],
                          double *speed)
{
    if (!gf_all_finite(x->q_bn, 4) || !gf_all_finite(x->v_n_m_s, 3) ||
        !gf_all_finite(x->gyro_rad_s, 3) || !isfinite(x->lat_rad) || !isfinite(x->lon_rad) ||
        !isfinite(x->h_m) || !gf_all_finite(l_gnss, 3) || !gf_all_finite(l_odo, 3))
        return GF_ERR_NONFINITE_INPUT;
    const gf_status st = gf_earth_update(e, x->lat_rad, x->h_m, NULL, 1.0);
    if (st != GF_OK)
        return st;
    gf_mat3 C; /* C_b^n */
    gf_q_to_dcm(x->q_bn, &C);
    double w_ie_b[3], w_eb[3], l_n[3], wxl[3], r[3], v_b[3];
    gf_m3t_mul_v3(&C, e->w_ie_n_rad_s, w_ie_b);
    gf_v3_sub(x->gyro_rad_s, w_ie_b, w_eb); /* w_eb^b = w_ib^b - C_n^b w_ie^n */
    /* antenna: p + C l (mapped), v^n + C (w_eb^b x l) */
    gf_m3_mul_v3(&C, l_gnss, l_n);
    double dlat, dlon;
    enu_to_geodetic(e, x->h_m, l_n, &dlat, &dlon);
    *lat = x->lat_rad + dlat;
    *lon = x->lon_rad + dlon;
    *h = x->h_m + l_n[2];
    gf_v3_cross(w_eb, l_gnss, wxl);
    gf_m3_mul_v3(&C, wxl, r);
    gf_v3_add(x->v_n_m_s, r, vel);
    /* wheel: [C^T v^n + w_eb^b x l_odo]_y */
    gf_m3t_mul_v3(&C, x->v_n_m_s, v_b);
    gf_v3_cross(w_eb, l_odo, wxl);
    *speed = v_b[1] + wxl[1];
    return GF_OK;
}

static const double ZERO3[3] = {0.0, 0.0, 0.0};

gf_status gf_aiding_truth(const gf_vehicle_sample *x, const double *l_gnss_m,
                          const double *l_odo_m, double *lat_rad, double *lon_rad, double *h_m,
                          double *vel_enu_m_s, double *speed_m_s)
{
    if (!x)
        return GF_ERR_NULL_POINTER;
    gf_earth e;
    double lat, lon, h, vel[3], speed;
    const gf_status st = geometry(x, l_gnss_m ? l_gnss_m : ZERO3, l_odo_m ? l_odo_m : ZERO3, &e,
                                  &lat, &lon, &h, vel, &speed);
    if (st != GF_OK)
        return st;
    if (lat_rad)
        *lat_rad = lat;
    if (lon_rad)
        *lon_rad = lon;
    if (h_m)
        *h_m = h;
    if (vel_enu_m_s)
        gf_v3_copy(vel, vel_enu_m_s);
    if (speed_m_s)
        *speed_m_s = speed;
    return GF_OK;
}

/* a = exp(-dt / tau) of a Gauss-Markov process sampled at the epochs (0: none). */
static double gm_a(double rate_hz, double tau_s)
{
    return tau_s > 0.0 ? exp(-(1.0 / rate_hz) / tau_s) : 0.0;
}

/* std * N(0, 1), nothing drawn for std = 0 */
static double white(gf_rng *r, double std)
{
    if (!(std > 0.0))
        return 0.0;
    double z;
    gf_rng_normal(r, 1, &z);
    return std * z;
}

static gf_status measure_gnss(gf_aiding_sim *s, const gf_vehicle_sample *x, double t_s,
                              gf_gnss_epoch *ep)
{
    const gf_gnss_params *g = &s->p.gnss;
    gf_earth e;
    double speed;
    gf_status st = geometry(x, g->lever_arm_m, ZERO3, &e, &ep->true_lat_rad, &ep->true_lon_rad,
                            &ep->true_h_m, ep->true_vel_enu_m_s, &speed);
    if (st != GF_OK)
        return st;
    st = gf_gauss_markov_step(&s->gnss_rng, 3, g->pos_gm_std_m, gm_a(g->rate_hz, g->pos_gm_tau_s),
                              s->gnss_k == 0, s->gnss_gm_m);
    if (st != GF_OK)
        return st;
    double dp[3], dlat, dlon;
    for (int i = 0; i < 3; ++i)
        dp[i] = s->gnss_gm_m[i] + white(&s->gnss_rng, g->pos_std_m[i]);
    for (int i = 0; i < 3; ++i)
        ep->vel_enu_m_s[i] = ep->true_vel_enu_m_s[i] + white(&s->gnss_rng, g->vel_std_m_s[i]);
    enu_to_geodetic(&e, x->h_m, dp, &dlat, &dlon);
    ep->t_s = t_s;
    ep->t_delivered_s = t_s + g->latency_s;
    ep->lat_rad = ep->true_lat_rad + dlat;
    ep->lon_rad = ep->true_lon_rad + dlon;
    ep->h_m = ep->true_h_m + dp[2];
    for (int i = 0; i < 3; ++i) {
        ep->pos_std_m[i] = sqrt(g->pos_std_m[i] * g->pos_std_m[i] +
                                g->pos_gm_std_m[i] * g->pos_gm_std_m[i]);
        ep->vel_std_m_s[i] = g->vel_std_m_s[i];
    }
    ep->quality = (double)g->quality;
    return GF_OK;
}

static gf_status measure_baro(gf_aiding_sim *s, const gf_vehicle_sample *x, double t_s,
                              gf_baro_epoch *ep)
{
    const gf_baro_params *b = &s->p.baro;
    const int first = s->baro_k == 0;
    const gf_status st = gf_gauss_markov_step(&s->baro_rng, 1, &b->bias_gm_std_m,
                                              gm_a(b->rate_hz, b->bias_gm_tau_s), first,
                                              &s->baro_gm_m);
    if (st != GF_OK)
        return st;
    if (!first)
        s->baro_rw_m += white(&s->baro_rng, b->bias_rw_m_sqrt_s * sqrt(1.0 / b->rate_hz));
    ep->t_s = t_s;
    ep->true_h_m = x->h_m;
    ep->bias_m = b->bias0_m + s->baro_rw_m + s->baro_gm_m;
    ep->h_m = (x->h_m + ep->bias_m) + white(&s->baro_rng, b->std_m);
    ep->std_m = b->std_m;
    return GF_OK;
}

static gf_status measure_odo(gf_aiding_sim *s, const gf_vehicle_sample *x, double t_s,
                             gf_odo_epoch *ep)
{
    const gf_odo_params *o = &s->p.odo;
    gf_earth e;
    double lat, lon, h, vel[3];
    const gf_status st = geometry(x, ZERO3, o->lever_arm_m, &e, &lat, &lon, &h, vel,
                                  &ep->true_speed_m_s);
    if (st != GF_OK)
        return st;
    ep->t_s = t_s;
    ep->speed_m_s = (1.0 + o->scale_error) * ep->true_speed_m_s + white(&s->odo_rng, o->std_m_s);
    ep->std_m_s = o->std_m_s;
    return GF_OK;
}

/* Where delivered epochs go: arrays (batch) and/or the newest of each (a step). */
typedef struct sink {
    gf_gnss_epoch *gnss;
    size_t gnss_cap, n_gnss;
    gf_baro_epoch *baro;
    size_t baro_cap, n_baro;
    gf_odo_epoch *odo;
    size_t odo_cap, n_odo;
    gf_aiding_output *latest;
    int overflow;
} sink;

static int32_t count_up(int32_t n) { return n < INT32_MAX ? n + 1 : n; }

static void deliver_gnss(sink *k, const gf_gnss_epoch *e)
{
    if (k->gnss) {
        if (k->n_gnss < k->gnss_cap)
            k->gnss[k->n_gnss] = *e;
        else
            k->overflow = 1;
    }
    ++k->n_gnss;
    if (k->latest) {
        k->latest->gnss = *e;
        k->latest->gnss_quality = (int32_t)e->quality;
        k->latest->gnss_new = count_up(k->latest->gnss_new);
    }
}

static void deliver_baro(sink *k, const gf_baro_epoch *e)
{
    if (k->baro) {
        if (k->n_baro < k->baro_cap)
            k->baro[k->n_baro] = *e;
        else
            k->overflow = 1;
    }
    ++k->n_baro;
    if (k->latest) {
        k->latest->baro = *e;
        k->latest->baro_new = count_up(k->latest->baro_new);
    }
}

static void deliver_odo(sink *k, const gf_odo_epoch *e)
{
    if (k->odo) {
        if (k->n_odo < k->odo_cap)
            k->odo[k->n_odo] = *e;
        else
            k->overflow = 1;
    }
    ++k->n_odo;
    if (k->latest) {
        k->latest->odo = *e;
        k->latest->odo_new = count_up(k->latest->odo_new);
    }
}

/* Delivers the queued GNSS epochs due by t_s (their delivery time <= t_s). */
static void deliver_due(gf_aiding_sim *s, double t_s, sink *k)
{
    while (s->queue_n > 0 && s->queue[s->queue_head].t_delivered_s <= t_s) {
        deliver_gnss(k, &s->queue[s->queue_head]);
        s->queue_head = (s->queue_head + 1) % GF_GNSS_QUEUE;
        --s->queue_n;
    }
}

/* The truth at epoch time t_s: the copy stepped there (or its truth when it is there). */
static gf_status truth_at(gf_aiding_sim *s, double t_s, gf_vehicle_sample *x)
{
    if (t_s > s->vehicle.time_s)
        return gf_vehicle_step(&s->vehicle, t_s, x);
    return gf_vehicle_truth(&s->vehicle, x);
}

/* Measures every epoch reached by t_end in time order, delivering as they fall due. */
static gf_status advance(gf_aiding_sim *s, double t_end_s, sink *k)
{
    const double lim = reach(t_end_s);
    for (;;) {
        const double tg = next_gnss(s), tb = next_baro(s), to = next_odo(s);
        const double t = fmin(tg, fmin(tb, to));
        if (!(t <= lim))
            break;
        gf_vehicle_sample x;
        gf_status st = truth_at(s, t, &x);
        if (st != GF_OK)
            return st;
        if (tg == t) {
            /* epochs due before this one leave the queue first: it holds at most
             * latency * rate + 2 <= GF_GNSS_QUEUE epochs */
            deliver_due(s, t, k);
            gf_gnss_epoch ep;
            st = measure_gnss(s, &x, t, &ep);
            if (st != GF_OK)
                return st;
            ++s->gnss_k;
            if (!in_outage(&s->p.gnss, t)) {
                if (s->queue_n >= GF_GNSS_QUEUE)
                    return GF_ERR_BAD_SIZE; /* prevented by the latency check */
                s->queue[(s->queue_head + s->queue_n) % GF_GNSS_QUEUE] = ep;
                ++s->queue_n;
            }
        }
        if (tb == t) {
            gf_baro_epoch ep;
            st = measure_baro(s, &x, t, &ep);
            if (st != GF_OK)
                return st;
            ++s->baro_k;
            deliver_baro(k, &ep);
        }
        if (to == t) {
            gf_odo_epoch ep;
            st = measure_odo(s, &x, t, &ep);
            if (st != GF_OK)
                return st;
            ++s->odo_k;
            deliver_odo(k, &ep);
        }
    }
    deliver_due(s, lim, k);
    s->t_s = fmax(s->t_s, t_end_s);
    return GF_OK;
}

/* ---- parameters ---------------------------------------------------------------- */

static int nonneg(double x) { return isfinite(x) && x >= 0.0; }

static int nonneg3(const double x[3]) { return nonneg(x[0]) && nonneg(x[1]) && nonneg(x[2]); }

static int rate_ok(double r) { return isfinite(r) && r > 0.0 && r <= GF_AIDING_MAX_RATE_HZ; }

static int lever_ok(const double l[3])
{
    return gf_all_finite(l, 3) && gf_v3_norm(l) <= GF_AIDING_MAX_LEVER_M;
}

/* tau must be > 0 (and finite) where a std is > 0; a finite tau >= 0 otherwise */
static int tau_ok(double tau_s, double std_max)
{
    return isfinite(tau_s) && (std_max > 0.0 ? tau_s > 0.0 : tau_s >= 0.0);
}

static int check_gnss(const gf_gnss_params *g)
{
    if (g->enabled != 0 && g->enabled != 1)
        return GF_AIDING_BAD_GNSS_ENABLED;
    if (!g->enabled)
        return 0;
    if (!rate_ok(g->rate_hz))
        return GF_AIDING_BAD_GNSS_RATE;
    if (!nonneg(g->offset_s))
        return GF_AIDING_BAD_GNSS_OFFSET;
    if (!nonneg(g->latency_s) || !(g->latency_s * g->rate_hz <= GF_GNSS_QUEUE - 2))
        return GF_AIDING_BAD_GNSS_LATENCY;
    if (!lever_ok(g->lever_arm_m))
        return GF_AIDING_BAD_GNSS_LEVER_ARM;
    if (!nonneg3(g->pos_std_m))
        return GF_AIDING_BAD_GNSS_POS_STD;
    if (!nonneg3(g->vel_std_m_s))
        return GF_AIDING_BAD_GNSS_VEL_STD;
    if (!nonneg3(g->pos_gm_std_m))
        return GF_AIDING_BAD_GNSS_GM_STD;
    const double gm_max = fmax(g->pos_gm_std_m[0], fmax(g->pos_gm_std_m[1], g->pos_gm_std_m[2]));
    if (!tau_ok(g->pos_gm_tau_s, gm_max))
        return GF_AIDING_BAD_GNSS_GM_TAU;
    if (g->quality < 0 || g->quality > 6)
        return GF_AIDING_BAD_GNSS_QUALITY;
    if (g->n_outages < 0 || g->n_outages > GF_AIDING_MAX_OUTAGES)
        return GF_AIDING_BAD_GNSS_N_OUTAGES;
    for (int32_t i = 0; i < g->n_outages; ++i)
        if (!isfinite(g->outage_start_s[i]) || !isfinite(g->outage_end_s[i]) ||
            !(g->outage_start_s[i] < g->outage_end_s[i]))
            return GF_AIDING_BAD_GNSS_OUTAGE + (int)i;
    if (!isfinite(g->outage_first_s) || !nonneg(g->outage_period_s) ||
        !nonneg(g->outage_duration_s) ||
        (g->outage_duration_s > 0.0 && !(g->outage_period_s > 0.0 &&
                                          g->outage_duration_s <= g->outage_period_s)))
        return GF_AIDING_BAD_GNSS_PERIODIC;
    return 0;
}

static int check_baro(const gf_baro_params *b)
{
    if (b->enabled != 0 && b->enabled != 1)
        return GF_AIDING_BAD_BARO_ENABLED;
    if (!b->enabled)
        return 0;
    if (!rate_ok(b->rate_hz))
        return GF_AIDING_BAD_BARO_RATE;
    if (!nonneg(b->offset_s))
        return GF_AIDING_BAD_BARO_OFFSET;
    if (!nonneg(b->std_m))
        return GF_AIDING_BAD_BARO_STD;
    if (!isfinite(b->bias0_m))
        return GF_AIDING_BAD_BARO_BIAS0;
    if (!nonneg(b->bias_rw_m_sqrt_s))
        return GF_AIDING_BAD_BARO_RW;
    if (!nonneg(b->bias_gm_std_m))
        return GF_AIDING_BAD_BARO_GM_STD;
    if (!tau_ok(b->bias_gm_tau_s, b->bias_gm_std_m))
        return GF_AIDING_BAD_BARO_GM_TAU;
    return 0;
}

static int check_odo(const gf_odo_params *o)
{
    if (o->enabled != 0 && o->enabled != 1)
        return GF_AIDING_BAD_ODO_ENABLED;
    if (!o->enabled)
        return 0;
    if (!rate_ok(o->rate_hz))
        return GF_AIDING_BAD_ODO_RATE;
    if (!nonneg(o->offset_s))
        return GF_AIDING_BAD_ODO_OFFSET;
    if (!lever_ok(o->lever_arm_m))
        return GF_AIDING_BAD_ODO_LEVER_ARM;
    if (!isfinite(o->scale_error) || !(fabs(o->scale_error) < 0.5))
        return GF_AIDING_BAD_ODO_SCALE;
    if (!nonneg(o->std_m_s))
        return GF_AIDING_BAD_ODO_STD;
    return 0;
}

const char *gf_aiding_bad_string(int bad)
{
    if (bad >= GF_AIDING_BAD_GNSS_OUTAGE)
        return "must have start < end, both finite";
    switch (bad) {
    case GF_AIDING_BAD_GNSS_ENABLED:
    case GF_AIDING_BAD_BARO_ENABLED:
    case GF_AIDING_BAD_ODO_ENABLED:
        return "must be 0 or 1";
    case GF_AIDING_BAD_GNSS_RATE:
    case GF_AIDING_BAD_BARO_RATE:
    case GF_AIDING_BAD_ODO_RATE:
        return "must be finite, > 0 and <= 1000 Hz";
    case GF_AIDING_BAD_GNSS_LATENCY:
        return "must be finite, >= 0 s and latency x rate <= 14 (epochs awaiting delivery)";
    case GF_AIDING_BAD_GNSS_LEVER_ARM:
    case GF_AIDING_BAD_ODO_LEVER_ARM:
        return "must be finite with |l| <= 100 m";
    case GF_AIDING_BAD_GNSS_GM_TAU:
    case GF_AIDING_BAD_BARO_GM_TAU:
        return "must be finite and > 0 s where its std is > 0 (>= 0 otherwise)";
    case GF_AIDING_BAD_GNSS_QUALITY:
        return "must be 0 .. 6 (RTKLIB Q: 1 fix, 2 float, 3 SBAS, 4 DGPS, 5 single, 6 PPP)";
    case GF_AIDING_BAD_GNSS_N_OUTAGES:
        return "must be 0 .. 8 (GF_AIDING_MAX_OUTAGES)";
    case GF_AIDING_BAD_GNSS_PERIODIC:
        return "(first, period, duration) must be finite, period and duration >= 0, and "
               "a duration > 0 needs 0 < duration <= period";
    case GF_AIDING_BAD_BARO_BIAS0:
        return "must be finite";
    case GF_AIDING_BAD_ODO_SCALE:
        return "must be finite with |k| < 0.5";
    case GF_AIDING_BAD_GNSS_OFFSET:
    case GF_AIDING_BAD_GNSS_POS_STD:
    case GF_AIDING_BAD_GNSS_VEL_STD:
    case GF_AIDING_BAD_GNSS_GM_STD:
    case GF_AIDING_BAD_BARO_OFFSET:
    case GF_AIDING_BAD_BARO_STD:
    case GF_AIDING_BAD_BARO_RW:
    case GF_AIDING_BAD_BARO_GM_STD:
    case GF_AIDING_BAD_ODO_OFFSET:
    case GF_AIDING_BAD_ODO_STD:
        return "must be finite and >= 0";
    default:
        return "is out of range";
    }
}

static void clear_output(gf_aiding_output *out)
{
    memset(out, 0, sizeof *out);
    double *f[] = {&out->gnss.t_s, &out->gnss.t_delivered_s, &out->gnss.lat_rad, &out->gnss.lon_rad,
                   &out->gnss.h_m, &out->gnss.true_lat_rad, &out->gnss.true_lon_rad,
                   &out->gnss.true_h_m, &out->gnss.quality, &out->baro.t_s, &out->baro.h_m,
                   &out->baro.std_m, &out->baro.true_h_m, &out->baro.bias_m, &out->odo.t_s,
                   &out->odo.speed_m_s, &out->odo.std_m_s, &out->odo.true_speed_m_s};
    for (size_t i = 0; i < sizeof f / sizeof f[0]; ++i)
        *f[i] = NAN;
    for (int i = 0; i < 3; ++i)
        out->gnss.vel_enu_m_s[i] = out->gnss.pos_std_m[i] = out->gnss.vel_std_m_s[i] =
            out->gnss.true_vel_enu_m_s[i] = NAN;
}

gf_status gf_aiding_init(gf_aiding_sim *sim, const gf_aiding_params *params,
                         const gf_vehicle_state *vehicle, uint64_t seed, gf_aiding_output *out,
                         int *bad)
{
    if (bad)
        *bad = GF_AIDING_BAD_NONE;
    if (!sim || !params || !vehicle)
        return GF_ERR_NULL_POINTER;
    if (!isfinite(vehicle->time_s))
        return GF_ERR_BAD_TIME;
    int which = check_gnss(&params->gnss);
    if (!which)
        which = check_baro(&params->baro);
    if (!which)
        which = check_odo(&params->odo);
    if (which) {
        if (bad)
            *bad = which;
        return GF_ERR_BAD_PARAMETER;
    }
    memset(sim, 0, sizeof *sim);
    sim->p = *params;
    sim->t0_s = sim->t_s = vehicle->time_s;
    sim->vehicle = *vehicle;
    gf_rng_seed(&sim->gnss_rng, seed ^ SEED_GNSS);
    gf_rng_seed(&sim->baro_rng, seed ^ SEED_BARO);
    gf_rng_seed(&sim->odo_rng, seed ^ SEED_ODO);
    if (out)
        clear_output(out);
    return GF_OK;
}

/* What a step uses to index the queue or size its loops (integer compares: every step). */
static int indices_valid(const gf_aiding_sim *s)
{
    return s->queue_head >= 0 && s->queue_head < GF_GNSS_QUEUE && s->queue_n >= 0 &&
           s->queue_n <= GF_GNSS_QUEUE && s->p.gnss.n_outages >= 0 &&
           s->p.gnss.n_outages <= GF_AIDING_MAX_OUTAGES;
}

gf_status gf_aiding_sim_check(const gf_aiding_sim *sim)
{
    if (!sim)
        return GF_ERR_NULL_POINTER;
    if (!indices_valid(sim))
        return GF_ERR_BAD_SIZE;
    if (check_gnss(&sim->p.gnss) || check_baro(&sim->p.baro) || check_odo(&sim->p.odo))
        return GF_ERR_BAD_PARAMETER;
    if (!isfinite(sim->t0_s) || !isfinite(sim->t_s) || !gf_all_finite(sim->gnss_gm_m, 3) ||
        !isfinite(sim->baro_rw_m) || !isfinite(sim->baro_gm_m))
        return GF_ERR_NONFINITE_INPUT;
    return gf_vehicle_state_check(&sim->vehicle);
}

gf_status gf_aiding_step(gf_aiding_sim *sim, double t_end_s, gf_aiding_output *out)
{
    if (!sim || !out)
        return GF_ERR_NULL_POINTER;
    if (!indices_valid(sim))
        return GF_ERR_BAD_SIZE;
    if (!time_ok(sim, t_end_s))
        return GF_ERR_BAD_TIME;
    const double lim = reach(t_end_s);
    const int due = sim->queue_n > 0 && sim->queue[sim->queue_head].t_delivered_s <= lim;
    if (!due && !(next_epoch(sim) <= lim)) { /* nothing to do (most steps): no copies */
        sim->t_s = fmax(sim->t_s, t_end_s);
        out->gnss_new = out->baro_new = out->odo_new = 0;
        return GF_OK;
    }
    gf_aiding_sim s = *sim;
    gf_aiding_output o = *out;
    o.gnss_new = o.baro_new = o.odo_new = 0;
    sink k = {0};
    k.latest = &o;
    const gf_status st = advance(&s, t_end_s, &k);
    if (st != GF_OK)
        return st;
    *sim = s;
    *out = o;
    return GF_OK;
}

gf_status gf_aiding_sync(gf_aiding_sim *sim, const gf_vehicle_state *vehicle)
{
    if (!sim || !vehicle)
        return GF_ERR_NULL_POINTER;
    const double t = vehicle->time_s;
    if (!isfinite(t) || next_epoch(sim) < t - tol(t))
        return GF_ERR_BAD_TIME;
    sim->vehicle = *vehicle;
    return GF_OK;
}

gf_status gf_aiding_run(gf_aiding_sim *sim, double t_end_s, gf_gnss_epoch *gnss,
                        size_t gnss_cap, size_t *n_gnss, gf_baro_epoch *baro, size_t baro_cap,
                        size_t *n_baro, gf_odo_epoch *odo, size_t odo_cap, size_t *n_odo)
{
    if (n_gnss)
        *n_gnss = 0;
    if (n_baro)
        *n_baro = 0;
    if (n_odo)
        *n_odo = 0;
    if (!sim || (sim->p.gnss.enabled && (!gnss || !n_gnss)) ||
        (sim->p.baro.enabled && (!baro || !n_baro)) || (sim->p.odo.enabled && (!odo || !n_odo)))
        return GF_ERR_NULL_POINTER;
    if (!indices_valid(sim))
        return GF_ERR_BAD_SIZE;
    if (!time_ok(sim, t_end_s))
        return GF_ERR_BAD_TIME;
    gf_aiding_sim s = *sim;
    sink k = {gnss, gnss_cap, 0, baro, baro_cap, 0, odo, odo_cap, 0, NULL, 0};
    const gf_status st = advance(&s, t_end_s, &k);
    if (n_gnss)
        *n_gnss = k.n_gnss < gnss_cap ? k.n_gnss : gnss_cap;
    if (n_baro)
        *n_baro = k.n_baro < baro_cap ? k.n_baro : baro_cap;
    if (n_odo)
        *n_odo = k.n_odo < odo_cap ? k.n_odo : odo_cap;
    if (st != GF_OK)
        return st;
    if (k.overflow)
        return GF_ERR_BAD_SIZE;
    *sim = s;
    return GF_OK;
}
