/* gf_gfins.c — the angular-rate strategies of gyro-free navigation; see gf_gfins.h. */
#include "gyrofree/gf_gfins.h"

#include <float.h>
#include <math.h>
#include <string.h>

#include "base/gf_linalg.h"
#include "base/gf_math.h"
#include "gyrofree/gf_gfins_internal.h"

/* d p / d w (6 x 3, row-major) in the orthonormal coordinates */
static void products_on_jacobian(const double w[3], double J[18])
{
    const double r = GF_SQRT2;
    const double x = w[0], y = w[1], z = w[2];
    const double Jv[18] = {2 * x, 0, 0, 0, 2 * y, 0, 0, 0, 2 * z,
                           r * y, r * x, 0, r * z, 0, r * x, 0, r * z, r * y};
    memcpy(J, Jv, sizeof Jv);
}

gf_status gf_rate_config_default(gf_rate_config *cfg)
{
    if (!cfg)
        return GF_ERR_NULL_POINTER;
    cfg->strategy = GF_RATE_INTEGRATE;
    cfg->accel_noise_m_s2 = 1e-4;
    cfg->bias_walk_rad_s2_sqrt_s = 1e-6;
    cfg->init_std_rad_s = 1e-2;
    cfg->init_bias_std_rad_s2 = 1e-3;
    return GF_OK;
}

static int estimates(const gf_array_solver *s, uint32_t groups)
{
    return (s->estimated & groups) == groups;
}

/* The rate model a strategy needs on this solver (GF_RATE_MODEL_*), NONE if it cannot run */
static int model_allowed(int32_t strategy, size_t n_obs, int32_t model)
{
    switch (strategy) {
    case GF_RATE_SQRT:
        return (model == GF_RATE_MODEL_FRAME && n_obs == 3) ||
               (model == GF_RATE_MODEL_FIT && n_obs >= 3 && n_obs <= 6);
    case GF_RATE_EIGEN:
        return model == GF_RATE_MODEL_FULL && n_obs == 6;
    default:
        return model == GF_RATE_MODEL_NONE;
    }
}

/* What a rate step uses to size loops, index arrays or select a branch: the solver's
 * sizes, the strategy and its rate model, and for FUSED the measurement count and the
 * filter dimension. Integer compares only: runs before every step. */
int gfins_rate_state_valid(const gf_gfins_state *st)
{
    if (!solver_valid(&st->solver) || st->cfg.strategy < GF_RATE_INTEGRATE ||
        st->cfg.strategy > GF_RATE_FUSED ||
        !model_allowed(st->cfg.strategy, st->solver.n_obs, st->rate_model))
        return 0;
    if (st->cfg.strategy == GF_RATE_FUSED)
        return st->n_w_meas >= 1 && (size_t)st->n_w_meas == st->solver.n_obs && st->kf.n == 6;
    return 1;
}

static int config_valid(const gf_rate_config *c)
{
    return c->strategy >= GF_RATE_INTEGRATE && c->strategy <= GF_RATE_FUSED &&
           c->accel_noise_m_s2 > 0.0 && isfinite(c->accel_noise_m_s2) &&
           c->bias_walk_rad_s2_sqrt_s >= 0.0 && isfinite(c->bias_walk_rad_s2_sqrt_s) &&
           c->init_std_rad_s > 0.0 && isfinite(c->init_std_rad_s) &&
           c->init_bias_std_rad_s2 >= 0.0 && isfinite(c->init_bias_std_rad_s2);
}

gf_status gf_gfins_state_check(const gf_gfins_state *st)
{
    if (!st)
        return GF_ERR_NULL_POINTER;
    if (!gfins_rate_state_valid(st))
        return GF_ERR_BAD_SIZE;
    const gf_array_solver *s = &st->solver;
    if (!config_valid(&st->cfg))
        return GF_ERR_BAD_PARAMETER;
    if ((s->present | s->estimated | s->from_rate) > 15u || s->rank != s->n_est ||
        !estimates(s, GF_GROUP_F | GF_GROUP_OMEGA_DOT))
        return GF_ERR_BAD_PARAMETER;
    if (!gf_all_finite(s->H, s->n_sensors * GF_X_N) || !gf_all_finite(s->noise_gain, GF_X_N) ||
        !isfinite(s->cond) || !gf_all_finite(s->basis, 36) || !gf_all_finite(s->K_pred, GF_X_N * 6))
        return GF_ERR_NONFINITE_INPUT;
    for (size_t r = 0; r < s->n_est; ++r)
        if (!gf_all_finite(s->pinv + r * NS, s->n_sensors))
            return GF_ERR_NONFINITE_INPUT;
    if (!gf_all_finite(s->pinv_t, s->n_sensors * GF_X_N))
        return GF_ERR_NONFINITE_INPUT;
    if (!gf_all_finite(st->omega_rad_s, 3) || !gf_all_finite(st->omega_ref_rad_s, 3) ||
        !gf_all_finite(st->omega_dot_rad_s2, 3) || !gf_all_finite(st->R_W, 36) ||
        !gf_all_finite(st->omega_dot_prev_rad_s2, 3) || !isfinite(st->dt_prev_s) ||
        !gf_all_finite(st->var_omega_dot, 9) || !gf_all_finite(st->frame, 9) ||
        !gf_all_finite(st->diag_map, 18) || !gf_all_finite(st->amb_rad_s, 3) ||
        !gf_all_finite(st->whiten, 36))
        return GF_ERR_NONFINITE_INPUT;
    if (st->cfg.strategy == GF_RATE_FUSED)
        return gf_kalman_check(&st->kf);
    return GF_OK;
}

/* symmetric 3x3 matrix of a vector in the orthonormal product coordinates */
static void sym_of(const double p[6], double M[9])
{
    M[0] = p[0]; M[4] = p[1]; M[8] = p[2];
    M[1] = M[3] = p[3] * GF_SQRT1_2;
    M[2] = M[6] = p[4] * GF_SQRT1_2;
    M[5] = M[7] = p[5] * GF_SQRT1_2;
}

/* column c of the solver's product basis as a symmetric matrix */
static void basis_matrix(const gf_array_solver *s, size_t c, double M[9])
{
    double p[6];
    for (int j = 0; j < 6; ++j)
        p[j] = s->basis[j * 6 + c];
    sym_of(p, M);
}

/* FRAME detection: the three observed combinations are the diagonal of W in one
 * orthonormal frame iff their matrices commute, i.e. are all diagonal in the
 * eigenbasis of a generic combination of them. The frame is made canonical (each axis
 * along the body axis it is closest to, in body-axis order where that is a permutation,
 * pointing to its positive side), so that Qin's array as tabled gives the body axes. */
static int find_frame(const gf_array_solver *s, double frame[9])
{
    if (s->n_obs != 3)
        return 0;
    double B[3][9];
    for (size_t c = 0; c < 3; ++c)
        basis_matrix(s, c, B[c]);
    static const double kMix[2][3] = {{1.0, 0.41421356237309505, 0.71828182845904524},
                                      {0.3, 1.0, -0.57721566490153286}};
    for (int attempt = 0; attempt < 2; ++attempt) {
        double M[9], ev[3], V[9];
        for (int i = 0; i < 9; ++i)
            M[i] = kMix[attempt][0] * B[0][i] + kMix[attempt][1] * B[1][i] + kMix[attempt][2] * B[2][i];
        gf_sym3_eig(M, ev, V);
        int ok = 1;
        for (size_t c = 0; c < 3 && ok; ++c) {
            double off = 0.0, nrm = 0.0;
            for (int i = 0; i < 9; ++i)
                nrm += B[c][i] * B[c][i];
            for (int p = 0; p < 3; ++p)
                for (int q = 0; q < 3; ++q) {
                    if (p == q)
                        continue;
                    double acc = 0.0; /* v_p^T B v_q */
                    for (int i = 0; i < 3; ++i)
                        for (int j = 0; j < 3; ++j)
                            acc += V[3 * i + p] * B[c][3 * i + j] * V[3 * j + q];
                    off += acc * acc;
                }
            ok = off <= 1e-18 * nrm;
        }
        if (!ok)
            continue;
        /* canonical order and signs */
        int axis_of[3], used[3] = {0, 0, 0}, perm = 1;
        for (int p = 0; p < 3; ++p) {
            int best = 0;
            for (int i = 1; i < 3; ++i)
                if (fabs(V[3 * i + p]) > fabs(V[3 * best + p]))
                    best = i;
            axis_of[p] = best;
            perm &= !used[best];
            used[best] = 1;
        }
        for (int p = 0; p < 3; ++p) {
            const int dst = perm ? axis_of[p] : p;
            const double sg = V[3 * axis_of[p] + p] < 0.0 ? -1.0 : 1.0;
            for (int i = 0; i < 3; ++i)
                frame[3 * i + dst] = sg * V[3 * i + p];
        }
        /* the body axes within round-off (Qin's array as tabled): exactly them, so that
         * the per-sample step can skip the frame rotations */
        double dI = 0.0;
        for (int i = 0; i < 9; ++i)
            dI = fmax(dI, fabs(frame[i] - (i % 4 == 0 ? 1.0 : 0.0)));
        if (dI <= 1e-13)
            for (int i = 0; i < 9; ++i)
                frame[i] = i % 4 == 0 ? 1.0 : 0.0;
        return 1;
    }
    return 0;
}

gf_status gf_gfins_init(gf_gfins_state *st, const gf_array_geometry *g, const gf_rate_config *cfg,
                        const double *omega_init, uint32_t *unobservable)
{
    if (!st || !g || !cfg)
        return GF_ERR_NULL_POINTER;
    if (!config_valid(cfg))
        return GF_ERR_BAD_PARAMETER;
    if (omega_init && !gf_v3_isfinite(omega_init))
        return GF_ERR_BAD_PARAMETER;
    memset(st, 0, sizeof *st);
    gf_status status = gf_array_solver_init(&st->solver, g, unobservable);
    if (status != GF_OK)
        return status;
    const gf_array_solver *s = &st->solver;
    const size_t no = s->n_obs;
    st->cfg = *cfg;
    /* the rate model of SQRT and EIGEN */
    if (cfg->strategy == GF_RATE_EIGEN) {
        st->rate_model = GF_RATE_MODEL_FULL;
        if (!model_allowed(cfg->strategy, no, st->rate_model))
            return GF_ERR_BAD_PARAMETER;
    } else if (cfg->strategy == GF_RATE_SQRT) {
        if (find_frame(s, st->frame))
            st->rate_model = GF_RATE_MODEL_FRAME;
        else if (no >= 3)
            st->rate_model = GF_RATE_MODEL_FIT;
        if (!model_allowed(cfg->strategy, no, st->rate_model))
            return GF_ERR_BAD_PARAMETER;
    }
    if (cfg->strategy == GF_RATE_FUSED && no == 0)
        return GF_ERR_BAD_PARAMETER;
    if (omega_init) {
        gf_v3_copy(omega_init, st->omega_rad_s);
        gf_v3_copy(omega_init, st->omega_ref_rad_s);
    }
    /* noise covariances of the linear estimates: sigma^2 P P^T over the pinv rows */
    const double s2 = cfg->accel_noise_m_s2 * cfg->accel_noise_m_s2;
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
            const double *pa = s->pinv + (size_t)(3 + a) * NS, *pb = s->pinv + (size_t)(3 + b) * NS;
            double acc = 0.0;
            for (size_t i = 0; i < s->n_sensors; ++i)
                acc += pa[i] * pb[i];
            st->var_omega_dot[3 * a + b] = s2 * acc;
        }
    for (size_t a = 0; a < no; ++a)
        for (size_t b = 0; b < no; ++b) {
            const double *pa = s->pinv + (6 + a) * NS, *pb = s->pinv + (6 + b) * NS;
            double acc = 0.0;
            for (size_t i = 0; i < s->n_sensors; ++i)
                acc += pa[i] * pb[i];
            st->R_W[no * a + b] = s2 * acc;
        }
    /* ambiguity resolution: 2.5 sqrt(std) of the products the rate is read from */
    if (st->rate_model == GF_RATE_MODEL_FRAME) {
        for (int k = 0; k < 3; ++k) {
            double M[9];
            for (size_t c = 0; c < 3; ++c) {
                basis_matrix(s, c, M);
                double acc = 0.0; /* a_k^T B_c a_k */
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j)
                        acc += st->frame[3 * i + k] * M[3 * i + j] * st->frame[3 * j + k];
                st->diag_map[3 * k + c] = acc;
            }
            double var = 0.0; /* of d_k = diag_map_k z */
            for (size_t a = 0; a < 3; ++a)
                for (size_t b = 0; b < 3; ++b)
                    var += st->diag_map[3 * k + a] * st->R_W[3 * a + b] * st->diag_map[3 * k + b];
            st->amb_rad_s[k] = 2.5 * sqrt(sqrt(var));
        }
    } else if (st->rate_model != GF_RATE_MODEL_NONE) {
        double vmax = 0.0;
        for (size_t a = 0; a < no; ++a)
            vmax = fmax(vmax, st->R_W[no * a + a]);
        st->amb_rad_s[0] = 2.5 * sqrt(sqrt(vmax));
        if (st->rate_model == GF_RATE_MODEL_FIT) {
            /* whitening L^-1 of R_W / vmax (the weights of the fit; scaled so that the
             * whitened Jacobian is in rad/s like the resolution) */
            double Lc[36];
            for (size_t i = 0; i < no * no; ++i)
                Lc[i] = st->R_W[i] / vmax;
            if (gf_cholesky(no, Lc) != GF_OK)
                return GF_ERR_SINGULAR_GEOMETRY;
            for (size_t c = 0; c < no; ++c) { /* column c of L^-1: forward substitution */
                for (size_t i = 0; i < no; ++i) {
                    double acc = i == c ? 1.0 : 0.0;
                    for (size_t j = 0; j < i; ++j)
                        acc -= Lc[i * no + j] * st->whiten[j * no + c];
                    st->whiten[i * no + c] = acc / Lc[i * no + i];
                }
            }
        }
    }
    if (cfg->strategy == GF_RATE_FUSED) {
        st->n_w_meas = (int32_t)no;
        double x0[6] = {0, 0, 0, 0, 0, 0}, P0[36];
        gf_v3_copy(st->omega_rad_s, x0);
        memset(P0, 0, sizeof P0);
        for (int i = 0; i < 3; ++i) {
            P0[7 * i] = cfg->init_std_rad_s * cfg->init_std_rad_s;
            P0[7 * (i + 3)] = cfg->init_bias_std_rad_s2 * cfg->init_bias_std_rad_s2;
        }
        status = gf_kalman_init(&st->kf, 6, x0, P0);
        if (status != GF_OK)
            return status;
    }
    /* a finite but absurd noise std (1e308 m/s^2) overflows the covariances: the state
     * would be refused when restored (found by fuzzing) */
    if (!gf_all_finite(st->var_omega_dot, 9) || !gf_all_finite(st->R_W, 36))
        return GF_ERR_BAD_PARAMETER;
    return GF_OK;
}


/* (n x 6) times (6 x 3) -> n x 3 */
static void times_jacobian(const double *M, size_t n, size_t stride, const double J[18], double *out)
{
    for (size_t r = 0; r < n; ++r)
        for (int c = 0; c < 3; ++c) {
            double acc = 0.0;
            for (int j = 0; j < 6; ++j)
                acc += M[r * stride + (size_t)j] * J[3 * j + c];
            out[3 * r + (size_t)c] = acc;
        }
}

/* A sign reference carries no information below this fraction of the rates' scale
 * (|reference|, |previous rate|): it is round-off of an integral started at zero. */
#define SIGN_INFO 1e-6

/* SQRT, FRAME: w.a_k = +-sqrt(a_k^T W a_k) with the sign of the reference (seed 000
 * eq. 4 and 6 in the array's frame); the reference is re-anchored on the axes that are
 * unambiguous */
static void rate_frame(const gf_gfins_state *st, const double *z, rate_step_result *r)
{
    double wp[3], refp[3], prevp[3];
    const double *fr = st->frame;
    const int body = fr[0] == 1.0 && fr[4] == 1.0 && fr[8] == 1.0; /* then exactly I */
    const double *w0 = st->omega_rad_s;
    const double tiny = SIGN_INFO * fmax(gf_v3_norm(r->ref), gf_v3_norm(w0));
    for (int k = 0; k < 3; ++k) {
        const double *fk = st->frame;
        refp[k] = body ? r->ref[k] : fk[k] * r->ref[0] + fk[3 + k] * r->ref[1] + fk[6 + k] * r->ref[2];
        prevp[k] = body ? w0[k] : fk[k] * w0[0] + fk[3 + k] * w0[1] + fk[6 + k] * w0[2];
        const double d = st->diag_map[3 * k] * z[0] + st->diag_map[3 * k + 1] * z[1] +
                         st->diag_map[3 * k + 2] * z[2];
        if (d >= 0.0) {
            const double mag = sqrt(d);
            /* the sign of the w_dot integral, or where it holds no information (a start at
             * rest from zero: round-off), the previous rate's: continuity */
            const double sref = fabs(refp[k]) > tiny ? refp[k] : prevp[k];
            wp[k] = sref < 0.0 ? -mag : mag;
            if (sref == 0.0 && mag > 0.0)
                r->flags |= GF_RATE_FLAG_SIGN_UNKNOWN;
            if (mag < st->amb_rad_s[k])
                r->flags |= GF_RATE_FLAG_AMBIGUOUS;
            else
                refp[k] = wp[k];
        } else {
            wp[k] = refp[k];
            r->flags |= (uint8_t)(GF_RATE_FLAG_NEG_X << k);
        }
    }
    if (body) {
        gf_v3_copy(wp, r->w);
        gf_v3_copy(refp, r->ref);
        return;
    }
    for (int i = 0; i < 3; ++i) {
        const double *fi = st->frame + 3 * i;
        r->w[i] = fi[0] * wp[0] + fi[1] * wp[1] + fi[2] * wp[2];
        r->ref[i] = fi[0] * refp[0] + fi[1] * refp[1] + fi[2] * refp[2];
    }
}

/* SQRT/EIGEN, FULL: dominant eigenpair of the measured W, global sign from the reference */
static void rate_full(const gf_gfins_state *st, const double *Wx, rate_step_result *r)
{
    const double W[9] = {Wx[0], Wx[3], Wx[4], Wx[3], Wx[1], Wx[5], Wx[4], Wx[5], Wx[2]};
    double ev[3], V[9];
    /* W ~ w w^T is nearly rank one, so power iteration from the previous rate
     * converges in a few steps (error ratio lambda_2/lambda_1 ~ noise / |w|^2 per
     * step); the Jacobi solver takes over when there is no usable start */
    double v0[3], nv;
    gf_v3_copy(st->omega_rad_s, v0);
    nv = gf_v3_norm(v0);
    int done_power = 0;
    if (nv > 0.0) {
        gf_v3_scale(v0, 1.0 / nv, v0);
        double wv[3];
        for (int it = 0; it < 4; ++it) {
            for (int i = 0; i < 3; ++i)
                wv[i] = W[3 * i] * v0[0] + W[3 * i + 1] * v0[1] + W[3 * i + 2] * v0[2];
            nv = gf_v3_norm(wv);
            if (!(nv > 0.0))
                break;
            gf_v3_scale(wv, 1.0 / nv, v0);
        }
        if (nv > 0.0) {
            for (int i = 0; i < 3; ++i)
                wv[i] = W[3 * i] * v0[0] + W[3 * i + 1] * v0[1] + W[3 * i + 2] * v0[2];
            ev[0] = gf_v3_dot(v0, wv);
            /* accept when v0 is an eigenvector far below any noise level */
            double res[3];
            gf_v3_axpy(wv, -ev[0], v0, res);
            if (gf_v3_norm(res) <= 1e-9 * fabs(ev[0])) {
                V[0] = v0[0]; V[3] = v0[1]; V[6] = v0[2];
                done_power = 1;
            }
        }
    }
    if (!done_power)
        gf_sym3_eig(W, ev, V);
    if (ev[0] > 0.0) {
        const double mag = sqrt(ev[0]);
        for (int k = 0; k < 3; ++k)
            r->w[k] = mag * V[3 * k];
        /* the sign of the w_dot integral, or the previous rate's where the integral holds
         * no information along w (a start at rest from zero: round-off) */
        double d = gf_v3_dot(r->w, r->ref);
        if (!(fabs(d) > SIGN_INFO * mag * fmax(gf_v3_norm(r->ref), gf_v3_norm(st->omega_rad_s))))
            d = gf_v3_dot(r->w, st->omega_rad_s);
        if (d < 0.0)
            gf_v3_scale(r->w, -1.0, r->w);
        else if (d == 0.0)
            r->flags |= GF_RATE_FLAG_SIGN_UNKNOWN;
        if (mag < st->amb_rad_s[0])
            r->flags |= GF_RATE_FLAG_AMBIGUOUS;
        else
            gf_v3_copy(r->w, r->ref);
    } else {
        gf_v3_copy(r->ref, r->w);
        r->flags |= GF_RATE_FLAG_NEG_X;
    }
}

/* SQRT, FIT: Gauss-Newton fit of w to the observed combinations z, weighted by R_W^-1,
 * from the reference (the branch of the w_dot integral); ambiguous where the whitened
 * Jacobian L^-1 B_o^T J(w) has sigma_min / 2 below the resolution (two branches meet
 * there; for Qin's array sigma_min = 2 |w_k|) */
static void rate_fit(const gf_gfins_state *st, const double *z, rate_step_result *r)
{
    const gf_array_solver *s = &st->solver;
    const size_t no = s->n_obs;
    double w[3];
    gf_v3_copy(r->ref, w);
    if (!(gf_v3_norm(r->ref) > SIGN_INFO * gf_v3_norm(st->omega_rad_s)))
        gf_v3_copy(st->omega_rad_s, w); /* the integral holds no information: continuity */
    double GtG[9] = {0};
    int converged = 0;
    for (int it = 0; it < 12; ++it) {
        double p[6], J[18], G[18], res[6], g[3] = {0, 0, 0};
        products_on(w, p);
        products_on_jacobian(w, J);
        double Gr[18], rr[6];
        for (size_t c = 0; c < no; ++c) {
            double acc = 0.0, gc[3] = {0, 0, 0};
            for (int j = 0; j < 6; ++j) {
                const double b = s->basis[j * 6 + c];
                acc += b * p[j];
                gc[0] += b * J[3 * j];
                gc[1] += b * J[3 * j + 1];
                gc[2] += b * J[3 * j + 2];
            }
            rr[c] = z[c] - acc;
            memcpy(Gr + 3 * c, gc, sizeof gc);
        }
        /* whitened: L^-1 r, L^-1 G */
        for (size_t i = 0; i < no; ++i) {
            double a0 = 0.0, g0 = 0.0, g1 = 0.0, g2 = 0.0;
            for (size_t j = 0; j <= i; ++j) {
                const double l = st->whiten[i * no + j];
                a0 += l * rr[j];
                g0 += l * Gr[3 * j];
                g1 += l * Gr[3 * j + 1];
                g2 += l * Gr[3 * j + 2];
            }
            res[i] = a0;
            G[3 * i] = g0, G[3 * i + 1] = g1, G[3 * i + 2] = g2;
        }
        for (int a = 0; a < 3; ++a) {
            for (int b = 0; b < 3; ++b) {
                double acc = 0.0;
                for (size_t c = 0; c < no; ++c)
                    acc += G[3 * c + a] * G[3 * c + b];
                GtG[3 * a + b] = acc;
            }
            for (size_t c = 0; c < no; ++c)
                g[a] += G[3 * c + a] * res[c];
        }
        double L[9];
        memcpy(L, GtG, sizeof L);
        if (gf_cholesky(3, L) != GF_OK)
            break;
        gf_cholesky_solve(3, L, 1, g);
        gf_v3_add(w, g, w);
        if (gf_v3_norm(g) <= 4.0 * DBL_EPSILON * gf_v3_norm(w)) {
            converged = 1;
            break;
        }
    }
    if (!converged || !gf_v3_isfinite(w)) {
        gf_v3_copy(r->ref, r->w);
        r->flags |= GF_RATE_FLAG_NEG_X;
        return;
    }
    gf_v3_copy(w, r->w);
    double ev[3], V[9];
    gf_sym3_eig(GtG, ev, V);
    if (!(ev[2] > 0.0) || 0.5 * sqrt(ev[2]) < st->amb_rad_s[0])
        r->flags |= GF_RATE_FLAG_AMBIGUOUS;
    else
        gf_v3_copy(w, r->ref);
}

/* the w_dot integral over the new interval (gf_gfins.h): third-order Adams-Moulton when
 * the two previous intervals are equal, else the trapezoid */
static int am3_ok(const gf_gfins_state *st, double dt)
{
    return st->n_samples >= 2 && fabs(dt - st->dt_prev_s) <= 1e-9 * dt;
}

static void wdot_integral(const gf_gfins_state *st, const double wd_new[3], double dt, double out[3])
{
    const double *w1 = st->omega_dot_rad_s2, *w2 = st->omega_dot_prev_rad_s2;
    if (am3_ok(st, dt))
        for (int k = 0; k < 3; ++k)
            out[k] = dt / 12.0 * (5.0 * wd_new[k] + 8.0 * w1[k] - w2[k]);
    else
        for (int k = 0; k < 3; ++k)
            out[k] = 0.5 * dt * (w1[k] + wd_new[k]);
}

gf_status gfins_rate_step(const gf_gfins_state *st, const double *A, double dt,
                          rate_step_result *r)
{
    const gf_array_solver *s = &st->solver;
    if (!gf_all_finite(A, s->n_sensors))
        return GF_ERR_NONFINITE_INPUT;
    const int first = st->n_samples == 0;
    if (!first && !(dt > 0.0 && isfinite(dt)))
        return GF_ERR_BAD_TIME;
    r->dt = dt;
    double pred[3], y[GF_X_N], z[6], p_pred[6];
    if (first)
        gf_v3_copy(st->omega_rad_s, pred);
    else if (am3_ok(st, dt))
        for (int k = 0; k < 3; ++k)
            pred[k] = st->omega_rad_s[k] +
                      0.5 * dt * (3.0 * st->omega_dot_rad_s2[k] - st->omega_dot_prev_rad_s2[k]);
    else
        gf_v3_axpy(st->omega_rad_s, dt, st->omega_dot_rad_s2, pred);
    /* y = pinv A; w_dot and the observed combinations less the confounded products of
     * the predicted rate */
    array_linear(s, A, y);
    gf_v3_copy(y + 3, r->wd);
    memcpy(z, y + 6, s->n_obs * sizeof(double));
    if (s->n_conf) {
        double kp[GF_X_N] = {0};
        products_on(pred, p_pred);
        kpred_times(s, 3, 3 + s->n_obs, p_pred, kp);
        for (int k = 0; k < 3; ++k)
            r->wd[k] -= kp[k];
        for (size_t c = 0; c < s->n_obs; ++c)
            z[c] -= kp[3 + c];
    }
    double dw[3] = {0, 0, 0};
    if (!first)
        wdot_integral(st, r->wd, dt, dw);
    gf_v3_add(st->omega_ref_rad_s, dw, r->ref);
    r->flags = 0;
    switch (st->cfg.strategy) {
    case GF_RATE_INTEGRATE:
        gf_v3_add(st->omega_rad_s, dw, r->w);
        gf_v3_copy(r->w, r->ref);
        break;
    case GF_RATE_SQRT:
    case GF_RATE_EIGEN:
        if (st->rate_model == GF_RATE_MODEL_FRAME) {
            rate_frame(st, z, r);
        } else if (st->rate_model == GF_RATE_MODEL_FULL) {
            double W[6];
            for (int j = 0; j < 6; ++j) {
                const double *wo = s->W_obs + j * 6;
                W[j] = wo[0] * z[0] + wo[1] * z[1] + wo[2] * z[2] + wo[3] * z[3] + wo[4] * z[4] +
                       wo[5] * z[5];
            }
            rate_full(st, W, r);
        } else {
            rate_fit(st, z, r);
        }
        break;
    case GF_RATE_FUSED: {
        /* EKF on [w, b]: w' = w_dot(w) - b, w_dot(w) = y_wd - K_wd p(w) (the confounded
         * products, if any, at the filter's rate); the observed combinations measure
         * h(w) = (B_o^T + K_z) p(w), exactly, whatever the prediction */
        gf_kalman kf;
        kf.n = 6;
        memcpy(kf.x, st->kf.x, 6 * sizeof(double));
        memcpy(kf.P, st->kf.P, 36 * sizeof(double));
        const size_t no = s->n_obs;
        if (!first) {
            double F[36], Q[36];
            memset(F, 0, sizeof F);
            memset(Q, 0, sizeof Q);
            for (int i = 0; i < 6; ++i)
                F[7 * i] = 1.0;
            const double qb = st->cfg.bias_walk_rad_s2_sqrt_s * st->cfg.bias_walk_rad_s2_sqrt_s * dt;
            for (int i = 0; i < 3; ++i) {
                F[6 * i + 3 + i] = -dt;
                for (int j = 0; j < 3; ++j) /* trapezoid of two noisy samples: ~dt^2 var */
                    Q[6 * i + j] = dt * dt * st->var_omega_dot[3 * i + j];
                Q[7 * (i + 3)] = qb;
            }
            if (s->n_conf) { /* the loop through the confounded products: dw' = -K_wd J dw */
                double J[18], Aw[9];
                products_on_jacobian(kf.x, J);
                times_jacobian(s->K_pred + 3 * 6, 3, 6, J, Aw);
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j)
                        F[6 * i + j] -= dt * Aw[3 * i + j];
            }
            for (int k = 0; k < 3; ++k)
                kf.x[k] += dw[k] - dt * kf.x[3 + k];
            gf_kalman_predict(&kf, F, Q, 0);
        }
        const double *w = kf.x;
        double p[6], J[18], M[GF_X_N * 6], H[36], res[6];
        products_on(w, p);
        products_on_jacobian(w, J);
        for (size_t c = 0; c < no; ++c)
            for (int j = 0; j < 6; ++j)
                M[c * 6 + (size_t)j] = s->basis[j * 6 + c] + s->K_pred[(6 + c) * 6 + (size_t)j];
        double Hw[18];
        times_jacobian(M, no, 6, J, Hw);
        memset(H, 0, sizeof H);
        for (size_t c = 0; c < no; ++c) {
            double hc = 0.0;
            for (int j = 0; j < 6; ++j)
                hc += M[c * 6 + (size_t)j] * p[j];
            res[c] = y[6 + c] - hc;
            H[c * 6 + 0] = Hw[3 * c];
            H[c * 6 + 1] = Hw[3 * c + 1];
            H[c * 6 + 2] = Hw[3 * c + 2];
        }
        if (gf_kalman_update(&kf, no, res, H, st->R_W, NULL) != GF_OK)
            r->flags |= GF_RATE_FLAG_UPDATE_SKIPPED;
        gf_v3_copy(kf.x, r->w);
        gf_v3_copy(kf.x, r->ref);
        memcpy(r->kf_x, kf.x, sizeof r->kf_x);
        memcpy(r->kf_P, kf.P, sizeof r->kf_P);
        break;
    }
    default:
        return GF_ERR_BAD_PARAMETER;
    }
    /* f and w_dot with the confounded products of the final rate: the w_dot kept for the
     * next intervals' integral is then that of the rate the strategy settled on, the
     * w' = w_dot(w) the filter models (the products W are formed only when a caller
     * asks for them: rate_products) */
    gf_v3_copy(y, r->f);
    if (s->n_conf) {
        double p[6], kf[6];
        products_on(r->w, p);
        kpred_times(s, 0, 6, p, kf);
        for (int k = 0; k < 3; ++k) {
            r->f[k] -= kf[k];
            r->wd[k] = y[3 + k] - kf[3 + k];
        }
    }
    memcpy(r->y, y, s->n_est * sizeof(double));
    /* every output and the state to commit (found by fuzzing: samples near 1e307 m/s^2
     * overflowed w_dot and the products with GF_OK) */
    if (!gf_all_finite(r->w, 3) || !gf_all_finite(r->f, 3) || !gf_all_finite(r->wd, 3) ||
        !gf_all_finite(r->y, s->n_est) || !gf_all_finite(r->ref, 3) ||
        (st->cfg.strategy == GF_RATE_FUSED &&
         (!gf_all_finite(r->kf_x, 6) || !gf_all_finite(r->kf_P, 36))))
        return GF_ERR_DIVERGED;
    return GF_OK;
}


gf_status gf_gfins_step(gf_gfins_state *st, const double *A, double dt, double *f, double *w,
                        double *wd, double *W, uint8_t *flags)
{
    if (!st || !A)
        return GF_ERR_NULL_POINTER;
    if (!gfins_rate_state_valid(st))
        return GF_ERR_BAD_SIZE;
    rate_step_result r;
    const gf_status status = gfins_rate_step(st, A, dt, &r);
    if (status != GF_OK)
        return status;
    /* the products of a finite but absurd rate overflow (found by fuzzing: w = 1.8e308
     * rad/s gave GF_OK with NaN products): checked before anything is committed */
    double Wk[6];
    if (W) {
        rate_products(&st->solver, &r, Wk);
        if (!gf_all_finite(Wk, 6))
            return GF_ERR_DIVERGED;
    }
    rate_commit(st, &r);
    if (f) gf_v3_copy(r.f, f);
    if (w) gf_v3_copy(r.w, w);
    if (wd) gf_v3_copy(r.wd, wd);
    if (W) memcpy(W, Wk, sizeof Wk);
    if (flags) *flags = r.flags;
    return GF_OK;
}

gf_status gf_gfins_run(gf_gfins_state *st, size_t n, const double *A, double dt, double *f,
                       double *w, double *wd, double *W, uint8_t *flags, size_t *n_done)
{
    if (n_done)
        *n_done = 0;
    if (!st || !A || !f || !w || !wd || !flags)
        return GF_ERR_NULL_POINTER;
    if (!gfins_rate_state_valid(st))
        return GF_ERR_BAD_SIZE;
    if (!(dt > 0.0 && isfinite(dt)))
        return GF_ERR_BAD_TIME;
    const size_t ns = st->solver.n_sensors;
    gf_status status = GF_OK;
    size_t k = 0;
    for (; k < n; ++k) {
        rate_step_result r;
        status = gfins_rate_step(st, A + ns * k, dt, &r);
        if (status != GF_OK)
            break;
        if (W) {   /* as in gf_gfins_step: overflowing products refuse the sample */
            rate_products(&st->solver, &r, W + 6 * k);
            if (!gf_all_finite(W + 6 * k, 6)) {
                status = GF_ERR_DIVERGED;
                break;
            }
        }
        rate_commit(st, &r);
        gf_v3_copy(r.f, f + 3 * k);
        gf_v3_copy(r.w, w + 3 * k);
        gf_v3_copy(r.wd, wd + 3 * k);
        flags[k] = r.flags;
    }
    if (n_done)
        *n_done = k;
    return status;
}

